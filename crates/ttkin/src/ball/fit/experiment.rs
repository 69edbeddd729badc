//! The calibration experiment: the held-out split, the published constants it is compared with,
//! the fit on the training flights and every model's prediction error on the held-out ones.

use super::prediction::{prediction_error, PredictionError, MIN_WINDOW};
use super::segments::{bounce_level, estimate_period, median, segment};
use super::{calibrate, Bounce, Calibration, FitModel, FitOptions, Recording};
use crate::ball::model::BallModel;
use crate::error::{Error, Result};
use rayon::prelude::*;

/// The held-out split: recordings sorted by name, every fourth (positions 3, 7, 11, … of the
/// sorted order) held out. Returns one flag per recording (true: held out).
pub fn held_out(names: &[&str]) -> Vec<bool> {
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by(|&a, &b| names[a].cmp(names[b]));
    let mut out = vec![false; names.len()];
    for (rank, &i) in order.iter().enumerate() {
        out[i] = rank % 4 == 3;
    }
    out
}

/// Published constants compared with the calibration on the same held-out flights, on the
/// recording's `surface` (m) and `period` (s): (name, model, source).
///
/// - `mpi_linear`: the MPI table-tennis code's ball model (drag k_d = 0.1414 /m, no spin, table
///   contact v' = (0.68·v_x, 0.72·v_y, −0.88·v_z); Mülling, Kober, Peters and Koç's robot
///   table-tennis code, github.com/RobotLearning `ball_params`/`loadTennisTableValues.m`, in the
///   same lab's frame as these recordings: y along the table). Its comment notes that 0.92 fits
///   observed data better than 0.88: `mpi_linear_092` uses c_z = 0.92.
/// - `muelling`, `tt3d`, `mpi`: the presets of [`BallModel`] (flight constants as published),
///   with this crate's impulse bounce at its pre-calibration constants (e = 0.93, μ = 0.25,
///   Nakashima et al. 2010).
/// - `aero_default`: the pre-calibration default (sphere aerodynamics, k_d = 0.1377, k_m = 0.00551).
pub fn published(surface: f64, period: f64) -> Vec<(&'static str, FitModel)> {
    let with = |model: BallModel, bounce: Bounce| FitModel {
        model,
        bounce,
        surface,
        period,
    };
    let pre = BallModel::from_air(1.184, 0.50, 1.0);
    let bounce = |m: BallModel| BallModel {
        table_restitution: 0.93,
        table_friction: 0.25,
        ..m
    };
    let flight = |k_drag: f64, k_magnus: f64| {
        bounce(BallModel {
            k_drag,
            k_magnus,
            ..pre
        })
    };
    vec![
        (
            "mpi_linear",
            with(flight(0.1414, 0.0), Bounce::Linear([0.68, 0.72, 0.88])),
        ),
        (
            "mpi_linear_092",
            with(flight(0.1414, 0.0), Bounce::Linear([0.68, 0.72, 0.92])),
        ),
        ("muelling", with(flight(0.1414, 0.001), Bounce::Impulse)),
        ("tt3d", with(flight(0.141, 0.0018), Bounce::Impulse)),
        ("mpi", with(flight(0.129, 0.00807), Bounce::Impulse)),
        ("aero_default", with(bounce(pre), Bounce::Impulse)),
    ]
}

/// One model's prediction errors on the held-out flights.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// Model name ("calibrated" or one of [`published`]).
    pub name: String,
    /// The model.
    pub model: FitModel,
    /// Per held-out flight (recording index, error); flights without a usable window left out.
    pub errors: Vec<(usize, PredictionError)>,
    /// Median over flights of the RMS error after the bounce (m).
    pub median_after_bounce: f64,
    /// Mean over flights of the RMS error after the bounce (m).
    pub mean_after_bounce: f64,
    /// Median over flights of the RMS error over every predicted frame (m).
    pub median_rms: f64,
}

/// The calibration experiment: frame period and bounce height from the data, the split
/// ([`held_out`]), the fit on the training flights and every model's prediction error on the
/// held-out flights from a `window`-frame start.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// Frame period (s) estimated from positions and velocities (the fit's starting value).
    pub period_estimate: f64,
    /// Height (m) of the bounces' lowest frames (median first minimum).
    pub bounce_level: f64,
    /// Held-out flag per recording.
    pub held_out: Vec<bool>,
    /// Recordings without a usable segment (indices).
    pub unusable: Vec<usize>,
    /// The fit on the training flights.
    pub calibration: Calibration,
    /// Calibrated first, then [`published`], on the same held-out flights.
    pub comparisons: Vec<Comparison>,
    /// Frames of the prediction window.
    pub window: usize,
}

