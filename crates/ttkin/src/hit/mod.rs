//! The hit pipeline of seed 002 (the gantry patent), for any chain: hit parameters → IK →
//! joint velocities → hitting stroke → inverse-dynamics torques, every limit checked.
//!
//! A [`Hit`] is the racket pose (racket frame of [`racket`] in the base frame, m), the twist of
//! the racket centre [v; ω] (base axes, m/s, rad/s) and the hit time (s from now). A
//! [`HitPlanner`] (immutable: chain, dynamics, limits, options) turns a hit and the current joint
//! state into a [`HitPlan`]:
//! 1. IK with the branch nearest the current state within the position limits (the analytic
//!    gantry solver when the chain has one, numeric IK otherwise); for a redundant chain (or
//!    [`HitTask::Racket5`]) seed 000's 5-D racket task (centre and face normal; the rotation about
//!    the normal is free), reached by the weighted least-norm tracker [`crate::clik`] along a line
//!    in task coordinates;
//! 2. joint velocities q̇ = J⁻¹V (square chain; the damped inverse flags singular hits), or the
//!    Chan–Dubey weighted least-norm solution of the 5-D task velocity (redundant chain);
//! 3. the stroke: current state → (q, q̇, q̈ = 0) at the hit time → rest at the ready pose, a
//!    quintic or a jerk-limited time-optimal trajectory ([`crate::traj::jerk`]), whichever meets
//!    the hit time within the limits ([`StrokeProfile::Auto`]);
//! 4. torques by inverse dynamics with joint friction (the drives' feed-forward) against the
//!    effective effort limits ([`crate::effort`]: the robot file's or the drive's, whichever is
//!    smaller, falling with speed where the drive's bus voltage limits it) at every instant: a
//!    certified bound of the peak, not check points ([`crate::dynamics::peak`]).
//!
//! Infeasible requests give a [`HitStatus`], not an error: too early (the plan is made for the
//! earliest feasible hit time, [`HitPlan::earliest_t_hit`]), unreachable, singular, a hit speed
//! beyond a joint's speed limit, a stroke leaving the position limits, or an effort limit no hit
//! time can meet. Errors are for bad input only (shapes, NaN, non-positive times).

pub mod racket;
mod solve;
mod stroke;

use nalgebra::{IsometryMatrix3, Vector3};
use rayon::prelude::*;

use crate::chain::Chain;
use crate::dynamics::{Dynamics, DynamicsData};
use crate::effort::EffortLimits;
use crate::error::{check_finite, check_vector, Error, Result};
use crate::ik::Analytic;
use crate::traj::limits::{KinematicLimits, Violation};
use crate::traj::{JointState, JointTrajectory};
pub use racket::{racket_axes, racket_frame, racket_state_batch, Racket, DEFAULT_HANDLE, RACKET_STATE_LEN};

/// Standard gravity (m/s², base frame: base z up).
pub const GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// Default jerk limit as a multiple of the acceleration limit (1/s): full acceleration is built up
/// in 5 ms (a servo drive's current loop settles in about 1 ms). Robot files carry no jerk limits.
pub const DEFAULT_JERK_PER_ACCELERATION: f64 = 200.0;

/// Hit parameters: where the racket is, how it moves, and when.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hit {
    /// Racket pose at the hit: racket frame (origin at the centre, z = face normal) in the base
    /// frame (m).
    pub pose: IsometryMatrix3<f64>,
    /// Racket-centre twist at the hit [v (m/s); ω (rad/s)], base axes.
    pub twist: [f64; 6],
    /// Hit time (s from now, > 0).
    pub t: f64,
}

impl Hit {
    /// A hit from its racket pose (base frame, m), racket-centre twist (base axes, m/s, rad/s) and
    /// hit time (s from now); checks finiteness and 0 < t ≤ [`crate::traj::duration::MAX_DURATION`].
    pub fn new(pose: IsometryMatrix3<f64>, twist: [f64; 6], t: f64) -> Result<Hit> {
        check_finite("twist", &twist)?;
        check_finite("pose", pose.translation.vector.as_slice())?;
        check_finite("pose", pose.rotation.matrix().as_slice())?;
        crate::traj::check_duration("t", t)?;
        let max = crate::traj::duration::MAX_DURATION;
        if t > max {
            // A later hit cannot be planned (no stroke is longer); refused here, not as an effort
            // limit with an infinite ratio or a sample count of the stroke.
            return Err(crate::Error::invalid(
                "t",
                format!("the hit time must be at most {max} s from now (the longest stroke), got {t} s"),
            ));
        }
        Ok(Hit { pose, twist, t })
    }

