//! Hit planning: where, when and how the robot hits the predicted ball so that it lands on a
//! target on the opponent's half.
//!
//! 1. **Candidates** (`candidates.rs`). The ball is predicted from its state (through its
//!    bounce on the robot's half, and on through a net contact within `NET_CLIP` = 2 cm of
//!    clearing the net, the estimate's uncertainty) and every 10 ms sample inside the hitting volume ([`Reach`],
//!    world frame; the same volume as the reachable region of [`super::reach`]), after the bounce
//!    and at least `min_stroke_time` after `now`, is a candidate; `candidates` of them, evenly
//!    spread, are tried (up to 12 when none of those is feasible). Each aims at the requested
//!    target or, when no racket with the approximate normal toward it has IK (see
//!    `roughly_placeable`), at the nearest fallback target on the opponent's half that has one; a
//!    candidate with none is tried in full only when no other gives a hit, and then the other
//!    placeable targets of every candidate (at most `FALLBACK_ATTEMPTS` shooting solves). The
//!    candidates later than `LATEST_AFTER_BOUNCE` after the bounce, cut when earlier ones exist,
//!    are searched the same way only when none of the early ones gives a feasible hit (issue 28:
//!    a later hit leaves the stroke more time, so less torque).
//! 2. **Outgoing velocity** (`shoot.rs`). Shooting: the velocity v₀ with which the ball, spinning with its
//!    post-impact spin, is at (x_t, y_t, r) after the return flight time T: Broyden's method on the
//!    3×3 map v₀ ↦ p(T), started from the drag-free solution with the linearised flight's
//!    Jacobian T·I + (T²/3)·∂a/∂v, on an 8× coarser RK4 step (80 ms; within 1.3e-5 m of the
//!    flight's own) to 0.01 mm; T from `return_times` in order until the flight (the same
//!    integration, guards every 10 ms) clears the net and first touches the table at the target
//!    (within 1 mm). The post-impact spin depends on the racket, which depends on v₀: every
//!    evaluation of the map solves the racket for its v₀ and flies the ball with that spin.
//! 3. **Racket.** [`super::impact::Racket::solve`] gives the face normal and the racket velocity
//!    (along the normal); the racket centre is the ball centre minus r·n (the ball touches the face
//!    centre; only when that has no IK, `contact_offset` across the table in the face plane); the racket frame has its z axis on the face normal and its x axis (the handle) as
//!    close to world up as possible (the convention of `python/ttmanip/pipeline.py`).
//! 4. **Robot** (`robot.rs`). The pose (for each racket roll of `rolls` about the normal) and twist go to the
//!    base frame ([`Placement`]), analytic IK (every branch within the limits), q̇ = J⁻¹·V, and the
//!    hit leg from the stroke's start state at `now` to (q, q̇, q̈) at the hit ([`super::leg`]): a
//!    quintic when its exact velocity, acceleration and jerk peaks are within the limits, else the
//!    jerk-limited (Ruckig) leg that reaches the hit state exactly at the hit time inside the
//!    position limits. Jerk limits: the robot files carry none, so
//!    [`crate::hit::DEFAULT_JERK_PER_ACCELERATION`] × the acceleration limits, as `plan_hit` uses.
//!    With `check_effort` (the default) the leg's torques (inverse dynamics with friction, world
//!    gravity) must also stay within the effective effort limits ([`crate::effort`]) at every
//!    instant, certified by [`crate::dynamics::peak`], checked last and only for a leg that
//!    would replace the best so far.
//! 5. **Choice.** Among feasible candidates, the one with the largest margin: the smallest of the
//!    joints' normalised distance to their position limits at the hit and the leg's margin
//!    (1 − peak/limit ratio for a quintic, 1 − fastest duration / hit time for a jerk-limited leg). Candidates are tried from the middle of the spread outward and the search
//!    stops at the first with a margin ≥ `good_margin` (0.25), which bounds the planning time.

mod candidates;
use crate::dynamics::Dynamics;
use crate::effort::EffortLimits;
use candidates::candidate_order;
mod correct;
mod poses;
use poses::RacketPoses;
mod robot;
mod shoot;

pub use shoot::shoot;

