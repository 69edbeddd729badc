//! Jerk-limited, time-optimal joint trajectories between arbitrary states: from a start state
//! (position, velocity, acceleration) to a target state, every joint within its velocity,
//! acceleration and jerk limits, all joints synchronised to finish together, optionally not before
//! a minimum duration (the hit time).
//!
//! The profiles are Ruckig's (Berscheid & Kröger, "Jerk-limited real-time trajectory generation
//! with arbitrary target states", RSS 2021): per joint up to seven phases of constant jerk, the
//! time-optimal duration found over every profile family, then the joints synchronised in time
//! (the slower joints' blocked intervals respected). The solver is the pure-Rust port
//! `rsruckig`; `docs/strokes.md` records why it was picked over the `ruckig` crate (a wrapper
//! of the C++ core) and how its durations compare with Python `ruckig` on the same problems.
//!
//! The result is a [`JointTrajectory`]: the union of every joint's phase boundaries becomes the
//! knot vector, and on each segment every joint is a cubic in local time (constant jerk). So the
//! exact limit checks, sampling and concatenation of [`super`] apply unchanged.

use rsruckig::prelude::{IgnoreErrorHandler, InputParameter, Ruckig, RuckigResult, Trajectory};

use super::limits::KinematicLimits;
use super::poly::Coeffs;
use super::{JointState, JointTrajectory};
use crate::error::{Error, Result};

/// Knots closer than this (s, relative to the duration) are merged.
const KNOT_MERGE: f64 = 1e-12;

/// A jerk-limited trajectory and the time-optimal duration of the same problem.
#[derive(Debug, Clone, PartialEq)]
pub struct JerkLimited {
    /// The trajectory, from 0 s to its duration (≥ the requested minimum duration).
    pub trajectory: JointTrajectory,
    /// Duration of the planned trajectory (s).
    pub duration: f64,
}

/// Whether Ruckig should keep the trajectory inside the position limits of `limits` (rsruckig's
/// own position-limit extension) or ignore them (the caller checks them afterwards).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PositionLimits {
    /// Plan without position limits (Ruckig community behaviour).
    Ignore,
    /// Keep every joint inside [lower, upper] (finite limits only).
    Respect,
}

/// The jerk-limited, time-optimal trajectory from `start` to `end` (rad or m, per s, per s²)
/// within the velocity, acceleration and jerk limits of `limits` (all finite), lasting at least
/// `minimum_duration` s when given (the trajectory then reaches `end` exactly at that time if
/// it can, otherwise at the earliest later time it can). Errors name the argument: a start or
/// end state outside the limits where no trajectory exists, non-finite limits, or a solver
/// failure.
pub fn jerk_limited(
    start: &JointState,
    end: &JointState,
    limits: &KinematicLimits,
    minimum_duration: Option<f64>,
    position: PositionLimits,
) -> Result<JerkLimited> {
    let stroke = Stroke::checked(start, end, limits, minimum_duration, position)?;
    stroke.solve_sized(true).map(|(duration, trajectory)| JerkLimited {
        trajectory: trajectory.expect("built"),
        duration,
    })
}

/// The duration (s) of [`jerk_limited`]'s trajectory for the same arguments and errors, without
/// building the trajectory (the hit leg's time-optimal bound).
pub fn jerk_limited_duration(
    start: &JointState,
    end: &JointState,
    limits: &KinematicLimits,
    minimum_duration: Option<f64>,
    position: PositionLimits,
) -> Result<f64> {
    let stroke = Stroke::checked(start, end, limits, minimum_duration, position)?;
    stroke.solve_sized(false).map(|(duration, _)| duration)
}

/// The arguments of [`jerk_limited`] after its checks.
struct Stroke<'a> {
    start: &'a JointState,
    end: &'a JointState,
    limits: &'a KinematicLimits,
    minimum_duration: Option<f64>,
    position: PositionLimits,
}

