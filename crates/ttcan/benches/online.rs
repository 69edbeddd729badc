//! The online handoff on the cycle thread: one cycle of a channel following a stroke (take any
//! stroke waiting in the ring, sample the active one, fill the setpoints), with a new stroke
//! handed over every cycle (the worst case) and without. Budget: well under the 2 µs of a
//! channel's per-cycle work.

#[path = "../tests/support/channel.rs"]
mod channel;
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::sync::Arc;
use ttcan::online::handoff::{self, Timeline};
use ttcan::runtime::channel::{CycleInfo, SetpointSource};
use ttcan::runtime::master::{AxisSetpoint, Phase};
use ttkin::traj::{JointState, JointTrajectory};

fn handoff_cycle(c: &mut Criterion) {
    let (master, _) = channel::running_channel();
    let tl = Arc::new(Timeline::new(1, 2, 1_000_000, 0));
    let (mut sender, mut follower) = handoff::channel(0, [Some(0), Some(1), None, None], tl.clone());
    let start = JointState::rest(&[0.0, 0.0]);
    let end = JointState::rest(&[0.3, -0.2]);
    let traj = JointTrajectory::quintic_between(&start, &end, 0.5).unwrap();
    let mut out = [AxisSetpoint::default(); 2];
    let mut qdd = [0.0; 2];
    let mut k = 0u64;
    let mut cycle = |follower: &mut handoff::StrokeFollower| {
        let info = CycleInfo {
            k,
            t: k as f64 * 1e-3,
            phase: Phase::Run,
            period: 1e-3,
        };
        k += 1;
        follower.fill(&info, &master, &mut out, &mut qdd);
        black_box(out[0].q + qdd[1])
    };
    cycle(&mut follower);
    let mut seq = 0u64;
    c.bench_function("online_cycle_following_a_stroke", |b| {
        seq += 1;
        tl.open(seq);
        sender.push(seq, 0, &traj);
        b.iter(|| cycle(&mut follower))
    });
    c.bench_function("online_cycle_taking_a_new_stroke", |b| {
        b.iter_batched(
            || {
                seq += 1;
                tl.open(seq);
                sender.push(seq, u64::MAX / 2, &traj);
            },
            |_| cycle(&mut follower),
            criterion::BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, handoff_cycle);
criterion_main!(benches);
