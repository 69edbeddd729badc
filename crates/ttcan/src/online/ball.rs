//! The ball mode's brain (seed 002's "global control system"): camera observations in, hits for
//! the runtime out. Per ball (a new ball id is a new incoming ball) it makes the rally's
//! decisions ([`ttkin::ball::decide`]: the first plan after the estimation window, one correction
//! after the bounce) and hands the runtime the stroke the ball planner built
//! ([`Command::Stroke`]: the accepted hit leg and the return to ready, `rally::execution`, exactly
//! what the offline rally executes), planned from the splice instant the runtime offers with the
//! observation ([`SpliceAt`]: the first cycle a stroke decided now can start at and the state
//! commanded then), so that the decision's `now` is the stroke's start. The hit goes with it in
//! the robot's base frame on the controller's clock; the correction keeps the stroke id, so that
//! the runtime replaces the stroke. [`Command::Ready`] follows `ready_after` past the hit, or
//! comes when the ball is lost before a hit was planned.
//!
//! **Clocks.** Observations carry the camera's time stamp; the planner works on the controller's
//! clock: controller time = camera time + offset, with the offset given ([`ClockRelation::Offset`],
//! e.g. both on one host's clock) or estimated as the smallest delay seen over the last
//! `clock_window` observations, which is the offset plus the shortest transit: from the header's
//! send time ([`ClockRelation::SendTime`], the camera stamps the send on its clock), or from the
//! exposure time stamp less the camera's known exposure-to-send latency
//! ([`ClockRelation::MinDelay`]).
//!
//! **Latency budget.** An observation whose exposure is more than `latency_budget` old on arrival
//! (controller clock) is dropped and counted (`stale`): a plan from it would start too late.

use super::brain::{Awaiting, Brain, Command, DecisionPath, Observed, PlannedStroke, SpliceAt};
use super::counters::Counters;
use super::speculator::{SpecJob, Speculator};
use super::wire::{HitMsg, ObservationMsg, PlanStatus, StatusMsg};
use std::collections::VecDeque;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};
use ttkin::ball::decide::{BallDecider, DecideConfig, Decision};
use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::{PlanBudget, ReturnHit, ReturnPlanner, ReturnStatus};
use ttkin::ball::rally::execution;
use ttkin::chain::Chain;
use ttkin::traj::JointState;

/// How camera time stamps map to the controller's clock (controller = camera + offset).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ClockRelation {
    /// A known offset (s).
    Offset(f64),
    /// The offset estimated as min(arrival − header send time) over the clock window (s).
    SendTime,
    /// The offset estimated as min(arrival − exposure time stamp) − `latency` over the clock
    /// window: the camera's shortest exposure-to-send delay (s) is known.
    MinDelay {
        /// The camera's exposure-to-send latency (s).
        latency: f64,
    },
}

/// Settings of a [`BallBrain`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallBrainConfig {
    /// The decision rules (target, estimation window, frame period, correction delay).
    pub decide: DecideConfig,
    /// Camera clock to controller clock.
    pub clock: ClockRelation,
    /// Observations over which the offset's minimum is taken (the offset may drift beyond it).
    pub clock_window: usize,
    /// Oldest observation (s from its exposure to its arrival, controller clock) still used.
    pub latency_budget: f64,
    /// Silence (s) of the current ball's camera before a hit was planned after which the ball is
    /// lost.
    pub lost_after: f64,
    /// Time (s) after a hit at which the robot is sent back to ready.
    pub ready_after: f64,
    /// Observations ahead of each decision at which its search is made
    /// ([`BallDecider::speculate`]), so that the deciding observation only plans that hit again
    /// (a fraction of the search, within the splice lead); 0: every decision searches when its
    /// observation comes, as the offline rally does.
    pub speculate_frames: usize,
    /// With the searches ahead on a worker thread ([`BallBrain::spawn_worker`]) and
    /// `speculate_frames` ≥ 2: each search ahead made again one frame before its decision from
    /// the newest estimate (`BallDecider::refresh`: the held hits planned again first).
    pub refresh_ahead: bool,
}