thread_local! {
    /// A 6-joint Ruckig solver and trajectory reused across calls (building them costs about as
    /// much as a solve; `calculate` keeps no state between problems).
    static SIX: std::cell::RefCell<Option<(Ruckig<6, IgnoreErrorHandler>, Trajectory<6>)>> =
        const { std::cell::RefCell::new(None) };
}

impl<'a> Stroke<'a> {
    /// The checks of [`jerk_limited`].
    fn checked(
        start: &'a JointState,
        end: &'a JointState,
        limits: &'a KinematicLimits,
        minimum_duration: Option<f64>,
        position: PositionLimits,
    ) -> Result<Self> {
        let n = start.check_pair("start", end, "end")?;
        limits.check_dof(n)?;
        for (what, v) in [
            ("velocity limits", &limits.velocity),
            ("acceleration limits", &limits.acceleration),
            ("jerk limits", &limits.jerk),
        ] {
            if let Some(j) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::invalid(
                    what,
                    format!("joint {j}: a jerk-limited stroke needs a finite limit, got {}", v[j]),
                ));
            }
        }
        if let Some(d) = minimum_duration {
            super::check_duration("minimum_duration", d)?;
        }
        Ok(Stroke {
            start,
            end,
            limits,
            minimum_duration,
            position,
        })
    }

    /// [`jerk_limited`] after the checks: the duration and, when `build`, the trajectory, with
    /// Ruckig's data on the stack for `N` > 0 joints (heap for `N` = 0, any count; the 6-joint
    /// solver reused per thread).
    /// [`Stroke::solve`] on Ruckig's fixed-size solver for 6 joints, its dynamic one otherwise.
    fn solve_sized(&self, build: bool) -> Result<(f64, Option<JointTrajectory>)> {
        match self.start.q.len() {
            6 => self.solve::<6>(build),
            _ => self.solve::<0>(build),
        }
    }

    fn solve<const N: usize>(&self, build: bool) -> Result<(f64, Option<JointTrajectory>)> {
        let n = self.start.q.len();
        let dofs = if N == 0 { Some(n) } else { None };
        let mut input = InputParameter::<N>::new(dofs);
        for j in 0..n {
            input.current_position[j] = self.start.q[j];
            input.current_velocity[j] = self.start.qd[j];
            input.current_acceleration[j] = self.start.qdd[j];
            input.target_position[j] = self.end.q[j];
            input.target_velocity[j] = self.end.qd[j];
            input.target_acceleration[j] = self.end.qdd[j];
            input.max_velocity[j] = self.limits.velocity[j];
            input.max_acceleration[j] = self.limits.acceleration[j];
            input.max_jerk[j] = self.limits.jerk[j];
        }
        input.minimum_duration = self.minimum_duration;
        if self.position == PositionLimits::Respect {
            let mut lo = input.current_position.clone();
            let mut hi = input.current_position.clone();
            for j in 0..n {
                lo[j] = if self.limits.lower[j].is_finite() {
                    self.limits.lower[j]
                } else {
                    -1e12
                };
                hi[j] = if self.limits.upper[j].is_finite() {
                    self.limits.upper[j]
                } else {
                    1e12
                };
            }
            input.min_position = Some(lo);
            input.max_position = Some(hi);
        }
        if N == 6 {
            // Same code as below on the thread's reused solver (N = 6 here, so the casts hold).
            let input6: &InputParameter<6> = as_six(&input);
            return SIX.with(|cell| {
                let mut slot = cell.borrow_mut();
                let (otg, traj) = slot.get_or_insert_with(|| {
                    (
                        Ruckig::<6, IgnoreErrorHandler>::new(None, 1e-3),
                        Trajectory::<6>::new(None),
                    )
                });
                let result = otg.calculate(input6, traj);
                finish::<6>(result, traj, n, build)
            });
        }
        let mut otg = Ruckig::<N, IgnoreErrorHandler>::new(dofs, 1e-3);
        let mut traj = Trajectory::<N>::new(dofs);
        let result = otg.calculate(&input, &mut traj);
        finish::<N>(result, &traj, n, build)
    }
}

