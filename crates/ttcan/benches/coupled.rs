//! Coupled multi-axis simulation timing (issue 10): one 20 kHz tick of mobile8's eight axes, each
//! a full cascade with its winding, on the robot's rigid-body dynamics (M and h refreshed every
//! four ticks, so a run of 4 ticks shows the amortised cost).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};

#[path = "../tests/support/coupled.rs"]
mod coupled;

fn coupled_tick(c: &mut Criterion) {
    let (mut sim, q0) = coupled::mobile8_sim();
    let mut g = c.benchmark_group("coupled_sim");
    g.throughput(Throughput::Elements(4));
    g.bench_function("mobile8_4_ticks_20khz", |b| {
        b.iter(|| coupled::four_ticks(&mut sim, &q0))
    });
    g.finish();
    assert!(
        sim.fault_names().iter().all(|f| f.is_empty()),
        "{:?}",
        sim.fault_names()
    );
}

criterion_group!(benches, coupled_tick);
criterion_main!(benches);
