//! The robot's decisions for one incoming ball, observation by observation: when to plan the
//! first hit, from which estimate, when and how to correct it after the bounce. The rally
//! ([`super::rally`]) and the controller's ball mode (`ttcan::online::ball`) both drive this one
//! state machine, so that the same observations give the same hits offline and at run time.
//!
//! The rules (those of the rally since the correction was introduced):
//! - **First plan** at the delivery of observation number `window_frames` of the ball (the
//!   rally's 0.2 s window at 200 Hz: 41 observations): the ball estimated from all of them
//!   ([`estimate`]), the hit planned for a stroke from rest at the ready configuration
//!   ([`ReturnPlanner::plan`]).
//! - **Correction**, once, at the delivery of the last observation taken at most
//!   `correction_delay` after the bounce the first estimate predicts: the estimate updated with
//!   the observations since ([`update_kick`]: the ball's own bounce fitted where the observations
//!   after it depart from the model's) and the hit planned again from the state the robot is
//!   commanded then ([`ReturnPlanner::plan_near`] near the first hit; without a first hit
//!   [`ReturnPlanner::plan_from`] from rest), shortest stroke 60 ms; skipped (the first hit stands)
//!   when less than that is left before the first hit, or when the update or the plan fails.
//!   "The last observation" is recognised causally: the one whose time plus one frame period
//!   passes the correction time (with every frame delivered, the rally's choice exactly); when
//!   frames are missing, the first observation past the correction time triggers it with the
//!   observations before it.
//! - **Wider correction** (`widen_correction`; the rally's default): when the search near the
//!   hit under way ([`ReturnPlanner::plan_near`]) finds no feasible hit, the correction searches
//!   in full from the commanded state ([`ReturnPlanner::plan_from`]: every candidate, the
//!   requested target and its fallbacks) before the hit under way is kept; it costs only then.
//! - **Second correction** (`second_correction` > 0; the rally's default 0.05 s): the same, that
//!   long after the first correction's time, with every observation since the first estimate,
//!   near the hit under way (the corrected one, else the first); skipped the same way.
//!
//! - **Speculation** (the controller's, never the rally's): a caller that cannot search within
//!   its latency may make a decision's search a few observations ahead of it
//!   ([`BallDecider::speculate`]); the decision then plans the hit so found again from its own
//!   estimate and state ([`ReturnPlanner::plan_same_hit`], the same absolute hit time and
//!   landing point, no search), then, when that is not feasible, the next best hits of the same
//!   search in turn ([`Speculation::others`]), and searches as above only when none is.
//!
//! Times are on one clock, the caller's: observation times, `now` and the hits' times (a hit's
//! `hit.t` counts from the `now` of its decision).

use super::estimate::{estimate, Estimate, EstimateError, EstimateOptions};
use super::flight::{BallState, EventKind, Flight};
use super::hitplan::{ReturnHit, ReturnPlan, ReturnPlanner, ReturnStatus};
use super::update::update_kick;
use crate::error::Error;
use crate::traj::JointState;

/// The decision rules' settings (the rally's: `DecideConfig::of(&rally_config)`, see
/// [`super::rally`]; the default is the default rally's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DecideConfig {
    /// Landing target of the return (x, y, m, world; on the opponent's half).
    pub target: [f64; 2],
    /// Observations of a ball the first plan waits for (and estimates from).
    pub window_frames: usize,
    /// The camera's frame period (s): how the last observation before the correction time is
    /// recognised on arrival.
    pub frame_period: f64,
    /// Time (s) after the predicted bounce at which the hit is corrected; 0 for none.
    pub correction_delay: f64,
    /// Prior standard deviation (m/s, world x, y, z) of the ball's own bounce kick fitted by the
    /// correction's update ([`update_kick`], kept only where the observations call for it);
    /// `None`: the model's bounce. The rally's: [`super::update::BOUNCE_SPREAD`].
    pub bounce_spread: Option<[f64; 3]>,
    /// Time (s) after the correction at which the hit is corrected a second time (the estimate
    /// updated with every observation since the first estimate, the hit planned again near the
    /// corrected one); 0 for none.
    pub second_correction: f64,
    /// Whether a correction whose search near the hit under way finds no feasible hit searches
    /// in full from the commanded state (module doc) before keeping the hit under way.
    pub widen_correction: bool,
}

