//! Criterion benchmarks of forward kinematics and the geometric Jacobian of the seed robots.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use nalgebra::Matrix6xX;
use ttkin::{robots, Chain, JacobianFrame};

fn configs() -> Vec<(&'static str, Chain, Vec<f64>)> {
    vec![
        ("gantry6", robots::gantry6(), vec![0.1, -0.2, 0.3, 0.4, 0.6, 0.1]),
        ("mobile8", robots::mobile8(), robots::mobile8_start().to_vec()),
    ]
}

fn fk(c: &mut Criterion) {
    let mut g = c.benchmark_group("fk");
    for (name, chain, q) in configs() {
        g.bench_with_input(BenchmarkId::from_parameter(name), &q, |b, q| {
            b.iter(|| chain.fk(black_box(q)).unwrap())
        });
    }
    g.finish();
}

fn jacobian(c: &mut Criterion) {
    let mut g = c.benchmark_group("jacobian");
    for (name, chain, q) in configs() {
        let mut j = Matrix6xX::zeros(chain.dof());
        g.bench_with_input(BenchmarkId::from_parameter(name), &q, |b, q| {
            b.iter(|| chain.jacobian_into(black_box(q), JacobianFrame::Base, &mut j))
        });
    }
    g.finish();
}

fn fk_batch(c: &mut Criterion) {
    let mut g = c.benchmark_group("fk_batch");
    let count = 100_000;
    g.throughput(Throughput::Elements(count as u64));
    for (name, chain, q) in configs() {
        let qs: Vec<f64> = (0..count)
            .flat_map(|k| q.iter().map(move |v| v + 1e-6 * k as f64))
            .collect();
        let mut out = vec![0.0; count * 16];
        g.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter(|| chain.fk_batch(black_box(&qs), &mut out))
        });
    }
    g.finish();
}

criterion_group!(benches, fk, jacobian, fk_batch);
criterion_main!(benches);
