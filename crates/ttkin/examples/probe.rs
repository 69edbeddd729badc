use ttkin::clik::*;
use ttkin::redundancy::*;
use ttkin::task::*;
use ttkin::wholebody::*;
fn main() {
    let chain = ttkin::robots::mobile8();
    let q0 = ttkin::robots::mobile8_start();
    let model = WholeBody::fixed(chain.clone());
    let t = model.tool_pose(&q0).unwrap();
    let task = Task::Racket { offset: 0.15 };
    let mut x0 = [0.0; 5];
    task.coordinates(&t, &mut x0);
    let xp0 = [0.4776, 0.8652, 0.2443, 0.2083, 1.3247];
    let xp1 = [0.5501, 1.0647, 0.3998, 0.4699, 1.0528];
    for dir in 0..1 {
        for &frac in &[0.15, 0.17] {
            let x1: Vec<f64> = (0..5)
                .map(|i| {
                    if dir == 0 {
                        x0[i] + frac * (xp1[i] - x0[i])
                    } else {
                        x0[i] + frac * (xp1[i] - xp0[i])
                    }
                })
                .collect();
            let mut line = format!("dir {dir} s {frac}: ");
            for (w, lim) in [(Weighting::ChanDubey, true), (Weighting::None, false)] {
                let traj = TaskTrajectory::line(task, &x0, &x1, 4.0, 1000.0).unwrap();
                let opts = ClikOptions {
                    weighting: w,
                    respect_limits: lim,
                    max_error: 10.0,
                    ..Default::default()
                };
                let t0 = std::time::Instant::now();
                let r = track(&model, &q0, &traj, opts).unwrap();
                let el = t0.elapsed();
                let maxe = r.error.iter().cloned().fold(0.0, f64::max);
                let minm = r.margin.iter().cloned().fold(f64::INFINITY, f64::min);
                let mins = r.sigma_min.iter().cloned().fold(f64::INFINITY, f64::min);
                let qd = r.qdot.iter().cloned().fold(0.0f64, |a, b| a.max(b.abs()));
                let st = match r.status {
                    ClikStatus::Completed => "ok".to_string(),
                    ClikStatus::Saturated { samples, .. } => format!("sat{samples}"),
                    ClikStatus::Failed { .. } => "FAIL".into(),
                };
                let n = r.len();
                let mut mm = String::new();
                for j in 0..8 {
                    let lo = (0..n).map(|k| r.q[k * 8 + j]).fold(f64::INFINITY, f64::min);
                    let hi = (0..n).map(|k| r.q[k * 8 + j]).fold(f64::NEG_INFINITY, f64::max);
                    let l = chain.limits()[j];
                    mm += &format!(
                        " j{} [{:.1},{:.1}] lim [{:.1},{:.1}]\n",
                        j + 1,
                        lo.to_degrees(),
                        hi.to_degrees(),
                        l.lower.to_degrees(),
                        l.upper.to_degrees()
                    );
                }
                println!("{:?}\n{}", w, mm);
                line += &format!(
                    "| {st} e {maxe:.1e} m {minm:.3} sig {mins:.1e} qd {qd:.2} {:.1}ms ",
                    el.as_secs_f64() * 1e3
                );
            }
            println!("{line}");
        }
    }
}
