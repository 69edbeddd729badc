//! What [`ReturnPlanner::plan_from`] and [`ReturnPlanner::plan_near`] share, written once: the
//! checks of their inputs (one error for the same bad input), the early exits (no bounce, out of
//! reach), the return-time loop of one candidate and the outcome choice.

use super::super::flight::BallState;
use super::super::impact::RacketAtImpact;
use super::{ReturnHit, ReturnPlan, ReturnPlanner, ReturnStatus};
use crate::error::{check_finite, Error, Result};
use crate::traj::JointState;
use nalgebra::Vector3;
use std::time::{Duration, Instant};

/// An outgoing shot: ball velocity after the impact (m/s, world), the racket producing it, and the
/// landing point (m, world).
pub(super) type Shot = (Vector3<f64>, RacketAtImpact, Vector3<f64>);

/// How a plan starts: already decided (no bounce, out of reach), or a search over candidates.
pub(super) enum Begin {
    /// The plan without a search.
    Done(ReturnPlan),
    /// The candidate ball states (in time order) and the empty search.
    Search(Vec<BallState>, Search),
}

/// How long a plan searches before it settles for the best feasible hit found so far (an
/// anytime search, [`super::ReturnPlanner::budget`]): once the budget is spent, the search ends at
/// the next candidate, shot or racket pose with the best hit it has; with none yet it goes on to
/// the first feasible one (or the end of the search, as without a budget).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanBudget {
    /// Until this instant of the monotonic clock (a controller's deadline: its splice cycle).
    Until(Instant),
    /// This much CPU time of the planning thread from the start of the plan (reproducible on a
    /// loaded machine, for off-line studies of the budget).
    ThreadCpu(Duration),
    /// Until this instant of the monotonic clock, then the search ends at the next candidate or
    /// shot even with no feasible hit found (a search made ahead of its need, which must not hold
    /// up what comes after it: a controller's speculation).
    Abandon(Instant),
}

/// A plan's budget resolved at its start (see [`PlanBudget`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Deadline {
    /// No budget: the search runs to its end.
    None,
    /// The monotonic clock's instant.
    Until(Instant),
    /// The thread's CPU clock reading (as a duration since its origin).
    ThreadCpu(Duration),
    /// The monotonic clock's instant, after which the search ends even with no hit.
    Abandon(Instant),
}

impl Deadline {
    /// The deadline of a plan starting now under `budget`.
    pub(super) fn start(budget: Option<PlanBudget>) -> Self {
        match budget {
            None => Deadline::None,
            Some(PlanBudget::Until(t)) => Deadline::Until(t),
            Some(PlanBudget::ThreadCpu(d)) => Deadline::ThreadCpu(cpu_time::ThreadTime::now().as_duration() + d),
            Some(PlanBudget::Abandon(t)) => Deadline::Abandon(t),
        }
    }

    /// Whether the budget is spent and the search is to end even with no hit.
    pub(super) fn abandoned(&self) -> bool {
        matches!(self, Deadline::Abandon(t) if Instant::now() >= *t)
    }

    /// Whether the budget is spent.
    pub(super) fn passed(&self) -> bool {
        match self {
            Deadline::None => false,
            Deadline::Until(t) | Deadline::Abandon(t) => Instant::now() >= *t,
            Deadline::ThreadCpu(d) => cpu_time::ThreadTime::now().as_duration() >= *d,
        }
    }
}

/// A search in progress: the best hit so far, whether any shot returned the ball, candidates tried.
pub(super) struct Search {
    /// The best hit so far (largest margin).
    pub(super) best: Option<ReturnHit>,
    /// The next best, each of another candidate, by decreasing margin (at most
    /// [`super::ALTERNATIVES`]).
    others: Vec<ReturnHit>,
    /// When the search settles for its best hit so far.
    pub(super) deadline: Deadline,
    any_return: bool,
    tried: usize,
    good_margin: f64,
    return_times: [f64; 3],
}

impl ReturnPlanner {
    /// The checks of a plan's inputs (one error for the same bad input in every plan): `goal` on
    /// the opponent's half, `start` of the chain's joint count and finite, `ball` valid, `now`
    /// finite and within the flight's span from `ball`.
    pub(super) fn check_inputs(&self, ball: &BallState, now: f64, goal: [f64; 2], start: &JointState) -> Result<()> {
        self.check_target(goal)?;
        if start.check("start")? != self.chain().dof() {
            return Err(Error::shape(
                "start.q",
                format!("{} values", self.chain().dof()),
                start.q.len(),
            ));
        }
        ball.validate("ball")?;
        check_finite("now", &[now])?;
        self.flight.check_span("now", ball, now)
    }

