//! Hit planning: where, when and how the robot hits the predicted ball so that it lands on a
//! target on the opponent's half.
//!
//! 1. **Candidates.** The ball is predicted from its state (through its bounce on the robot's half)
//!    and every 10 ms sample inside the hitting volume ([`Reach`], world frame; the same volume as
//!    the reachable region of [`super::reach`]), after the bounce and at least
//!    `min_stroke_time` after `now`, is a candidate; `candidates` of them, evenly spread, are tried
//!    (up to 12 when none of those is feasible). One with no IK for the approximate normal (see
//!    `roughly_placeable`) is skipped, and tried in full only when no other gives a hit.
//! 2. **Outgoing velocity.** Shooting: the velocity v₀ with which the ball, spinning with its
//!    post-impact spin, is at (x_t, y_t, r) after the return flight time T: Broyden's method on the
//!    3×3 map v₀ ↦ p(T), started from the drag-free solution with Jacobian T·I; T from
//!    `return_times` in order until the flight clears the net and first touches the table at the
//!    target (within 1 mm). The post-impact spin depends on the racket, which depends on v₀: every
//!    evaluation of the map solves the racket for its v₀ and flies the ball with that spin.
//! 3. **Racket.** [`super::impact::Racket::solve`] gives the face normal and the racket velocity
//!    (along the normal); the racket centre is the ball centre minus r·n (the ball touches the face
//!    centre); the racket frame has its z axis on the face normal and its x axis (the handle) as
//!    close to world up as possible (the convention of `python/ttmanip/pipeline.py`).
//! 4. **Robot.** The pose (for each racket roll of `rolls` about the normal) and twist go to the
//!    base frame ([`Placement`]), analytic IK (every branch within the limits), q̇ = J⁻¹·V, and the
//!    hit leg from the stroke's start state at `now` to (q, q̇, q̈) at the hit ([`super::leg`]): a
//!    quintic when its exact velocity, acceleration and jerk peaks are within the limits, else the
//!    jerk-limited (Ruckig) leg that reaches the hit state exactly at the hit time inside the
//!    position limits. Jerk limits: the robot files carry none, so
//!    [`crate::hit::DEFAULT_JERK_PER_ACCELERATION`] × the acceleration limits, as `plan_hit` uses.
//! 5. **Choice.** Among feasible candidates, the one with the largest margin: the smallest of the
//!    joints' normalised distance to their position limits at the hit and the leg's margin
//!    (1 − peak/limit ratio for a quintic, 1 − fastest duration / hit time for a jerk-limited leg). Candidates are tried from the middle of the spread outward and the search
//!    stops at the first with a margin ≥ `good_margin` (0.25), which bounds the planning time.

use super::flight::{BallState, EventKind, Flight};
use super::impact::{Racket, RacketHit};
use super::leg::{hit_leg, HitLeg};
use super::reach::walk_after_bounce;
pub use super::reach::{racket_rotation, Placement, Reach};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::ik::{joint_velocity, Analytic, LimitFilter};
use crate::traj::limits::KinematicLimits;
use crate::traj::JointState;
use nalgebra::{IsometryMatrix3, Matrix3, Translation3, Vector3};

/// Why a ball got no hit, or that it got one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HitStatus {
    /// A feasible hit was planned.
    Ok,
    /// The ball does not bounce on the robot's half and come back up (net, long, wide, floor).
    NoBounce,
    /// The ball never enters the hitting volume after its bounce, or too early for a stroke.
    OutOfReach,
    /// No outgoing flight reaches the target over the net.
    NoReturn,
    /// Every candidate violates the robot's limits (IK, joint velocity or stroke).
    Infeasible,
}

impl HitStatus {
    /// Short lower-case name ("ok", "no_bounce", "out_of_reach", "no_return", "infeasible").
    pub fn name(&self) -> &'static str {
        match self {
            HitStatus::Ok => "ok",
            HitStatus::NoBounce => "no_bounce",
            HitStatus::OutOfReach => "out_of_reach",
            HitStatus::NoReturn => "no_return",
            HitStatus::Infeasible => "infeasible",
        }
    }
}

