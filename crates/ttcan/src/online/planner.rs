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
//! whichever is longer, three tries in all). A brain deciding on an observation gets the first
//! cycle at least `splice_lead` after the observation's arrival (at least half the lead from
//! now, [`Splicer::splice_after`]), so that its in-time strokes start within the lead plus one
//! cycle of their observation. A stroke a [`Brain`] built
//! ([`Command::Stroke`]) is handed over as it is at the cycle it was planned for, when that cycle
//! is still ahead and the stroke starts from the state scheduled there; otherwise its hit is
//! planned again like an upper computer's (counted `splices_replanned`). A newer
//! hit with the same stroke id, while the older one's hit time is still ahead, replaces it from
//! the present state (the older one is answered `replaced`); a hit for another stroke is spliced
//! into the return leg after the pending hit. Silence longer than the timeout, or a
//! [`Command::Ready`], brings the robot back to the ready pose and holds it.
//!
//! The pieces: the commanded schedule ([`super::schedule`]), the planning state and the splice
//! ([`super::splicer`]), hit planning ([`super::hits`]) and keeping the channels in step
//! ([`super::resync`]); this module is the thread's loop.

use std::collections::VecDeque;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use ttkin::traj::JointState;

use super::brain::{Awaiting, Brain, Command, DecisionPath, Observed, PlannedStroke};
use super::counters::Counters;
use super::receiver::{controller_time, send_status, Inbound};
use super::splicer::status;
use super::wire::PlanStatus;

pub use super::schedule::Schedule;
pub use super::splicer::{hit_pose, HitOutcome, PlannerConfig, Splicer, StrokeMiss, HANDOVER_MARGIN};

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
            if let Some(s) = splicer.resync(counters) {
                seq += 1;
                send_status(socket, reply, seq, controller_time(), &s, counters);
                if let Some(b) = brain.as_deref_mut() {
                    b.outcome(&s);
                }
            }
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
                    let at = splicer.splice_after(arrival);
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
