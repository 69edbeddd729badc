//! Criterion benchmarks of the hit pipeline on gantry6: one `plan_hit` (IK + J⁻¹V + stroke +
//! effort check; no sampling) for hits on time and too early, a 1,000-hit batch, and the
//! jerk-limited leg alone.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use std::hint::black_box;
use ttkin::hit::{Hit, HitOptions, HitPlanner};
use ttkin::traj::jerk::{jerk_limited, PositionLimits};
use ttkin::traj::JointState;

/// Random gantry6 hits: centre x ∈ [−0.3, 0.3], y ∈ [−0.6, −0.2], z ∈ [−0.15, 0.15] m, normal
/// within 0.7 rad of −y about x and z, 1–4 m/s along the normal, at `t` s.
fn hits(count: usize, t: f64) -> Vec<Hit> {
    let mut rng = fastrand::Rng::with_seed(7);
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

fn plan(c: &mut Criterion) {
    let planner = HitPlanner::new(&ttkin::robots::gantry6(), HitOptions::default()).unwrap();
    for (name, t) in [("on_time", 0.6), ("too_early", 0.01)] {
        let hs = hits(256, t);
        let mut i = 0;
        c.bench_function(&format!("plan_hit/gantry6/{name}"), |b| {
            b.iter(|| {
                i = (i + 1) % hs.len();
                black_box(planner.plan(black_box(&hs[i]), None, None).unwrap())
            })
        });
    }
    let batch = hits(1000, 0.6);
    c.bench_function("plan_hits/gantry6/1000", |b| {
        b.iter(|| black_box(planner.plan_batch(black_box(&batch), None, None).unwrap()))
    });
    let plans = planner.plan_batch(&batch, None, None).unwrap();
    let legs: Vec<_> = plans
        .iter()
        .filter(|p| p.q_hit[0].is_finite())
        .map(|p| JointState {
            q: p.q_hit.clone(),
            qd: p.qd_hit.clone(),
            qdd: vec![0.0; 6],
        })
        .collect();
    let start = JointState::rest(planner.default_ready());
    let mut i = 0;
    c.bench_function("jerk_limited/gantry6", |b| {
        b.iter(|| {
            i = (i + 1) % legs.len();
            black_box(jerk_limited(
                &start,
                &legs[i],
                planner.limits(),
                None,
                PositionLimits::Ignore,
            ))
        })
    });
}

criterion_group!(benches, plan);
criterion_main!(benches);
