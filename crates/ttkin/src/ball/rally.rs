//! The closed loop in simulation: an opponent plays a ball, a camera observes it, the robot
//! estimates, plans and executes its stroke, the ball meets the racket and flies back.
//!
//! **Incoming balls** (ordinary club-level rallies, not elite play): played from behind the
//! opponent's end line, x ∈ [1.45, 1.9] m, |y| ≤ 0.5 m, 0.1–0.35 m above the surface, landing on
//! the robot's half at x ∈ [−1.15, −0.35] m, |y| ≤ 0.55 m after 0.35–0.6 s (ball speeds about 4–8
//! m/s), spin of 0–40 rev/s (0–250 rad/s) about an axis at a uniformly random angle between the
//! top/back-spin axis (horizontal, across the flight) and the side-spin axis (vertical), tilted
//! toward the flight direction by at most ±11° (`corkscrew` = 0.2). Spin about the flight direction
//! (corkscrew) produces no Magnus force, so it cannot be seen in flight, yet the bounce turns it
//! into sideways speed (r·ω = 2 m/s at 100 rad/s); ordinary strokes (drive, loop, push, chop,
//! side-spin serve) put the axis mostly across the flight, which is what is drawn here. Balls that
//! would touch the net are drawn again.
//!
//! **Camera**: 200 Hz, positions with Gaussian noise σ = 2 mm per axis, 2 % outliers displaced by
//! up to 10 cm, observed from 0.02 s to 0.22 s after the opponent's hit, delivered 10 ms later
//! (latency); planning happens at the delivery of the last observation.
//!
//! **Execution**: the planned stroke is executed exactly (no drive simulation): the racket follows
//! the hit leg the planner accepted ([`super::leg`]: quintic or jerk-limited; on a re-plan the new
//! leg from the state at that time; by default one correction 30 ms after the bounce with the
//! estimate updated through it, [`RallyConfig::correction_delay`]) and then a 0.4 s quintic back to the ready configuration; the racket pose and
//! velocity at the impact come from forward kinematics and the Jacobian along it. The true ball is
//! integrated at 1 ms; the impact happens when the ball's distance to the racket plane falls to its
//! radius (bisection) and counts when the contact point lies within the racket radius of its
//! centre; the ball then leaves by the racket impact model with the racket's actual normal and
//! point velocity. **Scoring**: returned when its first contact is the table on the opponent's
//! half. A ball is **in reach** when [`ReachRegion::classify`] says so: a return is physically
//! possible, by the robot's geometry, the ball and impact physics and the joint limits alone,
//! independently of the planner (see [`super::reach`]). Balls out of reach are counted
//! separately, with the reason.

use super::decide::{BallDecider, DecideConfig, Decision, CORRECTION_MIN_STROKE};
use super::estimate::{estimate, EstimateOptions};
use super::flight::{BallState, EventKind, Flight};
use super::hitplan::{shoot, Hit, HitPlanner, HitStatus};
use super::model::BallModel;
use super::reach::ReachRegion;
use crate::chain::JacobianFrame;
use crate::traj::{JointState, JointTrajectory};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::time::Instant;

/// Camera model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Frame rate (Hz).
    pub rate: f64,
    /// Delay from exposure to delivery (s).
    pub latency: f64,
    /// Position noise σ per axis (m).
    pub noise: f64,
    /// Probability of an outlier observation.
    pub outlier_rate: f64,
    /// Largest outlier displacement per axis (m).
    pub outlier_size: f64,
    /// First observation after the opponent's hit (s).
    pub start: f64,
    /// Observation window (s).
    pub window: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            rate: 200.0,
            latency: 0.010,
            noise: 0.002,
            outlier_rate: 0.02,
            outlier_size: 0.10,
            start: 0.02,
            window: 0.20,
        }
    }
}

/// How the simulated world departs from the planner's model, drawn anew for every ball (from its
/// own random stream, so the incoming balls are the same with and without it): the true ball's
/// drag and Magnus constants scaled by (1 + σ·N(0, 1)), its table restitution and friction moved
/// by σ·N(0, 1) (clamped to their physical ranges), and the camera's time stamps off by a constant
/// uniform in ±`latency_jitter` for the ball (the delivery latency differs from the one the
/// planner assumes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldSpread {
    /// Relative standard deviation of k_d.
    pub k_drag: f64,
    /// Relative standard deviation of k_m.
    pub k_magnus: f64,
    /// Standard deviation of the table restitution.
    pub restitution: f64,
    /// Standard deviation of the table friction.
    pub friction: f64,
    /// Largest time-stamp error (s) of the observations.
    pub latency_jitter: f64,
}