/// What one observation led to.
#[derive(Debug, Clone, PartialEq)]
pub enum Decision {
    /// The first estimate failed: nothing is planned for this ball.
    EstimateFailed(EstimateError),
    /// The first plan failed with an error: nothing is planned for this ball.
    PlanFailed(Error),
    /// The first plan at `now` (s): the estimate it started from and the plan (a hit to execute
    /// when its status is [`ReturnStatus::Ok`]; its `hit.t` counts from `now`).
    Planned {
        /// Decision time (s).
        now: f64,
        /// The ball estimate the plan started from.
        estimate: Box<Estimate>,
        /// The plan.
        plan: Box<ReturnPlan>,
    },
    /// The correction after the bounce was made at `now` (s): the hit replacing the first one
    /// (`hit.t` from `now`), or `None` when the first hit stands.
    Corrected {
        /// Decision time (s).
        now: f64,
        /// The new hit.
        hit: Option<Box<ReturnHit>>,
    },
}

#[derive(Debug, Clone, PartialEq)]
enum Phase {
    /// Collecting observations for the first plan.
    Observing,
    /// First plan made; a correction is due at this time (s; observation clock); whether it is
    /// the second.
    Correcting(f64, bool),
    /// Nothing more to decide for this ball.
    Done,
}

/// The decisions for one ball (see the module doc): feed its observations in time order with
/// [`BallDecider::observe`].
#[derive(Debug, Clone)]
pub struct BallDecider {
    cfg: DecideConfig,
    opts: EstimateOptions,
    times: Vec<f64>,
    obs: Vec<[f64; 3]>,
    phase: Phase,
    estimate: Option<Estimate>,
    /// The first hit and its absolute time (s).
    first: Option<(ReturnHit, f64)>,
    /// The hit of the last decision with a hit (first plan or correction) and its absolute time
    /// (s), and whether it is the first plan's: what [`BallDecider::refine`] plans again.
    last: Option<(ReturnHit, f64, bool)>,
    /// A hit found ahead of the next decision ([`BallDecider::hold`]), which that decision plans
    /// again from its own estimate instead of searching.
    held: Option<Speculation>,
    /// The decisions a speculation was made for (see [`BallDecider::speculation_due`]): bit 0
    /// the first plan, bit 1 the correction, bit 2 the second correction.
    speculated: u8,
    /// The decisions whose search ahead was made again one frame before them, bits as in
    /// `speculated` ([`BallDecider::refresh`]).
    refreshed: u8,
    /// How the last decision used a held hit: `Some(true)` planned again from it, `Some(false)`
    /// it could not be and the decision searched in full, `None` no hit held.
    spec_used: Option<bool>,
    /// Which of the held hits the last decision planned again (0: the best, 1…: the others).
    spec_rank: Option<usize>,
}

/// The bit of [`BallDecider`]'s `speculated` for a correction: the first's or the second's.
fn correction_bit(second: bool) -> u8 {
    if second {
        4
    } else {
        2
    }
}

/// A hit decided ahead of the decision that will use it, from the observations a few frames
/// before the deciding one ([`BallDecider::speculate`]): the controller's way to decide within
/// its splice lead (the search runs before the deciding observation, that observation only
/// plans the same hit again, [`ReturnPlanner::plan_same_hit`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Speculation {
    /// The hit found (`hit.t` from the `now` it was speculated at).
    pub hit: ReturnHit,
    /// Its absolute hit time (s, the decider's clock).
    pub t_hit: f64,
    /// For the correction after the bounce (else for the first plan).
    pub correction: bool,
    /// The next best hits of the same search (other hit times, by decreasing margin,
    /// [`ReturnPlan::alternatives`]) with their absolute hit times (s): tried in turn when `hit`
    /// cannot be planned again, before the decision searches.
    pub others: Vec<(ReturnHit, f64)>,
}

