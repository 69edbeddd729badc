//! Steps S104–S105 of the hit pipeline: the hitting stroke (start → hit state at the hit time →
//! rest at the ready pose), its kinematic limits, its torques against the effort limits, and
//! the earliest feasible hit time.
//!
//! Profile choice ([`StrokeProfile::Auto`]): the quintic when it meets the requested hit time
//! within the velocity, acceleration and jerk limits (one exact peak evaluation); otherwise the
//! jerk-limited leg with the requested time as minimum duration, which is the time-optimal one
//! (the earliest kinematically feasible hit time T*) when the request is earlier than T* (status
//! too early). The return leg is a quintic of nearly minimal duration (one Ruckig solve
//! less per plan; the return is not time-critical), replanned jerk-limited when it would leave
//! the position limits or exceed an effort limit.
//! T* is computed on demand ([`super::HitPlanner::earliest_t_hit`]) when planning did not need it.
//! A leg that leaves the position limits is replanned jerk-limited with position limits.
//! When the torques exceed an effective effort limit ([`crate::effort`]) at any instant, the
//! return leg is slowed, and the hit time is moved later (growth by 25 %, then bisection to
//! 0.1 %) until they do not, with the quintic hit leg at each time tried when it is within the
//! kinematic limits, else the jerk-limited one (`Auto`; `Quintic` and `Jerk` keep their family) (a time-optimal leg stretched in time keeps its
//! bang-bang torques: gantry6's demo hit needs 1.03 s jerk-limited, 0.50 s as a quintic). "At any instant" is certified, not sampled: the branch-and-bound
//! bound of [`crate::dynamics::peak`] decides each leg, and the reported `effort_ratio` is the
//! refined peak of the legs planned (to the options' `effort_tolerance`). A hit leg beyond the
//! effort limits is first replaced by the other family at the requested time (the quintic when it
//! is within the kinematic and position limits, the jerk-limited leg with position limits). The
//! hit-time search screens its legs by the torques at 33 instants (a necessary test, cheap) and
//! certifies only the leg it settles on; when that fails, it searches on from there certifying
//! every leg. Every leg is certified with the same stopping rule wherever it is checked, so a
//! plan requested for the time a `too_early` plan reports is accepted with the same leg. The final trajectory's speed, acceleration and jerk are checked exactly
//! as well ([`JointTrajectory::rate_violations`]; Ruckig's legs and the accepted quintics are
//! within them by construction, so this only catches a start state beyond the limits).
//!
//! Cost (gantry6, about 190k instructions per on-time plan): every check of a leg is made once
//! (a leg knows whether it is inside the position limits and its torques at the check points
//! until it is replaced); quintic limit ratios and position ranges are first bounded by the
//! polynomials' Bernstein coefficients ([`crate::traj::poly::bounds`]) and the exact extrema are
//! found only where a bound can change the answer, so plans are the same numbers bit for bit.
//! The certified effort check costs more than the 24 sampled inverse dynamics it replaced
//! (docs/hit_pipeline.md has the numbers): a leg far below its limits is decided by the first
//! eight interval enclosures, a leg near them by a few tens.
//!
//! Here the legs, the profile choice and the position limits; the torques against the effort
//! limits and the hit-time search under them in [`effort`](mod@effort).

mod effort;

use self::effort::{effort, within_effort_limits};
use super::{HitPlan, HitPlanner, HitStatus, StrokeProfile};
use crate::dynamics::{DynamicsData, EffortPeak, PeakStop};
use crate::error::Result;
use crate::traj::duration;
use crate::traj::jerk::{jerk_limited, PositionLimits};
use crate::traj::limits::{KinematicLimits, Quantity, LIMIT_TOLERANCE};
use crate::traj::{JointState, JointTrajectory};

/// Relative precision of the earliest hit time under effort limits.
const EFFORT_SEARCH_PRECISION: f64 = 1e-3;

