//! Hit planning: where, when and how the robot hits the predicted ball so that it lands on a
//! target on the opponent's half.
//!
//! 1. **Candidates** (`candidates.rs`). The ball is predicted from its state (through its
//!    bounce on the robot's half, and on through a net contact within `NET_CLIP` = 2 cm of
//!    clearing the net, the estimate's uncertainty) and every 10 ms sample inside the hitting volume ([`Reach`],
//!    world frame; the same volume as the reachable region of [`super::reach`]), after the bounce
//!    and at least `min_stroke_time` after `now`, is a candidate; `candidates` of them, evenly
//!    spread, are tried (up to `max_candidates`, 40, when none of those is feasible). Each aims at the requested
//!    target or, when no racket with the approximate normal toward it has IK (see
//!    `roughly_placeable`), at the nearest fallback target on the opponent's half that has one; a
//!    candidate with none is tried in full only when no other gives a hit, and then the other
//!    placeable targets of every candidate (at most `FALLBACK_ATTEMPTS` shooting solves). With
//!    still no feasible hit, the last resort ([`ReturnPlanner::last_resort_offsets`]) searches
//!    again with the ball 40–70 mm off the racket's centre.
//! 2. **Outgoing velocity** (`shoot.rs`). Shooting: the velocity v₀ with which the ball, spinning with its
//!    post-impact spin, is at (x_t, y_t, r) after the return flight time T: Broyden's method on the
//!    3×3 map v₀ ↦ p(T), started from the drag-free solution with the linearised flight's
//!    Jacobian T·I + (T²/3)·∂a/∂v, on an 8× coarser RK4 step (80 ms; within 1.3e-5 m of the
//!    flight's own) to 0.01 mm; T from `return_times` in order until the flight (the same
//!    integration, guards every 10 ms) clears the net and first touches the table at the target
//!    (within 1 mm). The post-impact spin depends on the racket, which depends on v₀: every
//!    evaluation of the map solves the racket for its v₀ and flies the ball with that spin.
//! 3. **Racket.** [`super::impact::RacketImpact::solve`] gives the face normal and the racket velocity
//!    (along the normal); the racket centre is the ball centre minus r·n (the ball touches the face
//!    centre; only when that has no IK, `contact_offset` across the table in the face plane); the racket frame has its z axis on the face normal and its x axis (the handle) as
//!    close to world up as possible (the convention of `python/ttmanip/pipeline.py`).
//! 4. **Robot** (`robot.rs`). The pose (for each racket roll of `rolls` about the normal) and twist go to the
//!    base frame ([`Placement`]) as a [`crate::hit::Hit`], handed to the one robot-side planner
//!    ([`crate::hit::HitPlanner::best_leg`]): analytic IK (every branch within the limits), q̇ = J⁻¹·V, and the
//!    hit leg from the stroke's start state at `now` to (q, q̇, q̈) at the hit ([`crate::hit::leg`]): a
//!    quintic when its exact velocity, acceleration and jerk peaks are within the limits, else the
//!    jerk-limited (Ruckig) leg that reaches the hit state exactly at the hit time inside the
//!    position limits. Jerk limits: the robot files carry none, so
//!    [`crate::hit::DEFAULT_JERK_PER_ACCELERATION`] × the acceleration limits, as `plan_hit` uses.
//!    With the robot planner's `check_effort` (the default) the leg's torques (inverse dynamics
//!    with friction, the robot's gravity [`crate::hit::HitOptions::gravity`]) must also stay within the effective effort limits ([`crate::effort`]) at every
//!    instant, certified by [`crate::dynamics::peak`], checked last and only for a leg that
//!    would replace the best so far. A leg beyond the torque is replaced by a gentler jerk-limited
//!    leg to the same hit state ([`crate::hit::leg::scaled_jerk_leg`], up to three, each checked
//!    the same way) before the hit state is given up.
//!    The follow-through after the hit back to rest at the ready configuration is checked against
//!    the same limits (certified effort included; [`crate::hit::HitPlanner::follow_through`]: a
//!    longer or gentler one when the 0.4 s quintic exceeds one) before the hit state is accepted.
//! 5. **Choice.** Among feasible candidates, the one with the largest margin: the smallest of the
//!    joints' normalised distance to their position limits at the hit and the leg's margin
//!    (1 − peak/limit ratio for a quintic, 1 − fastest duration / hit time for a jerk-limited leg). Candidates are tried from the middle of the spread outward and the search
//!    stops at the first with a margin ≥ `good_margin` (0.25), which bounds the planning time.
//!    With a [`PlanBudget`] (a controller deciding before its splice cycle) the search also stops
//!    at the first candidate, shot or racket pose after the budget is spent that has a feasible
//!    hit, with the best so far (an anytime search; without one found it goes on as without a
//!    budget). The off-line rally plans without a budget.
//!
//! [`ReturnPlanner::plan_from`] and the correction [`ReturnPlanner::plan_near`] share the checks,
//! the early exits, the return-time loop and the outcome choice (`search.rs`); they differ only in
//! the order of the candidates and the robot hit tried for each shot.