impl Default for BallBrainConfig {
    /// The rally's rules; the offset estimated from the send times over 2 s at 200 Hz; a 30 ms
    /// budget (the rally's camera delivers 10 ms after the exposure); lost after 50 ms of
    /// silence; ready 60 ms after the hit (the rally looks for the contact up to then); each
    /// decision's search made 3 observations (15 ms at 200 Hz) ahead of it, and again one frame
    /// before it on the worker.
    fn default() -> Self {
        BallBrainConfig {
            decide: DecideConfig::default(),
            clock: ClockRelation::SendTime,
            clock_window: 400,
            latency_budget: 0.030,
            lost_after: 0.050,
            ready_after: 0.060,
            speculate_frames: 3,
            refresh_ahead: true,
        }
    }
}

/// What the brain counted.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BallStats {
    /// Observations received.
    pub observations: u64,
    /// Dropped: older than the latency budget on arrival.
    pub stale: u64,
    /// Ignored: of a ball already decided, or not later than the ball's previous one.
    pub ignored: u64,
    /// Balls seen (distinct consecutive ids).
    pub balls: u64,
    /// Balls whose first estimate failed.
    pub estimate_failed: u64,
    /// Balls whose first plan failed or found no hit (and no correction found one).
    pub no_hit: u64,
    /// First hits sent.
    pub planned: u64,
    /// Corrected hits sent (same stroke as the first).
    pub corrected: u64,
    /// Balls lost before a hit was planned (camera silent for `lost_after`).
    pub lost: u64,
    /// Hits the runtime answered with another status than accepted or replaced.
    pub refused: u64,
    /// Strokes ready after their splice cycle whose hit was kept, its leg planned again from a
    /// later splice ([`Brain::retry`]).
    pub retimed: u64,
    /// Strokes ready after their splice cycle whose hit was planned again, without a search, from
    /// a newer observation ([`Brain::refine`]).
    pub refined: u64,
    /// Searches made ahead of a decision ([`BallBrainConfig::speculate_frames`]).
    pub speculated: u64,
    /// Decisions (first plans and corrections) that planned the hit found ahead again instead
    /// of searching.
    pub speculation_used: u64,
    /// Decisions with a hit found ahead that could not use it (not feasible from the decision's
    /// estimate and state, or no correction made) and searched as without one.
    pub speculation_unused: u64,
    /// Decisions due while their search ahead still ran on the worker thread
    /// ([`BallBrain::spawn_worker`]) that waited for it.
    pub speculation_waited: u64,
    /// Of those, the decisions whose search ahead had not ended by the end of their wait (they
    /// searched themselves).
    pub speculation_pending: u64,
    /// Decisions (within `speculation_used`) that planned again a next best hit of the search
    /// ahead, the best not being feasible any more.
    pub speculation_alternative: u64,
    /// Searches ahead made again one frame before their decision on the worker thread
    /// (`BallDecider::refresh`).
    pub refreshed: u64,
}

/// The ball in play.
#[derive(Debug, Clone)]
struct Ball {
    id: u32,
    decider: BallDecider,
    last_seen: f64,
    /// The absolute time (s, controller clock) and the ball planner's hit in force.
    hit: Option<(f64, ReturnHit)>,
    ended: bool,
    /// Decisions made for this ball so far (which one a search ahead is for).
    decisions: u32,
}

/// Time (s) a decision keeps of its splice deadline for planning the hit found ahead again when
/// it waits for a search ahead still running ([`BallBrain::spawn_worker`]).
const REPLAN_RESERVE: f64 = 4e-4;

/// The ball mode's brain (see the module doc).
#[derive(Debug)]
pub struct BallBrain {
    planner: ReturnPlanner,
    cfg: BallBrainConfig,
    delays: VecDeque<f64>,
    ball: Option<Ball>,
    stroke: u32,
    hit_id: u32,
    sent_ids: VecDeque<u32>,
    stats: BallStats,
    /// The brain as it was before the last observation, with that observation, when that one
    /// may have led to a decision: a decision whose splice instant passed before it was ready is
    /// made again from there ([`Brain::retry`]).
    before: Option<Box<Before>>,
    /// The last stroke sent is a decision (first plan or correction) not yet planned again: if
    /// it comes too late for its splice, its hit is planned again from a newer observation
    /// ([`Brain::refine`]).
    refinable: bool,
    /// The thread the searches ahead run on ([`BallBrain::spawn_worker`]); `None`: on the
    /// caller's thread, within [`Brain::observe`].
    worker: Option<Speculator>,
    /// How the last decision found its hit.
    path: Option<DecisionPath>,
    /// The search ahead of the decision of the observation being handled still ran at the end of
    /// its wait ([`BallBrain::collect`]).
    spec_pending: bool,
}

