//! The estimate updated through the bounce (`ttkin::ball::update`) and the correction of a planned
//! hit during its stroke (`ReturnPlanner::plan_near`, `RallyConfig::correction_delay`).

use nalgebra::Vector3;
use ttkin::ball::estimate::{estimate, EstimateError, EstimateOptions, Segment};
use ttkin::ball::flight::{BallState, EventKind, Flight};
use ttkin::ball::hitplan::{shoot, ReturnPlanner, ReturnStatus};
use ttkin::ball::predict::predict;
use ttkin::ball::rally::{self, RallyConfig};
use ttkin::ball::reach::ReachRegion;
use ttkin::ball::update::{update, update_kick};
use ttkin::traj::JointState;

fn truth() -> Flight {
    Flight {
        step: 0.001,
        ..Flight::default()
    }
}

/// A ball from the opponent's side to (−0.7, 0.1) on the robot's half in 0.45 s, its spin `w_along`
/// (rad/s) about its flight direction (horizontal) plus 120 rad/s about the horizontal axis across it.
fn corkscrew(w_along: f64) -> BallState {
    let p = Vector3::new(1.6, -0.2, 0.25);
    let land = Vector3::new(-0.7, 0.1, 0.02);
    let d = Vector3::new(land.x - p.x, land.y - p.y, 0.0).normalize();
    let w = d * w_along + Vector3::z().cross(&d) * 120.0;
    let v = shoot(&truth(), &p, &land, 0.45, |_| Some(w)).expect("a shot");
    BallState { t: 0.0, p, v, w }
}

/// Observations of `s` flying in the model's world ([`observe_in`] with `truth()`).
fn observe(s: &BallState, t_end: f64, sigma: f64, seed: u64) -> (Vec<f64>, Vec<[f64; 3]>) {
    observe_in(&truth(), s, t_end, sigma, seed)
}

fn bounce_time(s: &BallState) -> f64 {
    let (_, ev) = truth().run(s, 1.0, None);
    let e = ev.iter().find(|e| e.kind == EventKind::Table).unwrap();
    e.before.t
}

fn options() -> EstimateOptions {
    EstimateOptions {
        flight: Flight {
            step: 0.01,
            ..Flight::default()
        },
        ..EstimateOptions::default()
    }
}

/// The prediction error (m) at `t` (s) of the flight from `s` against the true ball `ball`.
fn error_at(s: &BallState, ball: &BallState, t: f64) -> f64 {
    let (a, _) = options().flight.run(s, t, None);
    let (b, _) = truth().run(ball, t, None);
    (a.p - b.p).norm()
}

#[test]
fn the_update_sees_the_spin_about_the_flight_direction_through_the_bounce() {
    // 45 rad/s about the flight direction: no Magnus force, so the first window's fit cannot see
    // it, but the bounce turns it into sideways speed.
    let ball = corkscrew(45.0);
    let tb = bounce_time(&ball);
    let t_hit = tb + 0.22;
    let (mut before, mut after, mut spin) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..20 {
        let (t, p) = observe(&ball, tb + 0.03, 0.002, seed);
        let first = t.partition_point(|&x| x <= 0.2201);
        let prior = estimate(&t[..first], &p[..first], &options()).unwrap();
        assert_eq!(prior.segment, Segment::Whole);
        let up = update(&prior, &t, &p, &options()).unwrap();
        assert!(up.bounced);
        assert_eq!(up.state.t, *t.last().unwrap());
        assert_eq!(up.outliers, 0);
        assert_eq!(up.used, t.len() - first);
        before.push(error_at(&prior.state, &ball, t_hit));
        after.push(error_at(&up.state, &ball, t_hit));
        spin.push(((prior.state.w - ball.w).norm(), (up.at_prior.w - ball.w).norm()));
    }
    before.sort_by(f64::total_cmp);
    after.sort_by(f64::total_cmp);
    let (b, a) = (before[10], after[10]);
    eprintln!(
        "error at the hit, median (worst): prior {b} m ({}), updated {a} m ({})",
        before[19], after[19]
    );
    assert!(b > 0.035, "prior's error at the hit {b} m");
    assert!(a < 0.4 * b && a < 0.015, "updated error at the hit {a} m");
    // The racket radius is 75 mm: the prior's prediction may miss it, the update's does not.
    assert!(
        before[19] > 0.075 && after[19] < 0.05,
        "worst {} m, updated {} m",
        before[19],
        after[19]
    );
    // The spin about the flight direction, unseen by the prior's window, is estimated.
    let mut prior_spin: Vec<f64> = spin.iter().map(|s| s.0).collect();
    let mut updated_spin: Vec<f64> = spin.iter().map(|s| s.1).collect();
    prior_spin.sort_by(f64::total_cmp);
    updated_spin.sort_by(f64::total_cmp);
    assert!(
        prior_spin[10] > 30.0 && updated_spin[10] < 15.0,
        "spin error median {} rad/s, updated {} rad/s",
        prior_spin[10],
        updated_spin[10]
    );
}

