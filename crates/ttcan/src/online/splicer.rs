//! The planning state of the online controller ([`Splicer`]): the hit planner, the commanded
//! schedule of every channel, the handoff senders, and the hit the robot is to execute next.
//! What it does is in three places: splicing a stroke into what runs (here: the splice deadline,
//! the mixed start state, the hand-over, the return to ready), planning hits
//! ([`super::hits`]) and keeping the channels in step for the pending hit ([`super::resync`]).

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3};
use ttkin::hit::HitPlanner;
use ttkin::traj::duration::minimal_quintic_duration;
use ttkin::traj::{JointState, JointTrajectory};

use super::brain::SpliceAt;
use super::counters::Counters;
use super::handoff::{Decision, Sender, Timeline, NO_HIT};
use super::receiver::controller_time;
use super::schedule::{Schedule, Splice};
use super::wire::{HitMsg, PlanStatus, StatusMsg};

/// Time (s) a brain's stroke needs from the end of its decision to its hand-over before the
/// splice cycle (the stroke built, checked and pushed; the cycle thread's wake-up): the planning
/// budget ends this long before the splice cycle ([`SpliceAt::deadline`]).
pub const HANDOVER_MARGIN: f64 = 1.5e-4;

/// Settings of the planning thread.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannerConfig {
    /// Time from the present cycle to the splice cycle, s (longer than a plan takes).
    pub splice_lead: f64,
    /// Silence (no valid datagram) after which the robot goes back to ready and holds, s.
    pub silence: f64,
}

/// The hit that the robot is executing or will execute next.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Committed {
    pub(super) id: u32,
    pub(super) stroke: u32,
    pub(super) t_hit: f64,
    /// Each channel's executed cycle of the hit: its stroke clock (a stall after the plan makes
    /// the hit later on the controller clock, not on this one).
    pub(super) hit: Vec<u64>,
    /// The deadlines each channel had skipped when the stroke was handed over: the channels are
    /// in step while their skips since then agree.
    pub(super) skips: Vec<u64>,
    /// The hit configuration (m, rad) and the tool twist at the hit (base axes), for a re-plan.
    pub(super) q_hit: Vec<f64>,
    pub(super) twist: [f64; 6],
}

/// The planning state: the planner, the schedule, the handoff senders.
pub struct Splicer {
    pub(super) planner: HitPlanner,
    pub(super) ready: Vec<f64>,
    pub(super) timeline: Arc<Timeline>,
    pub(super) senders: Vec<Sender>,
    pub(super) cfg: PlannerConfig,
    /// Per channel, on its own stroke clock.
    pub(super) schedules: Option<Vec<Schedule>>,
    pub(super) seq: u64,
    /// Strokes whose hit is to be checked in step (seq, controller time of the hit).
    pub(super) watch: Vec<(u64, f64)>,
    /// The id of the hit last answered `out_of_step` (once per hit).
    pub(super) announced: Option<u32>,
    /// Planning time of the re-plans (s, smoothed, the latest one at least): their lead.
    pub(super) resync_plan_s: f64,
    /// Each channel's start cycle of the last stroke the channels took.
    pub(super) last_starts: Vec<u64>,
    pub(super) last: Option<Committed>,
    /// The hit of another stroke that `last`'s stroke was spliced after (its hit still ahead at
    /// that splice): a replacement of `last` is spliced after it too, or it would be cut off.
    pub(super) earlier: Option<Committed>,
}

/// What came of a hit: its status and, when it replaced one, the older hit's `replaced` status.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitOutcome {
    /// The hit's own status.
    pub status: StatusMsg,
    /// The status of the hit it replaced.
    pub replaced: Option<StatusMsg>,
}

/// Why a brain's stroke was not handed over as it is ([`Splicer::stroke`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrokeMiss {
    /// Its splice cycle came before it was ready (the decision took longer than the lead).
    Late,
    /// It does not start from the state scheduled at its splice cycle.
    Discontinuous,
}

pub(super) fn status(id: u32, s: PlanStatus, earliest: f64, t_hit: f64, planning_time: f64) -> StatusMsg {
    StatusMsg {
        id,
        status: s,
        earliest_t_hit: earliest,
        t_hit,
        planning_time,
    }
}