/// The two legs, their hit-leg profile, and what is already known of each: inside the position
/// limits. Replacing a leg resets it.
struct Legs {
    hit: JointTrajectory,
    back: JointTrajectory,
    profile: StrokeProfile,
    hit_known: Known,
    back_known: Known,
}

/// What was already computed of one leg: inside the position limits, its refined effort peak.
#[derive(Default)]
struct Known {
    inside: bool,
    effort: Option<EffortPeak>,
}

impl Legs {
    fn new(hit: JointTrajectory, back: JointTrajectory, profile: StrokeProfile) -> Legs {
        Legs {
            hit,
            back,
            profile,
            hit_known: Known::default(),
            back_known: Known::default(),
        }
    }

    fn t_hit(&self) -> f64 {
        self.hit.duration()
    }

    fn set_hit(&mut self, hit: JointTrajectory) {
        self.hit = hit;
        self.hit_known = Known::default();
    }

    fn set_back(&mut self, back: JointTrajectory) {
        self.back = back;
        self.back_known = Known::default();
    }
}

/// Plans the stroke of `plan` (hit state already solved), filling status, times, trajectory,
/// violations and efforts.
pub(super) fn plan_stroke(p: &HitPlanner, plan: &mut HitPlan, mut data: Option<&mut DynamicsData>) -> Result<()> {
    let lim = &p.limits;
    let n = p.chain.dof();
    for j in 0..n {
        if plan.qd_hit[j].abs() > lim.velocity[j] * (1.0 + LIMIT_TOLERANCE) {
            plan.status = HitStatus::HitSpeedLimit;
            plan.message = format!(
                "joint '{}' must move at {:.3} at the hit, beyond its speed limit {:.3}",
                p.chain.joints()[j].name(),
                plan.qd_hit[j],
                lim.velocity[j]
            );
            return Ok(());
        }
    }
    let hit = JointState {
        q: plan.q_hit.clone(),
        qd: plan.qd_hit.clone(),
        qdd: vec![0.0; n],
    };
    let rest = JointState::rest(&plan.ready);
    let t_req = plan.hit.t;
    let profile = p.options.profile;

    let legs = match first_legs(p, &plan.start, &hit, &rest, t_req, profile) {
        Ok((legs, earliest)) => {
            plan.earliest_t_hit = earliest;
            legs
        }
        Err(e) => {
            plan.status = HitStatus::NoStroke;
            plan.message = e.to_string();
            return Ok(());
        }
    };
    let mut legs = match within_position_limits(p, &plan.start, &hit, &rest, legs) {
        Ok(l) => l,
        Err(message) => {
            plan.status = HitStatus::PositionLimit;
            plan.message = message;
            return Ok(());
        }
    };

    if let Some(d) = data.as_deref_mut() {
        if let Err(message) = within_effort_limits(p, d, &plan.start, &hit, &rest, &mut legs) {
            plan.status = HitStatus::EffortLimit;
            plan.message = message;
        }
    }
    let t_hit = legs.t_hit();
    if let Some(d) = data {
        let refine = PeakStop::refine(p.options.effort_tolerance);
        let e2 = legs
            .back_known
            .effort
            .take()
            .unwrap_or_else(|| effort(p, d, &legs.back, refine));
        let refine_hit = PeakStop {
            floor: e2.ratio,
            ..refine
        };
        let e1 = legs
            .hit_known
            .effort
            .take()
            .unwrap_or_else(|| effort(p, d, &legs.hit, refine_hit));
        plan.effort_ratio = e1.ratio.max(e2.ratio);
        plan.peak_effort = e1.peak.iter().zip(&e2.peak).map(|(a, b)| a.max(*b)).collect();
    }
    if t_hit > t_req * (1.0 + 1e-12) {
        if plan.status == HitStatus::Ok {
            plan.status = HitStatus::TooEarly;
            plan.message = format!(
                "hit at {t_req:.4} s is not feasible within the limits; planned for the earliest feasible {t_hit:.4} s"
            );
        }
        plan.earliest_t_hit = plan.earliest_t_hit.max(t_hit);
    }
    plan.t_hit = t_hit;
    plan.profile = legs.profile;
    plan.return_duration = legs.back.duration();
    // Speed, acceleration and jerk hold by construction (Ruckig's profiles; quintics accepted only
    // when their exact peaks are within the limits) from a start within the limits; checked
    // exactly all the same (cheap bounds first), with the position limits.
    if !legs.hit_known.inside {
        plan.violations = legs.hit.position_violations(&p.limits, 0.0);
    }
    if !legs.back_known.inside {
        plan.violations.extend(legs.back.position_violations(&p.limits, t_hit));
    }
    plan.violations.extend(legs.hit.rate_violations(&p.limits, 0.0));
    plan.violations.extend(legs.back.rate_violations(&p.limits, t_hit));
    let trajectory = legs.hit.append(legs.back);
    plan.trajectory = Some(trajectory);
    if matches!(plan.status, HitStatus::Ok | HitStatus::TooEarly) && !plan.violations.is_empty() {
        let v = &plan.violations[0];
        plan.status = if v.quantity == Quantity::Position {
            HitStatus::PositionLimit
        } else {
            HitStatus::NoStroke
        };
        plan.message = format!(
            "joint '{}' {} {:.4} beyond its limit {:.4} at {:.4} s",
            p.chain.joints()[v.joint].name(),
            v.quantity.name(),
            v.value,
            v.limit,
            v.time
        );
    }
    Ok(())
}

