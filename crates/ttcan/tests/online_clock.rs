//! The online handoff's per-channel stroke clocks: two channels follow the same stroke; when one
//! channel thread stalls and skips deadlines during the stroke, the other keeps moving (holding
//! drives in motion would stop them abruptly) and the stalled one resumes where it stopped, its
//! stroke clock behind by the stall. The next stroke, handed to each channel with its own start
//! cycle (the same deadline less the deadlines that channel skipped), brings them back in step:
//! both start it, and command its hit, at the same deadline. Stepped by hand: no threads, no
//! timing.

#[path = "support/channel.rs"]
mod channel;
use std::sync::Arc;
use ttcan::online::handoff::{self, Decision, Timeline};
use ttcan::runtime::channel::{CycleInfo, SetpointSource};
use ttcan::runtime::master::{AxisSetpoint, ChannelMaster, Phase};
use ttkin::traj::{JointState, JointTrajectory};

fn step(f: &mut handoff::StrokeFollower, master: &ChannelMaster, k: u64) -> [f64; 2] {
    let info = CycleInfo {
        k,
        t: k as f64 * 1e-3,
        phase: Phase::Run,
        period: 1e-3,
    };
    let mut out = [AxisSetpoint::default(); 2];
    let mut qdd = [0.0; 2];
    f.fill(&info, master, &mut out, &mut qdd);
    [out[0].q, out[1].q]
}

#[test]
fn a_stall_during_a_stroke_is_made_up_by_the_next_strokes_per_channel_start() {
    let (ma, _) = channel::running_channel();
    let (mb, _) = channel::running_channel();
    let tl = Arc::new(Timeline::new(2, 4, 1_000_000, 0));
    let (mut sa, mut fa) = handoff::channel(0, [Some(0), Some(1), None, None], tl.clone());
    let (mut sb, mut fb) = handoff::channel(1, [Some(2), Some(3), None, None], tl.clone());
    // Deadline 0: both enabled (hold published), then a 0.5 s stroke of all four joints from 0.
    step(&mut fa, &ma, 0);
    step(&mut fb, &mb, 0);
    let hold = tl.hold();
    let end: Vec<f64> = hold.iter().map(|h| h + 0.3).collect();
    let traj = JointTrajectory::quintic_between(&JointState::rest(&hold), &JointState::rest(&end), 0.5).unwrap();
    tl.open(1);
    assert!(sa.push(1, 2, &traj) && sb.push(1, 2, &traj));
    let (mut qa, mut qb) = (Vec::new(), Vec::new());
    for k in 1..=560u64 {
        qa.push((k, step(&mut fa, &ma, k)));
        // channel B's thread stalls during the stroke: deadlines 20..=24 skipped
        if !(20..=24).contains(&k) {
            qb.push((k, step(&mut fb, &mb, k)));
        }
    }
    assert_eq!(tl.decision(1), Decision::Taken);
    // The stroke sample at an executed cycle (the stroke starts at executed cycle 2).
    let sample = |k_exec: u64| traj.state(((k_exec as f64 - 2.0) * 1e-3).clamp(0.0, 0.5)).unwrap().q;
    // A never stalled and does not hold drives in motion: it follows the deadlines through the
    // stroke; B resumes where it stopped, 5 cycles behind, and nothing is held at rest either.
    for (k, q) in &qa {
        let want = sample(*k);
        assert!((q[0] - want[0]).abs() < 1e-12, "A at deadline {k}: {q:?} vs {want:?}");
    }
    for (k, q) in &qb {
        let exec = if *k < 20 { *k } else { *k - 5 };
        let want = sample(exec);
        assert!((q[0] - want[2]).abs() < 1e-12, "B at deadline {k}: {q:?} vs {want:?}");
    }
    assert_eq!(tl.skips(), vec![0, 5]);
    assert_eq!(tl.skipped(), 5);
    assert_eq!((tl.present_cycle(), tl.present_deadline()), (560, 560));
    // The next stroke at deadline 600, its hit 100 cycles in: each channel's start is the
    // deadline less its skips.
    let back = JointTrajectory::quintic_between(&JointState::rest(&end), &JointState::rest(&hold), 0.2).unwrap();
    tl.open(2);
    let d = 600;
    assert!(sa.push_hit(2, d, d + 100, &back) && sb.push_hit(2, d - 5, d - 5 + 100, &back));
    assert_eq!(tl.hit_deadlines(2), None, "no hit commanded yet");
    for k in 561..=900u64 {
        let (a, b) = (step(&mut fa, &ma, k), step(&mut fb, &mb, k));
        let want = back.state(((k as f64 - d as f64) * 1e-3).clamp(0.0, 0.2)).unwrap().q;
        assert!((a[0] - want[0]).abs() < 1e-12, "A at deadline {k}: {a:?} vs {want:?}");
        assert!((b[0] - want[2]).abs() < 1e-12, "B at deadline {k}: {b:?} vs {want:?}");
    }
    assert_eq!(tl.decision(2), Decision::Taken);
    assert_eq!(tl.hit_deadlines(2), Some(vec![d + 100, d + 100]), "the hit in step");
    assert_eq!(tl.hit_deadlines(1), None, "stroke 1 had no hit");
}

