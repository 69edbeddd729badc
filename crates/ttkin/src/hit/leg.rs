//! The hit leg of a stroke: the joint motion from the stroke's start state to the hit state
//! (q, q̇, q̈) at the hit time, the one the ball planner ([`crate::ball::hitplan`], through [`super::HitPlanner::best_leg`])
//! accepts and the rally executes.
//!
//! 1. **Quintic** (cheap, tried first): from the start state to (q, q̇, q̈) at `t_hit`, with q̈ = 0
//!    or a fraction (½, 1) of the end acceleration of the cubic through the same boundary
//!    positions and velocities, −6·Δq/T² + 2·(q̇0 + 2·q̇1)/T, whichever has the lowest exact
//!    peak/limit ratio r over velocity, acceleration and jerk. Accepted when r ≤ 1 and it stays
//!    inside the position limits (exact extrema: a hit near a joint's limit moving away from it
//!    can overshoot the limit before the hit, which the drives refuse); its margin is 1 − r.
//! 2. **Jerk-limited** (Ruckig, [`crate::traj::jerk`]), only when the quintic is beyond the
//!    limits: the time-optimal leg to (q, q̇, q̈ = 0) gives the shortest duration T*; when
//!    T* ≤ `t_hit`, the leg with `t_hit` as minimum duration is accepted if it reaches the hit
//!    state exactly at `t_hit` (duration within 1e-9 s) and stays inside the position limits
//!    (planned without them and checked exactly, then, if it leaves them, planned with them and
//!    checked again). Its margin is 1 − T*/`t_hit`: the fraction of the time available that the
//!    fastest stroke leaves unused.
//!
//! Cheap rejections first (the same legs): from rest, no Ruckig solve when a joint's jerk-free
//! minimum time to its hit state (`min_time_from_rest`) exceeds the hit time; the quintic's
//! peak search stops at the first peak above the best trial or the limit
//! ([`crate::traj::duration::quintic_limit_ratio_below`]); [`hit_leg_above`] skips the legs whose
//! margin cannot exceed a floor (the hit planner's best so far) before their solves.
//!
//! A quintic needs about 1.7 times the time-optimal duration for a rest-to-rest move, so the
//! jerk-limited leg reaches balls the quintic cannot (docs/ball.md). Margins of the two profiles
//! measure different things (peak ratio, time ratio); both are 0 at the limit and grow toward 1
//! with slack.

use crate::hit::StrokeProfile;
use crate::traj::duration::quintic_limit_ratio_below;
use crate::traj::jerk::{jerk_limited, jerk_limited_duration, PositionLimits};
use crate::traj::limits::KinematicLimits;
use crate::traj::{JointState, JointTrajectory};

/// Largest difference (s) between the jerk-limited leg's duration and the hit time.
const DURATION_TOLERANCE: f64 = 1e-9;

/// Ceiling of the quintic's peak/limit search: above the acceptance limit 1 by a rounding margin.
const ACCEPT_CEILING: f64 = 1.0 + 1e-12;

/// An accepted hit leg (joint frame: m, rad, from the stroke start at 0 s to the hit at `t_hit`).
#[derive(Debug, Clone, PartialEq)]
pub struct HitLeg {
    /// Which profile the leg is ([`StrokeProfile::Quintic`] or [`StrokeProfile::Jerk`]).
    pub profile: StrokeProfile,
    /// The leg, from the start state at 0 s to the hit state at its duration (= the hit time).
    pub trajectory: JointTrajectory,
    /// Joint accelerations (m/s², rad/s²) at the hit.
    pub qdd_hit: Vec<f64>,
    /// Margin to the kinematic limits (see the module doc), in [0, 1].
    pub margin: f64,
}

/// The leg from `start` to the configuration `q` with velocities `qd` (m, rad, per s) at `t_hit`
/// s within `limits`: the quintic when it is within them, else the jerk-limited leg when that
/// reaches the hit state on time inside the position limits; `None` when neither does.
pub fn hit_leg(start: &JointState, q: &[f64], qd: &[f64], t_hit: f64, limits: &KinematicLimits) -> Option<HitLeg> {
    hit_leg_above(start, q, qd, t_hit, limits, f64::NEG_INFINITY)
}