/// A planned hit: what the racket must do, and what the robot must do for it.
#[derive(Debug, Clone, PartialEq)]
pub struct Hit {
    /// Predicted ball state at the impact (world).
    pub ball: BallState,
    /// Outgoing ball velocity (m/s, world) and the racket producing it.
    pub v_out: Vector3<f64>,
    /// Racket normal, velocity and outgoing spin (world).
    pub racket: RacketHit,
    /// Racket pose (racket frame in the robot base frame, m): the `pose` of `ttmanip.Hit`.
    pub pose: IsometryMatrix3<f64>,
    /// Racket twist [v; ω] (m/s, rad/s, base axes): the `twist` of `ttmanip.Hit`.
    pub twist: [f64; 6],
    /// Hit time (s from `now`): the `t` of `ttmanip.Hit`.
    pub t_hit: f64,
    /// Joint configuration (m, rad) and velocities at the hit.
    pub q_hit: Vec<f64>,
    /// Joint velocities (m/s, rad/s) at the hit.
    pub qd_hit: Vec<f64>,
    /// Joint accelerations (m/s², rad/s²) at the hit chosen for the stroke (see [`super::leg`]).
    pub qdd_hit: Vec<f64>,
    /// The accepted hit leg (its profile and trajectory from the stroke start at `now` to the hit):
    /// what the rally executes.
    pub leg: HitLeg,
    /// Choice margin (see the module doc), in (0, 1].
    pub margin: f64,
    /// Landing point (m, world) of the exactly executed impact and its flight time (s).
    pub landing: Vector3<f64>,
}

/// The result of [`HitPlanner::plan`].
#[derive(Debug, Clone, PartialEq)]
pub struct HitPlan {
    /// Outcome.
    pub status: HitStatus,
    /// The hit when `status` is [`HitStatus::Ok`].
    pub hit: Option<Hit>,
    /// Candidates examined.
    pub candidates: usize,
}

/// The hit planner of one robot: its chain, placement, hitting volume, ready configuration and racket.
#[derive(Debug, Clone)]
pub struct HitPlanner {
    /// Robot chain (base frame as in [`Placement`]; tool frame = racket frame).
    pub chain: Chain,
    ik: Analytic,
    limits: KinematicLimits,
    /// Base frame in the world.
    pub placement: Placement,
    /// Hitting volume of the ball centre (world) searched for candidates.
    pub reach: Reach,
    /// Ready configuration (m, rad) from which strokes start at rest.
    pub ready: Vec<f64>,
    /// Racket rubber.
    pub racket: Racket,
    /// Flight model used for planning (10 ms RK4 step).
    pub flight: Flight,
    /// Shortest stroke (s) between planning and hitting.
    pub min_stroke_time: f64,
    /// Candidates tried first (evenly spread); all of them (up to 12) when none of these is feasible.
    pub candidates: usize,
    /// How far (m) beyond the hitting volume the planner still looks for hits, so that a ball whose
    /// estimate lies just outside the box is still tried (IK decides).
    pub search_margin: f64,
    /// Return flight times (s) tried in order (slower returns first: they need less racket speed).
    pub return_times: [f64; 3],
    /// A feasible hit with at least this margin ends the search (candidates are tried middle first).
    pub good_margin: f64,
    /// Rolls (rad) of the racket about its face normal tried in order (0: handle up); the ball
    /// does not see the roll, the joints do.
    pub rolls: Vec<f64>,
}