    /// Checks the inputs of a plan for `ball` at `now` (s) toward `goal` from the joint state
    /// `start` and predicts the candidates: the early exits, or the search to run.
    pub(super) fn begin(
        &self,
        ball: &BallState,
        now: f64,
        goal: [f64; 2],
        start: &JointState,
        after_bounce: bool,
    ) -> Result<Begin> {
        self.check_inputs(ball, now, goal, start)?;
        let (list, bounced) = self.candidate_states(&self.flight, ball, now, self.search_margin, after_bounce);
        let status = match (bounced, list.is_empty()) {
            (false, _) => ReturnStatus::NoBounce,
            (true, true) => ReturnStatus::OutOfReach,
            (true, false) => return Ok(Begin::Search(list, Search::new(self))),
        };
        Ok(Begin::Done(ReturnPlan {
            status,
            hit: None,
            candidates: 0,
            alternatives: Vec::new(),
        }))
    }
}

impl Search {
    /// An empty search with `planner`'s settings, its budget starting now.
    pub(super) fn new(planner: &ReturnPlanner) -> Self {
        Search {
            best: None,
            others: Vec::new(),
            any_return: false,
            tried: 0,
            good_margin: planner.good_margin,
            return_times: planner.return_times,
            deadline: Deadline::start(planner.budget),
        }
    }

    /// Whether the best hit so far is good enough to end the search: margin ≥ `good_margin`, or
    /// any hit once the budget is spent; anything once a [`PlanBudget::Abandon`] budget is.
    pub(super) fn good(&self) -> bool {
        self.best
            .as_ref()
            .is_some_and(|b| b.margin() >= self.good_margin || self.deadline.passed())
            || self.deadline.abandoned()
    }

    /// Candidates tried so far.
    pub(super) fn tried(&self) -> usize {
        self.tried
    }

    /// One candidate `s` aimed at `goal`: the return times in order, the shot of each
    /// (`ReturnPlanner::outgoing`), and the first whose robot hit (`robot`) is feasible, kept when
    /// its margin beats the best so far.
    pub(super) fn attempt(
        &mut self,
        planner: &ReturnPlanner,
        s: &BallState,
        goal: [f64; 2],
        robot: &dyn Fn(&BallState, Shot) -> Option<ReturnHit>,
    ) {
        let times = self.return_times;
        self.attempt_shots(s, times.iter().filter_map(|&tf| planner.outgoing(s, goal, tf)), robot);
    }

    /// One candidate `s` with its shots `shots` (computed as they are asked for, in the order
    /// tried): the first whose robot hit (`robot`) is feasible, kept as in [`Self::attempt`].
    pub(super) fn attempt_shots(
        &mut self,
        s: &BallState,
        shots: impl Iterator<Item = Shot>,
        robot: &dyn Fn(&BallState, Shot) -> Option<ReturnHit>,
    ) {
        self.tried += 1;
        for shot in shots {
            self.any_return = true;
            if let Some(hit) = robot(s, shot) {
                let runner = if self.best.as_ref().is_none_or(|b| hit.margin() > b.margin()) {
                    self.best.replace(hit)
                } else {
                    Some(hit)
                };
                if let Some(r) = runner {
                    self.keep_other(r);
                }
                break;
            }
        }
    }

    /// Keeps `hit` among the next best when its margin is among the top [`super::ALTERNATIVES`].
    fn keep_other(&mut self, hit: ReturnHit) {
        let at = self.others.partition_point(|o| o.margin() >= hit.margin());
        if at < super::ALTERNATIVES {
            self.others.insert(at, hit);
            self.others.truncate(super::ALTERNATIVES);
        }
    }

    /// The plan the search ends with: its best hit (`Ok`), or `Infeasible` when some shot returned
    /// the ball but no hit was feasible, else `NoReturn`.
    pub(super) fn finish(self) -> ReturnPlan {
        let status = match (&self.best, self.any_return) {
            (Some(_), _) => ReturnStatus::Ok,
            (None, true) => ReturnStatus::Infeasible,
            (None, false) => ReturnStatus::NoReturn,
        };
        ReturnPlan {
            status,
            hit: self.best,
            candidates: self.tried,
            alternatives: self.others,
        }
    }
}
