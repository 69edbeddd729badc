//! One ball of the rally from the robot's side: observe, estimate, plan, correct after the
//! bounce, re-plan, execute (exactly, or through an [`Executor`]), then [`super::score()`]'s impact
//! and score.

use super::camera::observe_ball;
use super::score::{racket_state, sample_path, score, BallOutcome, Executed};
use super::RallyConfig;
use crate::ball::decide::{BallDecider, DecideConfig, Decision, CORRECTION_MIN_STROKE};
use crate::ball::estimate::{estimate, EstimateOptions};
use crate::ball::flight::{BallState, EventKind, Flight};
use crate::ball::hitplan::{ReturnHit, ReturnPlanner, ReturnStatus};
use crate::ball::reach::ReachRegion;
use crate::traj::{JointState, JointTrajectory};
use std::time::Instant;

/// Executes a stroke on the robot (the rally's execution hook; `ttcan` implements it with the
/// coupled drive simulation, since `ttkin` may not depend on `ttcan`). The reference: samples at
/// `times` (s from the stroke's start, increasing, uniform) of q, q̇, q̈ (K × n, row-major), the
/// robot at rest at the first sample; `None` when the execution failed (a drive fault).
pub trait Executor: Sync {
    /// The executed motion for the reference (see the trait doc).
    fn execute(&self, times: &[f64], q: &[f64], qd: &[f64], qdd: &[f64]) -> Option<Executed>;
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

/// Plays ball `index` of the rally: serve, observe, classify against `region`, plan, re-plan,
/// execute, score.
pub fn play(
    planner: &ReturnPlanner,
    region: &ReachRegion,
    truth: &Flight,
    cfg: &RallyConfig,
    index: u64,
) -> BallOutcome {
    play_with(planner, region, truth, cfg, index, None, None)
}

/// [`play`] with the incoming ball given (`incoming`, e.g. a recorded shot; time stamps from its
/// `t`, re-based to 0) instead of served. With [`RallyConfig::world`] the ball flies in its own
/// world (constants drawn around `truth`'s, see [`super::WorldSpread`]) while the planner keeps its model.
/// With an `executor` the stroke (as planned, re-plans included) is executed by it from the
/// planning time to 60 ms after the hit, and the racket follows the executed motion.
pub fn play_with(
    planner: &ReturnPlanner,
    region: &ReachRegion,
    truth: &Flight,
    cfg: &RallyConfig,
    index: u64,
    incoming: Option<&BallState>,
    executor: Option<&dyn Executor>,
) -> BallOutcome {
    let seen = observe_ball(truth, cfg, index, incoming);
    let (s0, world) = (seen.incoming, seen.world);
    let (exposures, times, obs, first) = (seen.exposures, seen.times, seen.positions, seen.first);
    let truth = &world;
    let cam = &cfg.camera;
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
    // The decisions, observation by observation at its delivery ([`BallDecider`], the same state
    // machine as the controller's ball mode): the first plan after the window, then once,
    // `correction_delay` after the bounce the estimate predicts, the estimate updated with every
    // observation delivered since (through the bounce, [`crate::ball::update::update`]) and the
    // hit planned again from the robot's state then (from rest when the first plan had no hit).
    let keep_path = (index as usize) < cfg.paths;
    let n = planner.chain().dof();
    let ready = JointState::rest(&planner.ready);
    let mut decider = BallDecider::new(planner, DecideConfig::of(cfg));
    let mut motion = Motion { pieces: Vec::new() };
    let mut first_hit: Option<ReturnHit> = None;
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
                first_hit = plan.hit.filter(|_| plan.status == ReturnStatus::Ok);
                if let Some(h) = &first_hit {
                    motion.pieces.push((now, execution(h, &ready)));
                    hit_at = Some(now + h.hit.t);
                }
                est = Some(*estimate);
            }
            Some(Decision::Corrected { now: t_c, hit }) => {
                out.correction_time_us = cpu.elapsed().as_secs_f64() * 1e6;
                if let Some(h) = hit {
                    motion.pieces.push((t_c, execution(&h, &ready)));
                    hit_at = Some(t_c + h.hit.t);
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
    let leg = |hit: &ReturnHit| execution(hit, &ready);
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
                if let Some(h) = p.hit.filter(|_| p.status == ReturnStatus::Ok) {
                    hit = h;
                    hit_abs = t_plan + hit.hit.t;
                    motion.pieces.push((t_plan, leg(&hit)));
                    out.replans += 1;
                }
            }
        }
        t_plan += cfg.replan_period;
    }
    out.profile = hit.branch.leg.profile.name();
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
    // The racket (world) at time t (s, absolute).
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

/// The correction of a planned hit, as the rally makes it after the bounce: the stroke of `first`
/// (planned at `t_first`, s absolute, from rest at the planner's ready configuration) is under
/// way; at `now` (s) the hit is planned again for the ball `ball` (e.g. the estimate updated
/// through the bounce, [`crate::ball::update::update`]; `after_bounce` when it is past its bounce) from the stroke's
/// joint state then, near `first` ([`ReturnPlanner::plan_near`], shortest stroke 60 ms). An error
/// when `now` is before `t_first` or less than 60 ms before the first hit.
pub fn correct_hit(
    planner: &ReturnPlanner,
    first: &ReturnHit,
    t_first: f64,
    ball: &BallState,
    now: f64,
    after_bounce: bool,
) -> crate::error::Result<crate::ball::hitplan::ReturnPlan> {
    let t_prev = t_first + first.hit.t;
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
    let start = motion.state(now, planner.chain().dof());
    let mut replanner = planner.clone();
    replanner.min_stroke_time = CORRECTION_MIN_STROKE;
    replanner.plan_near(ball, now, &start, after_bounce, first, t_prev)
}

/// The executed stroke of `hit` (joint frame, from the stroke start): its accepted hit leg, then
/// its follow-through to rest at `ready` (the branch's [`crate::hit::BranchLeg::follow`], checked
/// against every limit by the planner; 0.4 s when that fits). For a `ready` other than the
/// follow-through's end (the planner's ready configuration), an unchecked 0.4 s quintic to it.
pub fn execution(hit: &ReturnHit, ready: &JointState) -> JointTrajectory {
    let follow = &hit.branch.follow;
    let ends_at_ready = follow
        .state(follow.duration())
        .is_ok_and(|s| s.q.iter().zip(&ready.q).all(|(a, b)| (a - b).abs() <= 1e-9));
    let back = if ends_at_ready && ready.qd.iter().chain(&ready.qdd).all(|x| *x == 0.0) {
        follow.clone()
    } else {
        let at_hit = JointState {
            q: hit.branch.q.clone(),
            qd: hit.branch.qd.clone(),
            qdd: hit.branch.leg.qdd_hit.clone(),
        };
        JointTrajectory::quintic_unchecked(&at_hit, ready, 0.4)
    };
    hit.branch.leg.trajectory.clone().append(back)
}