/// `input` as the 6-joint type when `N` = 6 (the same type then).
fn as_six<const N: usize>(input: &InputParameter<N>) -> &InputParameter<6> {
    (input as &dyn std::any::Any)
        .downcast_ref::<InputParameter<6>>()
        .expect("N = 6")
}

/// The duration and (when `build`) the trajectory of a Ruckig result, or the error it means.
fn finish<const N: usize>(
    result: std::result::Result<RuckigResult, rsruckig::prelude::RuckigError>,
    traj: &Trajectory<N>,
    n: usize,
    build: bool,
) -> Result<(f64, Option<JointTrajectory>)> {
    {
        let result = result.map_err(|e| Error::invalid("jerk-limited stroke", format!("{e:?}")))?;
        match result {
            RuckigResult::Working | RuckigResult::Finished => {}
            RuckigResult::ErrorPositionalLimits => {
                return Err(Error::invalid(
                    "position limits",
                    "no jerk-limited trajectory between these states stays inside the position limits",
                ))
            }
            other => {
                return Err(Error::invalid(
                    "jerk-limited stroke",
                    format!(
                        "no trajectory within the velocity, acceleration and jerk limits reaches the target state \
                         ({other:?}): is the target velocity or acceleration beyond the limits?"
                    ),
                ))
            }
        }
        let duration = traj.get_duration();
        if !(duration > 0.0) || !duration.is_finite() {
            return Err(Error::invalid(
                "jerk-limited stroke",
                format!("the solver returned a duration of {duration} s"),
            ));
        }
        Ok((duration, build.then(|| to_joint_trajectory::<N>(traj, n, duration))))
    }
}

/// Converts Ruckig's per-joint phase profiles into one piecewise-cubic [`JointTrajectory`] on
/// the union of the phase boundaries.
fn to_joint_trajectory<const N: usize>(traj: &Trajectory<N>, n: usize, duration: f64) -> JointTrajectory {
    let profiles = &traj.get_profiles()[0];
    let mut knots = Vec::with_capacity(9 * n + 2);
    knots.push(0.0);
    for j in 0..n {
        let p = &profiles[j];
        let brake = p.brake.duration;
        if brake > 0.0 {
            knots.push(p.brake.t[0]);
            knots.push(brake);
        }
        knots.extend(p.t_sum.iter().map(|t| brake + t));
    }
    knots.retain(|t| *t > 0.0 && *t < duration);
    knots.push(0.0);
    knots.push(duration);
    knots.sort_by(f64::total_cmp);
    knots.dedup_by(|b, a| *b - *a <= KNOT_MERGE * duration);
    let last = knots.len() - 1;
    knots[last] = duration;
    if knots.len() >= 3 && knots[last] - knots[last - 1] <= KNOT_MERGE * duration {
        knots.remove(last - 1);
    }

    let mut p = input_vec::<N>(n);
    let mut v = input_vec::<N>(n);
    let mut a = input_vec::<N>(n);
    let mut jerk = input_vec::<N>(n);
    let mut coeffs: Vec<Coeffs> = Vec::with_capacity((knots.len() - 1) * n);
    for w in knots.windows(2) {
        let (t0, t1) = (w[0], w[1]);
        // The state at the segment start (continuous across phases) and the jerk inside it.
        let mut section = None;
        traj.at_time(
            t0,
            &mut Some(&mut p),
            &mut Some(&mut v),
            &mut Some(&mut a),
            &mut None,
            &mut section,
        );
        traj.at_time(
            0.5 * (t0 + t1),
            &mut None,
            &mut None,
            &mut None,
            &mut Some(&mut jerk),
            &mut section,
        );
        for j in 0..n {
            coeffs.push([p[j], v[j], 0.5 * a[j], jerk[j] / 6.0, 0.0, 0.0]);
        }
    }
    JointTrajectory::from_parts(n, knots, coeffs)
}

