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

pub mod branch;
pub mod leg;
mod planner;
pub mod racket;
mod solve;
mod stroke;
mod types;

pub use branch::BranchLeg;
pub use leg::HitLeg;
pub use planner::HitPlanner;
#[allow(deprecated)]
pub use racket::Racket;
pub use racket::{racket_axes, racket_frame, racket_state_batch, RacketMount, DEFAULT_HANDLE, RACKET_STATE_LEN};
pub use types::{Hit, HitOptions, HitPlan, HitStatus, HitTask, StrokeProfile};

/// Default jerk limit as a multiple of the acceleration limit (1/s): full acceleration is built up
/// in 5 ms (a servo drive's current loop settles in about 1 ms). Robot files carry no jerk limits.
pub const DEFAULT_JERK_PER_ACCELERATION: f64 = 200.0;

#[cfg(test)]
mod tests;
