//! Fixed work of the gantry6 hit planner for instruction counts under valgrind and for comparing
//! plans bit for bit: `hit_icount plan N` plans N on-time hits (single thread),
//! `hit_icount dump SET` prints every product of 1,000 plans of set `ontime`, `early` or `moving`
//! with round-trip floats.
use nalgebra::Vector3;
use std::hint::black_box;
use ttkin::hit::{Hit, HitOptions, HitPlan, HitPlanner};
use ttkin::traj::JointState;

/// The bench distribution (see `benches/hit.rs`): centre x ∈ [−0.3, 0.3], y ∈ [−0.6, −0.2],
/// z ∈ [−0.15, 0.15] m, normal within 0.7 rad of −y, 1–4 m/s along the normal, at `t` s.
fn hits(count: usize, t: f64, seed: u64) -> Vec<Hit> {
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.f64();
    (0..count)
        .map(|_| {
            let (x, y, z) = (u(-0.3, 0.3), u(-0.6, -0.2), u(-0.15, 0.15));
            let (a, b, s) = (u(-0.7, 0.7), u(-0.7, 0.7), u(1.0, 4.0));
            let n = Vector3::new(a.sin(), -a.cos() * b.cos(), b.sin()).normalize();
            let v = n * s;
            Hit::from_normal([x, y, z], [n.x, n.y, n.z], [v.x, v.y, v.z], t, None, None).unwrap()
        })
        .collect()
}

fn dump(p: &HitPlan) {
    print!(
        "{} {} {:?} {:?} {} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        p.status.name(),
        p.branches,
        p.t_hit,
        p.earliest_t_hit,
        p.profile.name(),
        p.return_duration,
        p.q_hit,
        p.qd_hit,
        p.sigma_min,
        p.peak_effort,
        p.effort_ratio,
        p.violations,
        p.message,
        p.ready,
    );
    if let Some(t) = &p.trajectory {
        print!(" knots {:?}", t.knots());
        for s in 0..t.segments() {
            for j in 0..t.dof() {
                print!(" {:?}", t.coefficients(s, j));
            }
        }
    }
    println!();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let planner = HitPlanner::new(&ttkin::robots::gantry6(), HitOptions::default()).unwrap();
    match args[1].as_str() {
        "plan" => {
            let n: usize = args[2].parse().unwrap();
            let hs = hits(256, 0.6, 7);
            for i in 0..n {
                black_box(planner.plan(black_box(&hs[i % hs.len()]), None, None).unwrap());
            }
        }
        "dump" => {
            let (t, state) = match args[2].as_str() {
                "ontime" => (0.6, None),
                "early" => (0.01, None),
                _ => (
                    0.35,
                    Some(JointState {
                        q: vec![0.05, -0.1, 0.2, 0.5, 0.7, -0.3],
                        qd: vec![0.2, -0.1, 0.5, -0.3, 0.4, 0.6],
                        qdd: vec![0.5, 0.3, -1.0, 0.8, -0.6, 1.2],
                    }),
                ),
            };
            for h in hits(1000, t, 11) {
                dump(&planner.plan(&h, state.as_ref(), None).unwrap());
            }
        }
        other => panic!("unknown op {other}"),
    }
}
