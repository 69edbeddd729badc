//! The prediction error of a fixed model on one flight: its state fitted on the first frames,
//! then predicted through the bounce and compared with the later frames.

use super::problem::{fit_nuisance, flight_axes, start, state_of, Problem};
use super::segments::segment;
use super::{FitModel, FitOptions, Recording, SpinPrior};
use nalgebra::Vector3;

/// The shortest prediction window, frames: the observations a predicted state is fitted on.
pub const MIN_WINDOW: usize = 5;

/// Prediction error of one flight under a fixed model.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionError {
    /// Frames the state was fitted on.
    pub window: usize,
    /// Frames predicted (the rest of the segment).
    pub predicted: usize,
    /// RMS distance (m) between predicted and observed positions over the predicted frames
    /// after the bounce frame.
    pub rms_after_bounce: f64,
    /// RMS distance (m) over every predicted frame.
    pub rms: f64,
    /// Largest distance (m) over the predicted frames.
    pub max: f64,
    /// The predicted positions (m) at every frame of the segment (the window's included).
    pub path: Vec<[f64; 3]>,
}

/// The prediction error of `fm` on `recording` (see the module doc): its state fitted on the
/// first `window` frames, then predicted over the rest of its segment (found with `level`, the
/// bounces' height of [`bounce_level`](super::bounce_level)). `None` without a segment, or when the window does not
/// end at least two frames before the bounce.
pub fn prediction_error(
    recording: &Recording,
    fm: &FitModel,
    window: usize,
    level: f64,
    prior: &SpinPrior,
    opts: &FitOptions,
) -> Option<PredictionError> {
    let (end, b) = segment(recording, level, opts.bounce_band)?;
    if window < MIN_WINDOW || window + 2 > b {
        return None;
    }
    let x = start(recording, fm.period);
    let axes = flight_axes(&Vector3::new(x[3], x[4], x[5]));
    let mut pb = Problem {
        obs: &recording.positions[..window],
        weights: vec![1.0; window],
        x,
        spin_mean: axes * Vector3::from(prior.mean),
        prior_axes: axes.transpose(),
        prior_std: Vector3::from(prior.std),
    };
    pb.x.fixed_rows_mut::<3>(6).copy_from(&pb.spin_mean);
    fit_nuisance(fm, &mut pb, opts);
    let path = fm.path(&state_of(&pb.x), end, opts.step);
    let d: Vec<f64> = (window..end)
        .map(|k| (path[k] - Vector3::from(recording.positions[k])).norm())
        .collect();
    let rms = |s: &[f64]| (s.iter().map(|x| x * x).sum::<f64>() / s.len().max(1) as f64).sqrt();
    Some(PredictionError {
        window,
        predicted: d.len(),
        rms_after_bounce: rms(&d[(b + 1 - window)..]),
        rms: rms(&d),
        max: d.iter().copied().fold(0.0, f64::max),
        path: path.iter().map(|p| (*p).into()).collect(),
    })
}
