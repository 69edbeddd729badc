//! The stroke's torques against the effective effort limits: the certified peak of a leg, the
//! cheap screening at instants, and the search for the earliest hit time whose legs stay within
//! the limits at every instant (the return leg slowed, the hit leg moved later).

use super::{inside, Legs, EFFORT_SEARCH_PRECISION};
use crate::dynamics::{DynamicsData, EffortPeak, PeakStop};
use crate::hit::{HitPlanner, StrokeProfile};
use crate::traj::duration;
use crate::traj::jerk::{jerk_limited, PositionLimits};
use crate::traj::limits::LIMIT_TOLERANCE;
use crate::traj::{JointState, JointTrajectory};

/// The certified effort peak of `traj` against the planner's effective effort limits (inverse
/// dynamics with friction, gravity of the options), stopping as `stop` says.
pub(super) fn effort(p: &HitPlanner, data: &mut DynamicsData, traj: &JointTrajectory, stop: PeakStop) -> EffortPeak {
    let dynamics = p.dynamics.as_ref().expect("effort data exists only with dynamics");
    let gravity = nalgebra::Vector3::from(p.gravity);
    dynamics.effort_peak(data, traj, &p.effort, &gravity, stop)
}

/// Instants per leg at which the hit-time search screens the torques before certifying a leg.
const SCREEN_POINTS: usize = 33;

/// Largest |τ|/effective limit at `points` evenly spaced instants of `traj` (inverse dynamics
/// with friction, gravity of the options): a lower bound of the peak, a cheap necessary test.
fn screen(p: &HitPlanner, data: &mut DynamicsData, traj: &JointTrajectory, points: usize) -> f64 {
    (0..points)
        .map(|k| ratio_at(p, data, traj, traj.duration() * k as f64 / (points - 1) as f64))
        .fold(0.0, f64::max)
}

/// Largest |τ|/effective limit over the joints at time `t` of `traj`.
fn ratio_at(p: &HitPlanner, data: &mut DynamicsData, traj: &JointTrajectory, t: f64) -> f64 {
    let n = p.chain.dof();
    let dynamics = p.dynamics.as_ref().expect("effort data exists only with dynamics");
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    traj.sample_unchecked(t.min(traj.duration()), &mut q, &mut qd, &mut qdd);
    if !q.iter().chain(&qd).chain(&qdd).all(|v| v.is_finite()) {
        return f64::INFINITY;
    }
    let gravity = nalgebra::Vector3::from(p.gravity);
    let tau = dynamics.inverse_dynamics_unchecked(data, &q, &qd, &qdd, &gravity);
    let mut ratio: f64 = 0.0;
    for j in 0..n {
        let limit = p.effort.at(j, qd[j]);
        if tau[j] != 0.0 {
            ratio = ratio.max(if limit > 0.0 {
                tau[j].abs() / limit
            } else {
                f64::INFINITY
            });
        }
    }
    ratio
}

/// Whether a decided peak is within the limits (its certified bound at most the limit).
fn fits(e: &EffortPeak) -> bool {
    e.bound <= 1.0 + LIMIT_TOLERANCE
}

