//! Helpers shared by the ttcan tests: the reference motor, a running axis, a quintic,
//! step-response metrics.
#![allow(dead_code)]

use ttcan::{AxisConfig, AxisState, Mode, MotorModel, Setpoint, Simulation};

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

/// An axis with a changed configuration running at 15 rad/s after 200 ms in velocity mode.
pub fn running_with(f: impl FnOnce(&mut AxisConfig)) -> Simulation {
    let mut s = sim_with(f);
    assert!(s.enable(Mode::Velocity));
    s.run(0.2, |_| Setpoint::Velocity(15.0)).unwrap();
    assert_eq!(s.axis.state(), AxisState::Enabled);
    assert!(
        (s.plant.output_speed() - 15.0).abs() < 0.5,
        "speed {}",
        s.plant.output_speed()
    );
    s
}

/// The default axis running at 15 rad/s after 200 ms in velocity mode.
pub fn running() -> Simulation {
    running_with(|_| {})
}

/// Rest-to-rest quintic from 0 to `h` in `tf` seconds (ttkin's quintic with zero boundary
/// velocities and accelerations): (q, qd, qdd) at time t, held at the end after tf.
pub fn quintic(h: f64, tf: f64, t: f64) -> (f64, f64, f64) {
    let c = ttkin::traj::poly::quintic(0.0, 0.0, 0.0, h, 0.0, 0.0, tf);
    let [q, qd, qdd] = ttkin::traj::poly::eval3(&c, t.clamp(0.0, tf));
    if t >= tf {
        (q, 0.0, 0.0)
    } else {
        (q, qd, qdd)
    }
}

#[allow(unused_imports)]
pub use ttcan::sim::{overshoot, rise_time};

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