impl WorldSpread {
    /// The spreads between the calibrations of the four ball-gun groups of the PAM flights
    /// (docs/ball.md, "The world the planner does not know"): k_d 4 %, k_m 45 % (0.00064–0.00235),
    /// restitution 0.008; friction 0.05 and ±3 ms of latency jitter are assumed, not measured (the
    /// flights do not identify μ and carry no time stamps).
    pub fn measured() -> Self {
        WorldSpread {
            k_drag: 0.04,
            k_magnus: 0.45,
            restitution: 0.008,
            friction: 0.05,
            latency_jitter: 0.003,
        }
    }

    /// The ball model of one ball's world: `model` with its constants drawn with `rng`.
    pub fn draw(&self, model: &BallModel, rng: &mut fastrand::Rng) -> BallModel {
        BallModel {
            k_drag: (model.k_drag * (1.0 + self.k_drag * gauss(rng))).max(0.0),
            k_magnus: (model.k_magnus * (1.0 + self.k_magnus * gauss(rng))).max(0.0),
            table_restitution: (model.table_restitution + self.restitution * gauss(rng)).clamp(0.0, 1.0),
            table_friction: (model.table_friction + self.friction * gauss(rng)).max(0.0),
            ..*model
        }
    }
}

/// Rally settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RallyConfig {
    /// Camera.
    pub camera: Camera,
    /// Landing target of the return (x, y, m, world; on the opponent's half).
    pub target: [f64; 2],
    /// Largest incoming spin (rev/s).
    pub max_spin_rps: f64,
    /// Largest corkscrew tilt of the spin axis toward the flight direction (tan of the angle; 0.2 ≈ 11°).
    pub corkscrew: f64,
    /// Random seed.
    pub seed: u64,
    /// Balls for which the true flight is kept as a path (for figures): the first `paths`.
    pub paths: usize,
    /// Re-planning period (s) during the stroke with the newest observations; 0 (default) plans
    /// once. Experimental: with the estimator as it is, re-planning lowers the return rate (the
    /// spin along the flight direction is poorly observed and later windows move the hit point).
    pub replan_period: f64,
    /// Longest observation window (s) of a re-plan's estimate.
    pub max_window: f64,
    /// Time (s) after the bounce the first estimate predicts at which the stroke is corrected once:
    /// the estimate updated with the observations delivered by then ([`super::update::update`]) and the hit
    /// planned again from the robot's state; 0 for none.
    pub correction_delay: f64,
    /// The world's departure from the planner's model per ball; `None`: the world is the model.
    pub world: Option<WorldSpread>,
}

impl Default for RallyConfig {
    fn default() -> Self {
        RallyConfig {
            camera: Camera::default(),
            target: [0.9, 0.0],
            max_spin_rps: 40.0,
            corkscrew: 0.2,
            seed: 0,
            paths: 5,
            replan_period: 0.0,
            max_window: 0.25,
            correction_delay: 0.03,
            world: None,
        }
    }
}

impl DecideConfig {
    /// The rules of the rally `cfg`: its target, its camera's window and frame period, its
    /// correction delay.
    pub fn of(cfg: &RallyConfig) -> Self {
        DecideConfig {
            target: cfg.target,
            window_frames: (cfg.camera.window * cfg.camera.rate).round() as usize + 1,
            frame_period: 1.0 / cfg.camera.rate,
            correction_delay: cfg.correction_delay,
        }
    }
}

impl Default for DecideConfig {
    fn default() -> Self {
        DecideConfig::of(&RallyConfig::default())
    }
}

