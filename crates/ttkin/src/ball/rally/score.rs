//! Scoring one ball of the rally: where the racket meets the true ball (bisection on the gap to
//! the face plane), the ball's flight after the impact and where it lands; what happened to each
//! ball ([`BallOutcome`]) and a rally's outcomes as columns ([`Outcomes`]). [`score`] is the one
//! scoring of the rally and of the hardware-in-the-loop rally ([`score_executed`]: from sampled
//! joint states).

use crate::ball::flight::{BallState, EventKind, Flight};
use crate::ball::hitplan::ReturnPlanner;
use crate::chain::JacobianFrame;
use crate::error::{Error, Result};
use nalgebra::Vector3;

/// What happened to one ball.
#[derive(Debug, Clone, PartialEq)]
pub struct BallOutcome {
    /// Incoming state at the opponent's hit (t = 0).
    pub incoming: BallState,
    /// Whether the ball is in the robot's reachable region ([`crate::ball::reach::ReachRegion::classify`] of its true flight).
    pub in_reach: bool,
    /// The region's verdict: "in_reach", or why not (one of [`crate::ball::reach::Reachability::NAMES`]).
    pub reach: &'static str,
    /// Planner status name ("ok", "no_bounce", ...), or "estimate: ..." when estimation failed.
    pub status: String,
    /// Whether the racket met the ball.
    pub contact: bool,
    /// Whether the ball landed on the opponent's half.
    pub returned: bool,
    /// Distance (m) of the contact point from the racket centre (NaN without contact).
    pub racket_error: f64,
    /// Planning time (µs of this thread's CPU time): estimate, predict, choose hit, IK, stroke.
    pub plan_time_us: f64,
    /// The same planning step in wall-clock time (µs; includes preemption on a loaded machine).
    pub plan_wall_time_us: f64,
    /// Planning time (s, absolute): the delivery of the last observation used.
    pub now: f64,
    /// The estimated ball state the plan started from (`None` when estimation failed).
    pub estimate: Option<BallState>,
    /// Landing point (m, world) of the return (NaN when it did not touch the table).
    pub landing: [f64; 3],
    /// Distance (m) from the landing point to the target (NaN without landing).
    pub landing_error: f64,
    /// Error (m/s) of the estimated velocity at the last observation.
    pub velocity_error: f64,
    /// Re-plans adopted during the stroke (the correction after the bounce included).
    pub replans: usize,
    /// Thread CPU time (µs) of the correction after the bounce (update and plan; NaN without one).
    pub correction_time_us: f64,
    /// Predicted ball at the executed hit's impact (time absolute, s) and its face normal (world).
    pub planned: Option<(BallState, Vector3<f64>)>,
    /// Profile of the executed hit leg ("quintic", "jerk"; "" without a planned hit).
    pub profile: &'static str,
    /// Sampled true ball path (m, world; 5 ms) and racket-centre path, for the first balls.
    pub path: Vec<[f64; 3]>,
    /// Racket-centre path (m, world), same times as `path` while the stroke lasts.
    pub racket_path: Vec<[f64; 3]>,
}

/// What the robot actually did for a commanded stroke: joint positions and velocities at times
/// `t` (s from the stroke's start), `dof` columns, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Executed {
    /// Joints.
    pub dof: usize,
    /// Sample times (s from the stroke's start, increasing).
    pub t: Vec<f64>,
    /// Joint positions (rad or m), K × dof.
    pub q: Vec<f64>,
    /// Joint speeds (rad/s or m/s), K × dof.
    pub qd: Vec<f64>,
}

