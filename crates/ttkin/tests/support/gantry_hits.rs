//! The gantry6 hit sets shared by the hit test, the hit bench and the `hit_icount` example:
//! racket centre x ∈ [−0.3, 0.3], y ∈ [−0.6, −0.2], z ∈ [−0.15, 0.15] m, face normal within
//! 0.7 rad of −y about x and z, 1–4 m/s along the normal.
#![allow(dead_code)]

use nalgebra::Vector3;
use ttkin::hit::Hit;
use ttkin::traj::JointState;

/// `count` random hits at `t` s from the seeded generator `seed`.
pub fn hits(count: usize, t: f64, seed: u64) -> Vec<Hit> {
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

/// Names of the stored plan sets: on time (0.6 s from rest), too early (0.01 s from rest),
/// from a moving state (0.35 s).
pub const SETS: [&str; 3] = ["ontime", "early", "moving"];

/// Hit time (s) and start state (`None`: at rest at the ready pose) of set `name`.
pub fn set(name: &str) -> (f64, Option<JointState>) {
    match name {
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
    }
}

/// Hits of every stored set (1,000 each, seed 11).
pub fn set_hits(name: &str) -> Vec<Hit> {
    hits(1000, set(name).0, 11)
}