/// What happened to one ball.
#[derive(Debug, Clone, PartialEq)]
pub struct BallOutcome {
    /// Incoming state at the opponent's hit (t = 0).
    pub incoming: BallState,
    /// Whether the ball is in the robot's reachable region ([`ReachRegion::classify`] of its true flight).
    pub in_reach: bool,
    /// The region's verdict: "in_reach", or why not (one of [`super::reach::Reachability::NAMES`]).
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

fn gauss(rng: &mut fastrand::Rng) -> f64 {
    let u = rng.f64().max(1e-300);
    let v = rng.f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

fn uniform(rng: &mut fastrand::Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.f64()
}

/// An incoming ball from the opponent (see the module doc), drawn with `rng`.
pub fn serve(flight: &Flight, rng: &mut fastrand::Rng, max_spin_rps: f64, corkscrew: f64) -> BallState {
    let r = flight.model.radius;
    loop {
        let p = Vector3::new(
            uniform(rng, 1.45, 1.9),
            uniform(rng, -0.5, 0.5),
            uniform(rng, 0.10, 0.35),
        );
        let land = Vector3::new(uniform(rng, -1.15, -0.35), uniform(rng, -0.55, 0.55), r);
        let tf = uniform(rng, 0.35, 0.6);
        // Spin axis: top/back spin (horizontal, across the flight) to side spin (vertical), tilted
        // toward the flight direction (corkscrew spin) by at most `corkscrew` (tan of the tilt).
        let d = Vector3::new(land.x - p.x, land.y - p.y, 0.0).normalize();
        let phi = uniform(rng, 0.0, std::f64::consts::TAU);
        let axis =
            phi.cos() * Vector3::z().cross(&d) + phi.sin() * Vector3::z() + uniform(rng, -corkscrew, corkscrew) * d;
        let w = axis.normalize() * uniform(rng, 0.0, max_spin_rps) * std::f64::consts::TAU;
        let Some(v) = shoot(flight, &p, &land, tf, |_| Some(w)) else {
            continue;
        };
        let s = BallState { t: 0.0, p, v, w };
        let (_, ev) = flight.run(&s, tf + 0.1, None);
        if ev
            .first()
            .is_some_and(|e| e.kind == EventKind::Table && e.before.p.x < 0.0)
        {
            return s;
        }
    }
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

/// Executes a stroke on the robot (the rally's execution hook; `ttcan` implements it with the
/// coupled drive simulation, since `ttkin` may not depend on `ttcan`). The reference: samples at
/// `times` (s from the stroke's start, increasing, uniform) of q, q̇, q̈ (K × n, row-major), the
/// robot at rest at the first sample; `None` when the execution failed (a drive fault).
pub trait Executor: Sync {
    /// The executed motion for the reference (see the trait doc).
    fn execute(&self, times: &[f64], q: &[f64], qd: &[f64], qdd: &[f64]) -> Option<Executed>;
}

impl Executed {
    /// Joint state at `t` (s from the start): linear interpolation, held beyond the ends.
    fn sample(&self, t: f64, q: &mut [f64], qd: &mut [f64]) {
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

/// Sample period (s) of the reference handed to an [`Executor`].
const EXECUTION_PERIOD: f64 = 0.001;

/// A stroke made of pieces: each re-plan replaces the motion from its start time (s, absolute).
struct Motion {
    pieces: Vec<(f64, JointTrajectory)>,
}

impl Motion {
    /// Joint state at absolute time `t` (s); before the first piece, rest at its start.
    fn sample(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        let (t0, traj) = self
            .pieces
            .iter()
            .rev()
            .find(|(t0, _)| *t0 <= t)
            .unwrap_or(&self.pieces[0]);
        let tt = (t - t0).clamp(0.0, traj.duration());
        traj.sample(tt, q, qd, qdd).expect("sizes match");
        if t - t0 > traj.duration() {
            qd.fill(0.0);
            qdd.fill(0.0);
        }
    }

    fn state(&self, t: f64, n: usize) -> JointState {
        let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        self.sample(t, &mut q, &mut qd, &mut qdd);
        JointState { q, qd, qdd }
    }
}

/// One ball of the rally as the camera sees it: the incoming ball, the world it flies in, and its
/// observations (see [`play_with`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BallObservations {
    /// Incoming state at the opponent's hit (t = 0).
    pub incoming: BallState,
    /// The ball's world: `truth` with its constants drawn by [`RallyConfig::world`].
    pub world: Flight,
    /// Exposure times (s from the opponent's hit), the camera's whole run.
    pub exposures: Vec<f64>,
    /// The time stamps the planner sees (s): the exposures, off by the ball's time-stamp error.
    pub times: Vec<f64>,
    /// Observed ball centres (m, world): the true ones with the camera's noise and outliers.
    pub positions: Vec<[f64; 3]>,
}

/// Ball `index` of the rally as the camera sees it (served, or `incoming` when given, re-based to
/// t = 0): the same random streams as [`play_with`], so the same ball and observations.
pub fn observe_ball(truth: &Flight, cfg: &RallyConfig, index: u64, incoming: Option<&BallState>) -> BallObservations {
    let mut rng = fastrand::Rng::with_seed(
        cfg.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03),
    );
    let s0 = match incoming {
        Some(s) => BallState { t: 0.0, ..*s },
        None => serve(truth, &mut rng, cfg.max_spin_rps, cfg.corkscrew),
    };
    // The ball's own world, from a stream of its own (the serve and the camera noise unchanged).
    let mut world_rng = fastrand::Rng::with_seed(
        cfg.seed.wrapping_mul(0xA076_1D64_78BD_642F) ^ index.wrapping_mul(0xE703_7ED1_A0B4_28DB) ^ 0x5EED,
    );
    let (world, stamp_error) = match &cfg.world {
        Some(w) => (
            Flight {
                model: w.draw(&truth.model, &mut world_rng),
                ..*truth
            },
            w.latency_jitter * (2.0 * world_rng.f64() - 1.0),
        ),
        None => (*truth, 0.0),
    };
    let cam = &cfg.camera;
    // The camera runs for the whole incoming flight; each plan sees what was delivered by then.
    let count = (1.2 * cam.rate) as usize;
    let exposures: Vec<f64> = (0..count).map(|k| cam.start + k as f64 / cam.rate).collect();
    let truth_path = super::predict::predict(&world, &s0, &exposures).expect("valid times");
    // The time stamps the planner sees: the exposures, off by the ball's latency error.
    let times: Vec<f64> = exposures.iter().map(|t| t + stamp_error).collect();
    let obs: Vec<[f64; 3]> = truth_path
        .positions
        .iter()
        .map(|p| {
            let mut o = *p;
            let outlier = rng.f64() < cam.outlier_rate;
            for x in o.iter_mut() {
                *x += cam.noise * gauss(&mut rng);
                if outlier {
                    *x += uniform(&mut rng, -cam.outlier_size, cam.outlier_size);
                }
            }
            o
        })
        .collect();
    BallObservations {
        incoming: s0,
        world,
        exposures,
        times,
        positions: obs,
    }
}

/// Plays ball `index` of the rally: serve, observe, classify against `region`, plan, re-plan,
/// execute, score.
pub fn play(planner: &HitPlanner, region: &ReachRegion, truth: &Flight, cfg: &RallyConfig, index: u64) -> BallOutcome {
    play_with(planner, region, truth, cfg, index, None, None)
}

/// [`play`] with the incoming ball given (`incoming`, e.g. a recorded shot; time stamps from its
/// `t`, re-based to 0) instead of served. With [`RallyConfig::world`] the ball flies in its own
/// world (constants drawn around `truth`'s, see [`WorldSpread`]) while the planner keeps its model.
/// With an `executor` the stroke (as planned, re-plans included) is executed by it from the
/// planning time to 60 ms after the hit, and the racket follows the executed motion.
pub fn play_with(
    planner: &HitPlanner,
    region: &ReachRegion,
    truth: &Flight,
    cfg: &RallyConfig,
    index: u64,
    incoming: Option<&BallState>,
    executor: Option<&dyn Executor>,
) -> BallOutcome {
    let BallObservations {
        incoming: s0,
        world,
        exposures,
        times,
        positions: obs,
    } = observe_ball(truth, cfg, index, incoming);
    let truth = &world;
    let cam = &cfg.camera;
    let first = (cam.window * cam.rate).round() as usize + 1;
    let t_last = times[first - 1];
    let now = t_last + cam.latency;
    let (truth_at_last, _) = truth.run(&s0, exposures[first - 1], None);
    let reach = region.classify(truth, &s0, now);
    let mut out = BallOutcome {
        incoming: s0,
        in_reach: reach.in_reach(),
        reach: reach.name(),
        status: String::new(),
        contact: false,
        returned: false,
        racket_error: f64::NAN,
        plan_time_us: f64::NAN,
        plan_wall_time_us: f64::NAN,
        now,
        estimate: None,
        landing: [f64::NAN; 3],
        landing_error: f64::NAN,
        velocity_error: f64::NAN,
        replans: 0,
        correction_time_us: f64::NAN,
        planned: None,
        profile: "",
        path: Vec::new(),
        racket_path: Vec::new(),
    };
    let opts = EstimateOptions {
        flight: planner.flight,
        ..EstimateOptions::default()
    };
    // The decisions, observation by observation at its delivery ([`BallDecider`]): the first plan
    // after the window, then once, `correction_delay` after the bounce the estimate predicts, the
    // estimate updated with every observation delivered since (through the bounce, [`update`])
    // and the hit planned again from the robot's state then (from rest when the first plan had
    // no hit).
    let keep_path = (index as usize) < cfg.paths;
    let n = planner.chain.dof();
    let ready = JointState::rest(&planner.ready);
    let mut decider = BallDecider::new(planner, DecideConfig::of(cfg));
    let mut motion = Motion { pieces: Vec::new() };
    let mut first_hit: Option<Hit> = None;
    let mut hit_at = None;
    let mut est = None;
    for (&t, p) in times.iter().zip(&obs) {
        if decider.done() {
            break;
        }
        let clock = Instant::now();
        let cpu = cpu_time::ThreadTime::now();
        let decision = decider.observe(planner, t, *p, t + cam.latency, &|tc| motion.state(tc, n));
        match decision {
            None => {}
            Some(Decision::EstimateFailed(e)) => {
                out.status = format!("estimate: {e}");
                return out;
            }
            Some(Decision::PlanFailed(e)) => {
                out.plan_time_us = cpu.elapsed().as_secs_f64() * 1e6;
                out.plan_wall_time_us = clock.elapsed().as_secs_f64() * 1e6;
                if let Some(e) = decider.estimate() {
                    out.velocity_error = (e.state.v - truth_at_last.v).norm();
                    out.estimate = Some(e.state);
                }
                out.status = format!("plan: {e}");
                return out;
            }
            Some(Decision::Planned { now, estimate, plan }) => {
                out.plan_time_us = cpu.elapsed().as_secs_f64() * 1e6;
                out.plan_wall_time_us = clock.elapsed().as_secs_f64() * 1e6;
                out.velocity_error = (estimate.state.v - truth_at_last.v).norm();
                out.estimate = Some(estimate.state);
                out.status = plan.status.name().to_string();
                first_hit = plan.hit.filter(|_| plan.status == HitStatus::Ok);
                if let Some(h) = &first_hit {
                    motion.pieces.push((now, execution(h, &ready)));
                    hit_at = Some(now + h.t_hit);
                }
                est = Some(*estimate);
            }
            Some(Decision::Corrected { now: t_c, hit }) => {
                out.correction_time_us = cpu.elapsed().as_secs_f64() * 1e6;
                if let Some(h) = hit {
                    motion.pieces.push((t_c, execution(&h, &ready)));
                    hit_at = Some(t_c + h.t_hit);
                    first_hit = Some(*h);
                    out.replans += 1;
                }
            }
        }
    }
    let Some(est) = est else {
        return out;
    };
    let Some(mut hit) = first_hit else {
        if keep_path {
            out.path = sample_path(truth, &s0, 1.2);
        }
        return out;
    };
    let n = hit.q_hit.len();
    let leg = |hit: &Hit| execution(hit, &ready);
    let mut hit_abs = hit_at.expect("a hit has its time");
    // Re-plan every `replan_period` with the newest observations (at most `max_window` s of them)
    // while the stroke has at least `replan.min_stroke_time` left. Observations are split at the
    // bounce predicted by the latest estimate: before it the arc before the bounce is used; once
    // the arc after it lasts long enough to fit the spin, that arc alone.
    let mut replanner = planner.clone();
    replanner.min_stroke_time = 0.06;
    let bounce_of = |s: &BallState| {
        let (_, ev) = planner.flight.run(s, s.t + 1.5, None);
        ev.iter()
            .find(|e| e.kind == EventKind::Table && e.before.p.x < 0.0)
            .map(|e| e.before.t)
    };
    let mut t_bounce = bounce_of(&est.state);
    let mut t_plan = now + cfg.replan_period;
    while cfg.replan_period > 0.0 && hit_abs - t_plan > replanner.min_stroke_time {
        let seen = times.partition_point(|&t| t + cam.latency <= t_plan);
        let t_new = times[seen - 1];
        let (lo, hi, after) = match t_bounce {
            Some(tb) if t_new > tb + 0.005 + opts.spin_min_duration => (tb + 0.005, t_new, true),
            Some(tb) if t_new > tb - 0.005 => {
                t_plan += cfg.replan_period;
                continue;
            }
            _ => (t_new - cfg.max_window, t_new, false),
        };
        let from = times.partition_point(|&t| t < lo.max(t_new - cfg.max_window));
        let to = times.partition_point(|&t| t <= hi);
        if let Ok(e) = estimate(&times[from..to], &obs[from..to], &opts) {
            if !after {
                t_bounce = bounce_of(&e.state).or(t_bounce);
            }
            let start = motion.state(t_plan, n);
            if let Ok(p) = replanner.plan_from(&e.state, t_plan, cfg.target, &start, after) {
                if let Some(h) = p.hit.filter(|_| p.status == HitStatus::Ok) {
                    hit = h;
                    hit_abs = t_plan + hit.t_hit;
                    motion.pieces.push((t_plan, leg(&hit)));
                    out.replans += 1;
                }
            }
        }
        t_plan += cfg.replan_period;
    }
    out.profile = hit.leg.profile.name();
    out.planned = Some((hit.ball, hit.racket.normal));
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    // The executed motion, when an executor runs the stroke: from its start to 60 ms past the hit.
    let t_start = motion.pieces[0].0;
    let executed = match executor {
        Some(ex) => {
            let k = ((hit_abs + 0.06 - t_start) / EXECUTION_PERIOD).ceil() as usize + 1;
            let times: Vec<f64> = (0..k).map(|i| i as f64 * EXECUTION_PERIOD).collect();
            let (mut rq, mut rqd, mut rqdd) = (
                Vec::with_capacity(k * n),
                Vec::with_capacity(k * n),
                Vec::with_capacity(k * n),
            );
            for &t in &times {
                motion.sample(t_start + t, &mut q, &mut qd, &mut qdd);
                rq.extend_from_slice(&q);
                rqd.extend_from_slice(&qd);
                rqdd.extend_from_slice(&qdd);
            }
            match ex.execute(&times, &rq, &rqd, &rqdd) {
                Some(e) => Some(e),
                None => {
                    out.status = "execution_failed".into();
                    return out;
                }
            }
        }
        None => None,
    };
    // Racket centre, normal, velocity and angular velocity (world) at time t (s, absolute).
    let mut racket_at = |t: f64| {
        match &executed {
            Some(e) => e.sample(t - t_start, &mut q, &mut qd),
            None => motion.sample(t, &mut q, &mut qd, &mut qdd),
        }
        racket_state(planner, &q, &qd)
    };
    let sc = score(planner, truth, cfg.target, &truth_at_last, hit_abs, &mut racket_at);
    if keep_path {
        out.path = sample_path(truth, &s0, hit_abs);
        out.racket_path = (0..out.path.len())
            .map(|k| racket_at(k as f64 * 0.005).centre.into())
            .collect();
        if let Some(after) = &sc.after {
            out.path.extend(sample_path(truth, after, after.t + 1.0));
        }
    }
    out.racket_error = sc.racket_error;
    out.contact = sc.contact;
    out.landing = sc.landing;
    out.landing_error = sc.landing_error;
    out.returned = sc.returned;
    out.status = sc.status;
    out
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
pub fn racket_state(planner: &HitPlanner, q: &[f64], qd: &[f64]) -> RacketState {
    let world = planner.placement.world_from_base();
    let pose = world * planner.chain.fk(q).expect("sizes match");
    let jac = planner.chain.jacobian(q, JacobianFrame::Base).expect("sizes match");
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
    planner: &HitPlanner,
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
            if offset <= planner.racket.radius {
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
    let (v, w) = planner.racket.hit(&truth.model, &b.v, &b.w, &rkc.normal, &v_point);
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
    planner: &HitPlanner,
    truth: &Flight,
    target: [f64; 2],
    from: &BallState,
    hit_abs: f64,
    executed: &Executed,
    t_start: f64,
) -> crate::error::Result<Score> {
    let n = planner.chain.dof();
    let k = executed.t.len();
    if executed.dof != n || k == 0 || executed.q.len() != k * n || executed.qd.len() != k * n {
        return Err(crate::error::Error::shape(
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
        return Err(crate::error::Error::invalid(
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

/// The correction of a planned hit, as the rally makes it after the bounce: the stroke of `first`
/// (planned at `t_first`, s absolute, from rest at the planner's ready configuration) is under
/// way; at `now` (s) the hit is planned again for the ball `ball` (e.g. the estimate updated
/// through the bounce, [`super::update::update`]; `after_bounce` when it is past its bounce) from the stroke's
/// joint state then, near `first` ([`HitPlanner::plan_near`], shortest stroke 60 ms). An error
/// when `now` is before `t_first` or less than 60 ms before the first hit.
pub fn correct_hit(
    planner: &HitPlanner,
    first: &Hit,
    t_first: f64,
    ball: &BallState,
    now: f64,
    after_bounce: bool,
) -> crate::error::Result<super::hitplan::HitPlan> {
    let t_prev = t_first + first.t_hit;
    if !(now >= t_first && t_prev - now > CORRECTION_MIN_STROKE) {
        return Err(crate::error::Error::invalid(
            "now",
            format!(
                "a correction at {now} s needs the stroke under way (started {t_first} s) and at least \
                 {CORRECTION_MIN_STROKE} s before the first hit at {t_prev} s"
            ),
        ));
    }
    let motion = Motion {
        pieces: vec![(t_first, execution(first, &JointState::rest(&planner.ready)))],
    };
    let start = motion.state(now, planner.chain.dof());
    let mut replanner = planner.clone();
    replanner.min_stroke_time = CORRECTION_MIN_STROKE;
    replanner.plan_near(ball, now, &start, after_bounce, first, t_prev)
}

/// The executed stroke of `hit` (joint frame, from the stroke start): its accepted hit leg, then a
/// 0.4 s quintic from the hit state to rest at `ready`.
pub fn execution(hit: &Hit, ready: &JointState) -> JointTrajectory {
    let at_hit = JointState {
        q: hit.q_hit.clone(),
        qd: hit.qd_hit.clone(),
        qdd: hit.qdd_hit.clone(),
    };
    hit.leg
        .trajectory
        .clone()
        .append(JointTrajectory::quintic_unchecked(&at_hit, ready, 0.4))
}

/// True positions every 5 ms for `duration` s from `s`, ending at a terminal event.
fn sample_path(flight: &Flight, s: &BallState, duration: f64) -> Vec<[f64; 3]> {
    let times: Vec<f64> = (0..=((duration - s.t).max(0.0) / 0.005) as usize)
        .map(|k| s.t + k as f64 * 0.005)
        .collect();
    let pred = super::predict::predict(flight, s, &times).expect("valid times");
    pred.positions.into_iter().filter(|p| p[0].is_finite()).collect()
}

/// Plays the balls `incoming` (states at the opponent's hit, e.g. recorded shots; ball `i` is
/// `incoming[i]`) in parallel; see [`play_with`].
pub fn rally_from(
    planner: &HitPlanner,
    region: &ReachRegion,
    truth: &Flight,
    cfg: &RallyConfig,
    incoming: &[BallState],
) -> Vec<BallOutcome> {
    incoming
        .par_iter()
        .enumerate()
        .map(|(i, s)| play_with(planner, region, truth, cfg, i as u64, Some(s), None))
        .collect()
}

/// Plays balls 0..`n` in parallel.
pub fn rally(
    planner: &HitPlanner,
    region: &ReachRegion,
    truth: &Flight,
    cfg: &RallyConfig,
    n: usize,
) -> Vec<BallOutcome> {
    (0..n as u64)
        .into_par_iter()
        .map(|i| play(planner, region, truth, cfg, i))
        .collect()
}
