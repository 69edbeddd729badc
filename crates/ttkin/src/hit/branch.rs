//! A hit on every IK branch: the robot's side of a hit the ball planner
//! ([`crate::ball::hitplan`]) chose. For a [`Hit`] (racket pose, twist, time) and the stroke's
//! start state, each analytic IK branch within the position limits gets its joint velocities
//! q̇ = J⁻¹V, its hit leg ([`super::leg`]: quintic or jerk-limited, on time) and its effort check
//! (certified peak, [`crate::dynamics::peak`]); a leg beyond the effort limits is replaced by a
//! gentler jerk-limited leg to the same hit state: first with only the joint beyond its torque
//! slowed ([`super::leg::scaled_jerk_leg_joints`]: its acceleration and jerk limits scaled below the
//! rejected leg's peak use by its torque excess; the other joints keep theirs, so the leg still
//! arrives on time more often), then with every joint slowed alike
//! ([`super::leg::scaled_jerk_leg`]), at most `EFFORT_RETRIES` legs each, each leg certified like
//! the first, while that still arrives on time;
//! the branch with the largest margin is kept. Every accepted hit state also gets its
//! follow-through back to rest at the ready configuration ([`HitPlanner::follow_through`]), checked
//! against every limit the hit leg is (position, speed, acceleration, jerk, certified effort): a
//! 0.4 s quintic when that fits, else a longer quintic, else a jerk-limited leg with gentler
//! acceleration and jerk limits; the hit state is given up only when none fits.
//!
//! [`HitPlanner::plan`] plans one whole stroke (hit and return legs) on the branch nearest the
//! current state and moves a late hit; this is the cheaper question a search over thousands of
//! candidate hits asks: is this hit feasible on time, and with which margin?

use nalgebra::{IsometryMatrix3, Matrix6, Vector3, Vector6};

use super::leg::{hit_leg_above, min_joint_time, scaled_jerk_leg, scaled_jerk_leg_joints, HitLeg};
use super::{Hit, HitPlanner};
use crate::chain::JacobianFrame;
use crate::dynamics::{DynamicsData, PeakStop};
use crate::ik::{joint_velocity, DifferentialIk, Solutions};
use crate::linalg::cholesky::factor_in_place;
use crate::traj::duration::quintic_limit_ratio_above;
use crate::traj::jerk::{jerk_limited, PositionLimits};
use crate::traj::limits::LIMIT_TOLERANCE;
use crate::traj::{JointState, JointTrajectory};

/// Most gentler legs ([`scaled_jerk_leg`]) tried for a hit state whose leg exceeds the effort limits.
const EFFORT_RETRIES: usize = 3;
/// The scale of a gentler leg is the rejected leg's used acceleration times EFFORT_SAFETY / excess
/// (the inertial torque shrinks with it; gravity, friction and the velocity terms do not)...
const EFFORT_SAFETY: f64 = 0.95;
/// ...and at most EFFORT_STEP times it (each retry is a real step down).
const EFFORT_STEP: f64 = 0.85;

/// Durations (s) of the quintic follow-throughs tried in order: the rally's 0.4 s first, then
/// longer ones (lower accelerations after the hit, more travel past it).
pub const FOLLOW_DURATIONS: [f64; 4] = [0.4, 0.55, 0.75, 1.0];
/// Scales of the acceleration and jerk limits of the jerk-limited follow-throughs tried when no
/// quintic fits (time-optimal to rest under the scaled limits, inside the position limits).
const FOLLOW_SCALES: [f64; 5] = [1.0, 0.7, 0.5, 0.35, 0.25];

/// One IK branch's hit: configuration, joint velocities, hit leg and margin.
#[derive(Debug, Clone, PartialEq)]
pub struct BranchLeg {
    /// Hit configuration (m, rad).
    pub q: Vec<f64>,
    /// Joint velocities at the hit (m/s, rad/s).
    pub qd: Vec<f64>,
    /// The hit leg from the start state at 0 s to (q, q̇, q̈) at the hit time.
    pub leg: HitLeg,
    /// Margin in (0, 1]: the smaller of the joints' normalised distance to their position limits
    /// at the hit and the leg's margin ([`HitLeg::margin`]).
    pub margin: f64,
    /// The follow-through from the hit state (q, q̇, the leg's q̈ at the hit) at 0 s to rest at
    /// the ready configuration, within every limit ([`HitPlanner::follow_through`]).
    pub follow: JointTrajectory,
}