/// The brain's state before an observation, and the observation (see [`BallBrain`]'s `before`).
#[derive(Debug, Clone)]
struct Before {
    ball: Option<Ball>,
    stroke: u32,
    hit_id: u32,
    sent_ids: VecDeque<u32>,
    stats: BallStats,
    obs: ObservationMsg,
    sent: f64,
    now: f64,
}

impl BallBrain {
    /// The brain of the robot `chain` (base frame placed at the table by the core's rally
    /// placement, `ttkin::ball::reach::Placement::default`) with the default ball model; an error
    /// when the chain has no analytic IK or `cfg` is out of range.
    pub fn new(chain: Chain, cfg: BallBrainConfig) -> ttkin::Result<Self> {
        Self::with_planner(ReturnPlanner::new(chain, Flight::default())?, cfg)
    }

    /// The brain with a given ball planner (its robot, placement, flight model and racket).
    pub fn with_planner(planner: ReturnPlanner, cfg: BallBrainConfig) -> ttkin::Result<Self> {
        planner.check_target(cfg.decide.target)?;
        let positive = |what: &str, v: f64| {
            if v > 0.0 && v.is_finite() {
                Ok(())
            } else {
                Err(ttkin::Error::invalid(
                    what,
                    format!("must be finite and > 0 s, got {v}"),
                ))
            }
        };
        positive("latency_budget", cfg.latency_budget)?;
        positive("lost_after", cfg.lost_after)?;
        positive("frame_period", cfg.decide.frame_period)?;
        if !(cfg.ready_after >= 0.0 && cfg.ready_after.is_finite()) {
            return Err(ttkin::Error::invalid(
                "ready_after",
                format!("must be finite and ≥ 0 s, got {}", cfg.ready_after),
            ));
        }
        if cfg.decide.window_frames < 2 || cfg.clock_window == 0 {
            return Err(ttkin::Error::invalid(
                "window_frames",
                "the estimation window needs at least 2 observations and the clock window 1",
            ));
        }
        match cfg.clock {
            ClockRelation::Offset(o) if !o.is_finite() => {
                return Err(ttkin::Error::invalid(
                    "clock",
                    format!("offset must be finite, got {o}"),
                ))
            }
            ClockRelation::MinDelay { latency } if !(latency >= 0.0 && latency.is_finite()) => {
                return Err(ttkin::Error::invalid(
                    "clock",
                    format!("camera latency must be finite and ≥ 0 s, got {latency}"),
                ))
            }
            _ => {}
        }
        Ok(BallBrain {
            planner,
            delays: VecDeque::with_capacity(cfg.clock_window),
            cfg,
            ball: None,
            stroke: 0,
            hit_id: 0,
            sent_ids: VecDeque::with_capacity(16),
            stats: BallStats::default(),
            before: None,
            refinable: false,
            worker: None,
            path: None,
            spec_pending: false,
        })
    }

    /// Moves the searches ahead ([`BallBrainConfig::speculate_frames`]) to a worker thread of
    /// their own (at SCHED_FIFO `priority` when > 0 and allowed): the thread that observes is
    /// then free when a decision's observation comes; a decision whose search ahead still runs
    /// waits for it until 0.4 ms (`REPLAN_RESERVE`) before its splice deadline (without a deadline,
    /// until it ends). Nothing with `speculate_frames` 0.
    pub fn spawn_worker(&mut self, priority: u8) -> std::io::Result<()> {
        if self.cfg.speculate_frames > 0 && self.worker.is_none() {
            self.worker = Some(Speculator::spawn(self.planner.clone(), priority)?);
        }
        Ok(())
    }

    /// Whether the searches ahead run on a worker thread ([`BallBrain::spawn_worker`]).
    pub fn has_worker(&self) -> bool {
        self.worker.is_some()
    }