    /// A hit from the racket centre (m, base frame), the face normal (any length, base axes), the
    /// racket-centre velocity (m/s, base axes), the hit time (s) and the racket's angular velocity
    /// (rad/s, base axes, zero when `None`). The handle points as close as possible to `handle`
    /// ([`DEFAULT_HANDLE`] when `None`): see [`racket_frame`].
    pub fn from_normal(
        centre: [f64; 3],
        normal: [f64; 3],
        velocity: [f64; 3],
        t: f64,
        omega: Option<[f64; 3]>,
        handle: Option<[f64; 3]>,
    ) -> Result<Hit> {
        check_finite("centre", &centre)?;
        check_finite("velocity", &velocity)?;
        let w = omega.unwrap_or([0.0; 3]);
        check_finite("omega", &w)?;
        let r = racket_frame(&Vector3::from(normal), &Vector3::from(handle.unwrap_or(DEFAULT_HANDLE)))?;
        let pose = IsometryMatrix3::from_parts(Vector3::from(centre).into(), r);
        Hit::new(pose, [velocity[0], velocity[1], velocity[2], w[0], w[1], w[2]], t)
    }

    /// Racket centre (m, base frame).
    pub fn centre(&self) -> Vector3<f64> {
        self.pose.translation.vector
    }

    /// Unit face normal (base axes): the racket frame's z axis.
    pub fn normal(&self) -> Vector3<f64> {
        self.pose.rotation.matrix().column(2).into_owned()
    }
}

/// The family of the hit leg of a stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StrokeProfile {
    /// The quintic when it meets the hit time within the limits, else the jerk-limited stroke.
    Auto,
    /// The patent's quintic (S104); a late hit time is the earliest feasible quintic duration.
    Quintic,
    /// Jerk-limited, time-optimal up to the hit time ([`crate::traj::jerk`]).
    Jerk,
}

impl StrokeProfile {
    /// Parses `"auto"`, `"quintic"` or `"jerk"`.
    pub fn from_name(name: &str) -> Result<StrokeProfile> {
        match name {
            "auto" => Ok(StrokeProfile::Auto),
            "quintic" => Ok(StrokeProfile::Quintic),
            "jerk" | "ruckig" => Ok(StrokeProfile::Jerk),
            other => Err(Error::invalid(
                "profile",
                format!("unknown stroke profile '{other}'; choose 'auto', 'quintic' or 'jerk'"),
            )),
        }
    }

    /// The name `from_name` parses.
    pub fn name(&self) -> &'static str {
        match self {
            StrokeProfile::Auto => "auto",
            StrokeProfile::Quintic => "quintic",
            StrokeProfile::Jerk => "jerk",
        }
    }
}

/// Which part of the racket pose the hit prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum HitTask {
    /// Full pose for a chain of ≤ 6 joints, the 5-D racket task for a redundant chain.
    Auto,
    /// The full 6-D racket pose and twist.
    Pose,
    /// Seed 000's 5-D racket task: centre and face normal (rotation about the normal free), the
    /// centre velocity and the normal's rate.
    Racket5,
}

/// Planner settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HitOptions {
    /// Family of the hit leg.
    pub profile: StrokeProfile,
    /// Which part of the hit the IK must meet.
    pub task: HitTask,
    /// Jerk limits (rad/s³ or m/s³, one per joint); `None` for
    /// [`DEFAULT_JERK_PER_ACCELERATION`] × the acceleration limits.
    pub jerk: Option<Vec<f64>>,
    /// Gravity (m/s², base frame) for the torques.
    pub gravity: [f64; 3],
    /// Check (and retime for) the effort limits by inverse dynamics; off: kinematic limits only.
    pub check_effort: bool,
    /// Tolerance (ratio units) of the reported [`HitPlan::effort_ratio`]: the certified bound of
    /// the peak |τ|/limit is within it of the ratio reported (> 0; the feasibility decision itself
    /// is exact, [`crate::dynamics::peak`]).
    pub effort_tolerance: f64,
    /// Latest hit time (s) the earliest-feasible search tries.
    pub max_t_hit: f64,
}