impl Executed {
    /// Joint state at `t` (s from the start): linear interpolation, held beyond the ends.
    pub(super) fn sample(&self, t: f64, q: &mut [f64], qd: &mut [f64]) {
        let n = self.dof;
        let k = self.t.partition_point(|&x| x <= t).clamp(1, self.t.len().max(2) - 1);
        let (t0, t1) = (self.t[k - 1], self.t[k.min(self.t.len() - 1)]);
        let s = if t1 > t0 {
            ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let k1 = k.min(self.t.len() - 1);
        for j in 0..n {
            q[j] = self.q[(k - 1) * n + j] + s * (self.q[k1 * n + j] - self.q[(k - 1) * n + j]);
            qd[j] = self.qd[(k - 1) * n + j] + s * (self.qd[k1 * n + j] - self.qd[(k - 1) * n + j]);
        }
    }
}

/// The racket at one instant (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacketState {
    /// Racket centre (m).
    pub centre: Vector3<f64>,
    /// Face normal (unit).
    pub normal: Vector3<f64>,
    /// Velocity of the centre (m/s).
    pub velocity: Vector3<f64>,
    /// Angular velocity (rad/s).
    pub omega: Vector3<f64>,
}

/// The racket of `planner`'s robot (world frame, through its placement) at joint positions `q`
/// (m, rad) and velocities `qd`: forward kinematics and the Jacobian.
pub fn racket_state(planner: &ReturnPlanner, q: &[f64], qd: &[f64]) -> RacketState {
    let world = planner.placement.world_from_base();
    let pose = world * planner.chain().fk(q).expect("sizes match");
    let jac = planner.chain().jacobian(q, JacobianFrame::Base).expect("sizes match");
    let tw = jac * nalgebra::DVector::from_column_slice(qd);
    RacketState {
        centre: pose.translation.vector,
        normal: pose.rotation * Vector3::z(),
        velocity: world.rotation * Vector3::new(tw[0], tw[1], tw[2]),
        omega: world.rotation * Vector3::new(tw[3], tw[4], tw[5]),
    }
}

/// How a ball met the racket and where it went ([`score`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// Whether the racket met the ball (contact point within the racket radius of its centre).
    pub contact: bool,
    /// Whether the return's first contact is the table on the opponent's half.
    pub returned: bool,
    /// Distance (m) of the contact point from the racket centre; without contact the ball's
    /// closest distance to the racket's normal axis.
    pub racket_error: f64,
    /// Landing point (m, world) of the return (NaN when it did not touch the table).
    pub landing: [f64; 3],
    /// Distance (m) from the landing point to the target (NaN without landing).
    pub landing_error: f64,
    /// "returned", "landed_short", `return_hit_<event>`, "return_long" or "missed".
    pub status: String,
    /// The ball leaving the racket (world), with contact.
    pub after: Option<BallState>,
}