fn input_vec<const N: usize>(n: usize) -> rsruckig::prelude::DataArrayOrVec<f64, N> {
    rsruckig::prelude::DataArrayOrVec::new(if N == 0 { Some(n) } else { None }, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> KinematicLimits {
        KinematicLimits::new(&[3.0, 10.0], &[20.0, 100.0], &[1000.0, 5000.0]).unwrap()
    }

    #[test]
    fn rest_to_rest_reaches_target_within_limits() {
        let s = JointState::rest(&[0.0, 0.0]);
        let e = JointState::rest(&[0.5, -1.0]);
        let r = jerk_limited(&s, &e, &limits(), None, PositionLimits::Ignore).unwrap();
        let end = r.trajectory.state(r.duration).unwrap();
        for j in 0..2 {
            assert!((end.q[j] - e.q[j]).abs() < 1e-9, "{end:?}");
            assert!(end.qd[j].abs() < 1e-9 && end.qdd[j].abs() < 1e-9);
        }
        assert!(r.trajectory.check_limits(&limits()).unwrap().is_empty());
    }

    #[test]
    fn moving_target_is_met_exactly_at_the_minimum_duration() {
        let s = JointState::rest(&[0.0, 0.3]);
        let e = JointState {
            q: vec![0.4, -0.5],
            qd: vec![2.0, -6.0],
            qdd: vec![0.0, 0.0],
        };
        let fastest = jerk_limited(&s, &e, &limits(), None, PositionLimits::Ignore).unwrap();
        let want = fastest.duration * 1.3;
        let r = jerk_limited(&s, &e, &limits(), Some(want), PositionLimits::Ignore).unwrap();
        assert!((r.duration - want).abs() < 1e-9, "{} vs {want}", r.duration);
        let end = r.trajectory.state(r.duration).unwrap();
        for j in 0..2 {
            assert!((end.q[j] - e.q[j]).abs() < 1e-8);
            assert!((end.qd[j] - e.qd[j]).abs() < 1e-8);
            assert!(end.qdd[j].abs() < 1e-7);
        }
        assert!(r.trajectory.check_limits(&limits()).unwrap().is_empty());
        // The stretched one cannot be faster than the time-optimal one.
        assert!(fastest.duration <= r.duration);
    }

    #[test]
    fn duration_alone_is_the_built_trajectory_s() {
        let lim = KinematicLimits::new(&[2.0; 6], &[20.0; 6], &[4000.0; 6]).unwrap();
        let mut rng = fastrand::Rng::with_seed(11);
        for k in 0..200 {
            let r = |rng: &mut fastrand::Rng, a: f64| (0..6).map(|_| a * (2.0 * rng.f64() - 1.0)).collect::<Vec<f64>>();
            let s = JointState::rest(&r(&mut rng, 1.0));
            let e = JointState {
                q: r(&mut rng, 1.0),
                qd: r(&mut rng, 1.5),
                qdd: vec![0.0; 6],
            };
            let min = (k % 2 == 1).then(|| 0.5 + rng.f64());
            let alone = jerk_limited_duration(&s, &e, &lim, min, PositionLimits::Ignore).unwrap();
            let full = jerk_limited(&s, &e, &lim, min, PositionLimits::Ignore).unwrap();
            assert_eq!(alone.to_bits(), full.duration.to_bits(), "problem {k}");
        }
    }

    #[test]
    fn infinite_jerk_limit_is_an_error_naming_it() {
        let l = KinematicLimits::new(&[3.0], &[20.0], &[f64::INFINITY]).unwrap();
        let s = JointState::rest(&[0.0]);
        let e = JointState::rest(&[1.0]);
        let err = jerk_limited(&s, &e, &l, None, PositionLimits::Ignore).unwrap_err();
        assert!(err.to_string().contains("jerk limits"), "{err}");
    }

    #[test]
    fn target_speed_beyond_the_limit_is_an_error() {
        let s = JointState::rest(&[0.0, 0.0]);
        let e = JointState {
            q: vec![0.4, 0.0],
            qd: vec![5.0, 0.0],
            qdd: vec![0.0, 0.0],
        };
        assert!(jerk_limited(&s, &e, &limits(), None, PositionLimits::Ignore).is_err());
    }
}