/// The racket pose of a hit datagram, if its rotation is a rotation (orthonormal, det +1).
pub fn hit_pose(h: &HitMsg) -> Option<IsometryMatrix3<f64>> {
    let r = Matrix3::from_row_slice(&h.rotation);
    let err = (r.transpose() * r - Matrix3::identity()).abs().max();
    if !(err < 1e-6 && r.determinant() > 0.0) {
        return None;
    }
    Some(IsometryMatrix3::from_parts(
        Translation3::new(h.centre[0], h.centre[1], h.centre[2]),
        Rotation3::from_matrix_unchecked(r),
    ))
}

impl Splicer {
    /// A splicer planning with `planner` towards `planner.default_ready()`, handing over through
    /// `senders` (one per channel, same order as the timeline's channels).
    pub fn new(planner: HitPlanner, timeline: Arc<Timeline>, senders: Vec<Sender>, cfg: PlannerConfig) -> Self {
        Splicer {
            ready: planner.default_ready().to_vec(),
            planner,
            timeline,
            senders,
            cfg,
            schedules: None,
            seq: 0,
            watch: Vec::new(),
            last_starts: Vec::new(),
            resync_plan_s: 0.0,
            announced: None,
            last: None,
            earlier: None,
        }
    }

    /// Sets the ready pose (m or rad, one per joint; ball mode: the ball planner's, from which
    /// its strokes start); refused (`false`) once the schedule runs or with another joint count.
    pub fn set_ready(&mut self, ready: &[f64]) -> bool {
        if self.schedules.is_some() || ready.len() != self.ready.len() || ready.iter().any(|x| !x.is_finite()) {
            return false;
        }
        self.ready = ready.to_vec();
        true
    }

    /// The ready pose.
    pub fn ready(&self) -> &[f64] {
        &self.ready
    }

    /// The state commanded at deadline `d` as the channels' skips stand now (each joint from its
    /// channel's schedule at that channel's executed cycle); `None` before every channel is
    /// enabled.
    pub fn state_at_deadline(&self, d: u64) -> Option<JointState> {
        self.state_of(&Splice {
            deadline: d,
            skips: self.timeline.skips(),
        })
    }

    /// The state commanded at the present deadline ([`Splicer::state_at_deadline`]).
    pub fn commanded(&self) -> Option<JointState> {
        self.state_at_deadline(self.timeline.present_deadline())
    }

    /// The mixed state at splice `sp`: each channel's joints from its schedule at its start.
    pub(super) fn state_of(&self, sp: &Splice) -> Option<JointState> {
        let sch = self.schedules.as_ref()?;
        let mut out = sch.first()?.state_at(sp.start(0));
        for (c, snd) in self.senders.iter().enumerate().skip(1) {
            let st = sch.get(c)?.state_at(sp.start(c));
            for &j in snd.joints().iter().flatten() {
                if j < out.q.len() && j < st.q.len() {
                    out.q[j] = st.q[j];
                    out.qd[j] = st.qd[j];
                    out.qdd[j] = st.qdd[j];
                }
            }
        }
        Some(out)
    }

    /// True when some channel has already commanded its start cycle of `sp`.
    pub(super) fn is_late(&self, sp: &Splice) -> bool {
        (0..self.timeline.channels()).any(|c| self.timeline.clock_of(c).1 >= sp.start(c))
    }

    /// The deadlines (earliest, latest over the channels) at which the channels will command the
    /// hit of `c`, as their skips stand now.
    pub(super) fn hit_span(&self, c: &Committed) -> (u64, u64) {
        Self::span_with(c, &self.timeline.skips())
    }

    /// [`Splicer::hit_span`] with the skips `skips` (those of a splice: its start cycles and the
    /// hit's are then compared on each channel's own clock, whatever the channels skip since).
    pub(super) fn span_with(c: &Committed, skips: &[u64]) -> (u64, u64) {
        let d = c.hit.iter().zip(skips).map(|(h, s)| h + s);
        let lo = d.clone().min().unwrap_or(0);
        (lo, d.max().unwrap_or(0))
    }