    /// Takes the worker's result for the current ball's next decision, if there, and holds its
    /// hit; when the observation at `t` (s) is that decision's and its search still runs, waits
    /// for it until [`REPLAN_RESERVE`] before `deadline`. Sets `spec_pending` when the
    /// decision's search ahead was still running at the end (it searches itself).
    fn collect(&mut self, id: u32, t: f64, deadline: Option<Instant>) {
        self.spec_pending = false;
        let (Some(w), Some(ball)) = (self.worker.as_mut(), self.ball.as_mut().filter(|b| b.id == id)) else {
            return;
        };
        let key = (ball.id, ball.decisions);
        // Every result there, in order (the search ahead, then its refresh): the last hit found
        // is held.
        let take = |d: super::speculator::SpecDone, decider: &mut BallDecider| {
            if let Some(spec) = d.spec.filter(|_| d.key == key) {
                decider.hold(spec);
            }
        };
        while let Some(d) = w.poll() {
            take(d, &mut ball.decider);
        }
        let mut pending = false;
        if w.in_flight() == Some(key) && ball.decider.decides(t) {
            self.stats.speculation_waited += 1;
            let until = deadline.map(|d| d.checked_sub(Duration::from_secs_f64(REPLAN_RESERVE)).unwrap_or(d));
            while w.in_flight() == Some(key) {
                match w.wait(until) {
                    Some(d) => take(d, &mut ball.decider),
                    None => break,
                }
            }
            pending = w.in_flight() == Some(key);
            if pending {
                self.stats.speculation_pending += 1;
            }
        }
        self.spec_pending = pending;
    }

    /// The counters.
    pub fn stats(&self) -> BallStats {
        self.stats
    }

    /// The ball planner (robot, placement, flight model).
    pub fn planner(&self) -> &ReturnPlanner {
        &self.planner
    }

    /// The current offset (s) from camera time to controller time, once known.
    pub fn offset(&self) -> Option<f64> {
        match self.cfg.clock {
            ClockRelation::Offset(o) => Some(o),
            _ => self.delays.iter().copied().reduce(f64::min),
        }
    }

    /// The ball planner's hit in force for the current ball and its absolute time (s, controller
    /// clock), if any.
    pub fn hit(&self) -> Option<(&ReturnHit, f64)> {
        self.ball.as_ref()?.hit.as_ref().map(|(t, h)| (h, *t))
    }

    fn delay_sample(&mut self, d: f64) {
        if d.is_finite() {
            if self.delays.len() == self.cfg.clock_window {
                self.delays.pop_front();
            }
            self.delays.push_back(d);
        }
    }

    /// The stroke of the ball planner's `hit` decided for the splice `at`: its hit leg from the
    /// state at `at` and the return to rest at ready, as the offline rally executes it.
    fn command(&mut self, hit: &ReturnHit, at: &SpliceAt) -> Command {
        self.hit_id = self.hit_id.wrapping_add(1);
        if self.sent_ids.len() == self.sent_ids.capacity() {
            self.sent_ids.pop_front();
        }
        self.sent_ids.push_back(self.hit_id);
        Command::Stroke(Box::new(PlannedStroke {
            hit: hit_msg(hit, self.hit_id, self.stroke, at.t + hit.hit.t),
            cycle: at.cycle,
            start: at.t,
            traj: execution(hit, &JointState::rest(&self.planner.ready)),
        }))
    }

    /// The hit just decided (the current ball's, still ahead), kept for the later splice `at`: its
    /// hit leg planned again from the state there to the same hit state at the same time, its
    /// follow-through to the ball planner's ready (`HitPlanner::branch_leg_to`, the ball planner's
    /// legs and limits, effort included), as a new stroke; `None` when that is not feasible.
    fn retime(&mut self, at: &SpliceAt) -> Option<Command> {
        let (t_abs, old) = self.ball.as_ref()?.hit.clone()?;
        let t = t_abs - at.t;
        if t.is_nan() || t <= 0.0 {
            return None;
        }
        let hit = ttkin::hit::Hit { t, ..old.hit };
        let robot = &self.planner.robot;
        let twist = robot.tool_twist(&hit);
        let ready = &self.planner.ready;
        let branch = robot.branch_leg_to(&old.branch.q, &at.state, &twist, t, ready, f64::NEG_INFINITY)?;
        let new = ReturnHit { hit, branch, ..old };
        self.stats.retimed += 1;
        self.refinable = false;
        let c = self.command(&new, at);
        self.ball.as_mut().expect("has a hit").hit = Some((t_abs, new));
        Some(c)
    }

