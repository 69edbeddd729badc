//! The robot's side of a hit: racket pose and twist in the base frame, IK branches, joint velocities
//! at the hit, the hit leg and the choice margin.

use super::super::flight::BallState;
use super::super::impact::RacketHit;
use super::super::leg::{hit_leg_above, HitLeg};
use super::super::reach::min_joint_time;
use super::{Hit, HitPlanner, RacketPoses};
use crate::chain::JacobianFrame;
use crate::dynamics::{DynamicsData, PeakStop};
use crate::ik::{joint_velocity, DifferentialIk, Solutions};
use crate::linalg::cholesky::factor_in_place;
use crate::traj::limits::LIMIT_TOLERANCE;
use crate::traj::{JointState, JointTrajectory};
use nalgebra::{IsometryMatrix3, Matrix6, Vector3, Vector6};

impl HitPlanner {
    /// The best robot hit (largest margin) over the racket rolls `rolls` about the face normal and
    /// every IK branch within the limits, or `None` when none is feasible.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn robot_hit(
        &self,
        poses: &RacketPoses,
        s: &BallState,
        now: f64,
        start: &JointState,
        v_out: Vector3<f64>,
        racket: RacketHit,
        landing: Vector3<f64>,
    ) -> Option<Hit> {
        let rot_bw = self.placement.world_from_base().rotation.inverse();
        let v_b = rot_bw * racket.velocity;
        let twist = [v_b.x, v_b.y, v_b.z, 0.0, 0.0, 0.0];
        let t_hit = s.t - now;
        let mut best: Option<Hit> = None;
        let centres = self.racket_centres(&s.p, &racket.normal);
        for (k, roll) in (0..centres.len()).flat_map(|k| (0..poses.rolls()).map(move |r| (k, r))) {
            if best.as_ref().is_some_and(|b| b.margin >= self.good_margin || k > 0) {
                break;
            }
            let pose = poses.pose(&centres[k], &racket.normal, roll);
            for q in self.branches(&pose, Some(&start.q)).iter() {
                // Only a margin above the best so far can replace it: no solves for the rest.
                let floor = best.as_ref().map_or(f64::NEG_INFINITY, |b| b.margin);
                let Some((qd, leg, margin)) = self.stroke_margin(q, start, &twist, t_hit, floor) else {
                    continue;
                };
                if best.as_ref().is_none_or(|b| margin > b.margin) {
                    best = Some(Hit {
                        ball: *s,
                        v_out,
                        racket,
                        pose,
                        twist,
                        t_hit,
                        q_hit: q.to_vec(),
                        qd_hit: qd,
                        qdd_hit: leg.qdd_hit.clone(),
                        leg,
                        margin,
                        landing,
                    });
                }
            }
        }
        best
    }

    /// Joint velocities at the hit, the hit leg ([`super::leg`]) and the margin of the stroke from
    /// `start` to the configuration `q` moving the racket with `twist` (base frame) after `t_hit`
    /// s, or `None` when it is singular, no leg is within the limits or the margin is at most
    /// `floor` (−∞: any margin).
    pub(super) fn stroke_margin(
        &self,
        q: &[f64],
        start: &JointState,
        twist: &[f64; 6],
        t_hit: f64,
        floor: f64,
    ) -> Option<(Vec<f64>, HitLeg, f64)> {
        let mut pos_margin = f64::INFINITY;
        for (i, &qi) in q.iter().enumerate() {
            let (lo, hi) = (self.limits.lower[i], self.limits.upper[i]);
            if lo.is_finite() && hi.is_finite() {
                pos_margin = pos_margin.min(2.0 * (qi - lo).min(hi - qi) / (hi - lo));
            }
        }
        if pos_margin <= floor || self.too_far(q, start, t_hit) {
            return None;
        }
        let qdot = self.hit_joint_velocity(q, twist)?;
        let lim = &self.limits;
        if qdot.iter().zip(&lim.velocity).any(|(qd, v)| qd.abs() > *v) {
            return None;
        }
        let leg = hit_leg_above(start, q, &qdot, t_hit, &self.limits, floor)?;
        if !self.within_effort(&leg.trajectory) {
            return None;
        }
        let margin = pos_margin.min(leg.margin);
        Some((qdot, leg, margin))
    }

    /// Whether `leg`'s torques (inverse dynamics with friction under world gravity, in the base
    /// frame) stay within the effective effort limits at every instant (certified,
    /// [`crate::dynamics::peak`]); true without dynamics or with `check_effort` off.
    pub(super) fn within_effort(&self, leg: &JointTrajectory) -> bool {
        let Some(dynamics) = self.dynamics.as_ref().filter(|_| self.check_effort) else {
            return true;
        };
        let mut data = DynamicsData::new(dynamics);
        let rot_bw = self.placement.world_from_base().rotation.inverse();
        let gravity = rot_bw * Vector3::from(crate::hit::GRAVITY);
        let threshold = 1.0 + LIMIT_TOLERANCE;
        let stop = PeakStop::decide(threshold, 1e-3);
        let peak = dynamics.effort_peak(&mut data, leg, &self.effort, &gravity, stop);
        peak.bound <= threshold
    }

    /// q̇ = J⁻¹·V (base frame) at `q` for the racket twist `twist`, or `None` where
    /// [`joint_velocity`] calls the Jacobian singular (σ_min below its default threshold): for six
    /// joints on the stack, the threshold test by a Cholesky of JᵀJ − threshold²·I and q̇ from an
    /// LU solve (the same q̇ to rounding as the damped-SVD solve away from singularities).
    pub(super) fn hit_joint_velocity(&self, q: &[f64], twist: &[f64; 6]) -> Option<Vec<f64>> {
        if q.len() != 6 {
            let jv = joint_velocity(&self.chain, q, twist).ok()?;
            return (!jv.singular).then_some(jv.qdot);
        }
        let j = self.chain.jacobian(q, JacobianFrame::Base).ok()?;
        let m = Matrix6::from_iterator(j.iter().copied());
        // σ_min ≥ t exactly when JᵀJ − t²·I is positive definite: a 6 × 6 Cholesky instead of
        // an SVD (with t = 1e-3 the shift t² = 1e-6 is ten orders above the rounding of JᵀJ).
        let t = DifferentialIk::default().threshold;
        let mut shifted = m.transpose() * m - Matrix6::identity() * (t * t);
        if !m.iter().all(|x| x.is_finite()) || factor_in_place(shifted.as_mut_slice(), 6).is_err() {
            return None;
        }
        let qdot = m.lu().solve(&Vector6::from_column_slice(twist))?;
        Some(qdot.iter().copied().collect())
    }

    /// Racket centres (m, world) for a ball centre `p` touching a face with normal `n`, in the
    /// order tried: the ball on the face centre, then moved by ±`contact_offset` in the face plane
    /// along its direction closest to world y (across the table, the carriage's d2 axis), for a
    /// ball just beyond the carriage's stroke.
    pub(super) fn racket_centres(&self, p: &Vector3<f64>, n: &Vector3<f64>) -> [Vector3<f64>; 3] {
        let c = p - self.flight.model.radius * n;
        let across = Vector3::y() - n * n.y;
        let e = if across.norm() > 1e-6 {
            across.normalize() * self.contact_offset
        } else {
            Vector3::zeros()
        };
        [c, c + e, c - e]
    }

    /// Whether some joint cannot reach `q` from `start` within `t_hit` s even at full acceleration
    /// then full speed with any arrival speed (the bound of [`super::super::reach`]): a cheap
    /// necessary test before the hit leg's solves, from rest only (false when `start` moves).
    fn too_far(&self, q: &[f64], start: &JointState, t_hit: f64) -> bool {
        if start.qd.iter().chain(&start.qdd).any(|x| *x != 0.0) {
            return false;
        }
        let lim = &self.limits;
        (0..q.len()).any(|i| min_joint_time(q[i] - start.q[i], lim.velocity[i], lim.acceleration[i]) > t_hit)
    }

    /// The analytic IK branches of the racket pose `pose` (base frame) within the joint position
    /// limits, revolute angles moved by 2πk into them where that fits (the branches and values of
    /// [`LimitFilter::Enforce`], without building its error message for the dropped ones: the
    /// search asks for thousands of poses beyond the strokes), on the stack.
    pub(super) fn branches(&self, pose: &IsometryMatrix3<f64>, hint: Option<&[f64]>) -> Solutions {
        let mut sols = self
            .ik
            .solve_quiet(pose, hint)
            .unwrap_or_else(|| Solutions::empty(self.chain.dof()));
        sols.retain_map(|_, i, q| self.fit(i, q));
        sols
    }

    /// Joint `i`'s value `q` inside its position limits ([`crate::ik::fit_to_range`]).
    fn fit(&self, i: usize, q: f64) -> Option<f64> {
        let kind = self.chain.joints()[i].kind();
        crate::ik::fit_to_range(q, kind, self.limits.lower[i], self.limits.upper[i])
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::flight::Flight;
    use super::*;
    use crate::ik::LimitFilter;
    use nalgebra::Vector3;

    #[test]
    fn hit_joint_velocity_matches_differential_ik() {
        let pl = HitPlanner::new(crate::robots::gantry6(), Flight::default()).unwrap();
        let mut rng = fastrand::Rng::with_seed(7);
        let (mut regular, mut singular) = (0, 0);
        let mut near = (0, 0);
        for k in 0..3000 {
            let mut q: Vec<f64> = pl.ready.iter().map(|x| x + 2.0 * rng.f64() - 1.0).collect();
            if k % 10 == 0 {
                q[3] = std::f64::consts::FRAC_PI_2 + 1e-5 * (rng.f64() - 0.5); // c4 ≈ 0: singular
            } else if k % 10 == 1 {
                // σ_min around the threshold (1e-3) on both sides.
                q[3] = std::f64::consts::FRAC_PI_2 + 10f64.powf(-4.0 + 2.0 * rng.f64()) * (rng.f64() - 0.5).signum();
            }
            let twist = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0].map(|_| 4.0 * rng.f64() - 2.0);
            let twist = [twist[0], twist[1], twist[2], 0.0, 0.0, 0.0];
            let jv = joint_velocity(&pl.chain, &q, &twist).unwrap();
            if (0.3e-3..3e-3).contains(&jv.sigma_min) {
                if jv.singular {
                    near.1 += 1;
                } else {
                    near.0 += 1;
                }
            }
            match pl.hit_joint_velocity(&q, &twist) {
                Some(qd) => {
                    regular += 1;
                    assert!(!jv.singular, "{q:?}");
                    for (a, b) in qd.iter().zip(&jv.qdot) {
                        assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "{qd:?} vs {:?}", jv.qdot);
                    }
                }
                None => {
                    singular += 1;
                    assert!(jv.singular, "{q:?} sigma_min {}", jv.sigma_min);
                }
            }
        }
        assert!(
            regular > 1000 && singular > 100,
            "{regular} regular, {singular} singular"
        );
        assert!(
            near.0 > 20 && near.1 > 20,
            "{near:?} regular / singular near the threshold"
        );
    }

    #[test]
    fn own_branch_filter_matches_the_ik_limit_filter() {
        let pl = HitPlanner::new(crate::robots::gantry6(), Flight::default()).unwrap();
        let mut rng = fastrand::Rng::with_seed(4);
        let (mut some, mut none) = (0, 0);
        for _ in 0..2000 {
            let p = Vector3::new(-3.1 + 2.0 * rng.f64(), -1.1 + 2.2 * rng.f64(), 0.0 + 0.5 * rng.f64());
            let (az, el) = (rng.f64() - 0.5, rng.f64() - 0.5);
            let n = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
            let pose = pl.base_pose_rolled(&p, &n, 2.0 * rng.f64() - 1.0);
            let hint = pl.ready.clone();
            let ours: Vec<Vec<f64>> = pl.branches(&pose, Some(&hint)).iter().map(|q| q.to_vec()).collect();
            match pl.ik.solve(&pose, Some(&hint), LimitFilter::Enforce) {
                Ok(sols) => {
                    some += 1;
                    let theirs: Vec<Vec<f64>> = sols.iter().map(|q| q.to_vec()).collect();
                    assert_eq!(ours, theirs);
                }
                Err(_) => {
                    none += 1;
                    assert!(ours.is_empty());
                }
            }
        }
        assert!(some > 100 && none > 100, "{some} placeable, {none} not");
    }
}