impl HitPlanner {
    /// The planner for `chain` (an analytic-IK gantry6 structure) with defaults: placement and reach
    /// of gantry6, ready configuration = IK of a forward-facing racket at (−1.85, 0, 0.255) m (world).
    pub fn new(chain: Chain, flight: Flight) -> Result<Self> {
        let ik = Analytic::for_chain(&chain)
            .ok_or_else(|| Error::Model("hit planning needs a chain with analytic IK (gantry6)".into()))?;
        // Robot files carry no jerk limits: the same default as `plan_hit` (infinite when an
        // acceleration limit is, and then no jerk-limited leg).
        let jerk: Vec<f64> = chain
            .limits()
            .iter()
            .map(|l| l.acceleration.unwrap_or(f64::INFINITY) * crate::hit::DEFAULT_JERK_PER_ACCELERATION)
            .collect();
        let limits = KinematicLimits::from_chain(&chain, Some(&jerk))?;
        let mut planner = HitPlanner {
            ready: vec![0.0; chain.dof()],
            chain,
            ik,
            limits,
            placement: Placement::default(),
            reach: Reach::default(),
            racket: Racket::default(),
            flight: Flight { step: 0.01, ..flight },
            min_stroke_time: 0.12,
            candidates: 3,
            search_margin: 0.03,
            return_times: [0.8, 0.65, 0.95],
            good_margin: 0.25,
            rolls: [0.0, 30.0, -30.0].iter().map(|d: &f64| d.to_radians()).collect(),
        };
        // Ready: racket facing forward 0.48 m behind the end line, across the table's centre line,
        // at mid-height of the band, so that a stroke accelerates forward into the hit.
        let centre = Vector3::new(-1.85, 0.0, 0.5 * (planner.reach.lo.z + planner.reach.hi.z));
        let pose = planner.base_pose(&centre, &Vector3::x());
        planner.ready = planner.ik.nearest(&pose, &planner.ready, LimitFilter::Enforce)?;
        Ok(planner)
    }

    /// Racket pose in the base frame for a racket centre `c` and face normal `n` (world), handle
    /// as close to world up as possible.
    pub fn base_pose(&self, c: &Vector3<f64>, n: &Vector3<f64>) -> IsometryMatrix3<f64> {
        self.base_pose_rolled(c, n, 0.0)
    }

    /// [`HitPlanner::base_pose`] with the racket turned by `roll` (rad) about its normal.
    pub fn base_pose_rolled(&self, c: &Vector3<f64>, n: &Vector3<f64>, roll: f64) -> IsometryMatrix3<f64> {
        let world = IsometryMatrix3::from_parts(Translation3::from(*c), racket_rotation(n, roll));
        self.placement.world_from_base().inverse() * world
    }

    /// Checks that `target` (x, y in m, world) lies on the opponent's half, a ball radius inside.
    pub fn check_target(&self, target: [f64; 2]) -> Result<()> {
        let t = &self.flight.table;
        let r = self.flight.model.radius;
        let ok = target[0].is_finite()
            && target[1].is_finite()
            && target[0] > r
            && target[0] < t.half_length() - r
            && target[1].abs() < t.half_width() - r;
        if ok {
            Ok(())
        } else {
            Err(Error::invalid(
                "target",
                format!(
                    "({}, {}) m is off the opponent's half: need {r} < x < {} and |y| < {} (world frame)",
                    target[0],
                    target[1],
                    t.half_length() - r,
                    t.half_width() - r
                ),
            ))
        }
    }

    /// Plans the hit of the ball `ball` (state at time `ball.t`, s) for a stroke starting at rest
    /// at the ready configuration at time `now` (s), returning the ball to `target` (x, y, m, world).
    pub fn plan(&self, ball: &BallState, now: f64, target: [f64; 2]) -> Result<HitPlan> {
        self.plan_from(ball, now, target, &JointState::rest(&self.ready), false)
    }