/// The rally's scoring of one ball: the true ball `from` (any state of it before `hit_abs` − 60
/// ms, flying in `truth`) against the racket `racket_at(t)` (t absolute, s): the first time from
/// 60 ms before to 60 ms after `hit_abs` (s) the ball's distance to the face plane falls to its
/// radius (0.5 ms steps, then bisection) with the contact point within the racket radius of its
/// centre; the ball then leaves by `planner`'s racket impact model with the racket's normal and
/// point velocity, and flies until its first contact, which decides the return (landing on the
/// opponent's half; `target`, x, y m, for the landing error).
pub fn score(
    planner: &ReturnPlanner,
    truth: &Flight,
    target: [f64; 2],
    from: &BallState,
    hit_abs: f64,
    racket_at: &mut dyn FnMut(f64) -> RacketState,
) -> Score {
    let mut out = Score {
        contact: false,
        returned: false,
        racket_error: f64::NAN,
        landing: [f64::NAN; 3],
        landing_error: f64::NAN,
        status: "missed".into(),
        after: None,
    };
    let r = truth.model.radius;
    let t_open = hit_abs - 0.06;
    let (mut ball, _) = truth.run(from, t_open, None);
    let gap = |b: &BallState, rk: &RacketState| rk.normal.dot(&(b.p - rk.centre)) - r;
    let off = |b: &BallState, rk: &RacketState| {
        let d = b.p - rk.centre;
        (d - rk.normal * rk.normal.dot(&d)).norm()
    };
    let mut contact = None;
    let mut closest = f64::INFINITY;
    let dt = 0.0005;
    let mut g = gap(&ball, &racket_at(ball.t));
    while ball.t < hit_abs + 0.06 && contact.is_none() {
        let (next, ev) = truth.advance(&ball, ball.t + dt, None);
        if ev.is_some_and(|e| e.kind.terminal()) {
            break;
        }
        let rk1 = racket_at(next.t);
        let g1 = gap(&next, &rk1);
        closest = closest.min(off(&next, &rk1));
        if g > 0.0 && g1 <= 0.0 && ev.is_none() {
            let (mut lo, mut hi) = (0.0, next.t - ball.t);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                let b = truth.rk4(&ball, mid);
                if gap(&b, &racket_at(b.t)) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let b = truth.rk4(&ball, lo);
            let rkc = racket_at(b.t);
            let offset = off(&b, &rkc);
            // The face plane passing the ball outside the racket is no contact: keep looking.
            if offset <= planner.impact.radius {
                contact = Some((b, rkc, offset));
            }
        }
        ball = next;
        g = g1;
    }
    let Some((b, rkc, offset)) = contact else {
        out.racket_error = closest;
        return out;
    };
    out.racket_error = offset;
    out.contact = true;
    let point = b.p - r * rkc.normal;
    let v_point = rkc.velocity + rkc.omega.cross(&(point - rkc.centre));
    let (v, w) = planner.impact.hit(&truth.model, &b.v, &b.w, &rkc.normal, &v_point);
    let after = BallState { v, w, ..b };
    let (_, events) = truth.run(&after, b.t + 2.0, None);
    out.after = Some(after);
    match events.first() {
        Some(e) if e.kind == EventKind::Table => {
            out.landing = e.before.p.into();
            out.landing_error = (e.before.p.xy() - Vector3::new(target[0], target[1], 0.0).xy()).norm();
            out.returned = truth.table.on_opponent_half(e.before.p.x, e.before.p.y);
            out.status = if out.returned { "returned" } else { "landed_short" }.into();
        }
        Some(e) => out.status = format!("return_hit_{}", e.kind.name()),
        None => out.status = "return_long".into(),
    }
    out
}

/// [`score`] with the racket following a joint motion `executed` (e.g. the measured joint states
/// of a controller; its times from `t_start`, s absolute, linear interpolation, held beyond the
/// ends), through [`racket_state`].
pub fn score_executed(
    planner: &ReturnPlanner,
    truth: &Flight,
    target: [f64; 2],
    from: &BallState,
    hit_abs: f64,
    executed: &Executed,
    t_start: f64,
) -> Result<Score> {
    let n = planner.chain().dof();
    let k = executed.t.len();
    if executed.dof != n || k == 0 || executed.q.len() != k * n || executed.qd.len() != k * n {
        return Err(Error::shape(
            "executed",
            format!("{n} joints, positions and velocities of equal length ≥ 1 sample"),
            format!(
                "{} joints, {} times, {} q, {} qd",
                executed.dof,
                k,
                executed.q.len(),
                executed.qd.len()
            ),
        ));
    }
    if executed.t.windows(2).any(|w| !(w[1] > w[0])) || executed.q.iter().chain(&executed.qd).any(|x| !x.is_finite()) {
        return Err(Error::invalid(
            "executed",
            "times must increase and every joint value be finite",
        ));
    }
    let (mut q, mut qd) = (vec![0.0; n], vec![0.0; n]);
    let mut racket_at = |t: f64| {
        executed.sample(t - t_start, &mut q, &mut qd);
        racket_state(planner, &q, &qd)
    };
    Ok(score(planner, truth, target, from, hit_abs, &mut racket_at))
}

