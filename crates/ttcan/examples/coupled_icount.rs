//! Runs the coupled bench's set-up for a fixed number of 4-tick iterations (instruction counting).
use ttcan::{CoupledOptions, CoupledSim};
fn main() {
    let iters: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let chain = ttkin::robots::mobile8();
    let q0 = ttkin::robots::mobile8_start();
    let options = CoupledOptions {
        gravity: Some([0.0; 3]),
        ..CoupledOptions::default()
    };
    let mut sim = CoupledSim::from_chain(&chain, &q0, options).expect("mobile8 has drives");
    let zeros = [0.0; 8];
    let t0 = std::time::Instant::now();
    for _ in 0..iters {
        sim.set_setpoint(&q0, &zeros, &zeros, None).expect("8 values");
        sim.tick_n(std::hint::black_box(4));
    }
    let dt = t0.elapsed().as_secs_f64() / iters as f64 * 1e6;
    println!("{dt:.3} us per 4 ticks; faults {:?}", sim.fault_names());
}
