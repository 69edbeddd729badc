//! The hitting stroke of a table-tennis robot: from the current joint state, be at the hit
//! configuration with the hit velocity (and zero or a given acceleration) at the hit time, then
//! return to a ready configuration at rest.
//!
//! Both legs are quintics (the patent's step S104). The hit leg keeps the requested hit time when
//! it respects the velocity, acceleration and jerk limits; otherwise the hit time becomes the
//! earliest feasible one after it, found by root bracketing on the duration (growth, then the
//! Illinois regula falsi safeguarded by bisection) with the quintic's exact extrema (roots of its
//! derivative polynomials) at every step ([`duration::earliest_quintic_duration`]); not a closed
//! form, since the peaks of a quintic with nonzero boundary velocities are not monotone in T. The return leg takes the minimal
//! feasible duration ([`duration::minimal_quintic_duration`]) unless one is given.

use super::duration;
use super::limits::{KinematicLimits, Violation};
use super::{check_duration, JointState, JointTrajectory};
use crate::error::{check_vector, Result};

/// A planned stroke.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    /// Hit leg then return leg, one trajectory starting at 0 s (now).
    pub trajectory: JointTrajectory,
    /// Hit time actually planned (s from now).
    pub t_hit: f64,
    /// Hit time that was requested (s from now).
    pub requested_t_hit: f64,
    /// Duration of the return leg (s).
    pub return_duration: f64,
    /// Limit violations of the planned stroke, empty when it is feasible. The hit leg and a
    /// minimal-duration return leg respect velocity, acceleration and jerk limits by construction,
    /// so only position limits (or an imposed `return_duration`) can show up here.
    pub violations: Vec<Violation>,
}

impl Stroke {
    /// Whether the requested hit time was kept.
    pub fn on_time(&self) -> bool {
        self.t_hit == self.requested_t_hit
    }
}

/// Plans a stroke from `start` to `hit` at `t_hit` s (or the earliest feasible time after it), then
/// to rest at `ready` (rad or m) in `return_duration` s (minimal feasible when `None`).
pub fn stroke(
    start: &JointState,
    hit: &JointState,
    t_hit: f64,
    ready: &[f64],
    return_duration: Option<f64>,
    limits: &KinematicLimits,
) -> Result<Stroke> {
    let n = start.check_pair("start", hit, "hit")?;
    check_vector("ready", ready, n)?;
    check_duration("t_hit", t_hit)?;
    let planned = duration::earliest_quintic_duration(start, hit, limits, t_hit)?;
    let rest = JointState::rest(ready);
    let back = match return_duration {
        Some(d) => {
            check_duration("return_duration", d)?;
            d
        }
        None => duration::minimal_quintic_duration(hit, &rest, limits)?,
    };
    let first = JointTrajectory::quintic_unchecked(start, hit, planned);
    let second = JointTrajectory::quintic_unchecked(hit, &rest, back);
    let trajectory = first.append(second);
    let violations = trajectory.check_limits(limits)?;
    Ok(Stroke {
        trajectory,
        t_hit: planned,
        requested_t_hit: t_hit,
        return_duration: back,
        violations,
    })
}