mod candidates;
mod correct;
mod poses;
mod robot;
mod search;
mod shoot;

use candidates::candidate_order;
use poses::RacketPoses;
pub use search::PlanBudget;
use search::{Begin, Search};
pub use shoot::shoot;

use super::flight::{BallState, Flight};
use super::impact::{RacketAtImpact, RacketImpact};
pub use super::reach::{racket_rotation, Placement, Reach};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::hit::{BranchLeg, HitOptions, HitPlanner};
use crate::ik::LimitFilter;
use crate::traj::limits::KinematicLimits;
use crate::traj::JointState;
use nalgebra::{IsometryMatrix3, Translation3, Vector3};

/// Most shooting solves for the fallback targets of a ball no candidate hit otherwise (24 before
/// issue 28's seventh stop; 60 with `MAX_CANDIDATES` 40 returned 7 more of 906 in-reach balls of
/// seed 0's matched rally, docs/ball.md).
const FALLBACK_ATTEMPTS: usize = 60;

/// Most candidates tried when none of the first `candidates` is feasible (12 before issue 28's
/// seventh stop, docs/ball.md).
const MAX_CANDIDATES: usize = 40;

/// Off-centre contacts (m) of the last resort, [`ReturnPlanner::last_resort_offsets`] (issue 28's
/// ninth stop, docs/ball.md; the racket's face radius is 75 mm).
const LAST_RESORT_OFFSETS: [f64; 4] = [0.04, 0.05, 0.06, 0.07];

/// Most fallback-target solves of each last-resort search ([`ReturnPlanner::last_resort_attempts`]).
const LAST_RESORT_ATTEMPTS: usize = 200;

/// Why a ball got no return, or that it got one: the ball side's outcome. The robot side's
/// statuses are [`crate::hit::HitStatus`]; a ball with hit points but no feasible robot hit is `Infeasible`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReturnStatus {
    /// A feasible hit was planned.
    Ok,
    /// The ball does not bounce on the robot's half and come back up (net, long, wide, floor).
    NoBounce,
    /// The ball never enters the hitting volume after its bounce, or too early for a stroke.
    OutOfReach,
    /// No outgoing flight reaches the target over the net.
    NoReturn,
    /// Every candidate violates the robot's limits (IK, joint velocity or stroke).
    Infeasible,
}

impl ReturnStatus {
    /// Short lower-case name ("ok", "no_bounce", "out_of_reach", "no_return", "infeasible").
    pub fn name(&self) -> &'static str {
        match self {
            ReturnStatus::Ok => "ok",
            ReturnStatus::NoBounce => "no_bounce",
            ReturnStatus::OutOfReach => "out_of_reach",
            ReturnStatus::NoReturn => "no_return",
            ReturnStatus::Infeasible => "infeasible",
        }
    }
}