/// Makes both legs respect the effort limits at every instant: the return leg slowed by factors
/// of 1.25 (up to 10 times), the hit leg moved later (growth, then bisection). An error message
/// when no hit time up to `max_t_hit` is enough.
pub(super) fn within_effort_limits(
    p: &HitPlanner,
    data: &mut DynamicsData,
    start: &JointState,
    hit: &JointState,
    rest: &JointState,
    legs: &mut Legs,
) -> std::result::Result<(), String> {
    let lim = &p.limits;
    let name = |e: &EffortPeak, leg: &str| {
        format!(
            "the {leg} leg needs {:.2}× the effort limit of joint '{}' at every duration tried",
            e.ratio.max(1.0),
            p.chain.joints()[e.joint].name()
        )
    };
    // The legs as first planned are usually the final ones: refined at once (which decides them
    // too, conservatively within the tolerance), not decided then refined.
    let threshold = 1.0 + LIMIT_TOLERANCE;
    let refine = PeakStop::refine_below(p.options.effort_tolerance, threshold);
    let mut e_back = effort(p, data, &legs.back, refine);
    let mut d = legs.back.duration();
    for _ in 0..10 {
        if fits(&e_back) {
            break;
        }
        d *= 1.25;
        let Ok(b) = jerk_limited(hit, rest, lim, Some(d), PositionLimits::Respect) else {
            break;
        };
        legs.set_back(b.trajectory);
        e_back = effort(p, data, &legs.back, refine);
    }
    if !fits(&e_back) {
        return Err(name(&e_back, "return"));
    }
    // The hit leg's peak needs refining only above the return leg's.
    let refine_hit = PeakStop {
        floor: e_back.ratio,
        ..refine
    };
    legs.back_known.effort = Some(e_back);

    let e_hit = effort(p, data, &legs.hit, refine_hit);
    if fits(&e_hit) {
        legs.hit_known.effort = Some(e_hit);
        return Ok(());
    }
    // The torques at the start and at the hit depend on those states alone: when either is
    // beyond a limit, no hit time can help.
    for (at, what) in [(0.0, "start"), (legs.t_hit(), "hit")] {
        let r = ratio_at(p, data, &legs.hit, at);
        if r > threshold {
            return Err(format!(
                "the {what} state needs {r:.2}× the effort limit of some joint: no hit time can help"
            ));
        }
    }
    // The hit legs at hit time t: the quintic when it is within the kinematic and position
    // limits (smoother torques than a stretched time-optimal leg, which keeps its bang-bang
    // shape), and the jerk-limited leg with position limits respected.
    let legs_at = |t: f64| {
        let quintic = (p.options.profile != StrokeProfile::Jerk
            && duration::quintic_limit_ratio_above(start, hit, t, lim, 1.0 + LIMIT_TOLERANCE) <= 1.0 + LIMIT_TOLERANCE)
            .then(|| JointTrajectory::quintic_unchecked(start, hit, t))
            .filter(|q| inside(p, q))
            .map(|q| (q, StrokeProfile::Quintic));
        let jerk = move || {
            jerk_limited(start, hit, lim, Some(t), PositionLimits::Respect)
                .ok()
                .map(|j| (j.trajectory, StrokeProfile::Jerk))
        };
        quintic.into_iter().chain(std::iter::from_fn({
            let mut once = (p.options.profile != StrokeProfile::Quintic).then_some(jerk);
            move || once.take().and_then(|f| f())
        }))
    };
    // The search for the earliest hit time screens each leg by its torques at instants (cheap,
    // necessary); the leg it settles on is then certified. When that fails (a peak between the
    // instants), the search runs again from there with every leg certified.
    // A leg accepted at hit time t: the first of `legs_at(t)` whose certified peak (refined as the
    // reported one, so that the same leg gets the same answer wherever it is checked) fits. Every
    // time the search settles on is one at which a plan requested for it is accepted.
    let certified = |t: f64, data: &mut DynamicsData, skip: Option<&JointTrajectory>| {
        for (traj, profile) in legs_at(t) {
            // A torque above the limit at one of the screening instants rejects the leg at once
            // (the certified bound is at least every value the leg takes: the same answer).
            if skip == Some(&traj) || screen(p, data, &traj, SCREEN_POINTS) > threshold {
                continue;
            }
            let e = effort(p, data, &traj, refine_hit);
            if fits(&e) {
                return Some((traj, profile, e));
            }
        }
        None
    };
    // The other leg family at the requested time first (a stretched time-optimal leg or a
    // quintic may fit where the first choice does not).
    let t0 = legs.t_hit();
    if let Some((best, profile, e)) = certified(t0, data, Some(&legs.hit)) {
        legs.set_hit(best);
        legs.hit_known.effort = Some(e);
        legs.profile = profile;
        return Ok(());
    }
    let screened =
        |t: f64, data: &mut DynamicsData| legs_at(t).find(|(traj, _)| screen(p, data, traj, SCREEN_POINTS) <= 1.0);
    let Some((hi, (best, profile))) = earliest(t0, p.options.max_t_hit, data, screened) else {
        return Err(name(&e_hit, "hit"));
    };
    let e = effort(p, data, &best, refine_hit);
    if fits(&e) {
        legs.set_hit(best);
        legs.hit_known.effort = Some(e);
        legs.profile = profile;
        return Ok(());
    }
    let accept = |t: f64, data: &mut DynamicsData| certified(t, data, None).map(|(traj, profile, _)| (traj, profile));
    let Some((_, (best, profile))) = earliest(hi, p.options.max_t_hit, data, accept) else {
        return Err(name(&e, "hit"));
    };
    legs.set_hit(best);
    legs.profile = profile;
    Ok(())
}

/// Growth factor of the hit time in [`earliest`] before its bisection (25 %: half the steps of
/// 10 % to a hit that needs no time at all, e.g. `effort_limit`; the bisection adds two).
const GROWTH: f64 = 1.25;

/// The earliest hit time after `lo` s (not accepted) up to `max` s at which `accept` gives a leg,
/// to [`EFFORT_SEARCH_PRECISION`]: growth by [`GROWTH`], then bisection. The time and the leg with its profile.
fn earliest<F>(
    mut lo: f64,
    max: f64,
    data: &mut DynamicsData,
    mut accept: F,
) -> Option<(f64, (JointTrajectory, StrokeProfile))>
where
    F: FnMut(f64, &mut DynamicsData) -> Option<(JointTrajectory, StrokeProfile)>,
{
    let mut hi = lo * GROWTH;
    let mut best = loop {
        if hi > max {
            return None;
        }
        if let Some(traj) = accept(hi, data) {
            break traj;
        }
        lo = hi;
        hi *= GROWTH;
    };
    while hi - lo > EFFORT_SEARCH_PRECISION * hi {
        let mid = 0.5 * (lo + hi);
        match accept(mid, data) {
            Some(traj) => {
                best = traj;
                hi = mid;
            }
            None => lo = mid,
        }
    }
    Some((hi, best))
}