impl Speculation {
    /// The held hits in the order a decision tries them: `hit`, then `others`.
    fn tries(&self) -> impl Iterator<Item = (&ReturnHit, f64)> {
        std::iter::once((&self.hit, self.t_hit)).chain(self.others.iter().map(|(h, t)| (h, *t)))
    }
}

impl BallDecider {
    /// A decider for a new ball, estimating with `planner`'s flight model.
    pub fn new(planner: &ReturnPlanner, cfg: DecideConfig) -> Self {
        BallDecider {
            cfg,
            opts: EstimateOptions {
                flight: planner.flight,
                ..EstimateOptions::default()
            },
            times: Vec::with_capacity(cfg.window_frames * 3),
            obs: Vec::with_capacity(cfg.window_frames * 3),
            phase: Phase::Observing,
            estimate: None,
            first: None,
            last: None,
            held: None,
            speculated: 0,
            refreshed: 0,
            spec_used: None,
            spec_rank: None,
        }
    }

    /// Whether this ball needs no more observations (planned and corrected, or given up).
    pub fn done(&self) -> bool {
        self.phase == Phase::Done
    }

    /// Whether an observation at time `t` (s), or one up to a frame period either side of it,
    /// may lead to a decision ([`BallDecider::observe`] returning one): a caller that keeps its
    /// state from before each decision (to decide again) needs to keep it only then.
    pub fn may_decide(&self, t: f64) -> bool {
        match self.phase {
            Phase::Done => false,
            Phase::Observing => self.times.len() + 1 >= self.cfg.window_frames,
            Phase::Correcting(at, _) => t + 2.0 * self.cfg.frame_period > at,
        }
    }

    /// Whether an observation at time `t` (s), the next one fed, makes a decision
    /// ([`BallDecider::observe`] returns one): the window's last observation, or one whose time
    /// plus a frame period passes the correction time.
    pub fn decides(&self, t: f64) -> bool {
        if self.times.last().is_some_and(|&l| t <= l) || !t.is_finite() {
            return false;
        }
        match self.phase {
            Phase::Done => false,
            Phase::Observing => self.times.len() + 1 >= self.cfg.window_frames,
            Phase::Correcting(at, _) => t + self.cfg.frame_period > at,
        }
    }

    /// Records that the next decision's search was made ahead elsewhere (on another thread, from
    /// a clone of this decider, [`BallDecider::speculate`]): [`BallDecider::speculation_due`]
    /// turns false for that decision; its hit comes with [`BallDecider::hold`].
    pub fn mark_speculated(&mut self) {
        match self.phase {
            Phase::Done => {}
            Phase::Observing => self.speculated |= 1,
            Phase::Correcting(_, second) => self.speculated |= correction_bit(second),
        }
    }

    /// The observations so far: times (s) and positions (m, world).
    pub fn observations(&self) -> (&[f64], &[[f64; 3]]) {
        (&self.times, &self.obs)
    }

    /// The first estimate, once made.
    pub fn estimate(&self) -> Option<&Estimate> {
        self.estimate.as_ref()
    }

    /// Whether the next decision is at most `frames` observations away (every frame delivered)
    /// and no hit was speculated for it yet: the moment to [`BallDecider::speculate`]. The first
    /// plan's is `frames` observations before the window is full; the correction's, the
    /// observation whose time plus `frames + 1` frame periods passes the correction time.
    /// Never with `frames` 0.
    pub fn speculation_due(&self, frames: usize) -> bool {
        if frames == 0 {
            return false;
        }
        match self.phase {
            Phase::Done => false,
            Phase::Observing => self.speculated & 1 == 0 && self.times.len() + frames >= self.cfg.window_frames,
            Phase::Correcting(at, second) => {
                self.speculated & correction_bit(second) == 0
                    && self
                        .times
                        .last()
                        .is_some_and(|&t| t + (frames as f64 + 1.0) * self.cfg.frame_period > at)
            }
        }
    }