/// A planned return: the ball and the shot, the [`crate::hit::Hit`] handed to the robot planner,
/// and the robot's branch for it.
#[derive(Debug, Clone, PartialEq)]
pub struct ReturnHit {
    /// Predicted ball state at the impact (world).
    pub ball: BallState,
    /// Outgoing ball velocity (m/s, world) and the racket producing it.
    pub v_out: Vector3<f64>,
    /// Racket normal, velocity and outgoing spin (world).
    pub racket: RacketAtImpact,
    /// The hit (racket pose in the robot's base frame, m; racket-centre twist, base axes; time,
    /// s from `now`): the `ttmanip.Hit` of the plan.
    pub hit: crate::hit::Hit,
    /// The robot's side: hit configuration, joint velocities, the accepted hit leg (what the rally
    /// executes; q̈ at the hit is its `qdd_hit`) and the choice margin in (0, 1] (module doc).
    pub branch: BranchLeg,
    /// Landing point (m, world) of the exactly executed impact and its flight time (s).
    pub landing: Vector3<f64>,
}

impl ReturnHit {
    /// Hit time (s from the plan's `now`).
    pub fn t_hit(&self) -> f64 {
        self.hit.t
    }

    /// The choice margin (module doc), in (0, 1].
    pub fn margin(&self) -> f64 {
        self.branch.margin
    }
}

/// The result of [`ReturnPlanner::plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct ReturnPlan {
    /// Outcome.
    pub status: ReturnStatus,
    /// The hit when `status` is [`ReturnStatus::Ok`].
    pub hit: Option<ReturnHit>,
    /// Candidates examined.
    pub candidates: usize,
    /// The next best feasible hits the search found at other candidates (other hit times), by
    /// decreasing margin, at most [`ALTERNATIVES`]: fallbacks for a caller that plans the hit
    /// again later (a controller's speculation); empty for a plan without a search.
    pub alternatives: Vec<ReturnHit>,
}

/// Most [`ReturnPlan::alternatives`] a search keeps.
pub const ALTERNATIVES: usize = 2;