    /// The observation `obs` on the controller's clock with the header's send time `sent`
    /// (camera clock; NaN when unknown); a stroke decided now starts at `at`.
    /// (`again`: the same observation taken again, its delay already sampled.)
    fn receive(&mut self, obs: &ObservationMsg, sent: f64, now: f64, at: &SpliceAt, again: bool) -> Option<Command> {
        self.stats.observations += 1;
        match self.cfg.clock {
            _ if again => {}
            ClockRelation::SendTime => self.delay_sample(now - sent),
            ClockRelation::MinDelay { latency } => self.delay_sample(now - obs.camera_time - latency),
            ClockRelation::Offset(_) => {}
        }
        let t = obs.camera_time + self.offset()?;
        if now - t > self.cfg.latency_budget {
            self.stats.stale += 1;
            return None;
        }
        let mut out = None;
        if self.ball.as_ref().is_none_or(|b| b.id != obs.id) {
            // A new ball: the previous one is over; a stroke for it still to come is called off.
            if let Some(b) = self.ball.take() {
                if b.hit.as_ref().is_some_and(|(th, _)| *th > now) && !b.ended {
                    out = Some(Command::Ready);
                }
            }
            self.stats.balls += 1;
            self.ball = Some(Ball {
                id: obs.id,
                decider: BallDecider::new(&self.planner, self.cfg.decide),
                last_seen: now,
                hit: None,
                ended: false,
                decisions: 0,
            });
        }
        let ball = self.ball.as_mut().expect("set above");
        if ball.decider.done() || ball.ended {
            self.stats.ignored += 1;
            return out;
        }
        if ball.decider.observations().0.last().is_some_and(|&l| t <= l) {
            self.stats.ignored += 1;
            return out;
        }
        ball.last_seen = now;
        let pending = self.spec_pending;
        // Decided by the splice's deadline (an anytime search: the best hit found by then).
        self.planner.budget = at.deadline.map(PlanBudget::Until);
        // The decision's `now` is the splice instant: the stroke it plans starts there, from the
        // state commanded then (the offline rally decides at the delivery and starts there).
        let decision = ball
            .decider
            .observe(&self.planner, t, obs.position, at.t, &|_| at.state.clone());
        let done = ball.decider.done();
        if decision.is_some() {
            ball.decisions += 1;
            self.path = Some(match ball.decider.speculation_used() {
                Some(true) => {
                    self.stats.speculation_used += 1;
                    if ball.decider.speculation_rank().is_some_and(|r| r > 0) {
                        self.stats.speculation_alternative += 1;
                    }
                    DecisionPath::Held
                }
                Some(false) => {
                    self.stats.speculation_unused += 1;
                    DecisionPath::HeldInfeasible
                }
                None if pending => DecisionPath::SearchPending,
                None => DecisionPath::Searched,
            });
        } else if ball.decider.speculation_due(self.cfg.speculate_frames) {
            // The next decision's search, made now, before its observation comes: on the worker
            // thread given up 1 ms before that observation is due (the decision waits for it,
            // within its lead); on this thread 2 ms before (it must not hold that observation
            // up). Either way the decision searches itself when no hit was found. Without a
            // splice deadline (a brain driven off-line) it is not given up.
            let frames = self.cfg.speculate_frames as f64;
            let margin = if self.worker.is_some() { 1e-3 } else { 2e-3 };
            let left = (frames * self.cfg.decide.frame_period - margin).max(0.0);
            let abandon = at.deadline.map(|_| Instant::now() + Duration::from_secs_f64(left));
            self.stats.speculated += 1;
            match self.worker.as_mut() {
                Some(w) => {
                    ball.decider.mark_speculated();
                    w.submit(SpecJob {
                        key: (ball.id, ball.decisions),
                        decider: ball.decider.clone(),
                        now: at.t,
                        start: at.state.clone(),
                        abandon,
                        refresh: false,
                    });
                }
                None => {
                    self.planner.budget = abandon.map(PlanBudget::Abandon);
                    ball.decider.speculate(&self.planner, at.t, &at.state);
                    self.planner.budget = None;
                }
            }
        } else if self.cfg.refresh_ahead && self.cfg.speculate_frames >= 2 && ball.decider.refresh_due() {
            // One frame before the decision, on the worker only: its search ahead made again from
            // the newest estimate (the held hits planned again first, searched when none is
            // feasible any more), so that the deciding observation rarely searches in full.
            if let Some(w) = self.worker.as_mut() {
                let left = (self.cfg.decide.frame_period - 1e-3).max(0.0);
                let abandon = at.deadline.map(|_| Instant::now() + Duration::from_secs_f64(left));
                ball.decider.mark_refreshed();
                self.stats.refreshed += 1;
                w.submit(SpecJob {
                    key: (ball.id, ball.decisions),
                    decider: ball.decider.clone(),
                    now: at.t,
                    start: at.state.clone(),
                    abandon,
                    refresh: true,
                });
            }
        }
        match decision {
            None => {}
            Some(Decision::EstimateFailed(_)) => self.stats.estimate_failed += 1,
            Some(Decision::PlanFailed(_)) => self.stats.no_hit += 1,
            Some(Decision::Planned { now, plan, .. }) => match plan.hit.filter(|_| plan.status == ReturnStatus::Ok) {
                Some(hit) => {
                    self.stroke = self.stroke.wrapping_add(1);
                    self.stats.planned += 1;
                    self.refinable = true;
                    out = Some(self.command(&hit, at));
                    self.ball.as_mut().expect("set above").hit = Some((now + hit.hit.t, hit));
                }
                None if done => self.stats.no_hit += 1,
                None => {}
            },
            Some(Decision::Corrected { now, hit }) => {
                let first = self.ball.as_ref().is_some_and(|b| b.hit.is_some());
                match hit {
                    Some(hit) => {
                        if !first {
                            self.stroke = self.stroke.wrapping_add(1);
                        }
                        self.stats.corrected += 1;
                        self.refinable = true;
                        out = Some(self.command(&hit, at));
                        self.ball.as_mut().expect("set above").hit = Some((now + hit.hit.t, *hit));
                    }
                    // Counted once, at the last correction (a second may still come).
                    None if !first && done => self.stats.no_hit += 1,
                    None => {}
                }
            }
        }
        out
    }
}

