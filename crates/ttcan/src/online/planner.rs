//! The planning thread: commands in (hits from the receiver, or what a [`Brain`] makes of the
//! observations), strokes out. Each stroke is planned with `ttkin::hit::HitPlanner` from the state
//! the cycle threads will command at the splice cycle (position, velocity and acceleration of the
//! strokes already handed over, [`Schedule`]), built completely (hit leg and return to the ready
//! pose), then handed over ([`super::handoff`]); the status goes back to the upper computer once
//! the cycle threads have taken (or refused) the stroke. A hit that cannot be planned leaves the
//! robot doing what it did.
//!
//! Splice rules: the stroke starts at the first cycle at least `splice_lead` after the decision
//! (and after the present cycle; planning must finish before that cycle is commanded; if it did
//! not, the plan is made again with a lead of twice the one before or twice the planning time,
//! whichever is longer, three tries in all). A stroke a [`Brain`] built
//! ([`Command::Stroke`]) is handed over as it is at the cycle it was planned for, when that cycle
//! is still ahead and the stroke starts from the state scheduled there; otherwise its hit is
//! planned again like an upper computer's (counted `splices_replanned`). A newer
//! hit with the same stroke id, while the older one's hit time is still ahead, replaces it from
//! the present state (the older one is answered `replaced`); a hit for another stroke is spliced
//! into the return leg after the pending hit. Silence longer than the timeout, or a
//! [`Command::Ready`], brings the robot back to the ready pose and holds it.

use std::collections::VecDeque;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3};
use ttkin::hit::{Hit, HitPlanner, HitStatus};
use ttkin::traj::duration::minimal_quintic_duration;
use ttkin::traj::{JointState, JointTrajectory};

use super::brain::{Awaiting, Brain, Command, DecisionPath, Observed, PlannedStroke, SpliceAt};
use super::counters::Counters;
use super::handoff::{Decision, Sender, Timeline, NO_HIT};
use super::receiver::{controller_time, send_status, Inbound};
use super::wire::{HitMsg, PlanStatus, StatusMsg};

/// The strokes handed over, as the cycle threads follow them: the commanded state at any cycle.
#[derive(Debug, Clone)]
pub struct Schedule {
    hold: Vec<f64>,
    period: f64,
    segments: Vec<(u64, JointTrajectory)>,
}

impl Schedule {
    /// Holding `hold` (the enable positions) before any stroke; cycle period `period` s.
    pub fn new(hold: Vec<f64>, period: f64) -> Self {
        Schedule {
            hold,
            period,
            segments: Vec::new(),
        }
    }

    /// The state commanded at deadline `k`.
    pub fn state_at(&self, k: u64) -> JointState {
        match self.segments.iter().rev().find(|(s, _)| *s <= k) {
            Some((s, traj)) => {
                let t = ((k - s) as f64 * self.period).min(traj.duration());
                traj.state(t).unwrap_or_else(|_| JointState::rest(&self.hold))
            }
            None => JointState::rest(&self.hold),
        }
    }

    /// Adds a stroke starting at `start`: it supersedes every stroke starting at or after it
    /// (as [`super::handoff::StrokeFollower`] does).
    pub fn push(&mut self, start: u64, traj: JointTrajectory) {
        self.segments.retain(|(s, _)| *s < start);
        self.segments.push((start, traj));
        // only the last few are ever looked at
        if self.segments.len() > 16 {
            self.segments.drain(..self.segments.len() - 16);
        }
    }

    /// The cycle from which the schedule holds still: the end of the last stroke.
    pub fn end_cycle(&self) -> u64 {
        self.segments
            .last()
            .map_or(0, |(s, t)| s + (t.duration() / self.period).ceil() as u64)
    }
}

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

/// Fewest cycles from the present to the splice of a re-plan that brings the channels back in
/// step ([`Splicer::resync`]; its lead is the splice lead: a lead of 5 ms left the stroke to a
/// planning thread preempted between its late check and the hand-over).
const RESYNC_MIN_CYCLES: u64 = 3;

/// The hit that the robot is executing or will execute next.
#[derive(Debug, Clone, PartialEq)]
struct Committed {
    id: u32,
    stroke: u32,
    t_hit: f64,
    /// Each channel's executed cycle of the hit: its stroke clock (a stall after the plan makes
    /// the hit later on the controller clock, not on this one).
    hit: Vec<u64>,
    /// The deadlines each channel had skipped when the stroke was handed over: the channels are
    /// in step while their skips since then agree.
    skips: Vec<u64>,
    /// The hit configuration (m, rad) and the tool twist at the hit (base axes), for a re-plan.
    q_hit: Vec<f64>,
    twist: [f64; 6],
}