/// The ball planner of one robot: where and when to hit (placement, hitting volume, ready
/// configuration, racket rubber, the search's settings), over the one robot-side planner.
#[derive(Debug, Clone)]
pub struct ReturnPlanner {
    /// The robot-side planner: chain (base frame as in [`Placement`]), racket mount, analytic IK,
    /// kinematic limits (jerk as in the module doc), dynamics, effort limits and gravity.
    pub robot: HitPlanner,
    /// Base frame in the world.
    pub placement: Placement,
    /// Hitting volume of the ball centre (world) searched for candidates.
    pub reach: Reach,
    /// Ready configuration (m, rad) from which strokes start at rest.
    pub ready: Vec<f64>,
    /// The racket's impact model (rubber restitution, friction, face radius).
    pub impact: RacketImpact,
    /// Flight model used for planning (10 ms RK4 step).
    pub flight: Flight,
    /// Shortest stroke (s) between planning and hitting.
    pub min_stroke_time: f64,
    /// Candidates tried first (evenly spread); all of them (up to `max_candidates`) when none of
    /// these is feasible.
    pub candidates: usize,
    /// Most candidates (evenly spread) tried when none of the first `candidates` is feasible
    /// (`MAX_CANDIDATES`, 40).
    pub max_candidates: usize,
    /// Most shooting solves for the other landing targets of a ball no candidate hit otherwise
    /// (`FALLBACK_ATTEMPTS`, 60).
    pub fallback_attempts: usize,
    /// How far (m) beyond the hitting volume the planner still looks for hits, so that a ball whose
    /// estimate lies just outside the box is still tried (IK decides).
    pub search_margin: f64,
    /// Return flight times (s) tried in order: 0.8 s, then a faster and a slower return (0.55 and
    /// 1.05 s rather than 0.65 and 0.95 s returned 0.2 points more on seeds 0, 1 and 2, docs/ball.md).
    pub return_times: [f64; 3],
    /// A feasible hit with at least this margin ends the search (candidates are tried middle first).
    pub good_margin: f64,
    /// Largest distance (m) of the contact point from the racket centre the planner chooses (only
    /// when the ball on the centre has no IK within the limits); the rally counts a contact within
    /// the racket radius.
    pub contact_offset: f64,
    /// Off-centre contacts (m) along the face plane's direction closest to world up, tried after
    /// the centre and the `contact_offset` ones across the table (0: none; the last resort sets
    /// it, [`Self::last_resort_offsets`]).
    pub contact_offset_up: f64,
    /// The last resort of a plan that finds no feasible hit at all (often: no stroke reaches the
    /// ball's centre in time within the drives' torque): the search again, over the early and
    /// the late candidates, with the ball this far (m) off the racket's centre, each in order until
    /// one gives a hit, across the table and up the face alike, with `last_resort_attempts`
    /// fallback-target solves (empty: no last resort; skipped once a [`PlanBudget`] is spent, so
    /// an online controller's decision keeps its time). A ball that plans without it plans the same.
    pub last_resort_offsets: Vec<f64>,
    /// Most fallback-target shooting solves of each last-resort search (`LAST_RESORT_ATTEMPTS`).
    pub last_resort_attempts: usize,
    /// Rolls (rad) of the racket about its face normal tried in order (0: handle up); the ball
    /// does not see the roll, the joints do.
    pub rolls: Vec<f64>,
    /// Planning budget (an anytime search, [`PlanBudget`]); `None` (the default): every plan
    /// searches to its end, as the off-line rally does.
    pub budget: Option<PlanBudget>,
}

impl ReturnPlanner {
    /// The planner for `chain` (an analytic-IK gantry6 structure) with defaults: the robot planner
    /// of `chain` with default options (effort checked, the robot's gravity), placement and reach
    /// of gantry6, ready configuration = IK of a forward-facing racket at (−1.85, 0, 0.255) m (world).
    pub fn new(chain: Chain, flight: Flight) -> Result<Self> {
        let robot = HitPlanner::new(&chain, HitOptions::default())?;
        if robot.analytic().is_none() {
            return Err(Error::Model(format!(
                "robot '{}': the ball planner needs a chain with analytic IK (a gantry6 structure: \
                 every IK branch of a racket pose); this chain has none",
                chain.name()
            )));
        }
        let mut planner = ReturnPlanner {
            ready: vec![0.0; chain.dof()],
            robot,
            placement: Placement::default(),
            reach: Reach::default(),
            impact: RacketImpact::default(),
            flight: Flight { step: 0.01, ..flight },
            min_stroke_time: 0.12,
            candidates: 3,
            max_candidates: MAX_CANDIDATES,
            fallback_attempts: FALLBACK_ATTEMPTS,
            search_margin: 0.03,
            return_times: [0.8, 0.55, 1.05],
            good_margin: 0.25,
            contact_offset: 0.03,
            contact_offset_up: 0.0,
            last_resort_offsets: LAST_RESORT_OFFSETS.to_vec(),
            last_resort_attempts: LAST_RESORT_ATTEMPTS,
            rolls: [0.0, 30.0, -30.0].iter().map(|d: &f64| d.to_radians()).collect(),
            budget: None,
        };
        // Ready: racket facing forward 0.48 m behind the end line, across the table's centre line,
        // at mid-height of the band, so that a stroke accelerates forward into the hit.
        let centre = Vector3::new(-1.85, 0.0, 0.5 * (planner.reach.lo.z + planner.reach.hi.z));
        let pose = planner
            .robot
            .mount()
            .tool_pose(&planner.base_pose(&centre, &Vector3::x()));
        let ik = planner.robot.analytic().expect("checked above");
        planner.ready = ik.nearest(&pose, &planner.ready, LimitFilter::Enforce).map_err(|e| {
            Error::Model(format!(
                "robot '{}': the ball planner's ready racket pose (facing +x at ({:.3}, {:.3}, {:.3}) m, \
                 world, from the rally's placement) has no IK within the joint limits ({e}); the ball \
                 planner needs a robot that reaches it (gantry6)",
                chain.name(),
                centre.x,
                centre.y,
                centre.z
            ))
        })?;
        Ok(planner)
    }