/// [`hit_leg`] when the leg's margin exceeds `floor`, else `None` (also when `hit_leg` has no
/// leg): a caller keeping the largest margin skips the solves of legs it would not keep (the
/// jerk-limited leg's margin is known from its time-optimal duration, before the on-time solve).
pub fn hit_leg_above(
    start: &JointState,
    q: &[f64],
    qd: &[f64],
    t_hit: f64,
    limits: &KinematicLimits,
    floor: f64,
) -> Option<HitLeg> {
    if !(t_hit > 0.0 && t_hit.is_finite()) {
        return None;
    }
    let cubic: Vec<f64> = (0..q.len())
        .map(|i| -6.0 * (q[i] - start.q[i]) / (t_hit * t_hit) + 2.0 * (start.qd[i] + 2.0 * qd[i]) / t_hit)
        .collect();
    // One end state, its accelerations rewritten for each trial.
    let mut end = JointState {
        q: q.to_vec(),
        qd: qd.to_vec(),
        qdd: vec![0.0; q.len()],
    };
    let mut best: Option<(f64, f64)> = None;
    for alpha in [0.0, 0.5, 1.0] {
        for (a, c) in end.qdd.iter_mut().zip(&cubic) {
            *a = alpha * c;
        }
        // Exact below the best so far and below 1 (a ratio above both is neither chosen nor
        // accepted); the small excess over 1 keeps a ratio of exactly 1 exact.
        let ceiling = best.map_or(ACCEPT_CEILING, |(r, _)| r.min(ACCEPT_CEILING));
        let ratio = quintic_limit_ratio_below(start, &end, t_hit, limits, ceiling);
        if best.is_none_or(|(r, _)| ratio < r) {
            best = Some((ratio, alpha));
        }
    }
    let (ratio, alpha) = best.expect("three trials");
    if ratio <= 1.0 {
        for (a, c) in end.qdd.iter_mut().zip(&cubic) {
            *a = alpha * c;
        }
        // The quintic may overshoot a position limit between its ends (a hit near a joint's
        // limit, moving away from it): the drives refuse such a stroke, so it is no leg; the
        // jerk-limited leg, which can keep the position limits, is tried instead.
        let trajectory = JointTrajectory::quintic_unchecked(start, &end, t_hit);
        if inside(&trajectory, limits) {
            return (1.0 - ratio > floor).then_some(HitLeg {
                profile: StrokeProfile::Quintic,
                trajectory,
                qdd_hit: end.qdd,
                margin: 1.0 - ratio,
            });
        }
    }
    jerk_leg(start, q, qd, t_hit, limits, floor)
}

/// The jerk-limited leg of [`hit_leg`] (step 2 of the module doc).
fn jerk_leg(
    start: &JointState,
    q: &[f64],
    qd: &[f64],
    t_hit: f64,
    limits: &KinematicLimits,
    floor: f64,
) -> Option<HitLeg> {
    let end = JointState {
        q: q.to_vec(),
        qd: qd.to_vec(),
        qdd: vec![0.0; q.len()],
    };
    // From rest, a joint cannot reach its hit state sooner than without a jerk limit: no
    // Ruckig solve when that bound already exceeds the hit time.
    let at_rest = start.qd.iter().chain(&start.qdd).all(|x| *x == 0.0);
    if at_rest
        && (0..q.len()).any(|i| {
            let bound = min_time_from_rest(q[i] - start.q[i], qd[i], limits.velocity[i], limits.acceleration[i]);
            bound > t_hit * (1.0 + 1e-9)
        })
    {
        return None;
    }
    let fastest = jerk_limited_duration(start, &end, limits, None, PositionLimits::Ignore).ok()?;
    let margin = (1.0 - fastest / t_hit).clamp(0.0, 1.0);
    if fastest > t_hit || margin <= floor {
        return None;
    }
    let on_time = |position: PositionLimits| {
        jerk_limited(start, &end, limits, Some(t_hit), position)
            .ok()
            .filter(|leg| (leg.duration - t_hit).abs() <= DURATION_TOLERANCE && inside(&leg.trajectory, limits))
    };
    let leg = on_time(PositionLimits::Ignore).or_else(|| on_time(PositionLimits::Respect))?;
    Some(HitLeg {
        profile: StrokeProfile::Jerk,
        trajectory: leg.trajectory,
        qdd_hit: end.qdd,
        margin,
    })
}