impl HitPlanner {
    /// The branch of `hit` with the largest margin above `floor` (−∞: any) from the joint state
    /// `start` (at 0 s), its follow-through ending at rest at [`Self::default_ready`]: analytic
    /// IK within the position limits (the branch nearest `start` first on ties), or `None` when no
    /// branch is feasible (no analytic IK, singular, a joint speed beyond its limit, no leg on time
    /// within the limits, an effort limit exceeded, no follow-through within the limits).
    pub fn best_leg(&self, hit: &Hit, start: &JointState, floor: f64) -> Option<BranchLeg> {
        self.best_leg_to(hit, start, &self.ready, floor)
    }

    /// [`Self::best_leg`] with the follow-through ending at rest at `ready` (m, rad; the ball
    /// planner's ready configuration).
    pub fn best_leg_to(&self, hit: &Hit, start: &JointState, ready: &[f64], floor: f64) -> Option<BranchLeg> {
        let twist = self.tool_twist(hit);
        let mut best: Option<BranchLeg> = None;
        for q in self.branches(&hit.pose, Some(&start.q)).iter() {
            // Only a margin above the best so far can replace it: no solves for the rest.
            let floor = best.as_ref().map_or(floor, |b| b.margin);
            if let Some(b) = self.branch_leg_to(q, start, &twist, hit.t, ready, floor) {
                best = Some(b);
            }
        }
        best
    }

    /// The tool-point twist (base axes) of `hit`'s racket-centre twist on this robot's racket.
    pub fn tool_twist(&self, hit: &Hit) -> [f64; 6] {
        self.mount.tool_twist(&self.mount.tool_pose(&hit.pose), &hit.twist)
    }

    /// The hit at configuration `q` moving the tool with `tool_twist` (base axes) after `t_hit` s
    /// from `start`: q̇, leg, margin and follow-through to rest at [`Self::default_ready`], or
    /// `None` when it is singular, a joint speed exceeds its limit, no leg is within the limits,
    /// the effort limits are exceeded, the margin is at most `floor` (−∞: any margin) or no
    /// follow-through is within the limits.
    pub fn branch_leg(
        &self,
        q: &[f64],
        start: &JointState,
        tool_twist: &[f64; 6],
        t_hit: f64,
        floor: f64,
    ) -> Option<BranchLeg> {
        self.branch_leg_to(q, start, tool_twist, t_hit, &self.ready, floor)
    }

    /// [`Self::branch_leg`] with the follow-through ending at rest at `ready` (m, rad).
    pub fn branch_leg_to(
        &self,
        q: &[f64],
        start: &JointState,
        tool_twist: &[f64; 6],
        t_hit: f64,
        ready: &[f64],
        floor: f64,
    ) -> Option<BranchLeg> {
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
        let qd = self.hit_joint_velocity(q, tool_twist)?;
        let lim = &self.limits;
        if qd.iter().zip(&lim.velocity).any(|(v, vmax)| v.abs() > *vmax) {
            return None;
        }
        let first = hit_leg_above(start, q, &qd, t_hit, &self.limits, floor)?;
        let leg = self.within_torque(first, start, q, &qd, t_hit, floor)?;
        let margin = pos_margin.min(leg.margin);
        let at_hit = JointState {
            q: q.to_vec(),
            qd,
            qdd: leg.qdd_hit.clone(),
        };
        let follow = self.follow_through(&at_hit, ready)?;
        Some(BranchLeg {
            q: at_hit.q,
            qd: at_hit.qd,
            leg,
            margin,
            follow,
        })
    }

