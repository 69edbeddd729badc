//! The correction of a planned hit with a newer estimate, during its stroke: the hit points
//! nearest in time to the planned one, to the planned landing point, from the stroke's state.
//!
//! A correction is small (the newer estimate moves the ball by centimetres, the hit time by a few
//! ms), so the hit planned before is the best first guess: the candidates of the new prediction
//! (`candidate_states`) are tried nearest in time to it first, to its landing point, and the
//! search stops at the first feasible hit with a margin of at least `good_margin`, or once
//! `candidates` have been tried with some hit among them (up to 12 without one). No fallback
//! targets: the landing point planned before already has a placeable racket near there.

use super::super::flight::BallState;
use super::super::reach::walk_after_bounce_clip;
use super::candidates::NET_CLIP;
use super::search::{Begin, Search, Shot};
use super::{RacketPoses, ReturnHit, ReturnPlan, ReturnPlanner, ReturnStatus};
use crate::error::{check_finite, Result};
use crate::hit::Hit;
use crate::traj::JointState;
use nalgebra::{IsometryMatrix3, Vector3};

/// Most candidates a correction tries when none of the nearest `candidates` is feasible.
const MOST_CANDIDATES: usize = 12;

/// Largest difference (m/s) of a re-planned shot's outgoing velocity from the held hit's for the
/// same return time: a newer estimate moves the shot by a few cm/s, the return times' shots are
/// more than 1 m/s apart (their flight times differ by 0.25 s over ≈ 3 m).
const SAME_SHOT: f64 = 0.5;

impl ReturnPlanner {
    /// Plans the hit of the ball `ball` again for a stroke in the joint state `start` at `now`
    /// (s), near the hit `previous` planned before for the time `t_prev` (s, absolute): see the
    /// module doc. `after_bounce` says that `ball` is past its bounce on the robot's half.
    pub fn plan_near(
        &self,
        ball: &BallState,
        now: f64,
        start: &JointState,
        after_bounce: bool,
        previous: &ReturnHit,
        t_prev: f64,
    ) -> Result<ReturnPlan> {
        let goal = [previous.landing.x, previous.landing.y];
        check_finite("t_prev", &[t_prev])?;
        let (list, mut search) = match self.begin(ball, now, goal, start, after_bounce)? {
            Begin::Done(plan) => return Ok(plan),
            Begin::Search(list, search) => (list, search),
        };
        let mut order: Vec<usize> = (0..list.len()).collect();
        order.sort_by(|&a, &b| (list[a].t - t_prev).abs().total_cmp(&(list[b].t - t_prev).abs()));
        order.truncate(MOST_CANDIDATES);
        let poses = RacketPoses::new(self);
        let deadline = search.deadline;
        let robot = |s: &BallState, shot: Shot| {
            let near = self.robot_hit_near(&poses, s, now, start, shot, &previous.branch.q);
            near.or_else(|| self.robot_hit(&poses, s, now, start, shot, deadline))
        };
        for &i in &order {
            if search.deadline.abandoned()
                || search.best.is_some() && (search.good() || search.tried() >= self.candidates.max(1))
            {
                break;
            }
            search.attempt(self, &list[i], goal, &robot);
        }
        Ok(search.finish())
    }

    /// The hit `previous`, planned before for the absolute time `t_prev` (s), planned again without
    /// a search for a newer estimate `ball` and a stroke in the joint state `start` at `now` (s):
    /// the one candidate at `t_prev` (the ball predicted there, through its bounce on the robot's
    /// half; `after_bounce`: `ball` is past it), shot to `previous`'s landing point (the return
    /// times in order), the racket through the IK branch nearest `previous`'s (the joints' ranges
    /// as unit; no other pose is tried). For a decision that came too late for its splice: the
    /// same hit, where and when, from the newest observations, at a fraction of a search's cost.
    /// `NoBounce` when the new prediction does not bounce on the robot's half, `OutOfReach` when
    /// it has no free flight after the bounce at `t_prev` or `t_prev` is not after `now`,
    /// `Infeasible`/`NoReturn` as [`ReturnPlanner::plan_from`].
    pub fn plan_same_hit(
        &self,
        ball: &BallState,
        now: f64,
        start: &JointState,
        after_bounce: bool,
        previous: &ReturnHit,
        t_prev: f64,
    ) -> Result<ReturnPlan> {
        let goal = [previous.landing.x, previous.landing.y];
        check_finite("t_prev", &[t_prev])?;
        self.check_inputs(ball, now, goal, start)?;
        self.flight.check_span("t_prev", ball, t_prev)?;
        let none = |status| {
            Ok(ReturnPlan {
                status,
                hit: None,
                candidates: 0,
                alternatives: Vec::new(),
            })
        };
        // The last sample after the bounce at or before `t_prev`, then on to `t_prev` exactly.
        let mut before: Option<BallState> = None;
        let bounced = walk_after_bounce_clip(&self.flight, ball, 0.01, after_bounce, NET_CLIP, |s| {
            let on = s.t <= t_prev;
            if on {
                before = Some(*s);
            }
            on
        });
        if !bounced {
            return none(ReturnStatus::NoBounce);
        }
        let at = match before {
            Some(b) if t_prev > now && t_prev - b.t < 0.02 => match self.flight.advance(&b, t_prev, None) {
                (s, None) => s,
                (_, Some(_)) => return none(ReturnStatus::OutOfReach),
            },
            _ => return none(ReturnStatus::OutOfReach),
        };
        let mut search = Search::new(self);
        let poses = RacketPoses::new(self);
        let robot = |s: &BallState, shot: Shot| self.robot_hit_near(&poses, s, now, start, shot, &previous.branch.q);
        search.attempt_shots(&at, self.held_shot_first(&at, goal, &previous.v_out), &robot);
        Ok(search.finish())
    }