#[test]
fn the_update_rejects_an_outlier_and_keeps_a_ball_without_new_spin() {
    let ball = corkscrew(0.0);
    let tb = bounce_time(&ball);
    let (t, mut p) = observe(&ball, tb + 0.03, 0.002, 7);
    let first = t.partition_point(|&x| x <= 0.2201);
    let prior = estimate(&t[..first], &p[..first], &options()).unwrap();
    let clean = update(&prior, &t, &p, &options()).unwrap();
    let k = t.len() - 2;
    p[k][1] += 0.08;
    let up = update(&prior, &t, &p, &options()).unwrap();
    assert_eq!(up.outliers, 1);
    assert!((up.state.p - clean.state.p).norm() < 2e-3);
    assert!((up.state.v - clean.state.v).norm() < 0.05);
    assert!(error_at(&up.state, &ball, tb + 0.22) < 0.02);
}

#[test]
fn the_update_without_new_observations_is_the_prior_and_bad_input_is_an_error() {
    let ball = corkscrew(20.0);
    let (t, p) = observe(&ball, 0.22, 0.002, 3);
    let prior = estimate(&t, &p, &options()).unwrap();
    let up = update(&prior, &t, &p, &options()).unwrap();
    assert_eq!(up.state, prior.state);
    assert_eq!(up.at_prior, prior.state);
    assert_eq!(up.used, 0);
    assert!(!up.bounced);
    assert!(matches!(
        update(&prior, &t, &p[1..], &options()),
        Err(EstimateError::Shape { .. })
    ));
    let late = [0.3, 0.3];
    let late_p = [p[0], p[1]];
    assert!(matches!(
        update(&prior, &late, &late_p, &options()),
        Err(EstimateError::Times { index: 1, .. })
    ));
    let mut predicted = prior.clone();
    predicted.segment = Segment::BeforeBounce;
    assert!(update(&predicted, &t, &p, &options()).is_err());
}

fn planner() -> ReturnPlanner {
    ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap()
}

#[test]
fn a_correction_with_the_same_ball_keeps_the_hit_and_starts_from_the_stroke() {
    let mut pl = planner();
    let ready = JointState::rest(&pl.ready);
    let mut rng = fastrand::Rng::with_seed(21);
    let (mut tried, mut corrected) = (0, 0);
    for _ in 0..40 {
        let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
        let (s, _) = pl.flight.run(&s, 0.22, None);
        let now = 0.23;
        pl.min_stroke_time = 0.12;
        let Some(hit) = pl.plan(&s, now, [0.9, 0.0]).unwrap().hit else {
            continue;
        };
        let t_prev = now + hit.hit.t;
        let t_c = t_prev - 0.1;
        if t_c <= now {
            continue;
        }
        let stroke = rally::execution(&hit, &ready);
        let n = hit.branch.q.len();
        let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        stroke.sample(t_c - now, &mut q, &mut qd, &mut qdd).unwrap();
        let start = JointState { q, qd, qdd };
        let (ball, ev) = pl.flight.run(&s, t_c - 0.01, None);
        let bounced = ev.iter().any(|e| e.kind == EventKind::Table);
        // The rally's correction: strokes down to 60 ms.
        pl.min_stroke_time = 0.06;
        let plan = pl.plan_near(&ball, t_c, &start, bounced, &hit, t_prev).unwrap();
        tried += 1;
        let Some(new) = plan.hit else {
            assert_ne!(plan.status, ReturnStatus::Ok);
            continue;
        };
        assert_eq!(plan.status, ReturnStatus::Ok);
        corrected += 1;
        // The nearest candidate in time, to the same landing point, from the stroke's state.
        assert!(
            (t_c + new.hit.t - t_prev).abs() <= 0.0101,
            "{} vs {t_prev}",
            t_c + new.hit.t
        );
        assert!((new.landing - hit.landing).xy().norm() < 2e-3);
        let (mut q0, mut qd0, mut qdd0) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        new.branch
            .leg
            .trajectory
            .sample(0.0, &mut q0, &mut qd0, &mut qdd0)
            .unwrap();
        for i in 0..n {
            assert!((q0[i] - start.q[i]).abs() < 1e-9 && (qd0[i] - start.qd[i]).abs() < 1e-9);
        }
        // The racket is where the ball will be: the same hit point within the candidates' spacing.
        assert!((new.ball.p - hit.ball.p).norm() < 0.06);
    }
    eprintln!("{corrected} of {tried} corrected");
    // From the middle of a stroke near its limits the new leg may break one where the rest of the
    // old leg would not: most, not all, are corrected.
    assert!(
        corrected >= 15 && corrected * 10 >= tried * 8,
        "{corrected} of {tried} corrected"
    );
}