    /// The follow-through after a hit: from the joint state `at_hit` (at 0 s) to rest at `ready`
    /// (m, rad), within the position, speed, acceleration and jerk limits (exact extrema) and the
    /// effective effort limits at every instant (certified, as the hit leg): the first of the
    /// quintics of [`FOLLOW_DURATIONS`] that fits, else the first time-optimal jerk-limited leg
    /// under the acceleration and jerk limits scaled by 1, 0.7, 0.5, 0.35, 0.25 (position limits
    /// respected) that fits; `None` when none does (or `ready` has the wrong length).
    pub fn follow_through(&self, at_hit: &JointState, ready: &[f64]) -> Option<JointTrajectory> {
        if ready.len() != self.chain.dof() || at_hit.q.len() != ready.len() {
            return None;
        }
        let lim = &self.limits;
        let rest = JointState::rest(ready);
        let ceiling = 1.0 + LIMIT_TOLERANCE;
        for t in FOLLOW_DURATIONS {
            if quintic_limit_ratio_above(at_hit, &rest, t, lim, ceiling) > ceiling {
                continue;
            }
            let traj = JointTrajectory::quintic_unchecked(at_hit, &rest, t);
            if traj.position_violations(lim, 0.0).is_empty() && self.within_effort(&traj) {
                return Some(traj);
            }
        }
        for scale in FOLLOW_SCALES {
            let mut scaled = lim.clone();
            for (a, j) in scaled.acceleration.iter_mut().zip(scaled.jerk.iter_mut()) {
                *a *= scale;
                *j *= scale;
            }
            // The hit's acceleration must lie within the scaled limits.
            if at_hit.qdd.iter().zip(&scaled.acceleration).any(|(x, a)| x.abs() > *a) {
                break;
            }
            let Ok(leg) = jerk_limited(at_hit, &rest, &scaled, None, PositionLimits::Respect) else {
                continue;
            };
            let traj = leg.trajectory;
            if traj.check_limits(lim).is_ok_and(|v| v.is_empty()) && self.within_effort(&traj) {
                return Some(traj);
            }
        }
        None
    }

    /// `leg` when its torques are within the effective effort limits, else a gentler jerk-limited
    /// leg to the same hit state (q, `qd` at `t_hit` from `start`) that is: first only the joint
    /// beyond its limit slowed ([`scaled_jerk_leg_joints`]: its acceleration and jerk limits
    /// scaled below what the rejected leg used by the excess; the joint found beyond next, if
    /// another, too), then every joint alike ([`scaled_jerk_leg`]), at most `EFFORT_RETRIES`
    /// legs each, each certified like the first; `None` when none is within the torque on time.
    fn within_torque(
        &self,
        leg: HitLeg,
        start: &JointState,
        q: &[f64],
        qd: &[f64],
        t_hit: f64,
        floor: f64,
    ) -> Option<HitLeg> {
        // The gentler legs are searched without the floor and the result filtered by it, so that
        // a floor only removes the leg found without one (the best-margin search relies on it).
        self.within_torque_any(leg, start, q, qd, t_hit)
            .filter(|l| l.margin > floor)
    }

    /// [`Self::within_torque`] without a floor.
    fn within_torque_any(&self, leg: HitLeg, start: &JointState, q: &[f64], qd: &[f64], t_hit: f64) -> Option<HitLeg> {
        let floor = f64::NEG_INFINITY;
        let Some((excess, joint)) = self.effort_excess_joint(&leg.trajectory) else {
            return Some(leg);
        };
        let step = |excess: f64| (EFFORT_SAFETY / excess).min(EFFORT_STEP);
        // Only the joints beyond their torque.
        let mut scales = vec![1.0; q.len()];
        let (mut cur, mut excess_j, mut joint_j) = (leg.clone(), excess, joint);
        for _ in 0..EFFORT_RETRIES {
            scales[joint_j] = self.used_acceleration_of(&cur.trajectory, joint_j) * step(excess_j);
            let Some(next) = scaled_jerk_leg_joints(start, q, qd, t_hit, &self.limits, &scales, floor) else {
                break;
            };
            match self.effort_excess_joint(&next.trajectory) {
                None => return Some(next),
                Some((e, j)) => (cur, excess_j, joint_j) = (next, e, j),
            }
        }
        // Every joint alike.
        let (mut cur, mut excess) = (leg, excess);
        for _ in 0..EFFORT_RETRIES {
            let scale = self.used_acceleration(&cur.trajectory) * step(excess);
            let next = scaled_jerk_leg(start, q, qd, t_hit, &self.limits, scale, floor)?;
            match self.effort_excess(&next.trajectory) {
                None => return Some(next),
                Some(e) => (cur, excess) = (next, e),
            }
        }
        None
    }

    /// Whether `leg`'s torques (inverse dynamics with friction under the options' gravity, base
    /// frame) stay within the effective effort limits at every instant (certified,
    /// [`crate::dynamics::peak`]); true without dynamics or with `check_effort` off.
    pub fn within_effort(&self, leg: &JointTrajectory) -> bool {
        self.effort_excess(leg).is_none()
    }

    /// `None` when `leg`'s torques stay within the effective effort limits at every instant (as
    /// [`Self::within_effort`]), else the largest ratio |τ|/limit found at an instant (at least
    /// 1: a peak too close to the limit to decide counts as 1).
    pub fn effort_excess(&self, leg: &JointTrajectory) -> Option<f64> {
        self.effort_excess_joint(leg).map(|(e, _)| e)
    }

