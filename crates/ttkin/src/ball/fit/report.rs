//! The report form of the experiment (serde): plain records, the calibration's globals and their
//! standard deviations keyed by `GLOBAL_NAMES`, ball states as 10-value rows (`BallState::to_array`),
//! paths as rows of 3 (m); what `ttmanip.ball_fit` returns and writes.

use super::{Bounce, Calibration, Comparison, Experiment, FlightFit, PredictionError, GLOBAL_NAMES};

/// Values keyed by [`GLOBAL_NAMES`] (serde: a map).
struct Globals<'a>(&'a [f64; 6]);

impl serde::Serialize for Globals<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_map(GLOBAL_NAMES.iter().zip(self.0.iter()))
    }
}

/// Rows of fixed width as a sequence of sequences (serde).
fn rows<const N: usize>(rows: &[[f64; N]]) -> Vec<&[f64]> {
    rows.iter().map(|r| &r[..]).collect()
}

impl serde::Serialize for Experiment {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(7))?;
        m.serialize_entry("period_estimate", &self.period_estimate)?;
        m.serialize_entry("bounce_level", &self.bounce_level)?;
        m.serialize_entry("held_out", &self.held_out)?;
        m.serialize_entry("unusable", &self.unusable)?;
        m.serialize_entry("window", &self.window)?;
        m.serialize_entry("calibration", &self.calibration)?;
        m.serialize_entry("comparisons", &self.comparisons)?;
        m.end()
    }
}

impl serde::Serialize for Calibration {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(10))?;
        m.serialize_entry("globals", &Globals(&self.globals))?;
        m.serialize_entry("std", &Globals(&self.std))?;
        m.serialize_entry("correlation", &rows(&self.correlation))?;
        m.serialize_entry("sigma", &self.sigma)?;
        m.serialize_entry("rms", &self.rms)?;
        m.serialize_entry("iterations", &self.iterations)?;
        m.serialize_entry("observations", &self.observations)?;
        m.serialize_entry("spin_mean", &self.spin.mean[..])?;
        m.serialize_entry("spin_std", &self.spin.std[..])?;
        m.serialize_entry("flights", &self.flights)?;
        m.end()
    }
}

impl serde::Serialize for FlightFit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(6))?;
        m.serialize_entry("index", &self.index)?;
        m.serialize_entry("state", &self.state.to_array()[..])?;
        m.serialize_entry("frames", &self.frames)?;
        m.serialize_entry("bounce_frame", &self.bounce_frame)?;
        m.serialize_entry("rms", &self.rms)?;
        m.serialize_entry("friction_to_roll", &self.friction_to_roll)?;
        m.end()
    }
}

impl serde::Serialize for Comparison {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("name", &self.name)?;
        m.serialize_entry("k_drag", &self.model.model.k_drag)?;
        m.serialize_entry("k_magnus", &self.model.model.k_magnus)?;
        match self.model.bounce {
            Bounce::Impulse => {
                m.serialize_entry("bounce", "impulse")?;
                m.serialize_entry("table_restitution", &self.model.model.table_restitution)?;
                m.serialize_entry("table_friction", &self.model.model.table_friction)?;
            }
            Bounce::Linear(k) => {
                m.serialize_entry("bounce", "linear")?;
                m.serialize_entry("linear", &k[..])?;
            }
        }
        m.serialize_entry("median_after_bounce", &self.median_after_bounce)?;
        m.serialize_entry("mean_after_bounce", &self.mean_after_bounce)?;
        m.serialize_entry("median_rms", &self.median_rms)?;
        let errors: Vec<IndexedError<'_>> = self.errors.iter().map(|(i, e)| IndexedError(*i, e)).collect();
        m.serialize_entry("errors", &errors)?;
        m.end()
    }
}

/// A held-out flight's prediction error with the flight's index (serde: one record).
struct IndexedError<'a>(usize, &'a PredictionError);

impl serde::Serialize for IndexedError<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let e = self.1;
        let mut m = s.serialize_map(Some(7))?;
        m.serialize_entry("index", &self.0)?;
        m.serialize_entry("window", &e.window)?;
        m.serialize_entry("predicted", &e.predicted)?;
        m.serialize_entry("rms_after_bounce", &e.rms_after_bounce)?;
        m.serialize_entry("rms", &e.rms)?;
        m.serialize_entry("max", &e.max)?;
        m.serialize_entry("path", &rows(&e.path))?;
        m.end()
    }
}
