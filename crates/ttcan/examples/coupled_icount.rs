//! Runs the coupled bench's set-up for a fixed number of 4-tick iterations (instruction counting).
#[path = "../tests/support/coupled.rs"]
mod coupled;

fn main() {
    let iters: usize = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(100_000);
    let (mut sim, q0) = coupled::mobile8_sim();
    let t0 = std::time::Instant::now();
    for _ in 0..iters {
        coupled::four_ticks(&mut sim, &q0);
    }
    let dt = t0.elapsed().as_secs_f64() / iters as f64 * 1e6;
    println!("{dt:.3} us per 4 ticks; faults {:?}", sim.fault_names());
}