/// The jerk-limited leg of [`hit_leg`] under `limits` with every acceleration and jerk limit
/// scaled by `scale` in (0, 1] (speed and position limits kept): a slower, gentler stroke to the
/// same hit state (q, q̇, q̈ = 0) at `t_hit`, whose inertial torques shrink with `scale` (the
/// effort-limited stroke of [`super::HitPlanner::branch_leg`]). Its margin is 1 − T*ₛ/`t_hit`
/// with T*ₛ the time-optimal duration under the scaled limits; `None` when that exceeds `t_hit`,
/// the margin is at most `floor`, or the leg leaves the position limits.
pub fn scaled_jerk_leg(
    start: &JointState,
    q: &[f64],
    qd: &[f64],
    t_hit: f64,
    limits: &KinematicLimits,
    scale: f64,
    floor: f64,
) -> Option<HitLeg> {
    scaled_jerk_leg_joints(start, q, qd, t_hit, limits, &vec![scale; q.len()], floor)
}

/// [`scaled_jerk_leg`] with a scale of its own for each joint's acceleration and jerk limits
/// (`scales`, each in (0, 1]): only the joints beyond their torque slowed, the others keeping
/// their full limits (the effort-limited stroke of [`super::HitPlanner::branch_leg`] tries it
/// first). `None` as [`scaled_jerk_leg`], or when `scales` has the wrong length.
pub fn scaled_jerk_leg_joints(
    start: &JointState,
    q: &[f64],
    qd: &[f64],
    t_hit: f64,
    limits: &KinematicLimits,
    scales: &[f64],
    floor: f64,
) -> Option<HitLeg> {
    if scales.len() != q.len() || !scales.iter().all(|s| *s > 0.0 && *s <= 1.0) || !(t_hit > 0.0 && t_hit.is_finite()) {
        return None;
    }
    let mut scaled = limits.clone();
    for ((a, j), s) in scaled.acceleration.iter_mut().zip(scaled.jerk.iter_mut()).zip(scales) {
        *a *= s;
        *j *= s;
    }
    // The start state must lie within the scaled limits (a moving start's acceleration).
    if start.qdd.iter().zip(&scaled.acceleration).any(|(x, a)| x.abs() > *a) {
        return None;
    }
    jerk_leg(start, q, qd, t_hit, &scaled, floor)
}

/// Whether `traj` stays inside the position limits of `limits` (exact, to [`crate::traj::limits::LIMIT_TOLERANCE`]).
fn inside(traj: &JointTrajectory, limits: &KinematicLimits) -> bool {
    traj.position_violations(limits, 0.0).is_empty()
}

/// Per-joint minimum time (s) to move `delta` (m or rad) from rest under speed `v` and
/// acceleration `a`, arriving at any speed (jerk unlimited): a lower bound of every leg's time.
pub fn min_joint_time(delta: f64, v: f64, a: f64) -> f64 {
    let d = delta.abs();
    if d * 2.0 * a <= v * v {
        (2.0 * d / a).sqrt()
    } else {
        d / v + v / (2.0 * a)
    }
}