    /// [`HitPlanner::plan`] for a stroke starting from the joint state `start` at `now` (re-planning
    /// during a stroke with a newer estimate); `after_bounce` says that `ball` is already past its
    /// bounce on the robot's half (an estimate from observations after it).
    pub fn plan_from(
        &self,
        ball: &BallState,
        now: f64,
        target: [f64; 2],
        start: &JointState,
        after_bounce: bool,
    ) -> Result<HitPlan> {
        self.check_target(target)?;
        if start.check("start")? != self.chain.dof() {
            return Err(Error::shape(
                "start.q",
                format!("{} values", self.chain.dof()),
                start.q.len(),
            ));
        }
        ball.validate("ball")?;
        if !now.is_finite() {
            return Err(Error::NonFinite {
                what: "now".into(),
                index: 0,
                value: now,
            });
        }
        let (list, bounced) = self.candidate_states(&self.flight, ball, now, self.search_margin, after_bounce);
        if !bounced {
            return Ok(HitPlan {
                status: HitStatus::NoBounce,
                hit: None,
                candidates: 0,
            });
        }
        if list.is_empty() {
            return Ok(HitPlan {
                status: HitStatus::OutOfReach,
                hit: None,
                candidates: 0,
            });
        }
        // `candidates` evenly spread first; more of them only when none of those is feasible.
        let k = self.candidates.max(1).min(list.len());
        let extra = list.len().min(12);
        let mut best: Option<Hit> = None;
        let mut any_return = false;
        let mut tried = 0;
        // Candidates that fail the cheap placement test are skipped, and tried in full only when no
        // other candidate gives a hit (the test's normal is approximate).
        let mut skipped: Vec<usize> = Vec::new();
        for round in 0..3 {
            let picks: Vec<usize> = match round {
                0 | 1 => {
                    let count = if round == 0 { k } else { extra };
                    if round == 1 && (best.is_some() || extra <= k) {
                        continue;
                    }
                    // Middle of the spread first: it is the likeliest to have the largest margin.
                    let mut order: Vec<usize> = (0..count).collect();
                    order.sort_by_key(|&j| (2 * j + 1).abs_diff(count));
                    order.iter().map(|&j| (2 * j + 1) * list.len() / (2 * count)).collect()
                }
                _ if best.is_none() => std::mem::take(&mut skipped),
                _ => Vec::new(),
            };
            for i in picks {
                if best.as_ref().is_some_and(|b| b.margin >= self.good_margin) {
                    break;
                }
                let s = list[i];
                if round < 2 && !self.roughly_placeable(&s, target) {
                    skipped.push(i);
                    continue;
                }
                tried += 1;
                for &tf in &self.return_times {
                    let Some((v_out, racket, landing)) = self.outgoing(&s, target, tf) else {
                        continue;
                    };
                    any_return = true;
                    if let Some(hit) = self.robot_hit(&s, now, start, v_out, racket, landing) {
                        if best.as_ref().is_none_or(|b| hit.margin > b.margin) {
                            best = Some(hit);
                        }
                        break;
                    }
                }
            }
        }
        let k = tried;
        let status = match (&best, any_return) {
            (Some(_), _) => HitStatus::Ok,
            (None, true) => HitStatus::Infeasible,
            (None, false) => HitStatus::NoReturn,
        };
        Ok(HitPlan {
            status,
            hit: best,
            candidates: k,
        })
    }