/// True positions every 5 ms for `duration` s from `s`, ending at a terminal event.
pub(super) fn sample_path(flight: &Flight, s: &BallState, duration: f64) -> Vec<[f64; 3]> {
    let times: Vec<f64> = (0..=((duration - s.t).max(0.0) / 0.005) as usize)
        .map(|k| s.t + k as f64 * 0.005)
        .collect();
    let pred = crate::ball::predict::predict(flight, s, &times).expect("valid times");
    pred.positions.into_iter().filter(|p| p[0].is_finite()).collect()
}

/// One ball's sampled paths for figures (m, world; every 5 ms): the true ball and, while the
/// stroke lasts, the racket centre; with the ball's status.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SampledPath {
    /// Ball centre positions (m, world).
    pub ball: Vec<[f64; 3]>,
    /// Racket centre positions (m, world), at the same times as the first `ball` rows.
    pub racket: Vec<[f64; 3]>,
    /// The ball's status ([`BallOutcome::status`]).
    pub status: String,
}

/// A rally's outcomes as columns, one entry per ball in ball order ([`BallOutcome`]'s fields;
/// arrays of several values per ball row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct Outcomes {
    /// Balls.
    pub n: usize,
    /// Incoming states (n × 10: t (s), position (m), velocity (m/s), spin (rad/s), world).
    pub incoming: Vec<f64>,
    /// Whether each ball is in reach.
    pub in_reach: Vec<bool>,
    /// The region's verdict per ball.
    pub reach: Vec<&'static str>,
    /// Whether each ball was returned.
    pub returned: Vec<bool>,
    /// Whether the racket met each ball.
    pub contact: Vec<bool>,
    /// Status per ball.
    pub status: Vec<String>,
    /// Contact point's distance from the racket centre (m).
    pub racket_error: Vec<f64>,
    /// Planning CPU time (µs).
    pub plan_time_us: Vec<f64>,
    /// Planning wall-clock time (µs).
    pub plan_wall_time_us: Vec<f64>,
    /// Correction CPU time (µs).
    pub correction_time_us: Vec<f64>,
    /// Landing point's distance from the target (m).
    pub landing_error: Vec<f64>,
    /// Error of the estimated velocity (m/s).
    pub velocity_error: Vec<f64>,
    /// Landing points (n × 3, m, world).
    pub landing: Vec<f64>,
    /// The sampled paths of the balls that kept one ([`super::RallyConfig::paths`]), in ball order.
    pub paths: Vec<SampledPath>,
}

impl Outcomes {
    /// The columns of `balls`.
    pub fn new(balls: &[BallOutcome]) -> Self {
        let col = |f: fn(&BallOutcome) -> f64| balls.iter().map(f).collect::<Vec<f64>>();
        Outcomes {
            n: balls.len(),
            incoming: balls.iter().flat_map(|o| o.incoming.to_array()).collect(),
            in_reach: balls.iter().map(|o| o.in_reach).collect(),
            reach: balls.iter().map(|o| o.reach).collect(),
            returned: balls.iter().map(|o| o.returned).collect(),
            contact: balls.iter().map(|o| o.contact).collect(),
            status: balls.iter().map(|o| o.status.clone()).collect(),
            racket_error: col(|o| o.racket_error),
            plan_time_us: col(|o| o.plan_time_us),
            plan_wall_time_us: col(|o| o.plan_wall_time_us),
            correction_time_us: col(|o| o.correction_time_us),
            landing_error: col(|o| o.landing_error),
            velocity_error: col(|o| o.velocity_error),
            landing: balls.iter().flat_map(|o| o.landing).collect(),
            paths: balls
                .iter()
                .filter(|o| !o.path.is_empty())
                .map(|o| SampledPath {
                    ball: o.path.clone(),
                    racket: o.racket_path.clone(),
                    status: o.status.clone(),
                })
                .collect(),
        }
    }
}
