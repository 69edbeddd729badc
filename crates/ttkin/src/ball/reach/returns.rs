//! The return conditions of the reachable region (items 2–5 of [`super`]'s doc): at one sample of
//! the incoming flight, the grid of return shots (drag-free parabola to a target in a return time,
//! the racket of the impact model, the real landing check) and, for each shot, the racket pose by
//! IK over the rolls, the joint velocity q̇ = J⁻¹·V and the minimum time from the ready
//! configuration.

use super::super::flight::{BallState, EventKind, Flight};
use super::super::impact::RacketAtImpact;
use super::{ReachRegion, Reachability};
use crate::ik::{joint_velocity, LimitFilter};
use nalgebra::{IsometryMatrix3, Translation3, Vector3};

/// RK4 step (s) of the return flight's landing check (the planner's step; 1 mm at the landing).
const RETURN_STEP: f64 = 0.01;

/// How far one ball got through the conditions, deepest first wins (ordered as checked).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Stage {
    /// No sample in the volume yet.
    Nothing,
    /// A sample in the volume, no shot of the grid returns the ball.
    InVolume,
    /// A return shot, no racket pose within the position limits.
    Shot,
    /// A racket pose, no q̇ within the velocity limits.
    Pose,
    /// A pose within the velocity limits, but too late for the time bound.
    Speed,
}

impl Stage {
    /// The verdict for a ball whose deepest stage is `self` after a bounce (no feasible point).
    pub(super) fn verdict(self) -> Reachability {
        match self {
            Stage::Nothing => Reachability::OutsideVolume,
            Stage::InVolume => Reachability::NoReturn,
            Stage::Shot => Reachability::NoReturnPose,
            Stage::Pose => Reachability::ReturnSpeed,
            Stage::Speed => Reachability::TooEarly,
        }
    }
}

impl ReachRegion {
    /// The return conditions at the sample `s` (inside the volume) for a stroke from rest at the
    /// ready configuration at `now` (s): the minimum joint time (s) of the first shot, pose and
    /// roll meeting all of them, or `None`, with `deepest` raised to the deepest stage reached.
    /// `flight` flies the return (its model and table; `RETURN_STEP`).
    pub(super) fn return_at(&self, flight: &Flight, s: &BallState, now: f64, deepest: &mut Stage) -> Option<f64> {
        let back = Flight {
            step: RETURN_STEP,
            ..*flight
        };
        let g = Vector3::new(0.0, 0.0, -flight.model.gravity);
        *deepest = (*deepest).max(Stage::InVolume);
        for target in &self.targets {
            let goal = Vector3::new(target[0], target[1], flight.model.radius);
            for &tf in &self.return_times {
                let v_out = (goal - s.p - 0.5 * g * tf * tf) / tf;
                let Ok(racket) = self.impact.solve(&flight.model, &s.v, &s.w, &v_out) else {
                    continue;
                };
                // The robot's conditions first (IK and J⁻¹V cost about a µs, the landing check a
                // flight); the landing decides only a shot that would deepen the verdict.
                let (stage, min_time) = self.shot_stage(s, &racket, now, *deepest);
                if stage <= *deepest && min_time.is_none() {
                    continue;
                }
                if !lands_on_opponent_half(&back, s, &v_out, &racket.spin_out, tf) {
                    continue;
                }
                *deepest = (*deepest).max(stage);
                if min_time.is_some() {
                    return min_time;
                }
            }
        }
        None
    }

    /// The robot's conditions for the shot `racket` at the sample `s`: the deepest stage over the
    /// rolls and IK branches (`Shot` when no pose is within the position limits) and, when one
    /// meets them all, its minimum joint time (s). J⁻¹V (the costly test) is skipped for a pose
    /// out of time once the stage it could show is reached (`deepest` or this shot's).
    fn shot_stage(&self, s: &BallState, racket: &RacketAtImpact, now: f64, deepest: Stage) -> (Stage, Option<f64>) {
        let base_from_world = self.placement.world_from_base().inverse();
        let v_b = base_from_world.rotation * racket.velocity;
        let twist = [v_b.x, v_b.y, v_b.z, 0.0, 0.0, 0.0];
        let n = racket.normal;
        let c0 = s.p - self.ball_radius * n;
        let across = Vector3::y() - n * n.y;
        let e = if across.norm() > 1e-6 {
            across.normalize()
        } else {
            Vector3::zeros()
        };
        let mut stage = Stage::Shot;
        for (&off, &roll) in self
            .contact_offsets
            .iter()
            .flat_map(|o| self.rolls.iter().map(move |r| (o, r)))
        {
            let c = c0 + off * e;
            let world = IsometryMatrix3::from_parts(Translation3::from(c), super::racket_rotation(&n, roll));
            let Ok(sols) = self
                .ik
                .solve(&(base_from_world * world), Some(&self.ready), LimitFilter::Enforce)
            else {
                continue;
            };
            for q in sols.iter() {
                stage = stage.max(Stage::Pose);
                let t = self.min_time(q);
                let in_time = t <= s.t - now;
                if !in_time && stage.max(deepest) >= Stage::Speed {
                    continue;
                }
                let Ok(jv) = joint_velocity(&self.chain, q, &twist) else {
                    continue;
                };
                if jv.singular || jv.qd.iter().zip(&self.limits.velocity).any(|(qd, v)| qd.abs() > *v) {
                    continue;
                }
                stage = Stage::Speed;
                if in_time {
                    return (stage, Some(t));
                }
            }
        }
        (stage, None)
    }
}

/// Whether the ball at `s` leaving with velocity `v` and spin `w` (world) first touches the table
/// on the opponent's half (over the net) within `tf` + 1 s of flight by `flight`.
fn lands_on_opponent_half(flight: &Flight, s: &BallState, v: &Vector3<f64>, w: &Vector3<f64>, tf: f64) -> bool {
    let out = BallState { v: *v, w: *w, ..*s };
    let (_, ev) = flight.advance(&out, s.t + tf + 1.0, None);
    ev.is_some_and(|e| e.kind == EventKind::Table && flight.table.on_opponent_half(e.before.p.x, e.before.p.y))
}