use super::flight::{BallState, Flight};
use super::impact::{Racket, RacketHit};
use super::leg::HitLeg;
pub use super::reach::{racket_rotation, Placement, Reach};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::ik::{Analytic, LimitFilter};
use crate::traj::limits::KinematicLimits;
use crate::traj::JointState;
use nalgebra::{IsometryMatrix3, Translation3, Vector3};

/// Most shooting solves for the fallback targets of a ball no candidate hit otherwise.
const FALLBACK_ATTEMPTS: usize = 24;

/// Why a ball got no hit, or that it got one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HitStatus {
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

impl HitStatus {
    /// Short lower-case name ("ok", "no_bounce", "out_of_reach", "no_return", "infeasible").
    pub fn name(&self) -> &'static str {
        match self {
            HitStatus::Ok => "ok",
            HitStatus::NoBounce => "no_bounce",
            HitStatus::OutOfReach => "out_of_reach",
            HitStatus::NoReturn => "no_return",
            HitStatus::Infeasible => "infeasible",
        }
    }
}

/// A planned hit: what the racket must do, and what the robot must do for it.
#[derive(Debug, Clone, PartialEq)]
pub struct Hit {
    /// Predicted ball state at the impact (world).
    pub ball: BallState,
    /// Outgoing ball velocity (m/s, world) and the racket producing it.
    pub v_out: Vector3<f64>,
    /// Racket normal, velocity and outgoing spin (world).
    pub racket: RacketHit,
    /// Racket pose (racket frame in the robot base frame, m): the `pose` of `ttmanip.Hit`.
    pub pose: IsometryMatrix3<f64>,
    /// Racket twist [v; ω] (m/s, rad/s, base axes): the `twist` of `ttmanip.Hit`.
    pub twist: [f64; 6],
    /// Hit time (s from `now`): the `t` of `ttmanip.Hit`.
    pub t_hit: f64,
    /// Joint configuration (m, rad) and velocities at the hit.
    pub q_hit: Vec<f64>,
    /// Joint velocities (m/s, rad/s) at the hit.
    pub qd_hit: Vec<f64>,
    /// Joint accelerations (m/s², rad/s²) at the hit chosen for the stroke (see [`super::leg`]).
    pub qdd_hit: Vec<f64>,
    /// The accepted hit leg (its profile and trajectory from the stroke start at `now` to the hit):
    /// what the rally executes.
    pub leg: HitLeg,
    /// Choice margin (see the module doc), in (0, 1].
    pub margin: f64,
    /// Landing point (m, world) of the exactly executed impact and its flight time (s).
    pub landing: Vector3<f64>,
}

/// The result of [`HitPlanner::plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct HitPlan {
    /// Outcome.
    pub status: HitStatus,
    /// The hit when `status` is [`HitStatus::Ok`].
    pub hit: Option<Hit>,
    /// Candidates examined.
    pub candidates: usize,
}

/// The hit planner of one robot: its chain, placement, hitting volume, ready configuration and racket.
#[derive(Debug, Clone)]
pub struct HitPlanner {
    /// Robot chain (base frame as in [`Placement`]; tool frame = racket frame).
    pub chain: Chain,
    ik: Analytic,
    limits: KinematicLimits,
    /// Base frame in the world.
    pub placement: Placement,
    /// Hitting volume of the ball centre (world) searched for candidates.
    pub reach: Reach,
    /// Ready configuration (m, rad) from which strokes start at rest.
    pub ready: Vec<f64>,
    /// Racket rubber.
    pub racket: Racket,
    /// Flight model used for planning (10 ms RK4 step).
    pub flight: Flight,
    /// Shortest stroke (s) between planning and hitting.
    pub min_stroke_time: f64,
    /// Candidates tried first (evenly spread); all of them (up to 12) when none of these is feasible.
    pub candidates: usize,
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
    /// Rolls (rad) of the racket about its face normal tried in order (0: handle up); the ball
    /// does not see the roll, the joints do.
    pub rolls: Vec<f64>,
    /// Check the hit leg's torques against the effective effort limits at every instant (on by
    /// default; without inertials there is no dynamics and no check).
    pub check_effort: bool,
    dynamics: Option<Dynamics>,
    effort: EffortLimits,
}