    /// The search of the next decision (first plan or correction) made ahead of it at `now` (s),
    /// from the observations so far, for a stroke from `start` (a correction's; the first plan's
    /// starts from rest at ready), and its hit held: that decision then plans this hit again from
    /// its own estimate and state ([`ReturnPlanner::plan_same_hit`], no search), and searches in
    /// full only when that fails. Made once per decision (see [`BallDecider::speculation_due`]);
    /// true when a hit is held. The off-line rally never calls it.
    pub fn speculate(&mut self, planner: &ReturnPlanner, now: f64, start: &JointState) -> bool {
        self.held = None;
        let spec = match self.phase {
            Phase::Done => return false,
            Phase::Observing => {
                self.speculated |= 1;
                self.speculate_first(planner, now)
            }
            Phase::Correcting(at, second) => {
                self.speculated |= correction_bit(second);
                self.speculate_correction(planner, at, now, start)
            }
        };
        self.held = spec;
        self.held.is_some()
    }

    /// Whether the next observation makes the next decision (every frame delivered), that
    /// decision's search ahead was made ([`BallDecider::speculation_due`] false for it) and it was
    /// not made again yet: the moment to [`BallDecider::refresh`] it, one frame before the
    /// decision.
    pub fn refresh_due(&self) -> bool {
        match self.phase {
            Phase::Done => false,
            Phase::Observing => {
                self.speculated & 1 != 0 && self.refreshed & 1 == 0 && self.times.len() + 1 == self.cfg.window_frames
            }
            Phase::Correcting(at, second) => {
                let bit = correction_bit(second);
                self.speculated & bit != 0
                    && self.refreshed & bit == 0
                    && self
                        .times
                        .last()
                        .is_some_and(|&t| t + self.cfg.frame_period <= at && t + 2.0 * self.cfg.frame_period > at)
            }
        }
    }

    /// The next decision's search ahead made again at `now` (s) from the observations so far,
    /// one frame before that decision ([`BallDecider::refresh_due`]), for a stroke from `start`
    /// (a correction's): the held hits ([`BallDecider::held`]) are planned again first from the
    /// newest estimate, in order ([`ReturnPlanner::plan_same_hit`], no search), and the first
    /// feasible one is held, with the next ones after it; when none is (or none is held), the
    /// search is made again as [`BallDecider::speculate`] makes it. The deciding observation then
    /// plans a hit found from an estimate one frame old again, rarely in vain. True when a hit
    /// is held.
    pub fn refresh(&mut self, planner: &ReturnPlanner, now: f64, start: &JointState) -> bool {
        let held = self.held.take();
        let spec = match self.phase {
            Phase::Done => return false,
            Phase::Observing => {
                self.refreshed |= 1;
                let held = held.filter(|h| !h.correction);
                let est = estimate(&self.times, &self.obs, &self.opts).ok();
                let again = est.as_ref().zip(held.as_ref()).and_then(|(est, h)| {
                    let rest = JointState::rest(&planner.ready);
                    h.tries().enumerate().find_map(|(rank, (hit, t_hit))| {
                        let p = planner.plan_same_hit(&est.state, now, &rest, false, hit, t_hit).ok()?;
                        let new = p.hit.filter(|_| p.status == ReturnStatus::Ok)?;
                        Some(Speculation {
                            hit: new,
                            t_hit,
                            correction: false,
                            others: h.others.iter().skip(rank).cloned().collect(),
                        })
                    })
                });
                again.or_else(|| self.speculate_first(planner, now))
            }
            Phase::Correcting(at, second) => {
                self.refreshed |= correction_bit(second);
                let held = held.filter(|h| h.correction);
                let mut used = None;
                self.correction(planner, at, now, &|_| start.clone(), held, &mut used)
                    .map(|(hit, others)| Speculation {
                        t_hit: now + hit.hit.t,
                        hit,
                        correction: true,
                        others: others.into_iter().map(|h| (h.clone(), now + h.hit.t)).collect(),
                    })
            }
        };
        self.held = spec;
        self.held.is_some()
    }

