//! Success rate and solve times of the numeric IK over random reachable targets.
//!
//! `cargo run --release -p ttkin --example ik_success [-- N]`: for each case, N targets (default
//! 10,000) are the FK of uniformly random configurations within the limits; every solve starts
//! from the same fixed configuration. Prints success rate, median / p99 / max time, iterations.

use std::time::Instant;

use ttkin::ik::IkSolver;
use ttkin::task::{Task, SEED_RACKET_OFFSET};
use ttkin::Chain;

fn main() {
    let count: usize = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .and_then(|a| a.parse().ok())
        .unwrap_or(10_000);
    let ur5_start = [
        0.0,
        -std::f64::consts::FRAC_PI_2,
        std::f64::consts::FRAC_PI_2,
        0.0,
        std::f64::consts::FRAC_PI_2,
        0.0,
    ];
    let cases: [(&str, Chain, Task, Vec<f64>); 4] = [
        ("ur5 pose", ttkin::robots::ur5(), Task::Pose, ur5_start.to_vec()),
        (
            "mobile8 pose",
            ttkin::robots::mobile8(),
            Task::Pose,
            ttkin::robots::mobile8_start().to_vec(),
        ),
        (
            "mobile8 racket5",
            ttkin::robots::mobile8(),
            Task::Racket {
                offset: SEED_RACKET_OFFSET,
            },
            ttkin::robots::mobile8_start().to_vec(),
        ),
        ("ur5 position", ttkin::robots::ur5(), Task::Position, ur5_start.to_vec()),
    ];
    println!(
        "{:<18} {:>9} {:>10} {:>10} {:>10} {:>8} {:>9}",
        "case", "success%", "median µs", "p99 µs", "max µs", "iters", "restarts"
    );
    for (name, chain, task, q0) in cases {
        // `--no-budget`: restarts bounded by count only, to judge the algorithm on a loaded machine.
        let budget = if std::env::args().any(|a| a == "--no-budget") {
            None
        } else {
            IkSolver::default().time_budget
        };
        let solver = IkSolver {
            task,
            time_budget: budget,
            ..IkSolver::default()
        };
        let mut it_each = Vec::with_capacity(count);
        let mut rng = fastrand::Rng::with_seed(42);
        let limits = chain.limits();
        let mut scratch = ttkin::ik::IkScratch::new(&chain, ttkin::ik::numeric::residual_dim(&task));
        let (mut ok, mut iters, mut restarts) = (0usize, 0usize, 0usize);
        let mut times = Vec::with_capacity(count);
        let mut failed_restarts = Vec::new();
        for _ in 0..count {
            let q: Vec<f64> = limits
                .iter()
                .map(|l| l.lower + (l.upper - l.lower) * rng.f64())
                .collect();
            let target = chain.fk(&q).expect("valid configuration");
            let start = Instant::now();
            let r = solver
                .solve_with(&chain, &target, &q0, &mut scratch)
                .expect("valid input");
            let dt = start.elapsed().as_secs_f64() * 1e6;
            times.push(dt);
            if r.success && dt <= 1000.0 {
                ok += 1;
            }
            if !r.success {
                failed_restarts.push(r.restarts);
            }
            iters += r.iterations;
            it_each.push(r.iterations);
            restarts += r.restarts;
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{:<18} {:>9.3} {:>10.1} {:>10.1} {:>10.1} {:>8.1} {:>9.3}",
            name,
            100.0 * ok as f64 / count as f64,
            times[count / 2],
            times[count * 99 / 100],
            times[count - 1],
            iters as f64 / count as f64,
            restarts as f64 / count as f64
        );
        it_each.sort();
        println!(
            "    iterations p50 {} p99 {} p99.9 {} max {}",
            it_each[count / 2],
            it_each[count * 99 / 100],
            it_each[count * 999 / 1000],
            it_each[count - 1]
        );
        if !failed_restarts.is_empty() {
            println!(
                "    unsolved: {} (restarts used: {:?})",
                failed_restarts.len(),
                &failed_restarts[..failed_restarts.len().min(12)]
            );
        }
    }
}