#[test]
fn the_correction_after_the_bounce_removes_most_misses() {
    let pl = planner();
    let truth = truth();
    let region = ReachRegion::new(pl.chain(), pl.placement, pl.ready.clone(), truth.model.radius).unwrap();
    let count = |cfg: &RallyConfig| {
        let out = rally::rally(&pl, &region, &truth, cfg, 400);
        let in_reach: Vec<_> = out.iter().filter(|o| o.in_reach).collect();
        let returned = in_reach.iter().filter(|o| o.returned).count();
        let missed = in_reach.iter().filter(|o| o.status == "missed").count();
        let corrected = out.iter().filter(|o| o.replans > 0).count();
        let mut err: Vec<f64> = out.iter().filter(|o| o.returned).map(|o| o.racket_error).collect();
        err.sort_by(f64::total_cmp);
        (returned, missed, corrected, err[err.len() / 2])
    };
    let with = RallyConfig {
        seed: 9,
        ..RallyConfig::default()
    };
    assert!(with.correction_delay > 0.0);
    let without = RallyConfig {
        correction_delay: 0.0,
        ..with
    };
    let (r1, m1, c1, e1) = count(&with);
    let (r0, m0, c0, e0) = count(&without);
    eprintln!("with the correction {r1} returned, {m1} missed, {c1} corrected, racket error {e1}; without {r0}, {m0}, {c0}, {e0}");
    assert_eq!(c0, 0);
    assert!(c1 > 250, "{c1} corrected");
    assert!(m0 >= 3 && m1 * 3 <= m0, "missed {m1} with, {m0} without");
    assert!(r1 > r0, "returned {r1} with, {r0} without");
    // The ball still meets the racket within its radius (the branch kept may be off-centre).
    assert!(e1 < 0.075 && e0 < 0.075, "racket-centre error {e1} with, {e0} without");
}

#[test]
fn plan_and_plan_near_refuse_the_same_bad_input_with_the_same_error() {
    // One set of input checks for the plan and the re-plan (hitplan/search.rs): a non-finite
    // `now` is `Error::NonFinite` in both (plan_near said `Error::Invalid` before).
    let pl = planner();
    let ready = JointState::rest(&pl.ready);
    let mut rng = fastrand::Rng::with_seed(21);
    let (s, hit) = loop {
        let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
        let (s, _) = pl.flight.run(&s, 0.22, None);
        if let Some(h) = pl.plan(&s, 0.23, [0.9, 0.0]).unwrap().hit {
            break (s, h);
        }
    };
    for bad in [f64::NAN, f64::INFINITY] {
        let a = pl.plan_from(&s, bad, [0.9, 0.0], &ready, false).unwrap_err();
        let b = pl.plan_near(&s, bad, &ready, false, &hit, 0.5).unwrap_err();
        assert!(matches!(a, ttkin::Error::NonFinite { .. }), "{a:?}");
        assert!(matches!(b, ttkin::Error::NonFinite { .. }), "{b:?}");
    }
    let c = pl.plan_near(&s, 0.23, &ready, false, &hit, f64::NAN).unwrap_err();
    assert!(matches!(c, ttkin::Error::NonFinite { .. }), "{c:?}");
}

