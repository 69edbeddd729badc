//! Criterion benchmarks of the hit pipeline on gantry6: one `plan_hit` (IK + J⁻¹V + stroke +
//! effort check; no sampling) for hits on time and too early, a 1,000-hit batch, and the
//! jerk-limited leg alone.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use ttkin::hit::{HitOptions, HitPlanner};
use ttkin::traj::jerk::{jerk_limited, PositionLimits};
use ttkin::traj::JointState;

#[path = "../tests/support/gantry_hits.rs"]
mod gantry_hits;

/// The hits of the bench: see [`gantry_hits::hits`] (seed 7).
fn hits(count: usize, t: f64) -> Vec<ttkin::hit::Hit> {
    gantry_hits::hits(count, t, 7)
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