/// The wire form of a ball planner's hit: racket pose and twist in the robot's base frame, the
/// hit time `t_hit` (s, controller clock).
pub fn hit_msg(hit: &ReturnHit, id: u32, stroke: u32, t_hit: f64) -> HitMsg {
    HitMsg::from_pose(id, stroke, t_hit, &hit.hit.pose, hit.hit.twist)
}

impl Brain for BallBrain {
    fn observe(&mut self, obs: &ObservationMsg, sent: f64, now: f64, splice: &SpliceAt) -> Option<Command> {
        // The state before the observation is kept (cloned: the decider's observations, estimate
        // and hits) only when the observation may lead to a decision: a new ball, or the
        // decider's window or correction time near (a frame period either side, the offset may
        // move); otherwise nothing is kept and there is nothing to decide again.
        let t_guess = obs.camera_time + self.offset().unwrap_or(f64::NAN);
        // The hit found ahead on the worker, held before the state is kept (a decision made
        // again from it uses it too).
        self.collect(obs.id, t_guess, splice.deadline);
        let may_decide = match &self.ball {
            Some(b) if b.id == obs.id => !b.ended && b.decider.may_decide(t_guess),
            _ => true,
        };
        if !may_decide || t_guess.is_nan() {
            self.before = None;
            return self.receive(obs, sent, now, splice, false);
        }
        let before = Before {
            ball: self.ball.clone(),
            stroke: self.stroke,
            hit_id: self.hit_id,
            sent_ids: self.sent_ids.clone(),
            stats: self.stats,
            obs: *obs,
            sent,
            now,
        };
        match &mut self.before {
            Some(b) => **b = before,
            None => self.before = Some(Box::new(before)),
        }
        self.receive(obs, sent, now, splice, false)
    }