    /// [`Self::effort_excess`] with the joint of the ratio found.
    fn effort_excess_joint(&self, leg: &JointTrajectory) -> Option<(f64, usize)> {
        let dynamics = self.dynamics.as_ref()?;
        let mut data = DynamicsData::new(dynamics);
        let gravity = Vector3::from(self.gravity);
        let threshold = 1.0 + LIMIT_TOLERANCE;
        // The torque at the leg's knots first (the ends of its jerk phases: plateaus of the
        // acceleration, and the hit): a value above the limit at an instant rejects the leg at once,
        // as the certified search would after its enclosures (most rejected legs peak at a knot).
        let n = leg.dof();
        let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for &t in leg.knots() {
            leg.sample_unchecked(t, &mut q, &mut qd, &mut qdd);
            let tau = dynamics.inverse_dynamics_unchecked(&mut data, &q, &qd, &qdd, &gravity);
            let (excess, joint) = (0..n)
                .map(|j| (tau[j].abs() / self.effort.at(j, qd[j]), j))
                .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
            if excess > threshold {
                return Some((excess, joint));
            }
        }
        let stop = PeakStop::decide(threshold, 1e-3);
        let peak = dynamics.effort_peak(&mut data, leg, &self.effort, &gravity, stop);
        (peak.bound > threshold).then_some((peak.ratio.max(1.0), peak.joint))
    }

    /// Joint `j`'s peak |q̈| of `traj` over its acceleration limit (exact, ≤ 1 for a leg within
    /// the limits; 1 when the peak cannot be computed).
    fn used_acceleration_of(&self, traj: &JointTrajectory, j: usize) -> f64 {
        traj.peaks(2)
            .map_or(1.0, |p| p[j].value.abs() / self.limits.acceleration[j])
            .min(1.0)
    }

    /// The largest of `traj`'s joints' peak |q̈| over their acceleration limits (exact, ≤ 1 for
    /// a leg within the limits; 1 when a peak cannot be computed).
    fn used_acceleration(&self, traj: &JointTrajectory) -> f64 {
        let Ok(peaks) = traj.peaks(2) else {
            return 1.0;
        };
        peaks
            .iter()
            .zip(&self.limits.acceleration)
            .map(|(p, a)| p.value.abs() / a)
            .fold(0.0, f64::max)
            .min(1.0)
    }

    /// q̇ = J⁻¹·V (base frame) at `q` for the tool twist `twist`, or `None` where
    /// [`joint_velocity`] calls the Jacobian singular (σ_min below its default threshold): for six
    /// joints on the stack, the threshold test by a Cholesky of JᵀJ − threshold²·I and q̇ from an
    /// LU solve (the same q̇ to rounding as the damped-SVD solve away from singularities).
    pub fn hit_joint_velocity(&self, q: &[f64], twist: &[f64; 6]) -> Option<Vec<f64>> {
        if q.len() != 6 {
            let jv = joint_velocity(&self.chain, q, twist).ok()?;
            return (!jv.singular).then_some(jv.qd);
        }
        let j = self.chain.jacobian(q, JacobianFrame::Base).ok()?;
        let m = Matrix6::from_iterator(j.iter().copied());
        // σ_min ≥ t exactly when JᵀJ − t²·I is positive definite: a 6 × 6 Cholesky instead of
        // an SVD (with t = 1e-3 the shift t² = 1e-6 is ten orders above the rounding of JᵀJ).
        let t = DifferentialIk::default().epsilon;
        let mut shifted = m.transpose() * m - Matrix6::identity() * (t * t);
        if !m.iter().all(|x| x.is_finite()) || factor_in_place(shifted.as_mut_slice(), 6).is_err() {
            return None;
        }
        let qd = m.lu().solve(&Vector6::from_column_slice(twist))?;
        Some(qd.iter().copied().collect())
    }

    /// Whether some joint cannot reach `q` from `start` within `t_hit` s even at full acceleration
    /// then full speed with any arrival speed ([`min_joint_time`]): a cheap necessary test before
    /// the hit leg's solves, from rest only (false when `start` moves).
    fn too_far(&self, q: &[f64], start: &JointState, t_hit: f64) -> bool {
        if start.qd.iter().chain(&start.qdd).any(|x| *x != 0.0) {
            return false;
        }
        let lim = &self.limits;
        (0..q.len()).any(|i| min_joint_time(q[i] - start.q[i], lim.velocity[i], lim.acceleration[i]) > t_hit)
    }

