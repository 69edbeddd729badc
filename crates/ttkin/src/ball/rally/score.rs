//! Scoring one ball of the rally: where the racket meets the true ball (bisection on the gap to
//! the face plane), the ball's flight after the impact and where it lands; what happened to each
//! ball ([`BallOutcome`]) and a rally's outcomes as columns ([`Outcomes`]).

use super::RallyConfig;
use crate::ball::flight::{BallState, EventKind, Flight};
use crate::ball::hitplan::ReturnPlanner;
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

/// The racket at one instant (world): centre (m), face normal, centre velocity (m/s) and angular
/// velocity (rad/s).
pub type RacketSample = (Vector3<f64>, Vector3<f64>, Vector3<f64>, Vector3<f64>);

/// Plays out the impact of the true ball (at `truth_at_last` at the last observation of the first
/// window) on the racket following `racket_at` (s, absolute) around the hit at `hit_abs` (s):
/// contact, the ball's flight after it and the score, into `out`; with `keep_path` the sampled
/// ball and racket paths from `s0`.
#[allow(clippy::too_many_arguments)]
pub(super) fn strike(
    out: &mut BallOutcome,
    planner: &ReturnPlanner,
    truth: &Flight,
    cfg: &RallyConfig,
    s0: &BallState,
    truth_at_last: &BallState,
    hit_abs: f64,
    keep_path: bool,
    racket_at: &mut dyn FnMut(f64) -> RacketSample,
) {
    let r = truth.model.radius;
    let t_open = hit_abs - 0.06;
    let (mut ball, _) = truth.run(truth_at_last, t_open, None);
    let gap = |b: &BallState, rk: &RacketSample| rk.1.dot(&(b.p - rk.0)) - r;
    let mut contact = None;
    let mut closest = f64::INFINITY;
    let dt = 0.0005;
    let mut rk = racket_at(ball.t);
    let mut g = gap(&ball, &rk);
    while ball.t < hit_abs + 0.06 && contact.is_none() {
        let (next, ev) = truth.advance(&ball, ball.t + dt, None);
        if ev.is_some_and(|e| e.kind.terminal()) {
            break;
        }
        let rk1 = racket_at(next.t);
        let g1 = gap(&next, &rk1);
        let off = |b: &BallState, rk: &RacketSample| {
            let d = b.p - rk.0;
            (d - rk.1 * rk.1.dot(&d)).norm()
        };
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
            if offset <= planner.racket.radius {
                contact = Some((b, rkc, offset));
            }
        }
        ball = next;
        rk = rk1;
        g = g1;
    }
    let _ = rk;
    if keep_path {
        out.path = sample_path(truth, s0, hit_abs);
        out.racket_path = (0..out.path.len())
            .map(|k| racket_at(k as f64 * 0.005).0.into())
            .collect();
    }
    let Some((b, rkc, offset)) = contact else {
        out.racket_error = closest;
        out.status = "missed".into();
        return;
    };
    out.racket_error = offset;
    if offset > planner.racket.radius {
        out.status = "missed".into();
        return;
    }
    out.contact = true;
    let point = b.p - r * rkc.1;
    let v_point = rkc.2 + rkc.3.cross(&(point - rkc.0));
    let (v, w) = planner.racket.hit(&truth.model, &b.v, &b.w, &rkc.1, &v_point);
    let after = BallState { v, w, ..b };
    let (_, events) = truth.run(&after, b.t + 2.0, None);
    if keep_path {
        let tail = sample_path(truth, &after, after.t + 1.0);
        out.path.extend(tail);
    }
    match events.first() {
        Some(e) if e.kind == EventKind::Table => {
            out.landing = e.before.p.into();
            out.landing_error = (e.before.p.xy() - Vector3::new(cfg.target[0], cfg.target[1], 0.0).xy()).norm();
            out.returned = truth.table.on_opponent_half(e.before.p.x, e.before.p.y);
            out.status = if out.returned {
                "returned".into()
            } else {
                "landed_short".into()
            };
        }
        Some(e) => out.status = format!("return_hit_{}", e.kind.name()),
        None => out.status = "return_long".into(),
    }
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