impl Default for HitOptions {
    /// Auto profile and task, default jerk limits, standard gravity, effort ratio to 1e-4,
    /// search up to 10 s.
    fn default() -> Self {
        HitOptions {
            profile: StrokeProfile::Auto,
            task: HitTask::Auto,
            jerk: None,
            gravity: GRAVITY,
            check_effort: true,
            effort_tolerance: 1e-4,
            max_t_hit: 10.0,
        }
    }
}

/// How a plan came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum HitStatus {
    /// On time and within every limit.
    Ok,
    /// The requested hit time is earlier than feasible: the plan is made for
    /// [`HitPlan::earliest_t_hit`].
    TooEarly,
    /// No configuration within the position limits reaches the racket pose.
    Unreachable,
    /// The hit configuration is singular: the twist cannot be produced.
    Singular,
    /// The hit joint velocity exceeds a speed limit: no hit time can help.
    HitSpeedLimit,
    /// The stroke leaves the position limits.
    PositionLimit,
    /// The torques exceed an effort limit for every hit time up to the search limit.
    EffortLimit,
    /// No stroke within the velocity, acceleration and jerk limits reaches the hit state.
    NoStroke,
}

impl HitStatus {
    /// Short snake-case name (`"ok"`, `"too_early"`, `"unreachable"`, `"singular"`,
    /// `"hit_speed_limit"`, `"position_limit"`, `"effort_limit"`, `"no_stroke"`).
    pub fn name(&self) -> &'static str {
        match self {
            HitStatus::Ok => "ok",
            HitStatus::TooEarly => "too_early",
            HitStatus::Unreachable => "unreachable",
            HitStatus::Singular => "singular",
            HitStatus::HitSpeedLimit => "hit_speed_limit",
            HitStatus::PositionLimit => "position_limit",
            HitStatus::EffortLimit => "effort_limit",
            HitStatus::NoStroke => "no_stroke",
        }
    }
}

/// Every product of planning one hit. Joint values in rad or m, times in s from now.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HitPlan {
    /// The request.
    pub hit: Hit,
    /// Outcome.
    pub status: HitStatus,
    /// One line saying what limited the plan (empty when `Ok`).
    pub message: String,
    /// Joint state the stroke starts from (now).
    pub start: JointState,
    /// Rest configuration the stroke returns to.
    pub ready: Vec<f64>,
    /// Tool pose (base frame, m) that puts the racket at the hit pose.
    pub tool_target: IsometryMatrix3<f64>,
    /// Number of IK branches within the limits (1 for numeric or task IK, 0 when unreachable).
    pub branches: usize,
    /// Hit configuration (NaN when unreachable).
    pub q_hit: Vec<f64>,
    /// Hit joint velocities (NaN when unreachable).
    pub qd_hit: Vec<f64>,
    /// Smallest singular value of the (task) Jacobian at the hit (NaN when unreachable).
    pub sigma_min: f64,
    /// Planned hit time (s); NaN when no stroke was planned.
    pub t_hit: f64,
    /// Earliest feasible hit time (s) when planning found it (a late plan); NaN otherwise: then
    /// [`HitPlanner::earliest_t_hit`] computes it on demand.
    pub earliest_t_hit: f64,
    /// Profile of the hit leg actually used (`Quintic` or `Jerk`); `Auto` when no stroke.
    pub profile: StrokeProfile,
    /// Hit leg then return leg from 0 s (now); `None` when no stroke was planned.
    pub trajectory: Option<JointTrajectory>,
    /// Duration of the return leg (s).
    pub return_duration: f64,
    /// Kinematic limit violations of the trajectory (exact peaks), empty when within limits.
    pub violations: Vec<Violation>,
    /// Largest |joint torque| (N·m or N, with friction) per joint over the stroke (at the instants
    /// the certified peak search evaluated; within the effort tolerance of the true peak for the
    /// joints whose limit does not depend on speed).
    pub peak_effort: Vec<f64>,
    /// Largest |τ(t)|/effective effort limit over joints and the whole stroke, every instant
    /// ([`crate::effort`]: the robot file's limit or the drive's, whichever is smaller at q̇(t)):
    /// a value the stroke takes, within `effort_tolerance` of the certified peak (0 without
    /// dynamics or limits).
    pub effort_ratio: f64,
}