/// Shortest time (s) for one joint from rest to travel `delta` and arrive with velocity `v1` (m
/// or rad, per s) under the speed limit `vmax` and acceleration limit `amax`, jerk unlimited: the
/// time-optimal bang-bang (and cruise) profile of the double integrator (Pontryagin's maximum
/// principle; e.g. Kröger, "On-Line Trajectory Generation in Robotic Systems", 2010). Forward (peak ≥ v1) when delta ≥ v1²/(2·amax) after
/// turning signs so that v1 ≥ 0, else first backward then forward. A lower bound on any
/// jerk-limited profile of the same problem; infinite when |v1| > vmax.
pub(crate) fn min_time_from_rest(delta: f64, v1: f64, vmax: f64, amax: f64) -> f64 {
    let (d, v1) = if v1 < 0.0 { (-delta, -v1) } else { (delta, v1) };
    let (v, a) = (vmax, amax);
    if v1 > v {
        return f64::INFINITY;
    }
    if d >= v1 * v1 / (2.0 * a) {
        let peak = (a * d + 0.5 * v1 * v1).sqrt();
        if peak <= v {
            (2.0 * peak - v1) / a
        } else {
            (2.0 * v - v1) / a + (d - (2.0 * v * v - v1 * v1) / (2.0 * a)) / v
        }
    } else {
        let back = (0.5 * v1 * v1 - a * d).sqrt();
        if back <= v {
            (2.0 * back + v1) / a
        } else {
            (2.0 * v + v1) / a + ((v1 * v1 - 2.0 * v * v) / (2.0 * a) - d) / v
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::traj::jerk::jerk_limited;

    /// gantry6's ball planner (its ready configuration and limits) and a generator seeded `seed`.
    fn rig(seed: u64) -> (crate::ball::hitplan::ReturnPlanner, fastrand::Rng) {
        let pl = crate::ball::hitplan::ReturnPlanner::new(crate::robots::gantry6(), Default::default()).unwrap();
        (pl, fastrand::Rng::with_seed(seed))
    }

    /// `ready` with every joint moved by a uniform draw of ±`spread` (m, rad).
    fn around(ready: &[f64], spread: f64, rng: &mut fastrand::Rng) -> Vec<f64> {
        ready.iter().map(|x| x + spread * (2.0 * rng.f64() - 1.0)).collect()
    }

    #[test]
    fn leg_above_a_floor_is_the_leg_when_its_margin_exceeds_the_floor() {
        let (pl, mut rng) = rig(5);
        let lim = pl.robot.limits();
        let (mut quintic, mut jerk, mut none) = (0, 0, 0);
        let start = JointState::rest(&pl.ready);
        for _ in 0..400 {
            let q = around(&pl.ready, 0.6, &mut rng);
            let qd: Vec<f64> = lim.velocity.iter().map(|v| 0.8 * v * (2.0 * rng.f64() - 1.0)).collect();
            let t_hit = 0.15 + 0.5 * rng.f64();
            let full = hit_leg(&start, &q, &qd, t_hit, lim);
            match &full {
                Some(l) if l.profile == StrokeProfile::Quintic => quintic += 1,
                Some(_) => jerk += 1,
                None => none += 1,
            }
            for floor in [0.0, 0.1, 0.3, 0.6] {
                let above = hit_leg_above(&start, &q, &qd, t_hit, lim, floor);
                let want = full.clone().filter(|l| l.margin > floor);
                assert_eq!(above, want, "floor {floor}");
            }
        }
        assert!(
            quintic > 10 && jerk > 10 && none > 10,
            "{quintic} quintic, {jerk} jerk, {none} none"
        );
    }

    /// Hits within 2 cm (or 0.02 rad) of a joint's limit, moving away from it: the quintic to such
    /// a hit often overshoots the limit before the hit (the drives refuse that stroke: issue 28's
    /// `execution_failed`); every accepted leg stays inside the position limits at every instant.
    #[test]
    fn legs_to_hits_near_a_joint_limit_stay_inside_the_position_limits() {
        let (pl, mut rng) = rig(11);
        let lim = pl.robot.limits();
        let (mut accepted, mut overshooting_quintics) = (0, 0);
        let start = JointState::rest(&pl.ready);
        for _ in 0..400 {
            let mut q = around(&pl.ready, 0.05, &mut rng);
            let mut qd = vec![0.0; q.len()];
            let j = rng.usize(..q.len());
            let up = rng.bool();
            let edge = if up { lim.upper[j] } else { lim.lower[j] };
            if !edge.is_finite() {
                continue;
            }
            let away = if up { -1.0 } else { 1.0 };
            q[j] = edge + away * 0.02 * rng.f64();
            qd[j] = away * lim.velocity[j] * (0.1 + 0.4 * rng.f64());
            let t_hit = 0.3 + 0.4 * rng.f64();
            let end = JointState {
                q: q.clone(),
                qd: qd.clone(),
                qdd: vec![0.0; q.len()],
            };
            if !inside(&JointTrajectory::quintic_unchecked(&start, &end, t_hit), lim) {
                overshooting_quintics += 1;
            }
            if let Some(leg) = hit_leg(&start, &q, &qd, t_hit, lim) {
                accepted += 1;
                assert!(
                    leg.trajectory.position_violations(lim, 0.0).is_empty(),
                    "{:?} leg leaves the position limits",
                    leg.profile
                );
            }
        }
        assert!(
            accepted >= 10 && overshooting_quintics > 100,
            "{accepted} accepted, {overshooting_quintics} overshooting quintics"
        );
    }

    #[test]
    fn rest_bound_is_below_ruckig_and_tight_for_a_large_jerk_limit() {
        let mut rng = fastrand::Rng::with_seed(3);
        let (v, a) = (2.0, 20.0);
        let (mut worst_gap, mut cases) = (0.0f64, 0);
        for _ in 0..2000 {
            let delta = 2.0 * (2.0 * rng.f64() - 1.0);
            let v1 = v * (2.0 * rng.f64() - 1.0);
            let bound = min_time_from_rest(delta, v1, v, a);
            for (jerk, tight) in [(2000.0, false), (2e6, true)] {
                let lim = KinematicLimits::new(&[v], &[a], &[jerk]).unwrap();
                let end = JointState {
                    q: vec![delta],
                    qd: vec![v1],
                    qdd: vec![0.0],
                };
                let t = jerk_limited(&JointState::rest(&[0.0]), &end, &lim, None, PositionLimits::Ignore)
                    .unwrap()
                    .duration;
                assert!(
                    bound <= t * (1.0 + 1e-9),
                    "bound {bound} above Ruckig {t} ({delta}, {v1})"
                );
                if tight {
                    worst_gap = worst_gap.max(t - bound);
                    cases += 1;
                }
            }
        }
        assert!(cases == 2000 && worst_gap < 1e-3, "largest gap {worst_gap} s");
        assert_eq!(min_time_from_rest(0.5, 3.0, v, a), f64::INFINITY);
    }

    #[test]
    fn scaled_leg_keeps_its_scaled_limits_and_reaches_the_hit_on_time() {
        let (pl, mut rng) = rig(8);
        let lim = pl.robot.limits();
        let (mut some, mut none) = (0, 0);
        let start = JointState::rest(&pl.ready);
        for _ in 0..300 {
            let q = around(&pl.ready, 0.4, &mut rng);
            let qd: Vec<f64> = lim.velocity.iter().map(|v| 0.5 * v * (2.0 * rng.f64() - 1.0)).collect();
            let t_hit = 0.2 + 0.4 * rng.f64();
            let scale = 0.2 + 0.8 * rng.f64();
            let Some(leg) = scaled_jerk_leg(&start, &q, &qd, t_hit, lim, scale, f64::NEG_INFINITY) else {
                none += 1;
                continue;
            };
            some += 1;
            assert!((leg.trajectory.duration() - t_hit).abs() <= DURATION_TOLERANCE);
            let acc = leg.trajectory.peaks(2).unwrap();
            for (j, p) in acc.iter().enumerate() {
                assert!(p.value.abs() <= scale * lim.acceleration[j] * (1.0 + 1e-9), "joint {j}");
            }
            assert!(leg.trajectory.check_limits(lim).unwrap().is_empty());
            // Gentler limits leave less of the time unused than the full ones.
            if let Some(full) = scaled_jerk_leg(&start, &q, &qd, t_hit, lim, 1.0, f64::NEG_INFINITY) {
                assert!(leg.margin <= full.margin + 1e-12);
            }
        }
        assert!(some > 20 && none > 20, "{some} legs, {none} none");
        let start = JointState::rest(&pl.ready);
        assert!(scaled_jerk_leg(&start, &pl.ready, &[0.0; 6], 0.3, lim, 0.0, f64::NEG_INFINITY).is_none());
    }
}