    /// Predicted states every 10 ms inside the hitting volume after the bounce on the robot's half, and
    /// whether that bounce happens.
    fn candidate_states(
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

    /// Outgoing velocity, racket and landing point returning the ball at `s` to `target` in a
    /// return flight of `tf` s.
    fn outgoing(&self, s: &BallState, target: [f64; 2], tf: f64) -> Option<(Vector3<f64>, RacketHit, Vector3<f64>)> {
        let f = &self.flight;
        let goal = Vector3::new(target[0], target[1], f.model.radius);
        // Each solve starts from the previous one (the shooting iterates move v₀ a little).
        let last: std::cell::Cell<Option<RacketHit>> = std::cell::Cell::new(None);
        let racket = |v: &Vector3<f64>| {
            let guess = last.get();
            let hit = self
                .racket
                .solve_from(&f.model, &s.v, &s.w, v, guess.as_ref())
                .or_else(|_| self.racket.solve(&f.model, &s.v, &s.w, v))
                .ok();
            if hit.is_some() {
                last.set(hit);
            }
            hit
        };
        // The outgoing spin follows the racket, which follows v₀: solved together.
        let v_out = shoot(f, &s.p, &goal, tf, |v| racket(v).map(|r| r.spin_out))?;
        let hit = racket(&v_out)?;
        let out = BallState {
            v: v_out,
            w: hit.spin_out,
            ..*s
        };
        let (_, events) = f.run(&out, s.t + tf + 0.5, None);
        let e = events.first()?;
        let landing = e.before.p;
        let ok = e.kind == EventKind::Table
            && f.table.on_opponent_half(landing.x, landing.y)
            && (landing - goal).xy().norm() < 1e-3;
        ok.then_some((v_out, hit, landing))
    }

    /// Whether some roll of a racket with the frictionless, drag-free normal (along v_out − v_in,
    /// v_out the vacuum shot to `target` in the first return time) at the ball `s` has IK within the
    /// limits: a cheap test before the shooting solve.
    fn roughly_placeable(&self, s: &BallState, target: [f64; 2]) -> bool {
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

    /// The best robot hit (largest margin) over the racket rolls `rolls` about the face normal and
    /// every IK branch within the limits, or `None` when none is feasible.
    fn robot_hit(
        &self,
        s: &BallState,
        now: f64,
        start: &JointState,
        v_out: Vector3<f64>,
        racket: RacketHit,
        landing: Vector3<f64>,
    ) -> Option<Hit> {
        let r = self.flight.model.radius;
        let centre = s.p - r * racket.normal;
        let rot_bw = self.placement.world_from_base().rotation.inverse();
        let v_b = rot_bw * racket.velocity;
        let twist = [v_b.x, v_b.y, v_b.z, 0.0, 0.0, 0.0];
        let t_hit = s.t - now;
        let mut best: Option<Hit> = None;
        for &roll in &self.rolls {
            if best.as_ref().is_some_and(|b| b.margin >= self.good_margin) {
                break;
            }
            let pose = self.base_pose_rolled(&centre, &racket.normal, roll);
            let Ok(sols) = self.ik.solve(&pose, Some(&start.q), LimitFilter::Enforce) else {
                continue;
            };
            for q in sols.iter() {
                let Some((qd, leg, margin)) = self.stroke_margin(q, start, &twist, t_hit) else {
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
    /// s, or `None` when it is singular or no leg is within the limits.
    fn stroke_margin(
        &self,
        q: &[f64],
        start: &JointState,
        twist: &[f64; 6],
        t_hit: f64,
    ) -> Option<(Vec<f64>, HitLeg, f64)> {
        let jv = joint_velocity(&self.chain, q, twist).ok()?;
        if jv.singular {
            return None;
        }
        let leg = hit_leg(start, q, &jv.qdot, t_hit, &self.limits)?;
        let mut pos_margin = f64::INFINITY;
        for (i, &qi) in q.iter().enumerate() {
            let (lo, hi) = (self.limits.lower[i], self.limits.upper[i]);
            if lo.is_finite() && hi.is_finite() {
                pos_margin = pos_margin.min(2.0 * (qi - lo).min(hi - qi) / (hi - lo));
            }
        }
        let margin = pos_margin.min(leg.margin);
        Some((jv.qdot, leg, margin))
    }

    /// Kinematic limits of the strokes (joint order of the chain; jerk as in the module doc).
    pub fn limits(&self) -> &KinematicLimits {
        &self.limits
    }
}

/// Velocity v₀ (m/s) with which a ball at `p`, spinning with `spin(v₀)` (rad/s; a constant or the
/// spin a racket gives it), is at `goal` after `tf` s of free flight (no contacts): Broyden's method
/// from the drag-free solution, to 1e-5 m. `None` when `spin` has no answer or it does not converge.
pub fn shoot<S>(f: &Flight, p: &Vector3<f64>, goal: &Vector3<f64>, tf: f64, spin: S) -> Option<Vector3<f64>>
where
    S: Fn(&Vector3<f64>) -> Option<Vector3<f64>>,
{
    let g = Vector3::new(0.0, 0.0, -f.model.gravity);
    let mut v = (goal - p - 0.5 * g * tf * tf) / tf;
    let end = |v: &Vector3<f64>| {
        let Some(w) = spin(v) else {
            return Vector3::repeat(f64::NAN);
        };
        let mut s = BallState {
            t: 0.0,
            p: *p,
            v: *v,
            w,
        };
        while s.t < tf - 1e-12 {
            s = f.rk4(&s, f.step.min(tf - s.t));
        }
        s.p - goal
    };
    let mut jinv = Matrix3::identity() / tf; // inverse Jacobian (Broyden, "good" update on the inverse)
    let mut r = end(&v);
    if !r.norm().is_finite() {
        return None;
    }
    for _ in 0..20 {
        if r.norm() < 1e-5 {
            return Some(v);
        }
        let dv = -(jinv * r);
        let vn = v + dv;
        let rn = end(&vn);
        let dr = rn - r;
        let denom = dv.dot(&(jinv * dr));
        if denom.abs() > 1e-30 {
            jinv += (dv - jinv * dr) * (dv.transpose() * jinv) / denom;
        }
        v = vn;
        r = rn;
        if !r.norm().is_finite() {
            return None;
        }
    }
    (r.norm() < 1e-4).then_some(v)
}