    /// The robot's chain.
    pub fn chain(&self) -> &Chain {
        self.robot.chain()
    }

    /// Kinematic limits of the strokes (joint order of the chain; jerk as in the module doc).
    pub fn limits(&self) -> &KinematicLimits {
        self.robot.limits()
    }

    /// Racket pose in the base frame for a racket centre `c` and face normal `n` (world), handle
    /// as close to world up as possible.
    pub fn base_pose(&self, c: &Vector3<f64>, n: &Vector3<f64>) -> IsometryMatrix3<f64> {
        self.base_pose_rolled(c, n, 0.0)
    }

    /// [`ReturnPlanner::base_pose`] with the racket turned by `roll` (rad) about its normal.
    pub fn base_pose_rolled(&self, c: &Vector3<f64>, n: &Vector3<f64>, roll: f64) -> IsometryMatrix3<f64> {
        let world = IsometryMatrix3::from_parts(Translation3::from(*c), racket_rotation(n, roll));
        self.placement.world_from_base().inverse() * world
    }

    /// Checks that `target` (x, y in m, world) lies on the opponent's half, a ball radius inside.
    pub fn check_target(&self, target: [f64; 2]) -> Result<()> {
        let t = &self.flight.table;
        let r = self.flight.model.radius;
        let ok = target[0].is_finite()
            && target[1].is_finite()
            && target[0] > r
            && target[0] < t.half_length() - r
            && target[1].abs() < t.half_width() - r;
        if ok {
            Ok(())
        } else {
            Err(Error::invalid(
                "target",
                format!(
                    "({}, {}) m is off the opponent's half: need {r} < x < {} and |y| < {} (world frame)",
                    target[0],
                    target[1],
                    t.half_length() - r,
                    t.half_width() - r
                ),
            ))
        }
    }

    /// Plans the hit of the ball `ball` (state at time `ball.t`, s) for a stroke starting at rest
    /// at the ready configuration at time `now` (s), returning the ball to `target` (x, y, m, world).
    pub fn plan(&self, ball: &BallState, now: f64, target: [f64; 2]) -> Result<ReturnPlan> {
        self.plan_from(ball, now, target, &JointState::rest(&self.ready), false)
    }

    /// [`ReturnPlanner::plan`] for a stroke starting from the joint state `start` at `now` (re-planning
    /// during a stroke with a newer estimate); `after_bounce` says that `ball` is already past its
    /// bounce on the robot's half (an estimate from observations after it).
    pub fn plan_from(
        &self,
        ball: &BallState,
        now: f64,
        target: [f64; 2],
        start: &JointState,
        after_bounce: bool,
    ) -> Result<ReturnPlan> {
        let (list, mut search) = match self.begin(ball, now, target, start, after_bounce)? {
            Begin::Done(plan) => return Ok(plan),
            Begin::Search(list, search) => (list, search),
        };
        self.search_list(&list, now, target, start, &mut search);
        let mut late = Vec::new();
        if search.best.is_none() && !after_bounce {
            // No early hit is feasible (often: no stroke that fast within the drives' torque):
            // the later candidates the early ones had cut (issue 28).
            late = self.late_candidate_states(&self.flight, ball, now, self.search_margin);
            if !late.is_empty() {
                self.search_list(&late, now, target, start, &mut search);
            }
        }
        if search.best.is_none() {
            self.last_resort(&[&list, &late], now, target, start, &mut search);
        }
        Ok(search.finish())
    }