/// The decision on a stroke is taken for every channel by the first one that sees it: taken only
/// while no channel has commanded its start cycle yet, so no channel follows a stroke late (a jump
/// of its setpoints). Scripted: channel A's thread stalls, channel B runs past the stroke's start;
/// when A wakes first, within its own start, the stroke is refused for both (before: A took it
/// and B followed it late). A stroke in the rings whose decision is not open is left there.
#[test]
fn a_stroke_one_channel_would_follow_late_is_refused_for_all() {
    let (ma, _) = channel::running_channel();
    let (mb, _) = channel::running_channel();
    let tl = Arc::new(Timeline::new(2, 4, 1_000_000, 0));
    let (mut sa, mut fa) = handoff::channel(0, [Some(0), Some(1), None, None], tl.clone());
    let (mut sb, mut fb) = handoff::channel(1, [Some(2), Some(3), None, None], tl.clone());
    step(&mut fa, &ma, 0);
    step(&mut fb, &mb, 0);
    let hold = tl.hold();
    let end: Vec<f64> = hold.iter().map(|h| h + 0.3).collect();
    let traj = JointTrajectory::quintic_between(&JointState::rest(&hold), &JointState::rest(&end), 0.5).unwrap();
    // A stalls after deadline 5; B runs on to deadline 12, past the stroke's start (cycle 10 on
    // both clocks: no skips when it was planned)
    for k in 1..=5u64 {
        step(&mut fa, &ma, k);
    }
    for k in 1..=12u64 {
        step(&mut fb, &mb, k);
    }
    assert!(sa.push_joint(1, &[10, 10], 30, &traj) && sb.push_joint(1, &[10, 10], 30, &traj));
    // not opened yet: left in the rings
    step(&mut fb, &mb, 13);
    assert_eq!(tl.decision(1), Decision::Pending);
    assert!(!tl.seen_by_all(1));
    tl.open(1);
    // A wakes at deadline 14, its executed cycle 6: within its own start, but B commanded its
    // start already
    let a = step(&mut fa, &ma, 14);
    assert_eq!(tl.decision(1), Decision::Late);
    let b = step(&mut fb, &mb, 14);
    assert!(tl.seen_by_all(1));
    assert_eq!(tl.late_applied(), 0, "no channel followed it late");
    assert_eq!((a, b), ([hold[0], hold[1]], [hold[2], hold[3]]), "both hold");
    // The same stroke at deadline 28 for both (A skipped 8 deadlines: its start cycle 20; B
    // none: 28), its hit at deadline 48: taken, and both command the hit at that deadline.
    assert!(sa.push_joint(2, &[20, 28], 40, &traj) && sb.push_joint(2, &[20, 28], 48, &traj));
    tl.open(2);
    for k in 15..=60u64 {
        step(&mut fa, &ma, k);
        step(&mut fb, &mb, k);
    }
    assert_eq!(tl.decision(2), Decision::Taken);
    assert_eq!(tl.late_applied(), 0);
    assert_eq!(tl.skips(), vec![8, 0]);
    assert_eq!(tl.hit_deadlines(2), Some(vec![48, 48]), "the hit in step");
}