/// The legs before position and effort checks, and the earliest kinematically feasible hit time
/// when it came out of the planning for free (NaN otherwise: [`earliest_kinematic`] on demand).
fn first_legs(
    p: &HitPlanner,
    start: &JointState,
    hit: &JointState,
    rest: &JointState,
    t_req: f64,
    profile: StrokeProfile,
) -> Result<(Legs, f64)> {
    let lim = &p.limits;
    if profile == StrokeProfile::Quintic {
        let t = duration::earliest_quintic_duration(start, hit, lim, t_req)?;
        let legs = Legs::new(
            JointTrajectory::quintic_unchecked(start, hit, t),
            quick_quintic(hit, rest, lim),
            profile,
        );
        return Ok((legs, if t > t_req { t } else { f64::NAN }));
    }
    let fits = |t: f64| {
        duration::quintic_limit_ratio_above(start, hit, t, lim, 1.0 + LIMIT_TOLERANCE) <= 1.0 + LIMIT_TOLERANCE
    };
    if profile == StrokeProfile::Auto && fits(t_req) {
        let legs = Legs::new(
            JointTrajectory::quintic_unchecked(start, hit, t_req),
            quick_quintic(hit, rest, lim),
            StrokeProfile::Quintic,
        );
        return Ok((legs, f64::NAN));
    }
    // Ruckig with a minimum duration returns the time-optimal trajectory when that is later.
    let leg = jerk_limited(start, hit, lim, Some(t_req), PositionLimits::Ignore)?;
    let earliest = if leg.duration > t_req * (1.0 + 1e-12) {
        leg.duration
    } else {
        f64::NAN
    };
    let back = quick_quintic(hit, rest, lim);
    Ok((Legs::new(leg.trajectory, back, StrokeProfile::Jerk), earliest))
}

