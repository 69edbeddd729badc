//! The robot's side of a return: the racket placements of one shot (centres and rolls) as
//! [`crate::hit::Hit`]s handed to the robot-side planner ([`crate::hit::HitPlanner::best_leg`]),
//! and the best of them.

use super::super::flight::BallState;
use super::search::{Deadline, Shot};
use super::{RacketPoses, ReturnHit, ReturnPlanner};
use crate::hit::Hit;
use crate::traj::JointState;
use nalgebra::Vector3;

impl ReturnPlanner {
    /// The best robot hit (largest margin) of the shot `shot` at the ball `s` over the racket
    /// centres, the rolls about the face normal and (in the robot planner) every IK branch within
    /// the limits, for a stroke from `start` at `now` (s); `None` when none is feasible. Past the
    /// `deadline`, the first feasible pose ends the search.
    pub(super) fn robot_hit(
        &self,
        poses: &RacketPoses,
        s: &BallState,
        now: f64,
        start: &JointState,
        shot: Shot,
        deadline: Deadline,
    ) -> Option<ReturnHit> {
        let (v_out, racket, landing) = shot;
        let twist = self.base_twist(&racket.velocity);
        let t = s.t - now;
        let mut best: Option<ReturnHit> = None;
        let (centres, count) = self.racket_centres(&s.p, &racket.normal);
        for (k, roll) in (0..count).flat_map(|k| (0..poses.rolls()).map(move |r| (k, r))) {
            if best
                .as_ref()
                .is_some_and(|b| b.margin() >= self.good_margin || k > 0 || deadline.passed())
            {
                break;
            }
            let hit = Hit {
                pose: poses.pose(&centres[k], &racket.normal, roll),
                twist,
                t,
            };
            // Only a margin above the best so far can replace it.
            let floor = best.as_ref().map_or(f64::NEG_INFINITY, |b| b.margin());
            if let Some(branch) = self.robot.best_leg_to(&hit, start, &self.ready, floor) {
                best = Some(ReturnHit {
                    ball: *s,
                    v_out,
                    racket,
                    hit,
                    branch,
                    landing,
                });
            }
        }
        best
    }

    /// The racket-centre twist [v; 0] (base axes) of a racket moving with `velocity` (m/s, world)
    /// without turning.
    pub(super) fn base_twist(&self, velocity: &Vector3<f64>) -> [f64; 6] {
        let v_b = self.placement.world_from_base().rotation.inverse() * velocity;
        [v_b.x, v_b.y, v_b.z, 0.0, 0.0, 0.0]
    }

    /// Racket centres (m, world) for a ball centre `p` touching a face with normal `n`, in the
    /// order tried, and how many of the array's entries are used: the ball on the face centre,
    /// then moved by ±`contact_offset` in the face plane along its direction closest to world y
    /// (across the table, the carriage's d2 axis), for a ball just beyond the carriage's stroke;
    /// with `contact_offset_up` > 0 (the last resort, [`ReturnPlanner::last_resort_offsets`])
    /// also by ±`contact_offset_up` along the face plane's other direction (closest to world up).
    pub(super) fn racket_centres(&self, p: &Vector3<f64>, n: &Vector3<f64>) -> ([Vector3<f64>; 5], usize) {
        let c = p - self.flight.model.radius * n;
        let across = Vector3::y() - n * n.y;
        let (e, u) = if across.norm() > 1e-6 {
            let a = across.normalize();
            (
                a * self.contact_offset,
                n.cross(&a).normalize() * self.contact_offset_up,
            )
        } else {
            (Vector3::zeros(), Vector3::zeros())
        };
        let count = if self.contact_offset_up > 0.0 && u.norm() > 0.0 {
            5
        } else {
            3
        };
        ([c, c + e, c - e, c + u, c - u], count)
    }
}