#[test]
fn the_same_hit_planned_again_keeps_where_and_when_and_refuses_bad_input() {
    // `plan_same_hit` with the ball of the plan itself: the one candidate is the chosen one (the
    // same ball state at the same time), shot to the same landing point, from the same start.
    let pl = planner();
    let ready = JointState::rest(&pl.ready);
    let mut rng = fastrand::Rng::with_seed(33);
    let mut same = 0;
    for _ in 0..30 {
        let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
        let (s, _) = pl.flight.run(&s, 0.22, None);
        let now = 0.23;
        let Some(hit) = pl.plan(&s, now, [0.9, 0.0]).unwrap().hit else {
            continue;
        };
        let t_prev = now + hit.hit.t;
        let plan = pl.plan_same_hit(&s, now, &ready, false, &hit, t_prev).unwrap();
        assert_eq!(plan.candidates, 1);
        let Some(again) = plan.hit else {
            continue;
        };
        same += 1;
        assert!((again.hit.t - hit.hit.t).abs() < 1e-12);
        assert!(
            (again.ball.p - hit.ball.p).norm() < 1e-6,
            "{} vs {}",
            again.ball.p,
            hit.ball.p
        );
        assert!((again.landing - hit.landing).xy().norm() < 2e-3);
        let n = hit.branch.q.len();
        let (mut q0, mut qd0, mut qdd0) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        again
            .branch
            .leg
            .trajectory
            .sample(0.0, &mut q0, &mut qd0, &mut qdd0)
            .unwrap();
        for i in 0..n {
            assert!((q0[i] - ready.q[i]).abs() < 1e-9 && qd0[i].abs() < 1e-9);
        }
        // A hit time before `now`: no candidate.
        let late = pl
            .plan_same_hit(&s, t_prev + 0.01, &ready, false, &hit, t_prev)
            .unwrap();
        assert_eq!(late.status, ReturnStatus::OutOfReach);
        assert!(late.hit.is_none());
        // The same bad input, the same error as the other plans.
        let e = pl.plan_same_hit(&s, f64::NAN, &ready, false, &hit, t_prev).unwrap_err();
        assert!(matches!(e, ttkin::Error::NonFinite { .. }), "{e:?}");
        let e = pl.plan_same_hit(&s, now, &ready, false, &hit, f64::NAN).unwrap_err();
        assert!(matches!(e, ttkin::Error::NonFinite { .. }), "{e:?}");
    }
    assert!(same >= 10, "{same} planned again");
}

#[test]
fn a_late_decision_is_planned_again_from_the_newer_observations_for_the_same_hit() {
    use ttkin::ball::decide::{BallDecider, DecideConfig, Decision};
    let pl = planner();
    let ready = JointState::rest(&pl.ready);
    let cfg = DecideConfig::default();
    let mut rng = fastrand::Rng::with_seed(5);
    let mut refined = 0;
    for k in 0..20 {
        let s = rally::serve(&truth(), &mut rng, 30.0, 0.2);
        let (times, obs) = observe(&s, 0.6, 0.002, k);
        let mut d = BallDecider::new(&pl, cfg);
        let mut first = None;
        let mut next = 0;
        for (i, (t, p)) in times.iter().zip(&obs).enumerate() {
            // the first plan comes with the window's last observation, as said beforehand
            assert_eq!(d.may_decide(*t), i + 1 >= cfg.window_frames);
            if let Some(Decision::Planned { now, plan, .. }) = d.observe(&pl, *t, *p, *t, &|_| ready.clone()) {
                first = plan.hit.map(|h| (now + h.hit.t, h));
                next = i + 1;
                break;
            }
        }
        let Some((t_hit, hit)) = first else { continue };
        // Nothing newer than the decision's observations: nothing to plan again.
        let (t0, p0) = (times[next - 1], obs[next - 1]);
        assert!(d.refine(&pl, &[(t0, p0)], t0 + 0.002, &ready).is_none());
        // The next two frames came while the decision ran: the same hit time, to the same
        // landing point, from the state at the later start.
        let now = times[next + 1] + 0.001;
        let newer = [(times[next], obs[next]), (times[next + 1], obs[next + 1])];
        let Some(again) = d.refine(&pl, &newer, now, &ready) else {
            continue;
        };
        refined += 1;
        assert!(
            (now + again.hit.t - t_hit).abs() < 1e-9,
            "{} vs {t_hit}",
            now + again.hit.t
        );
        assert!((again.landing - hit.landing).xy().norm() < 2e-3);
        // The ball moved by the newer estimate, not by another candidate (10 ms apart).
        assert!(
            (again.ball.p - hit.ball.p).norm() < 0.03,
            "{}",
            (again.ball.p - hit.ball.p).norm()
        );
        // Observed as usual afterwards, the newer frames change nothing already decided.
        for (t, p) in &newer {
            assert!(d.observe(&pl, *t, *p, *t, &|_| ready.clone()).is_none());
        }
    }
    assert!(refined >= 8, "{refined} planned again");
}