impl HitPlanner {
    /// The planner for `chain` (an analytic-IK gantry6 structure) with defaults: placement and reach
    /// of gantry6, ready configuration = IK of a forward-facing racket at (−1.85, 0, 0.255) m (world).
    pub fn new(chain: Chain, flight: Flight) -> Result<Self> {
        let ik = Analytic::for_chain(&chain)
            .ok_or_else(|| Error::Model("hit planning needs a chain with analytic IK (gantry6)".into()))?;
        // Robot files carry no jerk limits: the same default as `plan_hit` (infinite when an
        // acceleration limit is, and then no jerk-limited leg).
        let jerk: Vec<f64> = chain
            .limits()
            .iter()
            .map(|l| l.acceleration.unwrap_or(f64::INFINITY) * crate::hit::DEFAULT_JERK_PER_ACCELERATION)
            .collect();
        let limits = KinematicLimits::from_chain(&chain, Some(&jerk))?;
        let (dynamics, effort) = (Dynamics::new(&chain).ok(), EffortLimits::of(&chain));
        let mut planner = HitPlanner {
            ready: vec![0.0; chain.dof()],
            chain,
            ik,
            limits,
            placement: Placement::default(),
            reach: Reach::default(),
            racket: Racket::default(),
            flight: Flight { step: 0.01, ..flight },
            min_stroke_time: 0.12,
            candidates: 3,
            search_margin: 0.03,
            return_times: [0.8, 0.55, 1.05],
            good_margin: 0.25,
            contact_offset: 0.03,
            rolls: [0.0, 30.0, -30.0].iter().map(|d: &f64| d.to_radians()).collect(),
            check_effort: true,
            dynamics,
            effort,
        };
        // Ready: racket facing forward 0.48 m behind the end line, across the table's centre line,
        // at mid-height of the band, so that a stroke accelerates forward into the hit.
        let centre = Vector3::new(-1.85, 0.0, 0.5 * (planner.reach.lo.z + planner.reach.hi.z));
        let pose = planner.base_pose(&centre, &Vector3::x());
        planner.ready = planner.ik.nearest(&pose, &planner.ready, LimitFilter::Enforce)?;
        Ok(planner)
    }

    /// Racket pose in the base frame for a racket centre `c` and face normal `n` (world), handle
    /// as close to world up as possible.
    pub fn base_pose(&self, c: &Vector3<f64>, n: &Vector3<f64>) -> IsometryMatrix3<f64> {
        self.base_pose_rolled(c, n, 0.0)
    }

    /// [`HitPlanner::base_pose`] with the racket turned by `roll` (rad) about its normal.
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
    pub fn plan(&self, ball: &BallState, now: f64, target: [f64; 2]) -> Result<HitPlan> {
        self.plan_from(ball, now, target, &JointState::rest(&self.ready), false)
    }

    /// Checks a re-plan's inputs: `start` a joint state of this robot, `ball` a valid ball state.
    pub(super) fn check_start(&self, ball: &BallState, start: &JointState) -> Result<()> {
        if start.check("start")? != self.chain.dof() {
            return Err(Error::shape(
                "start.q",
                format!("{} values", self.chain.dof()),
                start.q.len(),
            ));
        }
        ball.validate("ball")?;
        Ok(())
    }

    /// [`HitPlanner::plan`] for a stroke starting from the joint state `start` at `now` (re-planning
    /// during a stroke with a newer estimate); `after_bounce` says that `ball` is already past its
    /// bounce on the robot's half (an estimate from observations after it).
    pub fn plan_from(
        &self,
        ball: &BallState,
        now: f64,
        target: [f64; 2],
        start: &JointState,
        after_bounce: bool,
    ) -> Result<HitPlan> {
        self.check_target(target)?;
        self.check_start(ball, start)?;
        if !now.is_finite() {
            return Err(Error::NonFinite {
                what: "now".into(),
                index: 0,
                value: now,
            });
        }
        self.flight.check_span("now", ball, now)?;
        let (list, bounced) = self.candidate_states(&self.flight, ball, now, self.search_margin, after_bounce);
        if !bounced {
            return Ok(HitPlan {
                status: HitStatus::NoBounce,
                hit: None,
                candidates: 0,
            });
        }
        if list.is_empty() {
            return Ok(HitPlan {
                status: HitStatus::OutOfReach,
                hit: None,
                candidates: 0,
            });
        }
        let (mut best, mut any_return, mut tried) = (None, false, 0);
        self.search(&list, now, target, start, &mut best, &mut any_return, &mut tried);
        if best.is_none() && !after_bounce {
            // No early hit is feasible (often: no stroke that fast within the drives' torque):
            // the later candidates the early ones had cut.
            let late = self.late_candidate_states(&self.flight, ball, now, self.search_margin);
            if !late.is_empty() {
                self.search(&late, now, target, start, &mut best, &mut any_return, &mut tried);
            }
        }
        Ok(searched(best, any_return, tried))
    }

