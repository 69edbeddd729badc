//! Coupled multi-axis simulation timing (issue 10): one 20 kHz tick of mobile8's eight axes, each
//! a full cascade with its winding, on the robot's rigid-body dynamics (M and h refreshed every
//! four ticks, so a run of 4 ticks shows the amortised cost).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ttcan::{CoupledOptions, CoupledSim};

fn coupled_tick(c: &mut Criterion) {
    let chain = ttkin::robots::mobile8();
    let q0 = ttkin::robots::mobile8_start();
    // Without gravity: mobile8's first (prismatic) joint is vertical in its DH model and its drive
    // cannot hold the 15 kg base continuously (the I²t limit folds back after a second of
    // benchmark); the timing does not depend on it.
    let options = CoupledOptions {
        gravity: Some([0.0; 3]),
        ..CoupledOptions::default()
    };
    let mut sim = CoupledSim::from_chain(&chain, &q0, options).expect("mobile8 has drives");
    let zeros = [0.0; 8];
    let mut g = c.benchmark_group("coupled_sim");
    g.throughput(Throughput::Elements(4));
    g.bench_function("mobile8_4_ticks_20khz", |b| {
        b.iter(|| {
            sim.set_setpoint(&q0, &zeros, &zeros, None).expect("8 values");
            sim.tick_n(black_box(4));
        })
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