/// Observations of `s` flying in `world`, every 5 ms from 0.02 s to `t_end` (s), noise `sigma` (m).
fn observe_in(world: &Flight, s: &BallState, t_end: f64, sigma: f64, seed: u64) -> (Vec<f64>, Vec<[f64; 3]>) {
    let times: Vec<f64> = (0..)
        .map(|k| 0.02 + k as f64 * 0.005)
        .take_while(|t| *t <= t_end)
        .collect();
    let path = predict(world, s, &times).unwrap();
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut g = || {
        let (u, v) = (rng.f64().max(1e-300), rng.f64());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let p = path
        .positions
        .iter()
        .map(|q| [q[0] + sigma * g(), q[1] + sigma * g(), q[2] + sigma * g()])
        .collect();
    (times, p)
}

/// A ball whose own table friction and Magnus constant depart from the model's (μ 0.35 against
/// 0.25, k_m × 1.45: the spreads of `WorldSpread::measured` at 2σ and 1σ) leaves the bounce
/// faster or slower than the model predicts; with the bounce's kick fitted, the prediction 0.22 s
/// after the bounce is better; in the model's own world the kick is kept for few balls (the gate)
/// and the prediction is no worse.
#[test]
fn the_bounce_kick_follows_a_ball_whose_bounce_departs_from_the_model() {
    let model = options().flight.model;
    let world = Flight {
        model: ttkin::ball::model::BallModel {
            table_friction: model.table_friction + 0.1,
            k_magnus: model.k_magnus * 1.45,
            ..model
        },
        ..truth()
    };
    let spread = Some([0.3, 0.3, 0.05]);
    let ball = corkscrew(0.0);
    let (_, ev) = world.run(&ball, 1.0, None);
    let tb = ev.iter().find(|e| e.kind == EventKind::Table).unwrap().before.t;
    let t_hit = tb + 0.22;
    let err = |w: &Flight, s: &BallState| {
        let (a, _) = options().flight.run(s, t_hit, None);
        let (b, _) = w.run(&ball, t_hit, None);
        (a.p - b.p).norm()
    };
    let (mut plain, mut kicked, mut same_in_model) = (Vec::new(), Vec::new(), 0);
    let (mut plain_model, mut kicked_model) = (Vec::new(), Vec::new());
    for seed in 0..20 {
        for (w, mismatched) in [(&world, true), (&truth(), false)] {
            let (t, p) = observe_in(w, &ball, tb + 0.03, 0.002, seed);
            let first = t.partition_point(|&x| x <= 0.2201);
            let prior = estimate(&t[..first], &p[..first], &options()).unwrap();
            let a = update(&prior, &t, &p, &options()).unwrap();
            let b = update_kick(&prior, &t, &p, &options(), spread).unwrap();
            if mismatched {
                plain.push(err(w, &a.state));
                kicked.push(err(w, &b.state));
            } else {
                same_in_model += usize::from(a == b);
                plain_model.push(err(w, &a.state));
                kicked_model.push(err(w, &b.state));
            }
        }
    }
    for v in [&mut plain, &mut kicked, &mut plain_model, &mut kicked_model] {
        v.sort_by(f64::total_cmp);
    }
    eprintln!(
        "error 0.22 s after the bounce, median (worst): mismatched plain {:.4} ({:.4}), kicked {:.4} ({:.4}); \
         model plain {:.4} ({:.4}), kicked {:.4} ({:.4}); kick not kept in the model world {same_in_model} of 20",
        plain[10],
        plain[19],
        kicked[10],
        kicked[19],
        plain_model[10],
        plain_model[19],
        kicked_model[10],
        kicked_model[19]
    );
    assert!(
        kicked[10] < 0.5 * plain[10],
        "median {} against {}",
        kicked[10],
        plain[10]
    );
    assert!(
        same_in_model >= 16,
        "kick kept for {} of 20 balls in the model world",
        20 - same_in_model
    );
    assert!(kicked_model[10] <= plain_model[10] * 1.2 + 1e-4);
    assert!(update_kick(&corkscrew_prior(), &[], &[], &options(), Some([0.0, 0.3, 0.05])).is_err());
}

/// A window estimate of `corkscrew(0)` (for the argument checks).
fn corkscrew_prior() -> ttkin::ball::estimate::Estimate {
    let ball = corkscrew(0.0);
    let (t, p) = observe(&ball, 0.2201, 0.002, 1);
    estimate(&t, &p, &options()).unwrap()
}
