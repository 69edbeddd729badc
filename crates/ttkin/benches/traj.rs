//! Trajectory benchmarks: build an 8-joint quintic and sample it, the exact limit check, and the
//! hitting stroke with an infeasible requested hit time.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use ttkin::traj::{stroke, JointState, JointTrajectory, KinematicLimits};

fn quintic_build_and_sample(c: &mut Criterion) {
    // Vectors, not arrays, and sizes behind black_box: the joint and sample counts stay unknown to
    // the compiler, as in a call from Python.
    let q0 = black_box(vec![0.1, -0.2, 0.3, -0.4, 0.5, -0.6, 0.7, -0.8]);
    let q1 = black_box(vec![1.0, 0.9, -0.8, 0.7, -0.6, 0.5, 0.4, 0.3]);
    let v1 = black_box(vec![0.5; 8]);
    let n = black_box(101);
    let (mut t, mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; 8 * n], vec![0.0; 8 * n], vec![0.0; 8 * n]);
    c.bench_function("quintic8_build_sample101", |b| {
        b.iter(|| {
            let traj = JointTrajectory::quintic(&q0, &q1, None, Some(&v1), None, None, black_box(0.8)).unwrap();
            traj.sample_uniform_into(&mut t, &mut q, &mut qd, &mut qdd).unwrap();
            black_box(q[404])
        })
    });
    // Joint-major output (numpy Fortran order), as the Python binding uses.
    c.bench_function("quintic8_build_sample101_columns", |b| {
        b.iter(|| {
            let traj = JointTrajectory::quintic(&q0, &q1, None, Some(&v1), None, None, black_box(0.8)).unwrap();
            traj.sample_uniform_columns_into(&mut t, &mut q, &mut qd, &mut qdd)
                .unwrap();
            black_box(q[404])
        })
    });
}

fn limits_and_stroke(c: &mut Criterion) {
    let traj =
        JointTrajectory::quintic(&[0.0; 8], &[1.0; 8], Some(&[0.3; 8]), Some(&[1.0; 8]), None, None, 0.8).unwrap();
    let limits = KinematicLimits::new(&[3.0; 8], &[30.0; 8], &[600.0; 8]).unwrap();
    c.bench_function("check_limits_quintic8", |b| {
        b.iter(|| black_box(traj.check_limits(&limits).unwrap()))
    });
    let start = JointState::rest(&[0.0; 8]);
    let hit = JointState {
        q: vec![0.8, -0.4, 0.6, 1.0, 0.2, -0.3, 0.5, 0.1],
        qd: vec![2.0, -1.0, 1.5, 2.5, 0.5, 0.0, 1.0, -0.5],
        qdd: vec![0.0; 8],
    };
    c.bench_function("stroke8_infeasible_t_hit", |b| {
        b.iter(|| black_box(stroke(&start, &hit, 0.1, &[0.0; 8], None, &limits).unwrap()))
    });
}

criterion_group!(benches, quintic_build_and_sample, limits_and_stroke);
criterion_main!(benches);
