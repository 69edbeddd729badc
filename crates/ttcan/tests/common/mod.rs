//! Helpers shared by the ttcan tests: the reference motor, a quintic, step-response metrics.
#![allow(dead_code)]

use ttcan::{AxisConfig, MotorModel, Simulation};

/// The documented maxon RE 25 + GP 26 A 14:1 actuator.
pub fn model() -> MotorModel {
    MotorModel::maxon_re25_gp26()
}

/// Default axis on the reference actuator.
pub fn sim() -> Simulation {
    Simulation::new(&model(), &AxisConfig::new(model())).expect("reference configuration is valid")
}

/// Simulation with a changed configuration.
pub fn sim_with(f: impl FnOnce(&mut AxisConfig)) -> Simulation {
    let mut c = AxisConfig::new(model());
    f(&mut c);
    Simulation::new(&model(), &c).expect("test configuration is valid")
}

/// Rest-to-rest quintic from 0 to `h` in `tf` seconds (seed 002's quintic with zero boundary
/// velocities and accelerations): (q, qd, qdd) at time t, held at the end after tf.
pub fn quintic(h: f64, tf: f64, t: f64) -> (f64, f64, f64) {
    let s = (t / tf).clamp(0.0, 1.0);
    (
        h * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s),
        h / tf * 30.0 * s * s * (1.0 - s) * (1.0 - s),
        h / (tf * tf) * 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s),
    )
}

/// 10 %–90 % rise time of `y` towards `target`, s.
pub fn rise_time(t: &[f64], y: &[f64], target: f64) -> f64 {
    let first = |level: f64| t.iter().zip(y).find(|(_, v)| **v >= level * target).map(|(t, _)| *t);
    match (first(0.1), first(0.9)) {
        (Some(a), Some(b)) => b - a,
        _ => f64::INFINITY,
    }
}

/// Overshoot of `y` above `target`, as a fraction of `target`.
pub fn overshoot(y: &[f64], target: f64) -> f64 {
    y.iter().cloned().fold(f64::MIN, f64::max) / target - 1.0
}

/// Mean of the samples of `y` whose time is in [t0, t1).
pub fn mean_between(t: &[f64], y: &[f64], t0: f64, t1: f64) -> f64 {
    let v: Vec<f64> = t
        .iter()
        .zip(y)
        .filter(|(t, _)| **t >= t0 && **t < t1)
        .map(|(_, y)| *y)
        .collect();
    v.iter().sum::<f64>() / v.len() as f64
}