    /// The shots of the ball `s` to `goal` over the return times, the first whose outgoing
    /// velocity is within `SAME_SHOT` of `v_held` (m/s, world: the held hit's shot, the same
    /// return time) first, then the others in order; in order when none is. Each shot is solved
    /// when asked for, so a held hit of the first return time costs no more than the order.
    fn held_shot_first<'a>(
        &'a self,
        s: &'a BallState,
        goal: [f64; 2],
        v_held: &'a Vector3<f64>,
    ) -> impl Iterator<Item = Shot> + 'a {
        let mut times = self.return_times.iter();
        // Shots solved before the held one was found, in order.
        let mut before: Vec<Shot> = Vec::new();
        let mut found = false;
        std::iter::from_fn(move || {
            while !found {
                let Some(&tf) = times.next() else {
                    found = true;
                    break;
                };
                if let Some(shot) = self.outgoing(s, goal, tf) {
                    if (shot.0 - v_held).norm() < SAME_SHOT {
                        found = true;
                        return Some(shot);
                    }
                    before.push(shot);
                }
            }
            if !before.is_empty() {
                return Some(before.remove(0));
            }
            times.by_ref().find_map(|&tf| self.outgoing(s, goal, tf))
        })
    }

    /// The robot hit of the shot `shot` (outgoing velocity, racket, landing point) at the ball `s`
    /// through the IK branch nearest to `q_prev` (the joints' ranges as unit) over the racket
    /// centres and rolls, or `None` when that branch's stroke is not feasible: the joints are on
    /// their way to `q_prev`, so the nearest branch is the one to keep.
    fn robot_hit_near(
        &self,
        poses: &RacketPoses,
        s: &BallState,
        now: f64,
        start: &JointState,
        shot: Shot,
        q_prev: &[f64],
    ) -> Option<ReturnHit> {
        let (v_out, racket, landing) = shot;
        let lim = self.limits();
        let distance = |q: &[f64]| -> f64 {
            (0..q.len())
                .map(|i| {
                    let range = lim.upper[i] - lim.lower[i];
                    let d = q[i] - q_prev[i];
                    if range.is_finite() && range > 0.0 {
                        (d / range).powi(2)
                    } else {
                        d * d
                    }
                })
                .sum()
        };
        let mut nearest: Option<(f64, Vec<f64>, IsometryMatrix3<f64>)> = None;
        let (centres, count) = self.racket_centres(&s.p, &racket.normal);
        for c in &centres[..count] {
            for roll in 0..poses.rolls() {
                let pose = poses.pose(c, &racket.normal, roll);
                for q in self.robot.branches(&pose, Some(&start.q)).iter() {
                    let d = distance(q);
                    if nearest.as_ref().is_none_or(|(best, _, _)| d < *best) {
                        nearest = Some((d, q.to_vec(), pose));
                    }
                }
            }
        }
        let (_, q, pose) = nearest?;
        let hit = Hit {
            pose,
            twist: self.base_twist(&racket.velocity),
            t: s.t - now,
        };
        let twist = self.robot.tool_twist(&hit);
        let branch = self
            .robot
            .branch_leg_to(&q, start, &twist, hit.t, &self.ready, f64::NEG_INFINITY)?;
        Some(ReturnHit {
            ball: *s,
            v_out,
            racket,
            hit,
            branch,
            landing,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ball::flight::Flight;
    use crate::ball::rally;

    #[test]
    fn the_held_shot_comes_first_then_the_others_in_order() {
        let pl = ReturnPlanner::new(crate::robots::gantry6(), Flight::default()).unwrap();
        let mut rng = fastrand::Rng::with_seed(33);
        let mut reordered = 0;
        for _ in 0..20 {
            let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
            let (s, _) = pl.flight.run(&s, 0.22, None);
            let Some(hit) = pl.plan(&s, 0.23, [0.9, 0.0]).unwrap().hit else {
                continue;
            };
            let (b, goal) = (hit.ball, [hit.landing.x, hit.landing.y]);
            let shots: Vec<Shot> = pl
                .return_times
                .iter()
                .filter_map(|&tf| pl.outgoing(&b, goal, tf))
                .collect();
            // The return times' shots are far apart: a held shot matches one of them only.
            for (i, a) in shots.iter().enumerate() {
                for c in &shots[i + 1..] {
                    assert!((a.0 - c.0).norm() > 2.0 * SAME_SHOT, "{} {}", a.0, c.0);
                }
            }
            let v_out = |order: Vec<Shot>| order.iter().map(|s| s.0).collect::<Vec<_>>();
            let in_order = v_out(shots.clone());
            // No held shot among them: the return times in order.
            let far = hit.v_out + Vector3::new(0.0, 0.0, 10.0);
            assert_eq!(v_out(pl.held_shot_first(&b, goal, &far).collect()), in_order);
            for (k, held) in shots.iter().enumerate() {
                // a held shot a newer estimate moved a little
                let near = held.0 + Vector3::new(0.1, -0.1, 0.1);
                let mut want = in_order.clone();
                let first = want.remove(k);
                want.insert(0, first);
                assert_eq!(v_out(pl.held_shot_first(&b, goal, &near).collect()), want, "held {k}");
                reordered += usize::from(k > 0);
            }
        }
        assert!(reordered >= 5, "{reordered} held shots after the first return time");
    }
}