    /// The search of [`Self::plan_from`] over the candidate states `list`: the best hit into
    /// `best`, whether some shot returned the ball into `any_return`, candidates tried added to
    /// `tried`.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        list: &[BallState],
        now: f64,
        target: [f64; 2],
        start: &JointState,
        best: &mut Option<Hit>,
        any_return: &mut bool,
        tried: &mut usize,
    ) {
        let order = candidate_order(list.len(), self.candidates.max(1));
        let first = self.candidates.max(1).min(list.len());
        let targets = self.targets(target);
        let poses = RacketPoses::new(self);
        // Candidates that fail the cheap placement test for every target are skipped, and tried
        // in full (requested target) only when no other candidate gives a hit (the test's normal
        // is approximate).
        let mut skipped: Vec<usize> = Vec::new();
        // The target tried first for each candidate examined, in `order`.
        let mut first_goal: Vec<Option<[f64; 2]>> = Vec::new();
        // The placement test of (candidate, target), each computed once (the fallback asks again).
        let nt = targets.len();
        let mut placeable_memo: Vec<Option<bool>> = vec![None; list.len() * nt];
        let mut placeable = |i: usize, t: usize| -> bool {
            *placeable_memo[i * nt + t].get_or_insert_with(|| self.roughly_placeable(&poses, &list[i], targets[t]))
        };
        let mut attempt = |s: &BallState, goal: [f64; 2], best: &mut Option<Hit>| {
            *tried += 1;
            for &tf in &self.return_times {
                let Some((v_out, racket, landing)) = self.outgoing(s, goal, tf) else {
                    continue;
                };
                *any_return = true;
                if let Some(hit) = self.robot_hit(&poses, s, now, start, v_out, racket, landing) {
                    if best.as_ref().is_none_or(|b| hit.margin > b.margin) {
                        *best = Some(hit);
                    }
                    break;
                }
            }
        };
        for (rank, &i) in order.iter().enumerate() {
            // More than the first `candidates` only when none of those is feasible.
            if rank == first && best.is_some() {
                break;
            }
            if best.as_ref().is_some_and(|b| b.margin >= self.good_margin) {
                break;
            }
            let s = list[i];
            let Some(goal) = (0..nt).find(|&t| placeable(i, t)).map(|t| targets[t]) else {
                skipped.push(i);
                first_goal.push(None);
                continue;
            };
            first_goal.push(Some(goal));
            attempt(&s, goal, best);
        }
        if best.is_none() {
            for &i in &skipped {
                if best.is_some() {
                    break;
                }
                attempt(&list[i], target, best);
            }
        }
        // Still nothing: the other placeable targets of each candidate (another face normal, other
        // joint positions and velocities at the hit), at most `FALLBACK_ATTEMPTS` shooting solves.
        let mut budget = FALLBACK_ATTEMPTS;
        'fallback: for (&i, &tried_goal) in order.iter().zip(&first_goal) {
            if best.is_some() {
                break;
            }
            let s = list[i];
            for (t, &goal) in targets.iter().enumerate().filter(|(_, g)| Some(**g) != tried_goal) {
                if budget == 0 || best.is_some() {
                    break 'fallback;
                }
                if placeable(i, t) {
                    budget -= 1;
                    attempt(&s, goal, best);
                }
            }
        }
    }

    /// Kinematic limits of the strokes (joint order of the chain; jerk as in the module doc).
    pub fn limits(&self) -> &KinematicLimits {
        &self.limits
    }
}

/// The plan a search ends with: its best hit (`Ok`), or `Infeasible` when some shot returned the
/// ball but no hit was feasible, else `NoReturn`; `tried` candidates.
pub(super) fn searched(best: Option<Hit>, any_return: bool, tried: usize) -> HitPlan {
    let status = match (&best, any_return) {
        (Some(_), _) => HitStatus::Ok,
        (None, true) => HitStatus::Infeasible,
        (None, false) => HitStatus::NoReturn,
    };
    HitPlan {
        status,
        hit: best,
        candidates: tried,
    }
}
