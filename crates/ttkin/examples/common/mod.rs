//! Helpers the decision-timing examples share (`refine_time`, `speculate_time`): thread CPU time,
//! a percentile row, the joint state a stroke commands.
use ttkin::traj::{JointState, JointTrajectory};

/// `f()` and the thread CPU time it took (µs).
pub fn cpu_us<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let c = cpu_time::ThreadTime::now();
    let out = f();
    (out, c.elapsed().as_secs_f64() * 1e6)
}

/// Prints `v`'s count and p50/p90/p99/max (µs) under `name`, sorting `v`.
pub fn row(name: &str, v: &mut [f64]) {
    v.sort_by(f64::total_cmp);
    let q = |p: f64| {
        v.get(((v.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    println!(
        "{name:<34} n {:>5}  p50 {:>7.0} µs  p90 {:>7.0}  p99 {:>7.0}  max {:>7.0}",
        v.len(),
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0)
    );
}

/// The joint state commanded at `tc` (s): the stroke under way (start time, trajectory), else ready.
#[allow(dead_code)] // not every example runs strokes
pub fn state_of(stroke: &Option<(f64, JointTrajectory)>, ready: &JointState, tc: f64) -> JointState {
    match stroke {
        Some((t0, tr)) => {
            let n = ready.q.len();
            let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            tr.sample((tc - t0).clamp(0.0, tr.duration()), &mut q, &mut qd, &mut qdd)
                .expect("sample");
            JointState { q, qd, qdd }
        }
        None => ready.clone(),
    }
}
