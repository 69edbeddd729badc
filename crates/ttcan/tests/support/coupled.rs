//! The coupled simulation the bench (`benches/coupled.rs`) and the instruction-count example
//! (`examples/coupled_icount.rs`) measure: mobile8's eight axes at its start configuration, and
//! one measured step of four 20 kHz ticks holding that configuration.

use ttcan::{CoupledOptions, CoupledSim};

/// Zero joint velocities and accelerations (rad/s, rad/s²) for the held setpoint.
const ZEROS: [f64; 8] = [0.0; 8];

/// mobile8's coupled simulation at its start configuration (returned too, m and rad), without
/// gravity: mobile8's first (prismatic) joint is vertical in its DH model and its drive cannot
/// hold the 15 kg base continuously (the I²t limit folds back after a second of benchmark); the
/// timing does not depend on it.
pub fn mobile8_sim() -> (CoupledSim, [f64; 8]) {
    let chain = ttkin::robots::mobile8();
    let q0 = ttkin::robots::mobile8_start();
    let options = CoupledOptions {
        gravity: Some([0.0; 3]),
        ..CoupledOptions::default()
    };
    let sim = CoupledSim::from_chain(&chain, &q0, options).expect("mobile8 has drives");
    (sim, q0)
}

/// The measured step: the setpoint `q0` (m, rad) held at rest, then four ticks.
#[inline]
pub fn four_ticks(sim: &mut CoupledSim, q0: &[f64; 8]) {
    sim.set_setpoint(q0, &ZEROS, &ZEROS, None).expect("8 values");
    sim.tick_n(std::hint::black_box(4));
}
