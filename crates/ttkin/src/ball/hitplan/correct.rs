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
use super::super::impact::RacketHit;
use super::{Hit, HitPlan, HitPlanner, HitStatus, RacketPoses};
use crate::error::{Error, Result};
use crate::traj::JointState;
use nalgebra::{IsometryMatrix3, Vector3};

/// Most candidates a correction tries when none of the nearest `candidates` is feasible.
const MOST_CANDIDATES: usize = 12;

impl HitPlanner {
    /// Plans the hit of the ball `ball` again for a stroke in the joint state `start` at `now`
    /// (s), near the hit `previous` planned before for the time `t_prev` (s, absolute): see the
    /// module doc. `after_bounce` says that `ball` is past its bounce on the robot's half.
    pub fn plan_near(
        &self,
        ball: &BallState,
        now: f64,
        start: &JointState,
        after_bounce: bool,
        previous: &Hit,
        t_prev: f64,
    ) -> Result<HitPlan> {
        let goal = [previous.landing.x, previous.landing.y];
        self.check_target(goal)?;
        self.check_start(ball, start)?;
        if !(now.is_finite() && t_prev.is_finite()) {
            return Err(Error::invalid(
                "now, t_prev",
                format!("must be finite, got {now}, {t_prev}"),
            ));
        }
        let (list, bounced) = self.candidate_states(&self.flight, ball, now, self.search_margin, after_bounce);
        let status = match (bounced, list.is_empty()) {
            (false, _) => Some(HitStatus::NoBounce),
            (true, true) => Some(HitStatus::OutOfReach),
            _ => None,
        };
        if let Some(status) = status {
            return Ok(HitPlan {
                status,
                hit: None,
                candidates: 0,
            });
        }
        let mut order: Vec<usize> = (0..list.len()).collect();
        order.sort_by(|&a, &b| (list[a].t - t_prev).abs().total_cmp(&(list[b].t - t_prev).abs()));
        order.truncate(MOST_CANDIDATES);
        let poses = RacketPoses::new(self);
        let mut best: Option<Hit> = None;
        let mut any_return = false;
        let mut tried = 0;
        for &i in &order {
            if best
                .as_ref()
                .is_some_and(|b| b.margin >= self.good_margin || tried >= self.candidates.max(1))
            {
                break;
            }
            tried += 1;
            let s = &list[i];
            for &tf in &self.return_times {
                let Some((v_out, racket, landing)) = self.outgoing(s, goal, tf) else {
                    continue;
                };
                any_return = true;
                let near = self.robot_hit_near(&poses, s, now, start, (v_out, racket, landing), &previous.q_hit);
                let hit = near.or_else(|| self.robot_hit(&poses, s, now, start, v_out, racket, landing));
                if let Some(hit) = hit {
                    if best.as_ref().is_none_or(|b| hit.margin > b.margin) {
                        best = Some(hit);
                    }
                    break;
                }
            }
        }
        Ok(super::searched(best, any_return, tried))
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
        shot: (Vector3<f64>, RacketHit, Vector3<f64>),
        q_prev: &[f64],
    ) -> Option<Hit> {
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
        for c in &self.racket_centres(&s.p, &racket.normal) {
            for roll in 0..poses.rolls() {
                let pose = poses.pose(c, &racket.normal, roll);
                for q in self.branches(&pose, Some(&start.q)).iter() {
                    let d = distance(q);
                    if nearest.as_ref().is_none_or(|(best, _, _)| d < *best) {
                        nearest = Some((d, q.to_vec(), pose));
                    }
                }
            }
        }
        let (_, q, pose) = nearest?;
        let v_b = self.placement.world_from_base().rotation.inverse() * racket.velocity;
        let twist = [v_b.x, v_b.y, v_b.z, 0.0, 0.0, 0.0];
        let t_hit = s.t - now;
        let (qd, leg, margin) = self.stroke_margin(&q, start, &twist, t_hit, f64::NEG_INFINITY)?;
        Some(Hit {
            ball: *s,
            v_out,
            racket,
            pose,
            twist,
            t_hit,
            q_hit: q,
            qd_hit: qd,
            qdd_hit: leg.qdd_hit.clone(),
            leg,
            margin,
            landing,
        })
    }
}