    /// Records that the next decision's search ahead was made again elsewhere (on another
    /// thread, from a clone of this decider, [`BallDecider::refresh`]): [`BallDecider::refresh_due`]
    /// turns false for that decision; its hit comes with [`BallDecider::hold`].
    pub fn mark_refreshed(&mut self) {
        match self.phase {
            Phase::Done => {}
            Phase::Observing => self.refreshed |= 1,
            Phase::Correcting(_, second) => self.refreshed |= correction_bit(second),
        }
    }

    /// Holds `spec` for the next decision of its kind (a first plan's, or a correction's), as
    /// [`BallDecider::speculate`] does with the hit it finds (e.g. one searched on another
    /// thread from a clone of this decider).
    pub fn hold(&mut self, spec: Speculation) {
        self.held = Some(spec);
    }

    /// The hit held for the next decision ([`BallDecider::speculate`]), if any.
    pub fn held(&self) -> Option<&Speculation> {
        self.held.as_ref()
    }

    /// How the last decision used a held hit: `Some(true)` it planned that hit again (no
    /// search), `Some(false)` a hit was held but not used (not feasible from the decision's
    /// estimate and state, or no correction made), `None` none was held.
    pub fn speculation_used(&self) -> Option<bool> {
        self.spec_used
    }

    /// Which held hit the last decision planned again: `Some(0)` the one found best ahead,
    /// `Some(k)` the next best number `k` ([`Speculation::others`], the ones before it not
    /// feasible), `None` none (no hit held, or none feasible).
    pub fn speculation_rank(&self) -> Option<usize> {
        self.spec_rank
    }

    fn speculate_first(&self, planner: &ReturnPlanner, now: f64) -> Option<Speculation> {
        let est = estimate(&self.times, &self.obs, &self.opts).ok()?;
        let plan = planner.plan(&est.state, now, self.cfg.target).ok()?;
        let hit = plan.hit.filter(|_| plan.status == ReturnStatus::Ok)?;
        Some(Speculation {
            t_hit: now + hit.hit.t,
            hit,
            correction: false,
            others: plan
                .alternatives
                .into_iter()
                .map(|h| (h.clone(), now + h.hit.t))
                .collect(),
        })
    }

    fn speculate_correction(
        &self,
        planner: &ReturnPlanner,
        at: f64,
        now: f64,
        start: &JointState,
    ) -> Option<Speculation> {
        let mut used = None;
        let (hit, others) = self.correction(planner, at, now, &|_| start.clone(), None, &mut used)?;
        Some(Speculation {
            t_hit: now + hit.hit.t,
            hit,
            correction: true,
            others: others.into_iter().map(|h| (h.clone(), now + h.hit.t)).collect(),
        })
    }

    /// One observation: the ball at `position` (m, world) at time `t` (s), delivered at `now`
    /// (s, same clock); `commanded(t)` is the joint state the robot is commanded at time `t`
    /// (asked only for a correction while a first hit is under way). Observations must come in
    /// increasing time; one not later than the previous is ignored. Returns the decision it led
    /// to, if any.
    pub fn observe(
        &mut self,
        planner: &ReturnPlanner,
        t: f64,
        position: [f64; 3],
        now: f64,
        commanded: &dyn Fn(f64) -> JointState,
    ) -> Option<Decision> {
        if self.times.last().is_some_and(|&l| t <= l) || !t.is_finite() {
            return None;
        }
        match self.phase {
            Phase::Done => None,
            Phase::Observing => {
                self.times.push(t);
                self.obs.push(position);
                (self.times.len() >= self.cfg.window_frames).then(|| self.first_plan(planner, now))
            }
            Phase::Correcting(at, second) => {
                if t <= at {
                    self.times.push(t);
                    self.obs.push(position);
                    (t + self.cfg.frame_period > at).then(|| self.correct(planner, at, second, now, commanded))
                } else {
                    // The last frame before the correction time is missing: correct now with
                    // what came before it.
                    let d = self.correct(planner, at, second, now, commanded);
                    self.times.push(t);
                    self.obs.push(position);
                    Some(d)
                }
            }
        }
    }

