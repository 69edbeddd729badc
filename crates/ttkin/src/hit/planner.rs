//! The robot-side hit planner: the immutable model (chain, dynamics, IK, racket mount, limits,
//! effort limits, gravity, ready pose) and one hit planned on it, or a batch in parallel.

use rayon::prelude::*;

use super::{
    solve, stroke, Hit, HitOptions, HitPlan, HitStatus, RacketMount, StrokeProfile, DEFAULT_JERK_PER_ACCELERATION,
};
use crate::chain::Chain;
use crate::dynamics::{Dynamics, DynamicsData};
use crate::effort::EffortLimits;
use crate::error::{check_finite, check_vector, Error, Result};
use crate::ik::Analytic;
use crate::traj::limits::KinematicLimits;
use crate::traj::JointState;

/// The immutable planning model: chain, dynamics (when every link has an inertial), racket,
/// kinematic and effort limits, options. Plans allocate only their outputs' scratch.
#[derive(Debug, Clone)]
pub struct HitPlanner {
    pub(super) chain: Chain,
    pub(super) dynamics: Option<Dynamics>,
    pub(super) analytic: Option<Analytic>,
    pub(super) mount: RacketMount,
    pub(super) limits: KinematicLimits,
    pub(super) effort: EffortLimits,
    pub(super) options: HitOptions,
    pub(super) gravity: [f64; 3],
    pub(super) ready: Vec<f64>,
}

impl HitPlanner {
    /// A planner for `chain` (its racket from [`RacketMount::for_chain`]). Errors for options that do
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
        let gravity = options.gravity.unwrap_or_else(|| chain.gravity());
        check_finite("gravity", &gravity)?;
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
            mount: RacketMount::for_chain(chain),
            limits,
            effort,
            ready: chain.ready(),
            gravity,
            options,
        })
    }

    /// The chain.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// The analytic IK of the chain, when it has one ([`Analytic::for_chain`]).
    pub fn analytic(&self) -> Option<&Analytic> {
        self.analytic.as_ref()
    }

    /// The racket mount: where the chain carries its racket (racket frame in the tool frame).
    pub fn mount(&self) -> &RacketMount {
        &self.mount
    }

    /// Deprecated name of [`HitPlanner::mount`] (`racket` named the mount and the impact model).
    #[deprecated(note = "one name per concept: use `mount()` (the racket mount)")]
    pub fn racket(&self) -> &RacketMount {
        &self.mount
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

    /// Gravity (m/s², base frame) of the torques: the options', else the chain's.
    pub fn gravity(&self) -> [f64; 3] {
        self.gravity
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

    /// Checks that the plans of `count` hits for a robot of `dof` joints can fit in
    /// [`crate::budget::MAX_BYTES`]: `count` times a lower bound of one plan's bytes
    /// ([`HitPlan::bytes_at_least`]); the refusal says how many hits one call may take.
    pub fn check_batch(dof: usize, count: usize) -> Result<()> {
        let per_plan = HitPlan::bytes_at_least(dof);
        let most = crate::budget::MAX_BYTES / per_plan;
        if count > most {
            return Err(Error::invalid(
                "hits",
                format!(
                    "{count} hits: their plans take at least {per_plan} bytes each ({:.3e} bytes), more than the \
                     {} bytes (512 MiB) one call may hold: split the batch into calls of at most {most} hits",
                    count as f64 * per_plan as f64,
                    crate::budget::MAX_BYTES
                ),
            ));
        }
        Ok(())
    }

    /// [`HitPlanner::plan_batch`] that stops early when `stop()` turns true (checked before each
    /// hit; a caller's cancellation, e.g. Ctrl-C seen by the Python binding): then an error.
    ///
    /// The plans are bounded in bytes: the batch is checked by [`Self::check_batch`] before it
    /// starts, and the bytes of the plans made are counted as they come ([`HitPlan::bytes`]; a
    /// jerk-limited stroke has many more segments than a quintic one): past
    /// [`crate::budget::MAX_BYTES`] the batch ends with an error saying how many hits fit a call.
    pub fn plan_batch_until(
        &self,
        hits: &[Hit],
        state: Option<&JointState>,
        ready: Option<&[f64]>,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<Vec<HitPlan>> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        Self::check_batch(self.chain.dof(), hits.len())?;
        let (start, ready) = self.start_and_ready(state, ready)?;
        let (held, made) = (AtomicUsize::new(0), AtomicUsize::new(0));
        hits.par_iter()
            .map_init(
                || self.dynamics.as_ref().map(DynamicsData::new),
                |data, hit| {
                    if stop() {
                        return Err(crate::Error::invalid("hits", "planning stopped before this hit"));
                    }
                    let plan = self.plan_with(hit, Some(&start), Some(&ready), data.as_mut())?;
                    let bytes = plan.bytes();
                    let total = held.fetch_add(bytes, Ordering::Relaxed) + bytes;
                    let count = made.fetch_add(1, Ordering::Relaxed) + 1;
                    if total > crate::budget::MAX_BYTES {
                        let fit = (crate::budget::MAX_BYTES as f64 / (total as f64 / count as f64)) as usize;
                        return Err(Error::invalid(
                            "hits",
                            format!(
                                "the plans of {count} of the {} hits take {total} bytes, more than the {} bytes \
                                 (512 MiB) one call may hold ({} bytes a plan): split the batch into calls of at \
                                 most {fit} hits",
                                hits.len(),
                                crate::budget::MAX_BYTES,
                                total / count
                            ),
                        ));
                    }
                    Ok(plan)
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
        let tool_target = self.mount.tool_pose(&hit.pose);
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