    /// Once every channel runs: starts the schedule at the held positions and approaches the
    /// ready pose. True when the schedule exists.
    pub fn start(&mut self, counters: &Counters) -> bool {
        if self.schedules.is_some() {
            return true;
        }
        if !self.timeline.all_enabled() {
            return false;
        }
        let one = Schedule::new(self.timeline.hold(), self.timeline.period());
        self.schedules = Some(vec![one; self.timeline.channels().max(1)]);
        self.to_ready(counters);
        true
    }

    /// The splice of a decision made now: the first deadline at least `lead` s from now, after
    /// the present one, with the channels' skips. A stroke handed over before a channel commands
    /// its start cycle starts there.
    pub(super) fn splice_in(&self, lead: f64) -> Splice {
        self.splice_from(controller_time() + lead)
    }

    /// The splice at the first deadline at or after controller time `t` (s), after the present
    /// one, with the channels' skips.
    fn splice_from(&self, t: f64) -> Splice {
        let tl = &self.timeline;
        let skips = tl.skips();
        let present = (0..skips.len())
            .map(|c| {
                let (s, k) = tl.clock_of(c);
                s + k
            })
            .max()
            .unwrap_or(0);
        let at = tl.deadline_at(t);
        Splice {
            deadline: at.max(present + 1),
            skips,
        }
    }

    /// [`Splicer::splice_in`] `factor × splice_lead` ahead.
    pub(super) fn splice(&self, factor: f64) -> Splice {
        self.splice_in(self.cfg.splice_lead * factor)
    }

    /// The earliest splice a brain deciding now can plan from (cycle, time, commanded state):
    /// `factor × splice_lead` ahead; its deadline is [`HANDOVER_MARGIN`] before the cycle.
    pub fn splice_at(&self, factor: f64) -> SpliceAt {
        self.splice_at_deadline(self.splice(factor))
    }

    /// The earliest splice a brain deciding now on a datagram that arrived at `arrival` (s,
    /// controller clock) can plan from: the first deadline at least `splice_lead` after the
    /// arrival, so that a stroke handed over in time starts at most `splice_lead` + one cycle
    /// after it (its decision latency) whatever the datagram waited for the planning thread; but
    /// at least half the lead from now (a datagram that waited longer gets that much time).
    pub fn splice_after(&self, arrival: f64) -> SpliceAt {
        let lead = self.cfg.splice_lead;
        let t = if arrival.is_finite() {
            (arrival + lead).max(controller_time() + 0.5 * lead)
        } else {
            controller_time() + lead
        };
        self.splice_at_deadline(self.splice_from(t))
    }

    fn splice_at_deadline(&self, sp: Splice) -> SpliceAt {
        let state = self.state_of(&sp).unwrap_or_else(|| JointState::rest(&self.ready));
        let t = self.timeline.time_of(sp.deadline);
        let left = (t - controller_time() - HANDOVER_MARGIN).max(0.0);
        SpliceAt {
            cycle: sp.deadline,
            t,
            state,
            deadline: Some(Instant::now() + Duration::from_secs_f64(left)),
        }
    }

    /// Hands `traj` over to start at splice `sp` (each channel at its own start cycle; its hit,
    /// if any, `hit_after` cycles later); waits until every channel has decided. The stroke's
    /// seq when the channels took it.
    pub(super) fn hand_over(&mut self, sp: &Splice, traj: &JointTrajectory, hit_after: Option<u64>) -> Option<u64> {
        self.seq += 1;
        let seq = self.seq;
        let starts: Vec<u64> = (0..self.senders.len()).map(|c| sp.start(c)).collect();
        for s in self.senders.iter_mut() {
            let hit = hit_after.map_or(NO_HIT, |n| s.own(&starts) + n);
            if !s.push_joint(seq, &starts, hit, traj) {
                // the channels that hold it discard it
                self.timeline.refuse(seq);
                return None;
            }
        }
        // open once it is in every ring: the channel that decides takes it only while no
        // channel has commanded its start cycle, and every channel then takes it in time
        self.timeline.open(seq);
        // the channels see it at their next cycle; a stopped channel never will
        let give_up = controller_time() + 0.5;
        while !self.timeline.seen_by_all(seq) {
            if self.timeline.stopped.load(Ordering::Relaxed) || controller_time() > give_up {
                break;
            }
            std::thread::sleep(Duration::from_micros(100));
        }
        if self.timeline.decision(seq) == Decision::Pending {
            // no channel saw it in time: withdrawn, unless one decides meanwhile
            self.timeline.refuse(seq);
        }
        let taken = self.timeline.decision(seq) == Decision::Taken;
        if taken {
            self.last_starts = (0..self.senders.len()).map(|c| sp.start(c)).collect();
            if let Some(sch) = self.schedules.as_mut() {
                for (c, s) in sch.iter_mut().enumerate() {
                    s.push(sp.start(c), traj.clone());
                }
            }
        }
        taken.then_some(seq)
    }