impl HitPlan {
    /// True when the plan is on time and within every limit.
    pub fn ok(&self) -> bool {
        self.status == HitStatus::Ok
    }
}

/// The immutable planning model: chain, dynamics (when every link has an inertial), racket,
/// kinematic and effort limits, options. Plans allocate only their outputs' scratch.
#[derive(Debug, Clone)]
pub struct HitPlanner {
    chain: Chain,
    dynamics: Option<Dynamics>,
    analytic: Option<Analytic>,
    racket: Racket,
    limits: KinematicLimits,
    effort: EffortLimits,
    options: HitOptions,
    ready: Vec<f64>,
}

impl HitPlanner {
    /// A planner for `chain` (its racket from [`Racket::for_chain`]). Errors for options that do
    /// not fit the chain (jerk limits of the wrong length or ≤ 0, fewer than 2 effort points,
    /// missing speed or acceleration limits).
    pub fn new(chain: &Chain, options: HitOptions) -> Result<HitPlanner> {
        let n = chain.dof();
        let lim = chain.limits();
        let mut accel = Vec::with_capacity(n);
        for (j, l) in lim.iter().enumerate() {
            match (l.velocity, l.acceleration) {
                (Some(_), Some(a)) => accel.push(a),
                _ => {
                    return Err(Error::invalid(
                        "robot",
                        format!(
                            "joint '{}' has no speed or acceleration limit; a hit stroke needs both",
                            chain.joints()[j].name()
                        ),
                    ))
                }
            }
        }
        let jerk = match &options.jerk {
            Some(j) => {
                check_vector("jerk", j, n)?;
                j.clone()
            }
            None => accel.iter().map(|a| a * DEFAULT_JERK_PER_ACCELERATION).collect(),
        };
        let limits = KinematicLimits::from_chain(chain, Some(&jerk))?;
        if !(options.effort_tolerance > 0.0 && options.effort_tolerance.is_finite()) {
            return Err(Error::invalid(
                "effort_tolerance",
                format!("need a finite tolerance > 0, got {}", options.effort_tolerance),
            ));
        }
        check_finite("gravity", &options.gravity)?;
        crate::traj::check_duration("max_t_hit", options.max_t_hit)?;
        let effort = EffortLimits::of(chain);
        Ok(HitPlanner {
            chain: chain.clone(),
            dynamics: if options.check_effort {
                Dynamics::new(chain).ok()
            } else {
                None
            },
            analytic: Analytic::for_chain(chain),
            racket: Racket::for_chain(chain),
            limits,
            effort,
            ready: chain.ready(),
            options,
        })
    }

    /// The chain.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The racket mount.
    pub fn racket(&self) -> &Racket {
        &self.racket
    }

    /// Kinematic limits used (position, speed, acceleration, jerk).
    pub fn limits(&self) -> &KinematicLimits {
        &self.limits
    }

    /// Effective effort limits used ([`crate::effort`]).
    pub fn effort_limits(&self) -> &EffortLimits {
        &self.effort
    }

    /// The options.
    pub fn options(&self) -> &HitOptions {
        &self.options
    }

    /// Default rest configuration: the chain's [`Chain::ready`] (gantry6 (0, 0, 0, 0.6, 0.6, 0),
    /// mobile8 seed 000's start; otherwise the middle of each joint's position limits).
    pub fn default_ready(&self) -> &[f64] {
        &self.ready
    }

    /// The earliest feasible hit time (s) of `plan`: its own when planning found it (a
    /// `too_early` plan: planning for that time is accepted); for an `ok` plan the earliest time at
    /// which planning its hit state from its start is accepted, every limit and the certified
    /// effort check included (the kinematic earliest time when that is accepted, else a bisection
    /// to 0.1 % up to the plan's time whose result is always an accepted time; about ten plans of
    /// the stroke). For other plans with a stroke, the earliest time at which the planner's profile
    /// meets the velocity, acceleration and jerk limits (no time meets every limit). NaN when the
    /// plan has no hit state.
    pub fn earliest_t_hit(&self, plan: &HitPlan) -> f64 {
        if plan.earliest_t_hit.is_finite() || plan.trajectory.is_none() {
            return plan.earliest_t_hit;
        }
        let hit = JointState {
            q: plan.q_hit.clone(),
            qd: plan.qd_hit.clone(),
            qdd: vec![0.0; plan.q_hit.len()],
        };
        let Ok(t_kin) = stroke::earliest_kinematic(self, &plan.start, &hit) else {
            return f64::NAN;
        };
        let t_kin = t_kin.min(plan.t_hit);
        if plan.ok() {
            stroke::earliest_accepted(self, plan, t_kin)
        } else {
            t_kin
        }
    }

