//! Control-loop timing: one control cycle of 8 axes (the multi-rate stepper with its bookkeeping,
//! all three loops due on every tick as the worst case, and a whole position period of 20 ticks at
//! the default 20/5/1 kHz) and a single current-loop step.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ttcan::loops::{CurrentLoop, Pi};
use ttcan::{Axis, AxisConfig, AxisState, Measurement, Mode, MotorModel, Rates, Stepper};

const AXES: usize = 8;

/// 8 enabled position-mode axes on `rates`, plus 64 slightly varying measurements per axis.
fn stepper(rates: Rates) -> (Stepper<AXES>, Vec<[Measurement; AXES]>) {
    let mut config = AxisConfig::new(MotorModel::maxon_re25_gp26());
    config.rates = rates;
    let axis = Axis::new(&config).expect("valid configuration");
    let mut s = Stepper::new(std::array::from_fn(|_| axis.clone())).expect("same rates");
    let rest = [Measurement::default(); AXES];
    let mut duty = [0.0; AXES];
    s.cycle(&rest, &mut duty);
    for a in s.axes_mut() {
        a.enable(Mode::Position);
    }
    let samples = (0..64)
        .map(|k| {
            std::array::from_fn(|j| Measurement {
                current: 0.01 * (((k * 7 + j * 3) % 11) as f64 - 5.0),
                encoder_counts: ((k + j) % 3) as i64 - 1,
                bus_voltage: Some(24.0),
            })
        })
        .collect();
    (s, samples)
}

fn assert_running(s: &Stepper<AXES>) {
    for a in s.axes() {
        assert_eq!(a.state(), AxisState::Enabled, "the benchmark must time running axes");
    }
}

fn control_cycle(c: &mut Criterion) {
    let mut g = c.benchmark_group("control_cycle");
    let mut duty = [0.0; AXES];

    // Worst case: every loop due on every tick.
    let (mut s, samples) = stepper(Rates::new(20_000.0, 20_000.0, 20_000.0).unwrap());
    let mut k = 0usize;
    g.bench_function("8_axes_all_loops_due", |b| {
        b.iter(|| {
            k = (k + 1) & 63;
            for a in s.axes_mut() {
                a.set_position(1e-4, 0.0, 0.0);
            }
            s.cycle(black_box(&samples[k]), &mut duty);
            black_box(&duty);
        })
    });
    assert_running(&s);

    // One position period at 20/5/1 kHz: 20 current steps, 5 speed steps, 1 position step per axis.
    let (mut s, samples) = stepper(Rates::default());
    g.throughput(Throughput::Elements(20));
    g.bench_function("8_axes_20_ticks_default_rates", |b| {
        b.iter(|| {
            for a in s.axes_mut() {
                a.set_position(1e-4, 0.0, 0.0);
            }
            for m in &samples[..20] {
                s.cycle(black_box(m), &mut duty);
            }
            black_box(&duty);
        })
    });
    assert_running(&s);
    g.finish();
}

fn current_loop_step(c: &mut Criterion) {
    let mut l = CurrentLoop::new(Pi::new(1.62, 1.25e4, 5e-5, true), 24.0, 22.8, 0.61, 3.6);
    let mut k = 0u32;
    c.bench_function("current_loop_step", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let measured = 0.001 * (k & 15) as f64;
            black_box(l.step(black_box(1.0), black_box(measured), black_box(3.0)))
        })
    });
}

criterion_group!(benches, control_cycle, current_loop_step);
criterion_main!(benches);
