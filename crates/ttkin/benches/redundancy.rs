//! Redundancy resolution and CLIK timings: one weighted least-norm step of mobile8 (task Jacobian,
//! Chan–Dubey weights, solve) and the whole 4 s seed000 tracking at 1 kHz.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use ttkin::clik::{track, ClikOptions, TaskTrajectory};
use ttkin::redundancy::{Damping, Weighting, WlsStep};
use ttkin::task::Task;
use ttkin::wholebody::WholeBody;

#[path = "../tests/support/seed000.rs"]
mod seed000;

fn wls_step(c: &mut Criterion) {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q = ttkin::robots::mobile8_start();
    let task = Task::Racket { offset: 0.15 };
    let mut step = WlsStep::new(&model, task, Weighting::ChanDubey, Damping::default()).unwrap();
    let xdot = [0.1, 0.05, -0.08, 0.3, -0.2];
    let prev = [0.01; 8];
    c.bench_function("wls_step mobile8 racket5 chan-dubey", |b| {
        b.iter(|| {
            let (qd, _) = step.solve(black_box(&q), black_box(&xdot), &prev);
            black_box(qd[0])
        })
    });
}

fn seed000_track(c: &mut Criterion) {
    let (model, q0, task, x0, x1) = seed000::seed000_line(0.15);
    let mut group = c.benchmark_group("clik");
    group.sample_size(20);
    group.bench_function("track seed000 4 s at 1 kHz", |b| {
        b.iter(|| {
            let traj = TaskTrajectory::line(task, &x0, &x1, 4.0, 1000.0).unwrap();
            let r = track(&model, black_box(&q0), &traj, ClikOptions::default()).unwrap();
            black_box(r.error.len())
        })
    });
    group.finish();
}

criterion_group!(benches, wls_step, seed000_track);
criterion_main!(benches);