    /// Plans `hit` from `state` (at rest at `ready` when `None`) back to rest at `ready` (the
    /// start configuration when only `state` is given, [`Self::default_ready`] otherwise).
    pub fn plan(&self, hit: &Hit, state: Option<&JointState>, ready: Option<&[f64]>) -> Result<HitPlan> {
        let mut data = self.dynamics.as_ref().map(DynamicsData::new);
        self.plan_with(hit, state, ready, data.as_mut())
    }

    /// [`Self::plan`] for many hits from the same state, in parallel.
    pub fn plan_batch(&self, hits: &[Hit], state: Option<&JointState>, ready: Option<&[f64]>) -> Result<Vec<HitPlan>> {
        self.plan_batch_until(hits, state, ready, &|| false)
    }

    /// [`HitPlanner::plan_batch`] that stops early when `stop()` turns true (checked before each
    /// hit; a caller's cancellation, e.g. Ctrl-C seen by the Python binding): then an error.
    pub fn plan_batch_until(
        &self,
        hits: &[Hit],
        state: Option<&JointState>,
        ready: Option<&[f64]>,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<Vec<HitPlan>> {
        let (start, ready) = self.start_and_ready(state, ready)?;
        hits.par_iter()
            .map_init(
                || self.dynamics.as_ref().map(DynamicsData::new),
                |data, hit| {
                    if stop() {
                        return Err(crate::Error::invalid("hits", "planning stopped before this hit"));
                    }
                    self.plan_with(hit, Some(&start), Some(&ready), data.as_mut())
                },
            )
            .collect()
    }

    fn start_and_ready(&self, state: Option<&JointState>, ready: Option<&[f64]>) -> Result<(JointState, Vec<f64>)> {
        let n = self.chain.dof();
        let ready = match (ready, state) {
            (Some(r), _) => {
                check_vector("ready", r, n)?;
                r.to_vec()
            }
            (None, Some(s)) => s.q.clone(),
            (None, None) => self.ready.clone(),
        };
        let start = match state {
            Some(s) => {
                if s.check("state")? != n {
                    return Err(Error::shape("state.q", format!("{n} values"), s.q.len()));
                }
                s.clone()
            }
            None => JointState::rest(&ready),
        };
        Ok((start, ready))
    }

    fn plan_with(
        &self,
        hit: &Hit,
        state: Option<&JointState>,
        ready: Option<&[f64]>,
        data: Option<&mut DynamicsData>,
    ) -> Result<HitPlan> {
        let hit = Hit::new(hit.pose, hit.twist, hit.t)?;
        let (start, ready) = self.start_and_ready(state, ready)?;
        let n = self.chain.dof();
        let tool_target = self.racket.tool_pose(&hit.pose);
        let mut plan = HitPlan {
            hit,
            status: HitStatus::Ok,
            message: String::new(),
            start,
            ready,
            tool_target,
            branches: 0,
            q_hit: vec![f64::NAN; n],
            qd_hit: vec![f64::NAN; n],
            sigma_min: f64::NAN,
            t_hit: f64::NAN,
            earliest_t_hit: f64::NAN,
            profile: StrokeProfile::Auto,
            trajectory: None,
            return_duration: f64::NAN,
            violations: Vec::new(),
            peak_effort: vec![0.0; n],
            effort_ratio: 0.0,
        };
        match solve::hit_state(self, &plan.hit, &plan.tool_target, &plan.start.q) {
            Ok(s) => {
                plan.q_hit = s.q;
                plan.qd_hit = s.qd;
                plan.sigma_min = s.sigma_min;
                plan.branches = s.branches;
            }
            Err((status, message)) => {
                plan.status = status;
                plan.message = message;
                return Ok(plan);
            }
        }
        stroke::plan_stroke(self, &mut plan, data)?;
        Ok(plan)
    }
}

#[cfg(test)]
mod tests;
