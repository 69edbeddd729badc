//! Criterion benchmarks of inverse kinematics: analytic gantry6 / arm4 (one pose, every branch;
//! and a 10,000-pose batch), numeric IK on ur5 and mobile8 (one solve over a cycle of random
//! reachable targets from a fixed start), differential IK.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use ttkin::ik::{joint_velocity, numeric::residual_dim, Analytic, IkScratch, IkSolver, LimitFilter, MAX_BRANCHES};
use ttkin::task::Task;
use ttkin::transform::write_row_major;
use ttkin::Chain;

fn targets(chain: &Chain, count: usize) -> Vec<nalgebra::IsometryMatrix3<f64>> {
    let mut rng = fastrand::Rng::with_seed(1);
    let limits = chain.limits();
    (0..count)
        .map(|_| {
            let q: Vec<f64> = limits
                .iter()
                .map(|l| l.lower + (l.upper - l.lower) * rng.f64())
                .collect();
            chain.fk(&q).unwrap()
        })
        .collect()
}

fn analytic(c: &mut Criterion) {
    for chain in [ttkin::robots::gantry6(), ttkin::robots::arm4()] {
        let ik = Analytic::for_chain(&chain).unwrap();
        let poses = targets(&chain, 1024);
        let mut i = 0;
        c.bench_function(&format!("ik_all/{}", chain.name()), |b| {
            b.iter(|| {
                i = (i + 1) % poses.len();
                black_box(ik.solve(black_box(&poses[i]), None, LimitFilter::Off).unwrap())
            })
        });
        let poses = targets(&chain, 10_000);
        let mut flat = vec![0.0; 16 * poses.len()];
        for (t, o) in poses.iter().zip(flat.chunks_exact_mut(16)) {
            write_row_major(t, o);
        }
        let mut out = vec![0.0; poses.len() * MAX_BRANCHES * chain.dof()];
        let mut counts = vec![0; poses.len()];
        c.bench_function(&format!("ik_all_batch_10000/{}", chain.name()), |b| {
            b.iter(|| {
                ik.solve_batch(black_box(&flat), LimitFilter::Off, &mut out, &mut counts)
                    .unwrap()
            })
        });
    }
}

fn numeric(c: &mut Criterion) {
    let h = std::f64::consts::FRAC_PI_2;
    let ur5_start = vec![0.0, -h, h, 0.0, h, 0.0];
    let cases = [
        ("ur5/pose", ttkin::robots::ur5(), Task::Pose, ur5_start),
        (
            "mobile8/pose",
            ttkin::robots::mobile8(),
            Task::Pose,
            ttkin::robots::mobile8_start().to_vec(),
        ),
        (
            "mobile8/racket5",
            ttkin::robots::mobile8(),
            Task::Racket { offset: 0.15 },
            ttkin::robots::mobile8_start().to_vec(),
        ),
    ];
    for (name, chain, task, q0) in cases {
        let solver = IkSolver {
            task,
            ..IkSolver::default()
        };
        let poses = targets(&chain, 1024);
        let mut scratch = IkScratch::new(&chain, residual_dim(&task));
        let mut i = 0;
        c.bench_function(&format!("ik/{name}"), |b| {
            b.iter(|| {
                i = (i + 1) % poses.len();
                black_box(solver.solve_with(&chain, &poses[i], &q0, &mut scratch).unwrap())
            })
        });
    }
}

fn differential(c: &mut Criterion) {
    let chain = ttkin::robots::gantry6();
    let q = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
    let v = [0.3, -0.2, 0.5, 1.0, -0.7, 0.4];
    c.bench_function("joint_velocity/gantry6", |b| {
        b.iter(|| black_box(joint_velocity(&chain, black_box(&q), &v).unwrap()))
    });
}

criterion_group!(benches, analytic, numeric, differential);
criterion_main!(benches);