    /// The analytic IK branches of the racket pose `pose` (base frame) within the joint position
    /// limits, revolute angles moved by 2πk into them where that fits (the branches and values of
    /// [`crate::ik::LimitFilter::Enforce`], without building its error message for the dropped
    /// ones: a search asks for thousands of poses beyond the strokes), on the stack; none without
    /// an analytic IK.
    pub fn branches(&self, pose: &IsometryMatrix3<f64>, hint: Option<&[f64]>) -> Solutions {
        let n = self.chain.dof();
        let Some(ik) = self.analytic.as_ref() else {
            return Solutions::empty(n);
        };
        let mut sols = ik
            .solve_quiet(&self.mount.tool_pose(pose), hint)
            .unwrap_or_else(|| Solutions::empty(n));
        sols.retain_map(|_, i, q| {
            let kind = self.chain.joints()[i].kind();
            crate::ik::fit_to_range(q, kind, self.limits.lower[i], self.limits.upper[i])
        });
        sols
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ik::{Analytic, LimitFilter};
    use crate::traj::JointState;
    use nalgebra::{Rotation3, Translation3};

    fn gantry() -> HitPlanner {
        HitPlanner::new(&crate::robots::gantry6(), Default::default()).unwrap()
    }

    /// gantry6's planner, its ready configuration, the rest there and the tool pose there.
    fn at_ready() -> (HitPlanner, Vec<f64>, JointState, IsometryMatrix3<f64>) {
        let pl = gantry();
        let ready = pl.default_ready().to_vec();
        let start = JointState::rest(&ready);
        let tool = pl.chain().fk(&ready).unwrap();
        (pl, ready, start, tool)
    }

    /// A hit near the tool pose `tool`: moved by up to ±`reach` (m, base x, y, z), turned about x
    /// by up to `turn` rad, its racket-centre velocity up to ±`speed`/2 m/s per axis, at a time in
    /// [`t.0`, `t.0 + t.1`) s.
    fn hit_near(
        tool: IsometryMatrix3<f64>,
        reach: [f64; 3],
        turn: f64,
        speed: f64,
        t: (f64, f64),
        rng: &mut fastrand::Rng,
    ) -> Hit {
        let [x, y, z] = reach;
        let d = Translation3::new(
            2.0 * x * rng.f64() - x,
            2.0 * y * rng.f64() - y,
            2.0 * z * rng.f64() - z,
        );
        let pose = IsometryMatrix3::from_parts(d, Rotation3::from_euler_angles(turn * rng.f64(), 0.0, 0.0)) * tool;
        let v = Vector3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * speed;
        Hit::new(pose, [v.x, v.y, v.z, 0.0, 0.0, 0.0], t.0 + t.1 * rng.f64()).unwrap()
    }

    #[test]
    fn hit_joint_velocity_matches_differential_ik() {
        let pl = gantry();
        let ready = pl.default_ready().to_vec();
        let mut rng = fastrand::Rng::with_seed(7);
        let (mut regular, mut singular) = (0, 0);
        let mut near = (0, 0);
        for k in 0..3000 {
            let mut q: Vec<f64> = ready.iter().map(|x| x + 2.0 * rng.f64() - 1.0).collect();
            if k % 10 == 0 {
                q[3] = std::f64::consts::FRAC_PI_2 + 1e-5 * (rng.f64() - 0.5); // c4 ≈ 0: singular
            } else if k % 10 == 1 {
                // σ_min around the threshold (1e-3) on both sides.
                q[3] = std::f64::consts::FRAC_PI_2 + 10f64.powf(-4.0 + 2.0 * rng.f64()) * (rng.f64() - 0.5).signum();
            }
            let twist = [0.0, 1.0, 0.0, 0.0, 0.0, 0.0].map(|_| 4.0 * rng.f64() - 2.0);
            let twist = [twist[0], twist[1], twist[2], 0.0, 0.0, 0.0];
            let jv = joint_velocity(pl.chain(), &q, &twist).unwrap();
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
                    for (a, b) in qd.iter().zip(&jv.qd) {
                        assert!((a - b).abs() <= 1e-9 * (1.0 + b.abs()), "{qd:?} vs {:?}", jv.qd);
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
        let pl = gantry();
        let ik = Analytic::for_chain(pl.chain()).unwrap();
        let hint = pl.default_ready().to_vec();
        let mut rng = fastrand::Rng::with_seed(4);
        let (mut some, mut none) = (0, 0);
        for _ in 0..2000 {
            let p = Translation3::new(-0.8 + 1.6 * rng.f64(), -1.0 + 2.0 * rng.f64(), -0.3 + 0.6 * rng.f64());
            let r = Rotation3::from_euler_angles(rng.f64() - 0.5, rng.f64() - 0.5, 6.0 * rng.f64());
            let pose = IsometryMatrix3::from_parts(p, r);
            let ours: Vec<Vec<f64>> = pl.branches(&pose, Some(&hint)).iter().map(|q| q.to_vec()).collect();
            match ik.solve(&pose, Some(&hint), LimitFilter::Enforce) {
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

    #[test]
    fn best_leg_is_the_best_branch_and_its_floor_cuts() {
        // Hits around the ready pose's racket: best_leg's margin is the largest over the branches
        // (each through branch_leg), and a floor at or above it gives None.
        let (pl, _, start, tool) = at_ready();
        let mut rng = fastrand::Rng::with_seed(11);
        let (mut some, mut none) = (0, 0);
        for _ in 0..300 {
            let hit = hit_near(tool, [0.15, 0.15, 0.1], 0.2, 4.0, (0.15, 0.4), &mut rng);
            let each: Vec<f64> = pl
                .branches(&hit.pose, Some(&start.q))
                .iter()
                .filter_map(|q| pl.branch_leg(q, &start, &hit.twist, hit.t, f64::NEG_INFINITY))
                .map(|b| b.margin)
                .collect();
            match pl.best_leg(&hit, &start, f64::NEG_INFINITY) {
                Some(b) => {
                    some += 1;
                    assert_eq!(b.margin, each.iter().copied().fold(f64::NEG_INFINITY, f64::max));
                    assert!(pl.best_leg(&hit, &start, b.margin).is_none());
                    assert!((b.leg.trajectory.duration() - hit.t).abs() <= 1e-9);
                }
                None => {
                    none += 1;
                    assert!(each.is_empty());
                }
            }
        }
        assert!(some > 20 && none > 20, "{some} feasible, {none} not");
    }

    #[test]
    fn gentler_legs_reach_hits_beyond_the_torque_and_stay_within_it() {
        // Fast hits around the ready pose's racket: where the leg of `hit_leg_above` exceeds the
        // effort limits, `branch_leg` either gives up or returns a gentler jerk-limited leg to the
        // same hit state on time, whose torques sampled at 10 kHz stay within the limits.
        let (pl, _, start, tool) = at_ready();
        let dy = pl.dynamics.as_ref().unwrap();
        let mut data = DynamicsData::new(dy);
        let mut rng = fastrand::Rng::with_seed(23);
        let (mut rescued, mut lost, mut uniform_rescued, mut torque_rescued) = (0, 0, 0, 0);
        for _ in 0..1500 {
            let hit = hit_near(tool, [0.3, 0.3, 0.15], 0.3, 8.0, (0.12, 0.3), &mut rng);
            let twist = pl.tool_twist(&hit);
            for q in pl.branches(&hit.pose, Some(&start.q)).iter() {
                let Some(qd) = pl.hit_joint_velocity(q, &twist) else {
                    continue;
                };
                if qd.iter().zip(&pl.limits.velocity).any(|(v, m)| v.abs() > *m) {
                    continue;
                }
                let Some(first) = hit_leg_above(&start, q, &qd, hit.t, &pl.limits, f64::NEG_INFINITY) else {
                    continue;
                };
                // The knots' pre-check decides as the certified search alone.
                let g = Vector3::from(pl.gravity);
                let threshold = 1.0 + LIMIT_TOLERANCE;
                let stop = PeakStop::decide(threshold, 1e-3);
                let certified = dy.effort_peak(&mut data, &first.trajectory, &pl.effort, &g, stop);
                assert_eq!(pl.within_effort(&first.trajectory), certified.bound <= threshold);
                if pl.within_effort(&first.trajectory) {
                    continue;
                }
                // Every joint slowed alike only (the rescue before the joint-wise one).
                let mut uniform = Some(first.clone());
                for _ in 0..EFFORT_RETRIES {
                    let leg = uniform.take().unwrap();
                    let Some(e) = pl.effort_excess(&leg.trajectory) else {
                        uniform = Some(leg);
                        break;
                    };
                    let scale = pl.used_acceleration(&leg.trajectory) * (EFFORT_SAFETY / e).min(EFFORT_STEP);
                    let Some(next) = scaled_jerk_leg(&start, q, &qd, hit.t, &pl.limits, scale, f64::NEG_INFINITY)
                    else {
                        break;
                    };
                    uniform = Some(next);
                }
                let by_uniform = uniform.is_some_and(|l| pl.within_effort(&l.trajectory));
                let rescue = pl.within_torque(first.clone(), &start, q, &qd, hit.t, f64::NEG_INFINITY);
                assert!(
                    !by_uniform || rescue.is_some(),
                    "the uniform rescue found a leg, the planner none"
                );
                torque_rescued += usize::from(rescue.is_some());
                uniform_rescued += usize::from(by_uniform);
                let Some(b) = pl.branch_leg(q, &start, &twist, hit.t, f64::NEG_INFINITY) else {
                    lost += 1;
                    continue;
                };
                rescued += 1;
                let traj = &b.leg.trajectory;
                assert_eq!(b.leg.profile, crate::hit::StrokeProfile::Jerk);
                assert!((traj.duration() - hit.t).abs() <= 1e-9);
                assert!(traj.check_limits(&pl.limits).unwrap().is_empty());
                let n = q.len();
                let (mut qs, mut qds, mut qdds) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                traj.sample_unchecked(traj.duration(), &mut qs, &mut qds, &mut qdds);
                for j in 0..n {
                    assert!(
                        (qs[j] - q[j]).abs() < 1e-9 && (qds[j] - qd[j]).abs() < 1e-9,
                        "end state"
                    );
                }
                let k = (traj.duration() * 1e4).ceil() as usize;
                let g = Vector3::from(pl.gravity);
                for i in 0..=k {
                    traj.sample_unchecked(traj.duration() * i as f64 / k as f64, &mut qs, &mut qds, &mut qdds);
                    let tau = dy.inverse_dynamics_unchecked(&mut data, &qs, &qds, &qdds, &g);
                    for j in 0..n {
                        let limit = pl.effort.at(j, qds[j]);
                        assert!(tau[j].abs() <= limit * (1.0 + 1e-6), "joint {j}: {} > {limit}", tau[j]);
                    }
                }
            }
        }
        assert!(rescued > 5 && lost > 5, "{rescued} rescued, {lost} lost");
        // Slowing only the joint beyond its torque first rescues hit states the uniform slowing
        // does not (and loses none of its own).
        assert!(
            torque_rescued > uniform_rescued,
            "{torque_rescued} within the torque, {uniform_rescued} by uniform slowing"
        );
    }

    /// The largest ratio to its limit of every quantity of `traj` at 10 kHz (position: the excess
    /// over the range in m or rad, 0 inside; speed, acceleration, jerk and torque against their
    /// limits, the torque's at the sampled speed), as [position, speed, acceleration, jerk, effort].
    fn dense_ratios(pl: &HitPlanner, traj: &JointTrajectory) -> [f64; 5] {
        let dy = pl.dynamics.as_ref().unwrap();
        let mut data = DynamicsData::new(dy);
        let g = Vector3::from(pl.gravity);
        let lim = &pl.limits;
        let n = traj.dof();
        let (mut q, mut qd, mut qdd, mut jerk) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let k = (traj.duration() * 1e4).ceil() as usize;
        let mut out = [0.0f64; 5];
        for i in 0..=k {
            let t = traj.duration() * i as f64 / k as f64;
            traj.sample_unchecked(t, &mut q, &mut qd, &mut qdd);
            traj.jerk(t, &mut jerk).unwrap();
            let tau = dy.inverse_dynamics_unchecked(&mut data, &q, &qd, &qdd, &g);
            for j in 0..n {
                out[0] = out[0].max(q[j] - lim.upper[j]).max(lim.lower[j] - q[j]);
                out[1] = out[1].max(qd[j].abs() / lim.velocity[j]);
                out[2] = out[2].max(qdd[j].abs() / lim.acceleration[j]);
                out[3] = out[3].max(jerk[j].abs() / lim.jerk[j]);
                out[4] = out[4].max(tau[j].abs() / pl.effort.at(j, qd[j]));
            }
        }
        out
    }

    #[test]
    fn follow_throughs_stay_within_every_limit_at_10_khz() {
        // Fast hits around the ready pose's racket, to rest at the ready configuration: every
        // accepted branch's follow-through starts at its hit state, ends at rest at `ready`, and
        // is within every limit at 10 kHz. Where the rally's 0.4 s quintic is not (its torques or
        // speeds beyond a limit), a longer or gentler follow-through is chosen, not the hit lost.
        let (pl, ready, start, tool) = at_ready();
        let mut rng = fastrand::Rng::with_seed(31);
        let (mut accepted, mut longer) = (0, 0);
        for _ in 0..1500 {
            let hit = hit_near(tool, [0.3, 0.3, 0.15], 0.3, 10.0, (0.15, 0.4), &mut rng);
            let Some(b) = pl.best_leg_to(&hit, &start, &ready, f64::NEG_INFINITY) else {
                continue;
            };
            accepted += 1;
            let f = &b.follow;
            let begin = f.state(0.0).unwrap();
            let end = f.state(f.duration()).unwrap();
            for (j, r) in ready.iter().enumerate() {
                assert!((begin.q[j] - b.q[j]).abs() < 1e-9 && (begin.qd[j] - b.qd[j]).abs() < 1e-9);
                assert!((begin.qdd[j] - b.leg.qdd_hit[j]).abs() < 1e-9);
                assert!((end.q[j] - r).abs() < 1e-9 && end.qd[j].abs() < 1e-9 && end.qdd[j].abs() < 1e-9);
            }
            let r = dense_ratios(&pl, f);
            assert!(r[0] <= 1e-9, "position {r:?}");
            for (name, x) in ["speed", "acceleration", "jerk", "effort"].iter().zip(&r[1..]) {
                assert!(*x <= 1.0 + 1e-6, "{name} {r:?}");
            }
            let first = JointTrajectory::quintic_unchecked(&begin, &JointState::rest(&ready), FOLLOW_DURATIONS[0]);
            if f.duration() != FOLLOW_DURATIONS[0] || f.segments() > 1 {
                longer += 1;
                // Chosen only because the 0.4 s quintic exceeds a limit somewhere.
                let r0 = dense_ratios(&pl, &first);
                assert!(r0[0] > 0.0 || r0[1..].iter().any(|x| *x > 1.0 - 1e-3), "{r0:?}");
            } else {
                assert_eq!(f, &first);
            }
        }
        assert!(
            accepted > 80 && longer > 10,
            "{accepted} accepted, {longer} with a longer follow-through"
        );
    }

    #[test]
    fn follow_through_is_found_where_the_short_quintic_exceeds_a_limit() {
        // Hit states drawn in joint space (fast, near the ready pose): where the 0.4 s quintic to
        // rest exceeds a limit at 10 kHz, `follow_through` gives a motion within every limit (or
        // none); it keeps the 0.4 s quintic where that fits.
        let pl = gantry();
        let ready = pl.default_ready().to_vec();
        let lim = pl.limits.clone();
        let mut rng = fastrand::Rng::with_seed(5);
        let (mut kept, mut rescued, mut none) = (0, 0, 0);
        for _ in 0..400 {
            let q: Vec<f64> = (0..6)
                .map(|j| (ready[j] + 0.5 * (2.0 * rng.f64() - 1.0)).clamp(lim.lower[j] + 0.05, lim.upper[j] - 0.05))
                .collect();
            let qd: Vec<f64> = lim.velocity.iter().map(|v| 0.9 * v * (2.0 * rng.f64() - 1.0)).collect();
            let at_hit = JointState {
                q,
                qd,
                qdd: vec![0.0; 6],
            };
            let short = JointTrajectory::quintic_unchecked(&at_hit, &JointState::rest(&ready), 0.4);
            let r0 = dense_ratios(&pl, &short);
            let fits = r0[0] <= 0.0 && r0[1..].iter().all(|x| *x <= 1.0 - 1e-3);
            match pl.follow_through(&at_hit, &ready) {
                Some(f) => {
                    let r = dense_ratios(&pl, &f);
                    assert!(r[0] <= 1e-9 && r[1..].iter().all(|x| *x <= 1.0 + 1e-6), "{r:?}");
                    if fits {
                        assert_eq!(f, short);
                        kept += 1;
                    } else if f != short {
                        rescued += 1;
                    }
                }
                None => {
                    assert!(!fits, "{r0:?}");
                    none += 1;
                }
            }
        }
        assert!(kept > 20 && rescued > 20, "{kept} kept, {rescued} rescued, {none} none");
        assert!(pl.follow_through(&JointState::rest(&ready), &ready[..5]).is_none());
    }
}