    pub(super) fn stopped(&self) -> bool {
        self.timeline.stopped.load(Ordering::Relaxed)
    }

    /// Brings the robot back to the ready pose from the state commanded a splice lead from now
    /// (nothing when it holds there already). True when a stroke was handed over.
    pub fn to_ready(&mut self, counters: &Counters) -> bool {
        for factor in [1.0, 2.0, 4.0] {
            let sp = self.splice(factor);
            let (Some(schedules), Some(state)) = (self.schedules.as_ref(), self.state_of(&sp)) else {
                return false;
            };
            let ended = schedules.iter().enumerate().all(|(c, s)| sp.start(c) >= s.end_cycle());
            let at_ready = state.q.iter().zip(&self.ready).all(|(a, b)| (a - b).abs() < 1e-9)
                && state.qd.iter().chain(&state.qdd).all(|v| v.abs() < 1e-9);
            if at_ready && ended {
                return false;
            }
            let end = JointState::rest(&self.ready);
            let Ok(d) = minimal_quintic_duration(&state, &end, self.planner.limits()) else {
                return false;
            };
            let Ok(traj) = JointTrajectory::quintic_between(&state, &end, d) else {
                return false;
            };
            Counters::bump(&counters.plans);
            if self.is_late(&sp) {
                continue;
            }
            if self.hand_over(&sp, &traj, None).is_some() {
                Counters::bump(&counters.splices);
                // a hit still ahead will not happen
                self.last = None;
                self.earlier = None;
                return true;
            }
            Counters::bump(&counters.splices_late);
            return false;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::online::handoff;

    fn splicer(lead: f64) -> Splicer {
        let chain = ttkin::robots::gantry6();
        let planner = HitPlanner::new(&chain, ttkin::hit::HitOptions::default()).unwrap();
        let period_ns = 1_000_000;
        let tl = Arc::new(Timeline::new(1, 6, period_ns, crate::runtime::rt::now_ns()));
        let joints = [Some(0), Some(1), Some(2), Some(3)];
        let (s, _f) = handoff::channel(0, joints, tl.clone());
        let cfg = PlannerConfig {
            splice_lead: lead,
            silence: 1.0,
        };
        Splicer::new(planner, tl, vec![s], cfg)
    }

    #[test]
    fn a_decision_splices_a_lead_after_its_datagrams_arrival_or_half_a_lead_from_now() {
        let lead = 0.02;
        let sp = splicer(lead);
        let period = sp.timeline.period();
        // arrived just now: the first deadline at least a lead after the arrival
        let arrival = controller_time() - 1e-4;
        let at = sp.splice_after(arrival);
        assert!(
            at.t >= arrival + lead && at.t < arrival + lead + period + 1e-9,
            "{} {arrival}",
            at.t
        );
        assert_eq!(at.cycle, sp.timeline.deadline_at(arrival + lead));
        // waited in the queue longer than half the lead: half a lead from now
        let arrival = controller_time() - 0.05;
        let before = controller_time();
        let at = sp.splice_after(arrival);
        assert!(at.t >= before + 0.5 * lead, "{} {before}", at.t);
        assert!(at.t - arrival > lead + period);
        // no arrival known: a lead from now, as `splice_at(1.0)`
        let before = controller_time();
        let at = sp.splice_after(f64::NAN);
        assert!(at.t >= before + lead);
    }
}