/// Where a stroke starts: one deadline for all channels, each channel's start cycle on its own
/// stroke clock that deadline less the deadlines it had skipped (`skips`, read together).
#[derive(Debug, Clone, PartialEq)]
struct Splice {
    deadline: u64,
    skips: Vec<u64>,
}

impl Splice {
    /// Channel `c`'s executed cycle of the splice.
    fn start(&self, c: usize) -> u64 {
        self.deadline.saturating_sub(self.skips.get(c).copied().unwrap_or(0))
    }
}

/// The planning state: the planner, the schedule, the handoff senders.
pub struct Splicer {
    planner: HitPlanner,
    ready: Vec<f64>,
    timeline: Arc<Timeline>,
    senders: Vec<Sender>,
    cfg: PlannerConfig,
    /// Per channel, on its own stroke clock.
    schedules: Option<Vec<Schedule>>,
    seq: u64,
    /// Strokes whose hit is to be checked in step (seq, controller time of the hit).
    watch: Vec<(u64, f64)>,
    /// Each channel's start cycle of the last stroke the channels took.
    last_starts: Vec<u64>,
    last: Option<Committed>,
    /// The hit of another stroke that `last`'s stroke was spliced after (its hit still ahead at
    /// that splice): a replacement of `last` is spliced after it too, or it would be cut off.
    earlier: Option<Committed>,
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

fn status(id: u32, s: PlanStatus, earliest: f64, t_hit: f64, planning_time: f64) -> StatusMsg {
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
    fn state_of(&self, sp: &Splice) -> Option<JointState> {
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
    fn is_late(&self, sp: &Splice) -> bool {
        (0..self.timeline.channels()).any(|c| self.timeline.clock_of(c).1 >= sp.start(c))
    }

    /// The deadlines (earliest, latest over the channels) at which the channels will command the
    /// hit of `c`, as their skips stand now.
    fn hit_span(&self, c: &Committed) -> (u64, u64) {
        Self::span_with(c, &self.timeline.skips())
    }

    /// [`Splicer::hit_span`] with the skips `skips` (those of a splice: its start cycles and the
    /// hit's are then compared on each channel's own clock, whatever the channels skip since).
    fn span_with(c: &Committed, skips: &[u64]) -> (u64, u64) {
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
    fn splice_in(&self, lead: f64) -> Splice {
        let tl = &self.timeline;
        let skips = tl.skips();
        let present = (0..skips.len())
            .map(|c| {
                let (s, k) = tl.clock_of(c);
                s + k
            })
            .max()
            .unwrap_or(0);
        let at = tl.deadline_at(controller_time() + lead);
        Splice {
            deadline: at.max(present + 1),
            skips,
        }
    }

    /// [`Splicer::splice_in`] `factor × splice_lead` ahead.
    fn splice(&self, factor: f64) -> Splice {
        self.splice_in(self.cfg.splice_lead * factor)
    }

    /// The earliest splice a brain deciding now can plan from (cycle, time, commanded state):
    /// `factor × splice_lead` ahead; its deadline is [`HANDOVER_MARGIN`] before the cycle.
    pub fn splice_at(&self, factor: f64) -> SpliceAt {
        let sp = self.splice(factor);
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
    fn hand_over(&mut self, sp: &Splice, traj: &JointTrajectory, hit_after: Option<u64>) -> Option<u64> {
        self.seq += 1;
        let seq = self.seq;
        self.timeline.open(seq);
        for (c, s) in self.senders.iter_mut().enumerate() {
            let start = sp.start(c);
            let hit = hit_after.map_or(NO_HIT, |n| start + n);
            if !s.push_hit(seq, start, hit, traj) {
                return None;
            }
        }
        // the channels see it at their next cycle; a stopped channel never will
        let give_up = controller_time() + 0.5;
        while !self.timeline.seen_by_all(seq) {
            if self.timeline.stopped.load(Ordering::Relaxed) || controller_time() > give_up {
                break;
            }
            std::thread::sleep(Duration::from_micros(100));
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

    /// Watches the hit of stroke `seq` (at controller time `t_hit`): [`Splicer::check_hits`].
    fn watch_hit(&mut self, seq: u64, t_hit: f64) {
        self.watch.push((seq, t_hit));
    }

    /// Counts the watched hits every channel has commanded: in step (every channel at the same
    /// deadline) or not (`hits_out_of_step`, the largest spread in `hit_skew_max_cycles`); a hit
    /// no channel reaches (replaced, called off) is forgotten 2 s after its time.
    pub fn check_hits(&mut self, counters: &Counters) {
        let tl = self.timeline.clone();
        let now = controller_time();
        self.watch.retain(|&(seq, t)| match tl.hit_deadlines(seq) {
            Some(d) => {
                let skew = d.iter().max().unwrap_or(&0) - d.iter().min().unwrap_or(&0);
                if skew == 0 {
                    Counters::bump(&counters.hits_in_step);
                } else {
                    Counters::bump(&counters.hits_out_of_step);
                }
                counters.hit_skew_max_cycles.fetch_max(skew, Ordering::Relaxed);
                false
            }
            None => now < t + 2.0,
        });
    }

    /// Brings the channels back in step for the pending hit: when their skips have drifted apart
    /// since its stroke was handed over (a channel thread stalled while the joints moved, so its
    /// joints follow the stroke later than the others'), the hit leg is planned again from the
    /// state each channel commands at one splice deadline (each channel's joints at its own start
    /// cycle: continuous on every channel) to the same hit state, at the hit time answered when
    /// that is feasible (the lagging joints catch up), else when the channel furthest behind
    /// would reach it; handed to each channel with its own start cycle, so that every channel
    /// commands the hit at the same deadline. Not while an earlier stroke's hit is still to come
    /// (the pending stroke is spliced after it), nor within a few cycles of the hit. Counted
    /// `resyncs`, or `resyncs_failed` when no leg is feasible (the channels stay apart: the hit
    /// is counted out of step when it comes).
    pub fn resync(&mut self, counters: &Counters) {
        let Some(last) = self.last.clone() else { return };
        let tl = self.timeline.clone();
        let now_skips = tl.skips();
        let drift: Vec<i64> = now_skips
            .iter()
            .zip(&last.skips)
            .map(|(a, b)| *a as i64 - *b as i64)
            .collect();
        if drift.iter().all(|d| *d == drift[0]) || self.stopped() {
            return;
        }
        if let Some(e) = self.earlier.as_ref() {
            if self.hit_span(e).1 >= tl.present_deadline() {
                return;
            }
        }
        // One re-plan waiting at a time: a channel holds few strokes waiting for their start
        // ([`super::handoff::MAX_PENDING`]); re-plans a lead apart, none superseding the one
        // before, filled them (the first channel took a stroke another had no room for).
        if self.last_starts.iter().enumerate().any(|(c, &s)| tl.clock_of(c).1 < s) {
            return;
        }
        if self.hit_span(&last).0 <= tl.present_deadline() {
            // the hit is done (or being done): nothing to bring in step
            self.settle(&now_skips);
            return;
        }
        let mut lead = self.cfg.splice_lead.max(RESYNC_MIN_CYCLES as f64 * tl.period());
        for _ in 0..3 {
            let began = controller_time();
            let sp = self.splice_in(lead);
            let (first, latest) = Self::span_with(&last, &sp.skips);
            if sp.deadline + 2 >= first {
                break;
            }
            let Some(state) = self.state_of(&sp) else { return };
            let t_s = tl.time_of(sp.deadline);
            tl.planning.store(true, Ordering::Relaxed);
            let mut found = None;
            for t in [last.t_hit, tl.time_of(latest)] {
                let rel = t - t_s;
                if rel <= 2.0 * tl.period() {
                    continue;
                }
                let b =
                    self.planner
                        .branch_leg_to(&last.q_hit, &state, &last.twist, rel, &self.ready, f64::NEG_INFINITY);
                if let Some(b) = b {
                    found = Some((b, t, rel));
                    break;
                }
            }
            tl.planning.store(false, Ordering::Relaxed);
            Counters::bump(&counters.plans);
            let Some((b, t, rel)) = found else {
                break;
            };
            let Ok(traj) = b.leg.trajectory.then(b.follow) else {
                break;
            };
            if self.is_late(&sp) {
                // planning took longer than the lead: twice as far ahead or twice the planning time
                lead = (2.0 * lead).max(2.0 * (controller_time() - began));
                continue;
            }
            let n = (rel / tl.period()).round() as u64;
            let Some(seq) = self.hand_over(&sp, &traj, Some(n)) else {
                break;
            };
            Counters::bump(&counters.resyncs);
            self.watch_hit(seq, t);
            self.last = Some(Committed {
                t_hit: t,
                hit: (0..sp.skips.len()).map(|c| sp.start(c) + n).collect(),
                skips: sp.skips,
                ..last
            });
            return;
        }
        Counters::bump(&counters.resyncs_failed);
        self.settle(&now_skips);
    }

    /// The pending hit's channels taken as they are (no re-plan until their skips drift again).
    fn settle(&mut self, skips: &[u64]) {
        if let Some(l) = self.last.as_mut() {
            l.skips = skips.to_vec();
        }
    }

    fn stopped(&self) -> bool {
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

    /// Plans and splices one hit received at controller time `arrival` (s).
    pub fn hit(&mut self, h: &HitMsg, arrival: f64, counters: &Counters) -> HitOutcome {
        let reject = |t: f64| HitOutcome {
            status: status(h.id, PlanStatus::Rejected, f64::NAN, f64::NAN, controller_time() - t),
            replaced: None,
        };
        let now = controller_time();
        let (Some(pose), true) = (hit_pose(h), h.t_hit > now) else {
            return reject(arrival);
        };
        if self.schedules.is_none() || self.stopped() {
            return reject(arrival);
        }
        let tl = self.timeline.clone();
        let mut factor: f64 = 1.0;
        for _ in 0..3 {
            let began = controller_time();
            let mut sp = self.splice(factor);
            let mut replaces = None;
            let mut after = None;
            // a hit some channel has not commanded by the splice is still ahead
            if let Some(last) = self
                .last
                .clone()
                .filter(|l| Self::span_with(l, &sp.skips).1 >= sp.deadline)
            {
                if last.stroke == h.stroke && Self::span_with(&last, &sp.skips).0 <= sp.deadline {
                    // a channel commands it before the splice: being done, nothing to replace
                    return reject(arrival);
                }
                if last.stroke == h.stroke {
                    // spliced after the hit the replaced stroke was spliced after, while that
                    // one is still ahead (a replacement from the present state cut it off)
                    if let Some(e) = self
                        .earlier
                        .clone()
                        .filter(|e| Self::span_with(e, &sp.skips).1 >= sp.deadline)
                    {
                        let e_end = Self::span_with(&e, &sp.skips).1;
                        if h.t_hit <= tl.time_of(e_end) + 2.0 * tl.period() {
                            return reject(arrival);
                        }
                        sp.deadline = sp.deadline.max(e_end + 1);
                        after = Some(e);
                    }
                    replaces = Some(last);
                } else {
                    let l_end = Self::span_with(&last, &sp.skips).1;
                    if h.t_hit <= tl.time_of(l_end) + 2.0 * tl.period() {
                        // another stroke's hit comes first
                        return reject(arrival);
                    }
                    sp.deadline = sp.deadline.max(l_end + 1);
                    after = Some(last);
                }
            } else if self.last.as_ref().is_some_and(|l| l.stroke == h.stroke) {
                // that stroke's hit is done: nothing left to replace
                return reject(arrival);
            }
            let Some(state) = self.state_of(&sp) else {
                return reject(arrival);
            };
            let t_s = tl.time_of(sp.deadline);
            let t_rel = (h.t_hit - t_s).max(1e-3);
            let hit = Hit {
                pose,
                twist: h.twist,
                t: t_rel,
            };
            tl.planning.store(true, Ordering::Relaxed);
            let plan = self.planner.plan(&hit, Some(&state), Some(&self.ready));
            tl.planning.store(false, Ordering::Relaxed);
            Counters::bump(&counters.plans);
            let plan = match plan {
                Ok(p) => p,
                Err(_) => return reject(arrival),
            };
            let code = match plan.status {
                HitStatus::Ok => PlanStatus::Accepted,
                HitStatus::TooEarly => PlanStatus::TooEarly,
                HitStatus::Unreachable | HitStatus::Singular => PlanStatus::Unreachable,
                _ => PlanStatus::Infeasible,
            };
            let elapsed = controller_time() - arrival;
            if code != PlanStatus::Accepted {
                let earliest = match code {
                    PlanStatus::TooEarly => t_s + self.planner.earliest_t_hit(&plan),
                    _ => f64::NAN,
                };
                return HitOutcome {
                    status: status(h.id, code, earliest, f64::NAN, elapsed),
                    replaced: None,
                };
            }
            let Some(traj) = plan.trajectory.as_ref() else {
                return reject(arrival);
            };
            if self.is_late(&sp) {
                // planning took longer than the lead: again, twice as far ahead or twice the
                // planning time, whichever is further
                factor = (2.0 * factor).max(2.0 * (controller_time() - began) / self.cfg.splice_lead);
                continue;
            }
            let n = (plan.t_hit / tl.period()).round() as u64;
            let Some(seq) = self.hand_over(&sp, traj, Some(n)) else {
                Counters::bump(&counters.splices_late);
                return reject(arrival);
            };
            Counters::bump(&counters.splices);
            counters.latency.record(t_s - arrival);
            let t_hit = t_s + plan.t_hit;
            self.watch_hit(seq, t_hit);
            self.earlier = after;
            self.last = Some(Committed {
                id: h.id,
                stroke: h.stroke,
                t_hit,
                hit: (0..sp.skips.len()).map(|c| sp.start(c) + n).collect(),
                skips: sp.skips.clone(),
                q_hit: plan.q_hit.clone(),
                twist: self.planner.tool_twist(&hit),
            });
            let elapsed = controller_time() - arrival;
            let us = (elapsed * 1e6) as u64;
            counters.plan_time_max_us.fetch_max(us, Ordering::Relaxed);
            return HitOutcome {
                status: status(h.id, PlanStatus::Accepted, f64::NAN, t_hit, elapsed),
                replaced: replaces.map(|r| status(r.id, PlanStatus::Replaced, f64::NAN, f64::NAN, elapsed)),
            };
        }
        reject(arrival)
    }

    /// Splices a stroke a brain built for its splice deadline (decided on a datagram received at
    /// controller time `arrival`, s): handed over as it is when that deadline is still ahead and
    /// the stroke starts from the state scheduled there; otherwise nothing changes and the error
    /// says why (the caller decides again or re-plans the hit, [`Splicer::replan`]). The
    /// replacement rules are [`Splicer::hit`]'s; while another stroke's hit is still to come,
    /// the hit is planned into that one's return leg.
    pub fn stroke(&mut self, st: &PlannedStroke, arrival: f64, counters: &Counters) -> Result<HitOutcome, StrokeMiss> {
        let h = &st.hit;
        let reject = |t: f64| HitOutcome {
            status: status(h.id, PlanStatus::Rejected, f64::NAN, f64::NAN, controller_time() - t),
            replaced: None,
        };
        let now = controller_time();
        let pose = hit_pose(h);
        if pose.is_none() || h.t_hit <= now || self.stopped() {
            return Ok(reject(arrival));
        }
        let tl = self.timeline.clone();
        let sp = Splice {
            deadline: st.cycle,
            skips: tl.skips(),
        };
        let mut replaces = None;
        if let Some(last) = self
            .last
            .clone()
            .filter(|l| Self::span_with(l, &sp.skips).1 >= sp.deadline)
        {
            let before = self
                .earlier
                .as_ref()
                .is_none_or(|e| Self::span_with(e, &sp.skips).1 < sp.deadline);
            if last.stroke == h.stroke && before && Self::span_with(&last, &sp.skips).0 > sp.deadline {
                replaces = Some(last);
            } else {
                // another stroke's hit is still to come: spliced into its return leg as a hit
                return Ok(self.replan(h, arrival, counters));
            }
        } else if self.last.as_ref().is_some_and(|l| l.stroke == h.stroke) {
            return Ok(reject(arrival));
        }
        // Continuous with what runs: the stroke starts from the state scheduled at its splice.
        let Some(from) = self.state_of(&sp) else {
            return Ok(reject(arrival));
        };
        let Ok(start) = st.traj.state(0.0) else {
            return Err(StrokeMiss::Discontinuous);
        };
        let close =
            |a: &[f64], b: &[f64], tol: f64| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        let continuous =
            close(&start.q, &from.q, 1e-9) && close(&start.qd, &from.qd, 1e-7) && close(&start.qdd, &from.qdd, 1e-5);
        if !continuous {
            return Err(StrokeMiss::Discontinuous);
        }
        if self.is_late(&sp) || (tl.time_of(sp.deadline) - st.start).abs() > 0.25 * tl.period() {
            return Err(StrokeMiss::Late);
        }
        let t_rel = (h.t_hit - st.start).max(0.0);
        let n = (t_rel / tl.period()).round() as u64;
        let Some(seq) = self.hand_over(&sp, &st.traj, Some(n)) else {
            Counters::bump(&counters.splices_late);
            return Err(StrokeMiss::Late);
        };
        Counters::bump(&counters.splices);
        counters.latency.record(tl.time_of(sp.deadline) - arrival);
        self.watch_hit(seq, h.t_hit);
        self.earlier = None;
        let q_hit = st.traj.state(t_rel).map(|s| s.q).unwrap_or_default();
        let twist = pose.map_or([0.0; 6], |pose| {
            self.planner.tool_twist(&Hit {
                pose,
                twist: h.twist,
                t: t_rel,
            })
        });
        self.last = Some(Committed {
            id: h.id,
            stroke: h.stroke,
            t_hit: h.t_hit,
            hit: (0..sp.skips.len()).map(|c| sp.start(c) + n).collect(),
            skips: sp.skips.clone(),
            q_hit,
            twist,
        });
        let elapsed = controller_time() - arrival;
        counters
            .plan_time_max_us
            .fetch_max((elapsed * 1e6) as u64, Ordering::Relaxed);
        Ok(HitOutcome {
            status: status(h.id, PlanStatus::Accepted, f64::NAN, h.t_hit, elapsed),
            replaced: replaces.map(|r| status(r.id, PlanStatus::Replaced, f64::NAN, f64::NAN, elapsed)),
        })
    }

    /// Plans a brain's hit `h` again like an upper computer's hit ([`Splicer::hit`]), counted.
    pub fn replan(&mut self, h: &HitMsg, arrival: f64, counters: &Counters) -> HitOutcome {
        Counters::bump(&counters.splices_replanned);
        self.hit(h, arrival, counters)
    }
}

/// Runs the planning thread until `stop`: takes what the receiver hands over, plans, splices,
/// answers every hit with a status to `reply` (from `socket`); in ball mode `brain` decides.
pub fn run_planner(
    mut splicer: Splicer,
    inbound: &Receiver<Inbound>,
    mut brain: Option<&mut dyn Brain>,
    socket: &UdpSocket,
    reply: SocketAddr,
    counters: &Counters,
    stop: &AtomicBool,
) {
    let mut seq = 0u64;
    let mut last_heard: Option<f64> = None;
    let mut silent = false;
    // Datagrams taken off the queue while a late stroke waited for a newer observation
    // (`splice_stroke`), handled next, in order.
    let mut pending: VecDeque<Inbound> = VecDeque::with_capacity(64);
    while !stop.load(Ordering::Relaxed) {
        let started = splicer.start(counters);
        if started {
            splicer.resync(counters);
            splicer.check_hits(counters);
        }
        let msg = match pending.pop_front() {
            Some(m) => Ok(m),
            None => inbound.recv_timeout(Duration::from_millis(5)),
        };
        let now = controller_time();
        let commanded = |sp: &Splicer| sp.commanded().unwrap_or_else(|| JointState::rest(sp.ready()));
        let mut command = None;
        match msg {
            Ok(Inbound::Hit { hit, arrival }) => {
                Counters::bump(&counters.hits);
                last_heard = Some(arrival);
                silent = false;
                command = Some((Command::Hit(hit), arrival));
            }
            Ok(Inbound::Observation { obs, sent, arrival }) => {
                Counters::bump(&counters.observations);
                last_heard = Some(arrival);
                silent = false;
                if let Some(b) = brain.as_deref_mut() {
                    let at = splicer.splice_at(1.0);
                    tl_planning(&splicer, true);
                    command = b.observe(&obs, sent, now, &at).map(|c| (c, arrival));
                    tl_planning(&splicer, false);
                    b.publish(counters);
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return,
        }
        if command.is_none() {
            if let Some(b) = brain.as_deref_mut() {
                let state = commanded(&splicer);
                command = b.tick(now, &state).map(|c| (c, now));
                b.publish(counters);
            }
        }
        if let Some(t) = last_heard {
            if !silent && now - t > splicer.cfg.silence {
                silent = true;
                Counters::bump(&counters.silence_timeouts);
                command = command.or(Some((Command::Ready, now)));
            }
        }
        match command {
            Some((Command::Ready, _)) => {
                splicer.to_ready(counters);
            }
            Some((c, arrival)) => {
                let out = match c {
                    _ if !started => {
                        let id = match &c {
                            Command::Stroke(st) => st.hit.id,
                            Command::Hit(h) => h.id,
                            Command::Ready => 0,
                        };
                        Some(HitOutcome {
                            status: status(id, PlanStatus::Rejected, f64::NAN, f64::NAN, now - arrival),
                            replaced: None,
                        })
                    }
                    Command::Stroke(st) => {
                        let queue = Queue {
                            inbound,
                            pending: &mut pending,
                        };
                        let queued = now - arrival;
                        splice_stroke(&mut splicer, brain.as_deref_mut(), st, arrival, queued, queue, counters)
                    }
                    Command::Hit(h) => Some(splicer.hit(&h, arrival, counters)),
                    Command::Ready => None,
                };
                let Some(out) = out else { continue };
                for s in out.replaced.iter().chain(std::iter::once(&out.status)) {
                    seq += 1;
                    send_status(socket, reply, seq, controller_time(), s, counters);
                    if let Some(b) = brain.as_deref_mut() {
                        b.outcome(s);
                    }
                }
            }
            None => {}
        }
    }
}

/// How recent (s) a queued observation must be for a late stroke to be planned again from it
/// without waiting for the next frame ([`Queue::newer`]).
const FRESH: f64 = 2.5e-4;

/// The planning thread's inbound datagrams: the receiver's queue and those taken off it early.
struct Queue<'q> {
    inbound: &'q Receiver<Inbound>,
    pending: &'q mut VecDeque<Inbound>,
}

impl Queue<'_> {
    /// The observations of the awaited ball that came after the one being handled: those queued
    /// already, and the next one within the wait unless one of them arrived within the last
    /// [`FRESH`] (a stroke decided on an observation that waited in the queue for most of a frame
    /// would start that much later after it); every datagram taken off the receiver's queue stays
    /// pending, to be handled as usual afterwards.
    fn newer(&mut self, aw: Awaiting) -> Vec<Observed> {
        while let Ok(m) = self.inbound.try_recv() {
            self.pending.push_back(m);
        }
        let of_ball = |m: &Inbound| matches!(m, Inbound::Observation { obs, .. } if obs.id == aw.ball);
        let since = controller_time() - FRESH;
        let fresh = |m: &Inbound| of_ball(m) && matches!(m, Inbound::Observation { arrival, .. } if *arrival >= since);
        if !self.pending.iter().any(fresh) {
            let until = Instant::now() + Duration::from_secs_f64(aw.wait.clamp(0.0, 0.1));
            loop {
                let left = until.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break;
                }
                let Ok(m) = self.inbound.recv_timeout(left) else { break };
                let found = of_ball(&m);
                self.pending.push_back(m);
                if found {
                    break;
                }
            }
        }
        self.pending
            .iter()
            .filter_map(|m| match *m {
                Inbound::Observation { obs, sent, arrival } if obs.id == aw.ball => {
                    Some(Observed { obs, sent, arrival })
                }
                _ => None,
            })
            .collect()
    }
}

/// Splices a brain's stroke. When its splice cycle passed before it was ready (the decision took
/// longer than the lead), the brain first plans its hit again, without a search, from the
/// observations that came since, waiting for the next one when none has ([`Brain::awaits`],
/// [`Brain::refine`]; the latency then counts from the newest observation used); then, and when
/// that stroke is late too, it retries for a later splice ([`Brain::retry`]: the same hit with
/// its leg planned again from there, a few tens of µs, or else the decision made again): first
/// twice the lead ahead, then twice its last retry time ahead (at most 3 times), then the hit
/// is planned again from a later cycle; a stroke that does not start from the scheduled state
/// is planned again at once. `None` when the decision made again has no hit (nothing to answer).
#[allow(clippy::too_many_arguments)]
fn splice_stroke<'c>(
    splicer: &mut Splicer,
    mut brain: Option<&mut (dyn Brain + 'c)>,
    mut st: Box<PlannedStroke>,
    mut arrival: f64,
    queued: f64,
    mut queue: Queue<'_>,
    counters: &Counters,
) -> Option<HitOutcome> {
    // the first retry (the same hit from a later splice) takes little time, whatever the decision took
    let mut decided_in = 0.0;
    let mut refined = false;
    let mut late = None;
    for tries in 0..4 {
        match splicer.stroke(&st, arrival, counters) {
            Ok(out) => {
                if out.status.status == PlanStatus::Accepted {
                    let latency = st.start - arrival;
                    if tries > 0 {
                        counters.latency_late.record(latency);
                    }
                    if latency > 2e-3 {
                        Counters::bump(late.map_or(&counters.over_2ms_in_time, |c: LateCause| c.over_2ms(counters)));
                    }
                }
                return Some(out);
            }
            Err(StrokeMiss::Discontinuous) => break,
            Err(StrokeMiss::Late) => {}
        }
        let Some(b) = brain.as_deref_mut() else { break };
        if late.is_none() {
            let cause = LateCause::of(queued, splicer.cfg.splice_lead, b.decision_path());
            Counters::bump(cause.late(counters));
            late = Some(cause);
        }
        Counters::bump(&counters.splices_redecided);
        if let (false, Some(aw)) = (refined, b.awaits()) {
            refined = true;
            let newer = queue.newer(aw);
            if !newer.is_empty() {
                let at = splicer.splice_at(1.0);
                tl_planning(splicer, true);
                let next = b.refine(&newer, &at);
                tl_planning(splicer, false);
                b.publish(counters);
                if let Some((Command::Stroke(n), i)) = next {
                    st = n;
                    arrival = newer[i].arrival;
                    continue;
                }
            }
        }
        let factor = (2.0 * decided_in / splicer.cfg.splice_lead).max(2.0);
        let at = splicer.splice_at(factor);
        let t0 = controller_time();
        tl_planning(splicer, true);
        let next = b.retry(&at);
        tl_planning(splicer, false);
        decided_in = controller_time() - t0;
        b.publish(counters);
        match next {
            Some(Command::Stroke(n)) => st = n,
            Some(Command::Hit(h)) => return Some(splicer.hit(&h, arrival, counters)),
            Some(Command::Ready) => {
                splicer.to_ready(counters);
                return None;
            }
            None => return None,
        }
    }
    Some(splicer.replan(&st.hit, arrival, counters))
}

/// Why a brain's stroke was ready after its splice cycle (the `late_*` counters).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LateCause {
    /// Its observation waited for the planning thread longer than half the lead.
    Queued,
    /// The brain's decision path.
    Path(DecisionPath),
    /// Not known (a brain without [`Brain::decision_path`]).
    Other,
}

impl LateCause {
    /// The cause of a late stroke whose observation waited `queued` s for the planning thread
    /// with a splice lead `lead` s, decided by `path`.
    fn of(queued: f64, lead: f64, path: Option<DecisionPath>) -> Self {
        if queued > 0.5 * lead {
            return LateCause::Queued;
        }
        path.map_or(LateCause::Other, LateCause::Path)
    }

    /// Its `late_*` counter.
    fn late(self, c: &Counters) -> &std::sync::atomic::AtomicU64 {
        match self {
            LateCause::Queued => &c.late_queued,
            LateCause::Path(DecisionPath::Held) => &c.late_replan_slow,
            LateCause::Path(DecisionPath::HeldInfeasible) => &c.late_held_infeasible,
            LateCause::Path(DecisionPath::SearchPending) => &c.late_search_pending,
            LateCause::Path(DecisionPath::Searched) => &c.late_searched,
            LateCause::Other => &c.late_other,
        }
    }

    /// Its `over_2ms_*` counter.
    fn over_2ms(self, c: &Counters) -> &std::sync::atomic::AtomicU64 {
        match self {
            LateCause::Queued => &c.over_2ms_queued,
            LateCause::Path(DecisionPath::Held) => &c.over_2ms_replan_slow,
            LateCause::Path(DecisionPath::HeldInfeasible) => &c.over_2ms_held_infeasible,
            LateCause::Path(DecisionPath::SearchPending) => &c.over_2ms_search_pending,
            LateCause::Path(DecisionPath::Searched) => &c.over_2ms_searched,
            LateCause::Other => &c.over_2ms_other,
        }
    }
}

fn tl_planning(splicer: &Splicer, on: bool) {
    splicer.timeline.planning.store(on, Ordering::Relaxed);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_late_stroke_is_counted_under_its_cause() {
        let c = Counters::default();
        let lead = 8e-4;
        // an observation that waited for the planning thread more than half the lead: queued,
        // whatever the decision's path
        let q = LateCause::of(5e-4, lead, Some(DecisionPath::Held));
        assert_eq!(q, LateCause::Queued);
        Counters::bump(q.late(&c));
        Counters::bump(q.over_2ms(&c));
        for (path, n) in [
            (DecisionPath::Held, 1),
            (DecisionPath::HeldInfeasible, 2),
            (DecisionPath::SearchPending, 3),
            (DecisionPath::Searched, 4),
        ] {
            let cause = LateCause::of(1e-4, lead, Some(path));
            assert_eq!(cause, LateCause::Path(path));
            for _ in 0..n {
                Counters::bump(cause.late(&c));
            }
        }
        Counters::bump(LateCause::of(0.0, lead, None).late(&c));
        let s = c.snapshot();
        assert_eq!(
            (
                s.late_queued,
                s.late_replan_slow,
                s.late_held_infeasible,
                s.late_search_pending,
                s.late_searched,
                s.late_other
            ),
            (1, 1, 2, 3, 4, 1)
        );
        assert_eq!(
            (s.over_2ms_queued, s.over_2ms_replan_slow, s.over_2ms_in_time),
            (1, 0, 0)
        );
    }
}