    /// The last resort of a plan with no feasible hit ([`Self::last_resort_offsets`]): the
    /// candidate lists `lists` searched again with the ball further off the racket's centre, the
    /// smallest offset first, until a hit is found; not at all, or no further, once a budget
    /// ([`PlanBudget`]) is spent.
    fn last_resort(&self, lists: &[&[BallState]], now: f64, target: [f64; 2], start: &JointState, search: &mut Search) {
        for &offset in &self.last_resort_offsets {
            // Only within the budget: a controller past its deadline keeps its decision's time.
            if search.best.is_some() || search.deadline.passed() {
                return;
            }
            let wide = ReturnPlanner {
                contact_offset: offset.max(self.contact_offset),
                contact_offset_up: offset,
                fallback_attempts: self.last_resort_attempts,
                last_resort_offsets: Vec::new(),
                ..self.clone()
            };
            for list in lists.iter().filter(|l| !l.is_empty()) {
                if search.best.is_some() || search.deadline.passed() {
                    return;
                }
                wide.search_list(list, now, target, start, search);
            }
        }
    }

    /// The search of [`Self::plan_from`] over the candidate states `list` into `search`.
    fn search_list(&self, list: &[BallState], now: f64, target: [f64; 2], start: &JointState, search: &mut Search) {
        let order = candidate_order(list.len(), self.candidates.max(1), self.max_candidates);
        let first = self.candidates.max(1).min(list.len());
        let targets = self.targets(target);
        // Candidates that fail the cheap placement test for every target are skipped, and tried
        // in full (requested target) only when no other candidate gives a hit (the test's normal
        // is approximate).
        let mut skipped: Vec<usize> = Vec::new();
        // The target tried first for each candidate examined, in `order`.
        let mut first_goal: Vec<Option<[f64; 2]>> = Vec::new();
        // The placement test of (candidate, target), each computed once (the fallback asks again).
        let nt = targets.len();
        let mut placeable_memo: Vec<Option<bool>> = vec![None; list.len() * nt];
        let poses = RacketPoses::new(self);
        let mut placeable = |i: usize, t: usize| -> bool {
            *placeable_memo[i * nt + t].get_or_insert_with(|| self.roughly_placeable(&poses, &list[i], targets[t]))
        };
        let deadline = search.deadline;
        let robot = |s: &BallState, shot: search::Shot| self.robot_hit(&poses, s, now, start, shot, deadline);
        for (rank, &i) in order.iter().enumerate() {
            // More than the first `candidates` only when none of those is feasible.
            if rank == first && search.best.is_some() {
                break;
            }
            if search.good() {
                break;
            }
            let Some(goal) = (0..nt).find(|&t| placeable(i, t)).map(|t| targets[t]) else {
                skipped.push(i);
                first_goal.push(None);
                continue;
            };
            first_goal.push(Some(goal));
            search.attempt(self, &list[i], goal, &robot);
        }
        for &i in &skipped {
            if search.best.is_some() || search.deadline.abandoned() {
                break;
            }
            search.attempt(self, &list[i], target, &robot);
        }
        // Still nothing: the other placeable targets of each candidate (another face normal, other
        // joint positions and velocities at the hit), at most `FALLBACK_ATTEMPTS` shooting solves.
        let mut budget = self.fallback_attempts;
        'fallback: for (&i, &tried_goal) in order.iter().zip(&first_goal) {
            if search.best.is_some() || search.deadline.abandoned() {
                break;
            }
            for (t, &goal) in targets.iter().enumerate().filter(|(_, g)| Some(**g) != tried_goal) {
                if budget == 0 || search.best.is_some() {
                    break 'fallback;
                }
                if placeable(i, t) {
                    budget -= 1;
                    search.attempt(self, &list[i], goal, &robot);
                }
            }
        }
    }
}