    fn retry(&mut self, splice: &SpliceAt) -> Option<Command> {
        if let Some(c) = self.retime(splice) {
            return Some(c);
        }
        let b = self.before.as_deref()?.clone();
        self.ball = b.ball;
        self.stroke = b.stroke;
        self.hit_id = b.hit_id;
        self.sent_ids = b.sent_ids;
        self.stats = b.stats;
        self.receive(&b.obs, b.sent, b.now, splice, true)
    }

    fn awaits(&self) -> Option<Awaiting> {
        let b = self.ball.as_ref()?;
        (self.refinable && b.hit.is_some() && !b.ended).then_some(Awaiting {
            ball: b.id,
            wait: 1.5 * self.cfg.decide.frame_period,
        })
    }

    fn refine(&mut self, newer: &[Observed], splice: &SpliceAt) -> Option<(Command, usize)> {
        if !std::mem::take(&mut self.refinable) {
            return None;
        }
        let offset = self.offset()?;
        let ball = self.ball.as_ref()?;
        let t_hit = ball.hit.as_ref().map(|(t, _)| *t)?;
        if t_hit <= splice.t {
            return None;
        }
        // The current ball's observations after the last one the decider has, within the budget.
        let mut last = ball
            .decider
            .observations()
            .0
            .last()
            .copied()
            .unwrap_or(f64::NEG_INFINITY);
        let mut used = Vec::with_capacity(newer.len());
        let mut newest = None;
        for (i, o) in newer.iter().enumerate() {
            let t = o.obs.camera_time + offset;
            if o.obs.id == ball.id && t > last && o.arrival - t <= self.cfg.latency_budget {
                used.push((t, o.obs.position));
                newest = Some(i);
                last = t;
            }
        }
        let newest = newest?;
        self.planner.budget = None;
        let ball = self.ball.as_mut().expect("checked above");
        let hit = ball.decider.refine(&self.planner, &used, splice.t, &splice.state)?;
        self.stats.refined += 1;
        let c = self.command(&hit, splice);
        self.ball.as_mut().expect("checked above").hit = Some((t_hit, hit));
        Some((c, newest))
    }

    fn publish(&self, c: &Counters) {
        let s = &self.stats;
        for (a, v) in [
            (&c.ball_observations, s.observations),
            (&c.ball_stale, s.stale),
            (&c.ball_ignored, s.ignored),
            (&c.balls, s.balls),
            (&c.ball_estimate_failed, s.estimate_failed),
            (&c.ball_no_hit, s.no_hit),
            (&c.ball_planned, s.planned),
            (&c.ball_corrected, s.corrected),
            (&c.ball_lost, s.lost),
            (&c.ball_refused, s.refused),
            (&c.ball_retimed, s.retimed),
            (&c.ball_refined, s.refined),
            (&c.ball_speculated, s.speculated),
            (&c.ball_speculation_used, s.speculation_used),
            (&c.ball_speculation_unused, s.speculation_unused),
            (&c.ball_speculation_waited, s.speculation_waited),
            (&c.ball_speculation_pending, s.speculation_pending),
            (&c.ball_speculation_alternative, s.speculation_alternative),
            (&c.ball_speculation_refreshed, s.refreshed),
        ] {
            a.store(v, Ordering::Relaxed);
        }
    }

    fn tick(&mut self, now: f64, _commanded: &JointState) -> Option<Command> {
        let ball = self.ball.as_mut()?;
        if ball.ended {
            return None;
        }
        match &ball.hit {
            Some((t_hit, _)) if now >= t_hit + self.cfg.ready_after => {
                ball.ended = true;
                Some(Command::Ready)
            }
            None if !ball.decider.done() && now - ball.last_seen > self.cfg.lost_after => {
                ball.ended = true;
                self.stats.lost += 1;
                Some(Command::Ready)
            }
            _ => None,
        }
    }

    fn decision_path(&self) -> Option<DecisionPath> {
        self.path
    }

    fn outcome(&mut self, status: &StatusMsg) {
        if self.sent_ids.contains(&status.id)
            && !matches!(
                status.status,
                PlanStatus::Accepted | PlanStatus::Replaced | PlanStatus::OutOfStep
            )
        {
            self.stats.refused += 1;
        }
    }
}
