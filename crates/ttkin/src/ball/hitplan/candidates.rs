//! Hit-point candidates of the hit planner: the predicted ball every 10 ms in the hitting volume,
//! and the cheap placement test that skips the ones no racket reaches before the shooting solve.

use super::super::flight::{BallState, Flight};
use super::super::reach::{walk_after_bounce, Reach};
use super::HitPlanner;
use crate::ik::LimitFilter;
use nalgebra::Vector3;

impl HitPlanner {
    /// Predicted states every 10 ms inside the hitting volume after the bounce on the robot's half, and
    /// whether that bounce happens.
    pub(super) fn candidate_states(
        &self,
        f: &Flight,
        ball: &BallState,
        now: f64,
        margin: f64,
        after_bounce: bool,
    ) -> (Vec<BallState>, bool) {
        let reach = Reach {
            lo: self.reach.lo - Vector3::repeat(margin),
            hi: self.reach.hi + Vector3::repeat(margin),
        };
        let mut out = Vec::new();
        let bounced = walk_after_bounce(f, ball, 0.01, after_bounce, |s| {
            if s.t >= now + self.min_stroke_time && reach.contains(&s.p) {
                out.push(*s);
            }
            s.p.x >= self.reach.lo.x - 0.05
        });
        (out, bounced)
    }

    /// Whether some roll of a racket with the frictionless, drag-free normal (along v_out − v_in,
    /// v_out the vacuum shot to `target` in the first return time) at the ball `s` has IK within the
    /// limits: a cheap test before the shooting solve.
    pub(super) fn roughly_placeable(&self, s: &BallState, target: [f64; 2]) -> bool {
        let tf = self.return_times[0];
        let goal = Vector3::new(target[0], target[1], self.flight.model.radius);
        let g = Vector3::new(0.0, 0.0, -self.flight.model.gravity);
        let v_out = (goal - s.p - 0.5 * g * tf * tf) / tf;
        let n = (v_out - s.v).normalize();
        let c = s.p - self.flight.model.radius * n;
        self.rolls.iter().any(|&roll| {
            self.ik
                .solve(&self.base_pose_rolled(&c, &n, roll), None, LimitFilter::Enforce)
                .is_ok()
        })
    }
}