    fn first_plan(&mut self, planner: &ReturnPlanner, now: f64) -> Decision {
        self.phase = Phase::Done;
        let est = match estimate(&self.times, &self.obs, &self.opts) {
            Ok(e) => e,
            Err(e) => return Decision::EstimateFailed(e),
        };
        self.estimate = Some(est.clone());
        let held = self.held.take().filter(|h| !h.correction);
        self.spec_used = held.as_ref().map(|_| false);
        self.spec_rank = None;
        let start = JointState::rest(&planner.ready);
        let again = held.as_ref().and_then(|h| {
            h.tries().enumerate().find_map(|(rank, (hit, t_hit))| {
                let p = planner.plan_same_hit(&est.state, now, &start, false, hit, t_hit).ok()?;
                (p.status == ReturnStatus::Ok && p.hit.is_some()).then_some((rank, p))
            })
        });
        let plan = match again {
            Some((rank, p)) => {
                self.spec_used = Some(true);
                self.spec_rank = Some(rank);
                p
            }
            None => match planner.plan(&est.state, now, self.cfg.target) {
                Ok(p) => p,
                Err(e) => return Decision::PlanFailed(e),
            },
        };
        self.first = plan
            .hit
            .as_ref()
            .filter(|_| plan.status == ReturnStatus::Ok)
            .map(|h| (h.clone(), now + h.hit.t));
        self.last = self.first.clone().map(|(h, t)| (h, t, true));
        if self.cfg.correction_delay > 0.0 {
            if let Some(tb) = bounce_time(&planner.flight, &est.state) {
                let at = tb + self.cfg.correction_delay;
                if at >= *self.times.last().expect("observed") {
                    self.phase = Phase::Correcting(at, false);
                }
            }
        }
        Decision::Planned {
            now,
            estimate: Box::new(est),
            plan: Box::new(plan),
        }
    }

    fn correct(
        &mut self,
        planner: &ReturnPlanner,
        at: f64,
        second: bool,
        now: f64,
        commanded: &dyn Fn(f64) -> JointState,
    ) -> Decision {
        self.phase = if !second && self.cfg.second_correction > 0.0 {
            Phase::Correcting(at + self.cfg.second_correction, true)
        } else {
            Phase::Done
        };
        let held = self.held.take().filter(|h| h.correction);
        let mut used = None;
        let hit = self
            .correction(planner, at, now, commanded, held, &mut used)
            .map(|(h, _)| h);
        self.spec_rank = used.flatten();
        self.spec_used = used.map(|r| r.is_some());
        if let Some(h) = &hit {
            self.last = Some((h.clone(), now + h.hit.t, false));
        }
        Decision::Corrected {
            now,
            hit: hit.map(Box::new),
        }
    }

    /// The last decision's hit (the first plan's or the correction's) planned again at `now`
    /// (s) for a stroke from `start`, with the observations that came after the decision: the
    /// first estimate updated as the correction's is ([`update_kick`]) with every observation after it recorded so far and
    /// `newer` (times, s, and positions, m, world; those later than the last recorded one are
    /// used, in increasing time; they are not recorded: feed them to [`BallDecider::observe`]
    /// as usual), and the one hit at the same absolute time to the same landing point
    /// ([`ReturnPlanner::plan_same_hit`], no search). For a controller whose decision came after
    /// its splice: the hit it chose, from the newest observation, decided again in a fraction of
    /// a search. Returns the new hit (`hit.t` from `now`), which becomes the decision's hit (a
    /// later correction starts near it), or `None` (nothing changes) without a hit to plan
    /// again, without an observation after the estimate, or when the update or the plan fails.
    /// The off-line rally never calls it (it decides in zero time).
    pub fn refine(
        &mut self,
        planner: &ReturnPlanner,
        newer: &[(f64, [f64; 3])],
        now: f64,
        start: &JointState,
    ) -> Option<ReturnHit> {
        let (hit, t_hit, first) = self.last.as_ref()?;
        let est = self.estimate.as_ref()?;
        let from = self.times.partition_point(|&t| t <= est.state.t);
        let mut last = self.times.last().copied().unwrap_or(f64::NEG_INFINITY);
        let mut times = self.times[from..].to_vec();
        let mut obs = self.obs[from..].to_vec();
        for &(t, p) in newer {
            if t > last && t > est.state.t && t.is_finite() && p.iter().all(|x| x.is_finite()) {
                times.push(t);
                obs.push(p);
                last = t;
            }
        }
        if times.is_empty() {
            return None;
        }
        let up = update_kick(est, &times, &obs, &self.opts, self.cfg.bounce_spread).ok()?;
        let plan = planner
            .plan_same_hit(&up.state, now, start, up.bounced, hit, *t_hit)
            .ok()?;
        let new = plan.hit.filter(|_| plan.status == ReturnStatus::Ok)?;
        let (t_hit, first) = (*t_hit, *first);
        if first {
            self.first = Some((new.clone(), t_hit));
        }
        self.last = Some((new.clone(), t_hit, first));
        Some(new)
    }