/// Default prediction window (frames) of the calibration experiment: the observations a
/// prediction starts from.
pub const WINDOW: usize = 20;
/// The camera frame periods [`experiment`] takes, s (10 µs to 0.1 s: 100 kHz to 10 Hz), given
/// or estimated: the flights are integrated over their frames, and a period of 1e300 s ran for
/// hours (issue 29).
pub const FRAME_PERIOD_RANGE: (f64, f64) = (1e-5, 0.1);

/// Runs the calibration experiment (see [`Experiment`]); `period` overrides the estimate when given.
pub fn experiment(
    recordings: &[Recording],
    window: usize,
    period: Option<f64>,
    opts: &FitOptions,
) -> Result<Experiment> {
    if recordings.is_empty() {
        return Err(Error::invalid("recordings", "no flights given"));
    }
    if window < MIN_WINDOW {
        // no flight could be compared: the experiment would report no prediction error at all
        return Err(Error::invalid(
            "window",
            format!("at least {MIN_WINDOW} frames (the observations a prediction starts from), got {window}"),
        ));
    }
    for r in recordings {
        if !r.velocities.is_empty() && r.velocities.len() != r.positions.len() {
            return Err(Error::invalid(
                "recordings",
                format!(
                    "{}: {} velocities for {} positions",
                    r.name,
                    r.velocities.len(),
                    r.positions.len()
                ),
            ));
        }
    }
    let (lo, hi) = FRAME_PERIOD_RANGE;
    let period_estimate = match period {
        Some(p) if (lo..=hi).contains(&p) => p,
        Some(p) => {
            return Err(Error::invalid(
                "period",
                format!("a camera frame period in [{lo:e}, {hi}] s, got {p}"),
            ))
        }
        None => match estimate_period(recordings)? {
            p if (lo..=hi).contains(&p) => p,
            p => {
                return Err(Error::invalid(
                    "period",
                    format!(
                        "the frame period estimated from the flights' velocities, {p} s, is not a camera's \
                         (in [{lo:e}, {hi}] s): give the period"
                    ),
                ))
            }
        },
    };
    let level = bounce_level(recordings)?;
    let names: Vec<&str> = recordings.iter().map(|r| r.name.as_str()).collect();
    let held = held_out(&names);
    let unusable: Vec<usize> = (0..recordings.len())
        .filter(|&i| segment(&recordings[i], level, opts.bounce_band).is_none())
        .collect();
    let train: Vec<Recording> = recordings
        .iter()
        .zip(&held)
        .filter(|(_, &h)| !h)
        .map(|(r, _)| r.clone())
        .collect();
    let start_model = FitModel {
        model: BallModel {
            k_drag: 0.14,
            k_magnus: 0.002,
            table_restitution: 0.9,
            table_friction: 0.25,
            ..BallModel::default()
        },
        bounce: Bounce::Impulse,
        surface: level - BallModel::default().radius,
        period: period_estimate,
    };
    let calibration = calibrate(&train, &start_model, opts)?;
    let fit = calibration.fit;
    let prior = calibration.spin;
    let mut models = vec![("calibrated", fit)];
    models.extend(published(fit.surface, fit.period));
    let test: Vec<usize> = (0..recordings.len()).filter(|&i| held[i]).collect();
    let comparisons = models
        .into_iter()
        .map(|(name, model)| {
            let errors: Vec<(usize, PredictionError)> = test
                .par_iter()
                .filter_map(|&i| prediction_error(&recordings[i], &model, window, level, &prior, opts).map(|e| (i, e)))
                .collect();
            let mut after: Vec<f64> = errors.iter().map(|(_, e)| e.rms_after_bounce).collect();
            let mut all: Vec<f64> = errors.iter().map(|(_, e)| e.rms).collect();
            let mean_after_bounce = after.iter().sum::<f64>() / after.len().max(1) as f64;
            Comparison {
                name: name.to_string(),
                model,
                median_after_bounce: if after.is_empty() { f64::NAN } else { median(&mut after) },
                mean_after_bounce,
                median_rms: if all.is_empty() { f64::NAN } else { median(&mut all) },
                errors,
            }
        })
        .collect();
    Ok(Experiment {
        period_estimate,
        bounce_level: level,
        held_out: held,
        unusable,
        calibration,
        comparisons,
        window,
    })
}
