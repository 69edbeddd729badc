//! Hit-point candidates of the hit planner: the predicted ball every 10 ms in the hitting volume,
//! and the cheap placement test that skips the ones no racket reaches before the shooting solve.

use super::super::flight::{BallState, Flight};
use super::super::reach::{walk_after_bounce_clip, Reach};
use super::{RacketPoses, ReturnPlanner};
use nalgebra::Vector3;

impl ReturnPlanner {
    /// Predicted states every 10 ms inside the hitting volume after the bounce on the robot's half
    /// (a ball clipping the net flies on; only those at most `LATEST_AFTER_BOUNCE` after it when there are any, and not on a re-plan
    /// after the bounce), and whether that bounce happens.
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
        let mut out: Vec<BallState> = Vec::new();
        let mut t_bounce = None;
        // A ball predicted to clip the net's top (within `NET_CLIP`) may clear it: the estimate
        // is that uncertain, and a stroke prepared for a net ball costs nothing.
        let bounced = walk_after_bounce_clip(f, ball, 0.01, after_bounce, NET_CLIP, |s| {
            let tb = *t_bounce.get_or_insert(s.t);
            // Past the latest early hit with an early one found, the rest would be cut below.
            if !after_bounce
                && s.t > tb + LATEST_AFTER_BOUNCE
                && out.first().is_some_and(|c| c.t <= tb + LATEST_AFTER_BOUNCE)
            {
                return false;
            }
            if s.t >= now + self.min_stroke_time && reach.contains(&s.p) {
                out.push(*s);
            }
            s.p.x >= self.reach.lo.x - 0.05
        });
        // Prefer hits soon after the bounce: the prediction's error across the flight grows with
        // the time since the bounce (the bounce turns the unobservable spin along the flight into
        // sideways speed), and the misses are the late hits (docs/ball.md).
        if let (Some(tb), false) = (t_bounce, after_bounce) {
            let early = out.partition_point(|s| s.t <= tb + LATEST_AFTER_BOUNCE);
            if early > 0 {
                out.truncate(early);
            }
        }
        (out, bounced)
    }

    /// The predicted states every 10 ms inside the hitting volume later than `LATEST_AFTER_BOUNCE`
    /// after the bounce on the robot's half, when [`Self::candidate_states`] cut them (some
    /// candidate was earlier); empty otherwise. The planner tries them only when no early
    /// candidate gives a feasible hit: a later hit leaves the stroke more time (less torque) and
    /// is missed more often (the prediction's error grows after the bounce), a better chance than
    /// none.
    pub(super) fn late_candidate_states(&self, f: &Flight, ball: &BallState, now: f64, margin: f64) -> Vec<BallState> {
        let reach = Reach {
            lo: self.reach.lo - Vector3::repeat(margin),
            hi: self.reach.hi + Vector3::repeat(margin),
        };
        let mut out: Vec<BallState> = Vec::new();
        let mut early = false;
        let mut t_bounce = None;
        walk_after_bounce_clip(f, ball, 0.01, false, NET_CLIP, |s| {
            let tb = *t_bounce.get_or_insert(s.t);
            if s.t >= now + self.min_stroke_time && reach.contains(&s.p) {
                if s.t <= tb + LATEST_AFTER_BOUNCE {
                    early = true;
                } else {
                    out.push(*s);
                }
            }
            s.p.x >= self.reach.lo.x - 0.05
        });
        if !early {
            out.clear();
        }
        out
    }

    /// Whether some roll of a racket with the frictionless, drag-free normal (along v_out − v_in,
    /// v_out the vacuum shot to `target` in the first return time) at the ball `s` has IK within the
    /// limits: a cheap test before the shooting solve.
    pub(super) fn roughly_placeable(&self, poses: &RacketPoses, s: &BallState, target: [f64; 2]) -> bool {
        let tf = self.return_times[0];
        let goal = Vector3::new(target[0], target[1], self.flight.model.radius);
        let g = Vector3::new(0.0, 0.0, -self.flight.model.gravity);
        let v_out = (goal - s.p - 0.5 * g * tf * tf) / tf;
        let n = (v_out - s.v).normalize();
        let (centres, count) = self.racket_centres(&s.p, &n);
        centres[..count]
            .iter()
            .any(|c| (0..poses.rolls()).any(|k| !self.robot.branches(&poses.pose(c, &n, k), None).is_empty()))
    }

    /// Landing targets (x, y, m, world) tried in order for a hit point: the requested `target`,
    /// then the points of `FALLBACK_TARGETS` by distance from it. A racket whose face must turn
    /// the ball toward the requested target may be beyond the joints (a ball wide of the table
    /// returned across it needs the carriage past its stroke) where a return along the line is not.
    pub(super) fn targets(&self, target: [f64; 2]) -> Vec<[f64; 2]> {
        let mut out = vec![target];
        let mut rest: Vec<[f64; 2]> = FALLBACK_TARGETS.iter().copied().filter(|t| *t != target).collect();
        let d = |t: &[f64; 2]| (t[0] - target[0]).hypot(t[1] - target[1]);
        rest.sort_by(|a, b| d(a).total_cmp(&d(b)));
        out.extend(rest);
        out
    }
}

/// Latest hit (s after the first predicted sample past the bounce) among the candidates when
/// some are that early: on seed 0 (3000 balls) the racket missed 0.7 % of the balls hit within
/// 0.25 s of the bounce, 2 % at 0.25–0.3 s, 3 % at 0.3–0.35 s, 11 % at 0.35–0.4 s; 0.25 s loses
/// more balls to the joints' time than it saves, 0.35 s saves fewer misses (docs/ball.md).
const LATEST_AFTER_BOUNCE: f64 = 0.3;

/// How far (m) below clearing the net's top a predicted ball may touch it and still be planned
/// for (flying on as if it cleared): the estimate's height error at the net, a few mm (velocity
/// error ≈ 0.025 m/s median over ≈ 0.2 s of flight plus the 2 mm camera noise), with margin. On
/// 10 000 balls of seed 0 the prediction stopped 19 in-reach balls at the net without it
/// (`no_bounce`; 9 before the flight checked the net's plane, when the 10 ms steps at times
/// passed through the net), none with it.
pub(super) const NET_CLIP: f64 = 0.02;

/// Fallback landing targets (x, y, m, world) on the opponent's half, at least 0.2 m inside its
/// end and side lines and 0.5 m past the net.
const FALLBACK_TARGETS: [[f64; 2]; 15] = [
    [0.9, 0.0],
    [0.9, 0.25],
    [0.9, -0.25],
    [0.9, 0.5],
    [0.9, -0.5],
    [0.6, 0.0],
    [0.6, 0.25],
    [0.6, -0.25],
    [0.6, 0.5],
    [0.6, -0.5],
    [1.15, 0.0],
    [1.15, 0.25],
    [1.15, -0.25],
    [1.15, 0.5],
    [1.15, -0.5],
];

/// Indices into a list of `len` candidates in the order tried: `first` evenly spread, middle of
/// the spread first (the likeliest to have the largest margin), then up to `max` evenly spread
/// (middle first), each index once.
pub(super) fn candidate_order(len: usize, first: usize, max: usize) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for count in [first.min(len), len.min(max.max(first))] {
        let mut spread: Vec<usize> = (0..count).collect();
        spread.sort_by_key(|&j| (2 * j + 1).abs_diff(count));
        for j in spread {
            let i = (2 * j + 1) * len / (2 * count);
            if !out.contains(&i) {
                out.push(i);
            }
        }
    }
    out
}
