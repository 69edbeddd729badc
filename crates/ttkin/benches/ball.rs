//! Ball benchmarks: estimation from a 0.2 s window, prediction to the hitting plane, and the whole
//! per-ball planning step (estimate, predict, choose hit, IK, stroke) of the rally.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use std::hint::black_box;
use ttkin::ball::estimate::estimate;
use ttkin::ball::flight::{BallState, Flight, Plane};
use ttkin::ball::hitplan::ReturnPlanner;
use ttkin::ball::predict::crossing;
#[path = "../tests/support/ball_windows.rs"]
mod ball_windows;
use ball_windows::{estimate_options, observations};

fn ball(c: &mut Criterion) {
    let obs = observations(64);
    let opts = estimate_options();
    let mut k = 0;
    c.bench_function("ball_estimate_41obs", |b| {
        b.iter(|| {
            k = (k + 1) % obs.len();
            black_box(estimate(&obs[k].0, &obs[k].1, &opts).unwrap())
        })
    });
    let states: Vec<BallState> = obs.iter().map(|o| estimate(&o.0, &o.1, &opts).unwrap().state).collect();
    let plane = Plane {
        point: Vector3::new(-1.6, 0.0, 0.0),
        normal: Vector3::x(),
    };
    let flight = Flight::default();
    c.bench_function("ball_crossing_hitting_plane", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            black_box(crossing(&flight, &states[k], &plane, 2.0).unwrap())
        })
    });
    let planner = ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap();
    c.bench_function("ball_plan_per_ball", |b| {
        b.iter(|| {
            k = (k + 1) % obs.len();
            let e = estimate(&obs[k].0, &obs[k].1, &opts).unwrap();
            black_box(planner.plan(&e.state, 0.23, [0.9, 0.0]).unwrap())
        })
    });
}

criterion_group!(benches, ball);
criterion_main!(benches);