    fn correction(
        &self,
        planner: &ReturnPlanner,
        at: f64,
        now: f64,
        commanded: &dyn Fn(f64) -> JointState,
        held: Option<Speculation>,
        used: &mut Option<Option<usize>>,
    ) -> Option<(ReturnHit, Vec<ReturnHit>)> {
        *used = held.as_ref().map(|_| None);
        let est = self.estimate.as_ref()?;
        // The hit under way: the first plan's, or the first correction's at the second.
        let current = self.last.as_ref().map(|(h, t, _)| (h, *t));
        if current.is_some_and(|(_, t)| t - now <= CORRECTION_MIN_STROKE) {
            return None;
        }
        let mut replanner = planner.clone();
        replanner.min_stroke_time = CORRECTION_MIN_STROKE;
        let from = self.times.partition_point(|&t| t <= est.state.t);
        let last = self.times.partition_point(|&t| t <= at);
        let up = update_kick(
            est,
            &self.times[from..last],
            &self.obs[from..last],
            &self.opts,
            self.cfg.bounce_spread,
        )
        .ok()?;
        // The stroke under way (the hit's), else one from rest at ready; asked only then, as
        // before any speculation (the rally's motion has no state without a hit).
        let start = match current {
            Some(_) => commanded(now),
            None => JointState::rest(&planner.ready),
        };
        if let Some(h) = held {
            for (rank, (hit, t_hit)) in h.tries().enumerate() {
                let again = replanner.plan_same_hit(&up.state, now, &start, up.bounced, hit, t_hit);
                if let Some(hit) = again.ok().and_then(|p| p.hit.filter(|_| p.status == ReturnStatus::Ok)) {
                    *used = Some(Some(rank));
                    return Some((hit, Vec::new()));
                }
            }
        }
        let full = || replanner.plan_from(&up.state, now, self.cfg.target, &start, up.bounced);
        // the hit with the search's next best (for a speculation: `Speculation::others`)
        let ok = |plan: Result<ReturnPlan, Error>| {
            let p = plan.ok()?;
            let found = p.status == ReturnStatus::Ok;
            p.hit.filter(|_| found).map(|h| (h, p.alternatives))
        };
        match current {
            Some((hit, t_prev)) => ok(replanner.plan_near(&up.state, now, &start, up.bounced, hit, t_prev))
                .or_else(|| self.cfg.widen_correction.then(|| ok(full())).flatten()),
            None => ok(full()),
        }
    }
}

/// Shortest stroke (s) of the correction after the bounce: the rest of a stroke under way.
pub(super) const CORRECTION_MIN_STROKE: f64 = 0.06;

/// Time (s) of the first table bounce on the robot's half of the flight from `s` (within 1.5 s),
/// flying no further than that.
pub(super) fn bounce_time(flight: &Flight, s: &BallState) -> Option<f64> {
    let mut cur = *s;
    while cur.t < s.t + 1.5 {
        let (next, ev) = flight.advance(&cur, s.t + 1.5, None);
        match ev {
            Some(e) if e.kind == EventKind::Table && e.before.p.x < 0.0 => return Some(e.before.t),
            Some(e) if e.kind.terminal() => return None,
            _ => cur = next,
        }
    }
    None
}