/// The earliest hit time (s) at which a plan of `plan`'s hit state from its start is accepted
/// (status ok: on time, every kinematic and effort limit met), for an `ok` plan: the kinematic
/// earliest time ([`earliest_kinematic`]) when a plan there is accepted, otherwise bisection between
/// it and the plan's own time to [`EFFORT_SEARCH_PRECISION`], each step a full plan of the stroke.
/// The time returned is always one at which planning is accepted (acceptance need not be monotone
/// in the hit time: an earlier accepted time may exist between the kinematic bound and it).
pub(super) fn earliest_accepted(p: &HitPlanner, plan: &HitPlan, t_kin: f64) -> f64 {
    let mut data = p.dynamics.as_ref().map(DynamicsData::new);
    let mut accepted = |t: f64| {
        let mut trial = plan.clone();
        trial.hit.t = t;
        trial.status = HitStatus::Ok;
        trial.message.clear();
        trial.violations.clear();
        trial.trajectory = None;
        trial.earliest_t_hit = f64::NAN;
        plan_stroke(p, &mut trial, data.as_mut()).is_ok() && trial.status == HitStatus::Ok
    };
    let (mut lo, mut hi) = (t_kin, plan.t_hit);
    if lo >= hi {
        return hi;
    }
    if accepted(lo) {
        return lo;
    }
    while hi - lo > EFFORT_SEARCH_PRECISION * hi {
        let mid = 0.5 * (lo + hi);
        if accepted(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The earliest hit time (s) at which the planner's profile meets the velocity, acceleration and
/// jerk limits from `start` to `hit`: the time-optimal jerk-limited duration (`Auto`, `Jerk`) or
/// the minimal quintic duration (`Quintic`).
pub(super) fn earliest_kinematic(p: &HitPlanner, start: &JointState, hit: &JointState) -> Result<f64> {
    match p.options.profile {
        StrokeProfile::Quintic => duration::minimal_quintic_duration(start, hit, &p.limits),
        _ => Ok(jerk_limited(start, hit, &p.limits, None, PositionLimits::Ignore)?.duration),
    }
}

/// Factor by which [`quick_quintic`] grows the return leg until it respects the limits.
const QUICK_GROWTH: f64 = 1.1;

/// A quintic from `from` to `to` within the velocity, acceleration and jerk limits, not minimal:
/// the duration starts at [`duration::quintic_start_duration`] (the rest-to-rest quintic bound and
/// the time to cancel the start velocity and acceleration), and grows by √(peak/limit) (at least
/// [`QUICK_GROWTH`]) until the exact peaks are within the limits; not minimal, typically within a
/// few tens of percent of the minimal duration of that family.
fn quick_quintic(from: &JointState, to: &JointState, lim: &KinematicLimits) -> JointTrajectory {
    let mut t = duration::quintic_start_duration(from, to, lim);
    for _ in 0..200 {
        let ratio = duration::quintic_limit_ratio_above(from, to, t, lim, 1.0 + LIMIT_TOLERANCE);
        if ratio <= 1.0 + LIMIT_TOLERANCE {
            break;
        }
        // Peaks fall like T⁻¹ to T⁻³ as T grows: √ratio is a step that rarely overshoots by much.
        t *= ratio.sqrt().clamp(QUICK_GROWTH, 4.0);
    }
    JointTrajectory::quintic_unchecked(from, to, t)
}

/// True when `traj` stays inside the position limits (exact extrema).
fn inside(p: &HitPlanner, traj: &JointTrajectory) -> bool {
    traj.position_violations(&p.limits, 0.0).is_empty()
}

/// Replans a leg that leaves the position limits jerk-limited with position limits (the hit leg
/// at its hit time); an error message when that is impossible.
fn within_position_limits(
    p: &HitPlanner,
    start: &JointState,
    hit: &JointState,
    rest: &JointState,
    mut legs: Legs,
) -> std::result::Result<Legs, String> {
    let lim = &p.limits;
    let why = |leg: &str, e: crate::Error| format!("the {leg} leg cannot stay inside the position limits: {e}");
    if inside(p, &legs.hit) {
        legs.hit_known.inside = true;
    } else {
        let t = legs.t_hit();
        legs.set_hit(
            jerk_limited(start, hit, lim, Some(t), PositionLimits::Respect)
                .map_err(|e| why("hit", e))?
                .trajectory,
        );
        legs.profile = StrokeProfile::Jerk;
    }
    if inside(p, &legs.back) {
        legs.back_known.inside = true;
    } else {
        legs.set_back(
            jerk_limited(hit, rest, lim, None, PositionLimits::Respect)
                .map_err(|e| why("return", e))?
                .trajectory,
        );
    }
    Ok(legs)
}
