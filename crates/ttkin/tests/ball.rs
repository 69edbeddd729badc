//! Ball flight, contacts, estimation, prediction, impact and hit planning (issue 13).

use nalgebra::Vector3;
use proptest::prelude::*;
use ttkin::ball::contact::{energy, impulse};
use ttkin::ball::estimate::{estimate, EstimateError, EstimateOptions, Segment};
use ttkin::ball::flight::{BallState, EventKind, Flight, Plane};
use ttkin::ball::hitplan::{ReturnPlanner, ReturnStatus};
use ttkin::ball::impact::RacketImpact;
use ttkin::ball::model::{BallModel, Table};
use ttkin::ball::predict::{crossing, predict, CrossingOutcome};
use ttkin::ball::rally::{self, BallOutcome, Rally, RallyConfig};
use ttkin::ball::reach::{walk_after_bounce, walk_after_bounce_clip};
use ttkin::hit::StrokeProfile;
use ttkin::traj::duration::quintic_limit_ratio;
use ttkin::traj::{JointState, JointTrajectory};

fn fine() -> Flight {
    Flight {
        step: 5e-5,
        ..Flight::default()
    }
}

#[test]
fn vacuum_flight_is_the_closed_form_parabola() {
    let f = Flight {
        model: BallModel::vacuum(),
        ..Flight::default()
    };
    let s = BallState::new(0.0, [-1.0, 0.2, 0.5], [3.0, -0.4, 2.0], [0.0, 100.0, 0.0]);
    let times: Vec<f64> = (0..30).map(|k| k as f64 * 0.01).collect();
    let pred = predict(&f, &s, &times).unwrap();
    assert!(pred.events.is_empty());
    for (t, p) in times.iter().zip(&pred.positions) {
        let exact = [-1.0 + 3.0 * t, 0.2 - 0.4 * t, 0.5 + 2.0 * t - 0.5 * 9.81 * t * t];
        for k in 0..3 {
            assert!((p[k] - exact[k]).abs() < 1e-12, "t = {t}: {p:?} vs {exact:?}");
        }
    }
}

#[test]
fn rk4_at_the_default_step_matches_a_fine_reference() {
    let s = BallState::new(0.0, [1.6, 0.1, 0.3], [-6.0, 0.5, 1.0], [50.0, -120.0, 80.0]);
    let times: Vec<f64> = (0..=20).map(|k| k as f64 * 0.05).collect();
    let a = predict(&Flight::default(), &s, &times).unwrap();
    let b = predict(&fine(), &s, &times).unwrap();
    for (p, q) in a.positions.iter().zip(&b.positions) {
        if p[0].is_finite() {
            let d = (Vector3::from(*p) - Vector3::from(*q)).norm();
            assert!(d < 1e-6, "{d}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn energy_never_increases_in_flight(
        v in prop::array::uniform3(-10.0f64..10.0), w in prop::array::uniform3(-300.0f64..300.0),
    ) {
        let f = Flight::default();
        let m = f.model;
        let mut s = BallState::new(0.0, [0.0, 3.0, 1.5], v, w); // off the table: free flight
        let e = |s: &BallState| 0.5 * m.mass * s.v.norm_squared() + m.mass * m.gravity * s.p.z;
        let mut last = e(&s);
        for _ in 0..100 {
            s = f.rk4(&s, 0.002);
            let now = e(&s);
            prop_assert!(now <= last + 1e-12, "{now} > {last}");
            last = now;
        }
    }

    #[test]
    fn bounce_scales_normal_speed_by_e_and_never_adds_energy(
        vt in prop::array::uniform2(-8.0f64..8.0), vz in -8.0f64..-0.1, w in prop::array::uniform3(-400.0f64..400.0),
    ) {
        let m = BallModel::default();
        let v = Vector3::new(vt[0], vt[1], vz);
        let w = Vector3::from(w);
        let n = Vector3::z();
        let (dv, dw) = impulse(&m, &v, &w, &n, m.table_restitution, m.table_friction);
        let (v1, w1) = (v + dv, w + dw);
        prop_assert!((v1.z + m.table_restitution * vz).abs() < 1e-12);
        prop_assert!(energy(&m, &v1, &w1) <= energy(&m, &v, &w) + 1e-12);
        prop_assert!((w1.z - w.z).abs() < 1e-12); // spin about the normal unchanged
        // Tangential impulse: Coulomb-bounded and against the slip.
        let slip = |v: &Vector3<f64>, w: &Vector3<f64>| Vector3::new(v.x - m.radius * w.y, v.y + m.radius * w.x, 0.0);
        let (u0, u1) = (slip(&v, &w), slip(&v1, &w1));
        let jt = Vector3::new(dv.x, dv.y, 0.0);
        prop_assert!(jt.norm() <= m.table_friction * (1.0 + m.table_restitution) * -vz + 1e-12);
        prop_assert!(jt.dot(&u0) <= 1e-12);
        prop_assert!(u1.norm() <= u0.norm() + 1e-12);
        // Angular impulse matches the linear one about the contact point: m r × j = I Δω.
        let r = Vector3::new(0.0, 0.0, -m.radius);
        prop_assert!((m.mass * r.cross(&jt) - m.inertia() * dw).norm() < 1e-12);
    }

    #[test]
    fn racket_impact_inverse_reproduces_the_wanted_velocity(
        vin in prop::array::uniform3(-1.0f64..1.0), w in prop::array::uniform3(-200.0f64..200.0),
        vout in prop::array::uniform3(-1.0f64..1.0),
    ) {
        let m = BallModel::default();
        let racket = RacketImpact::default();
        let v_in = Vector3::new(-5.0 + vin[0], vin[1], -1.0 + vin[2]);
        let v_out = Vector3::new(5.0 + vout[0], vout[1], 2.0 + vout[2]);
        let w = Vector3::from(w);
        let sol = racket.solve(&m, &v_in, &w, &v_out).unwrap();
        let (v, spin) = racket.hit(&m, &v_in, &w, &sol.normal, &sol.velocity);
        prop_assert!((v - v_out).norm() < 1e-6);
        prop_assert!((spin - sol.spin_out).norm() < 1e-9);
        prop_assert!((sol.normal.norm() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn bounce_on_the_table_reverses_and_damps_the_normal_speed() {
    let f = Flight::default();
    let s = BallState::new(0.0, [-0.5, 0.0, 0.3], [-2.0, 0.0, 0.0], [0.0, 0.0, 0.0]);
    let (_, events) = f.run(&s, 1.0, None);
    let e = events.iter().find(|e| e.kind == EventKind::Table).unwrap();
    assert!((e.before.p.z - f.model.radius).abs() < 1e-9);
    assert!((e.after.v.z + f.model.table_restitution * e.before.v.z).abs() < 1e-12);
    // A ball without spin skidding forward picks up topspin (ω_y > 0 when moving −x... sign by r × j).
    assert!(e.after.w.y.abs() > 0.0);
    assert!(e.after.v.x.abs() < e.before.v.x.abs());
}

#[test]
fn net_and_floor_end_the_flight() {
    let f = Flight::default();
    let s = BallState::new(0.0, [0.8, 0.0, 0.05], [-3.0, 0.0, 0.0], [0.0; 3]);
    let pred = predict(&f, &s, &[0.2, 0.4, 0.6, 1.0]).unwrap();
    // It may bounce first, then hits the net low.
    assert_eq!(pred.end, Some(EventKind::Net));
    assert!(pred.positions.last().unwrap()[0].is_nan());
    let s = BallState::new(0.0, [-2.0, 0.0, 0.3], [-3.0, 0.0, 0.0], [0.0; 3]);
    let pred = predict(&f, &s, &[2.0]).unwrap();
    assert_eq!(pred.end, Some(EventKind::Floor));
}

#[test]
fn sampled_guards_find_the_events_of_the_short_step() {
    // An 80 ms step with its guards sampled every 10 ms finds the first event of the 10 ms
    // flight: same kind, and the contact within the two integrations' difference.
    let fine = Flight {
        step: 0.01,
        ..Flight::default()
    };
    let long = Flight { step: 0.08, ..fine };
    let mut rng = fastrand::Rng::with_seed(3);
    let (mut kinds, mut worst) = (std::collections::BTreeMap::new(), 0.0f64);
    for _ in 0..300 {
        // Returns from behind the robot's end line toward the opponent's half, some into the net.
        let s = BallState::new(
            1.3 * rng.f64(),
            [-1.6 - 0.4 * rng.f64(), 0.8 * (rng.f64() - 0.5), 0.05 + 0.3 * rng.f64()],
            [2.0 + 4.0 * rng.f64(), 0.6 * (rng.f64() - 0.5), 0.5 + 2.0 * rng.f64()],
            [0.0, 150.0 * (rng.f64() - 0.5), 60.0 * (rng.f64() - 0.5)],
        );
        let t_end = s.t + 1.3;
        let (_, want) = fine.advance_sampled(&s, t_end, None, 1);
        let (_, got) = long.advance_sampled(&s, t_end, None, 8);
        let (Some(want), Some(got)) = (want, got) else {
            assert_eq!(want.map(|e| e.kind), got.map(|e| e.kind));
            continue;
        };
        assert_eq!(want.kind, got.kind, "{s:?}");
        *kinds.entry(want.kind.name()).or_insert(0) += 1;
        worst = worst.max((want.before.p - got.before.p).norm());
        assert!(
            (want.before.t - got.before.t).abs() < 1e-5,
            "{} vs {}",
            want.before.t,
            got.before.t
        );
    }
    assert!(worst < 1e-4, "contacts {worst} m apart");
    assert!(
        kinds.get("table").copied().unwrap_or(0) > 50 && kinds.get("net").copied().unwrap_or(0) > 10,
        "{kinds:?}"
    );
    // One sample per step is `advance`.
    let s = BallState::new(0.0, [-0.3, 0.0, 0.08], [5.0, 0.0, 0.0], [0.0; 3]);
    assert_eq!(long.advance_sampled(&s, 1.0, None, 1), long.advance(&s, 1.0, None));
}

#[test]
fn a_fast_ball_does_not_pass_through_the_net_between_steps() {
    // Step ends 0.1–0.4 m apart, either side of the 42 mm the net spans for the ball centre: the
    // crossing of the net's plane is checked, so the ball hits the net (low) or flies on (high).
    let mut rng = fastrand::Rng::with_seed(8);
    for step in [0.01, 0.02, 0.05] {
        let f = Flight {
            step,
            ..Flight::default()
        };
        for _ in 0..50 {
            let vx = 8.0 + 4.0 * rng.f64();
            let x0 = -0.5 - 0.3 * rng.f64();
            let s = BallState::new(0.0, [x0, 0.3 * (rng.f64() - 0.5), 0.10], [vx, 0.0, 0.4], [0.0; 3]);
            let (_, ev) = f.advance(&s, 1.0, None);
            let e = ev.expect("an event");
            assert_eq!(e.kind, EventKind::Net, "step {step}: {e:?}");
            assert!(e.before.p.x.abs() < 0.03, "{:?}", e.before.p);
            // Over the net (drag-free height there ≥ 0.2 m, the net's top 0.1525 m) toward x = 1.0 m:
            // no net event.
            let (z0, t_land) = (0.4, (1.0 - x0) / vx);
            let vz = (0.02 - z0 + 4.905 * t_land * t_land) / t_land;
            let t_net = -x0 / vx;
            assert!(z0 + vz * t_net - 4.905 * t_net * t_net > 0.2);
            let high = BallState::new(0.0, [x0, 0.0, z0], [vx, 0.0, vz], [0.0; 3]);
            let (_, ev) = f.advance(&high, 1.0, None);
            let e = ev.expect("an event");
            assert_eq!(e.kind, EventKind::Table, "step {step}: {e:?}");
            assert!(e.before.p.x > 0.3, "{:?}", e.before.p);
        }
    }
}

#[test]
fn a_walk_flies_on_through_a_net_clip_only_within_the_clip() {
    let f = Flight {
        step: 0.01,
        ..Flight::default()
    };
    // Flat toward the robot at 6 m/s, its centre at the net `below` m under clearing the top (it
    // falls 12.3 mm on the way).
    let clear = f.table.net_height + f.model.radius;
    let ball = |below: f64| BallState::new(0.0, [0.3, 0.0, clear - below + 0.0123], [-6.0, 0.0, 0.0], [0.0; 3]);
    let walk = |below: f64, clip: f64| {
        let mut visited = 0;
        let bounced = walk_after_bounce_clip(&f, &ball(below), 0.01, false, clip, |_| {
            visited += 1;
            true
        });
        (bounced, visited)
    };
    for below in [0.005, 0.015] {
        assert!(
            !walk_after_bounce(&f, &ball(below), 0.01, false, |_| true),
            "{below}: the net stops it"
        );
        let (bounced, visited) = walk(below, 0.02);
        assert!(bounced && visited > 0, "{below}: a clip within 2 cm flies on");
        assert!(!walk(below, 0.0).0);
    }
    // Well into the net: stopped even with the clip.
    assert!(!walk(0.08, 0.02).0);
}

#[test]
fn edge_contact_has_a_non_vertical_normal() {
    let f = Flight::default();
    // Falls onto the end line's edge, just beyond it.
    let s = BallState::new(0.0, [-1.37 - 0.012, 0.0, 0.2], [0.0, 0.0, 0.0], [0.0; 3]);
    let (_, events) = f.run(&s, 0.5, None);
    assert_eq!(events[0].kind, EventKind::Edge);
    assert!(events[0].after.v.x < 0.0, "the edge pushes the ball outward");
}

#[test]
fn prediction_at_the_hitting_plane_is_within_1mm_of_a_fine_reference() {
    let plane = Plane {
        point: Vector3::new(-1.6, 0.0, 0.0),
        normal: Vector3::x(),
    };
    let mut rng = fastrand::Rng::with_seed(7);
    for _ in 0..40 {
        let s = rally::serve(&fine(), &mut rng, 40.0, 0.2);
        let a = crossing(&Flight::default(), &s, &plane, 2.0).unwrap();
        let b = crossing(&fine(), &s, &plane, 2.0).unwrap();
        match (a, b) {
            (CrossingOutcome::Crossed { state: x, bounces: bx }, CrossingOutcome::Crossed { state: y, .. }) => {
                assert!(!bx.is_empty());
                assert!((x.p - y.p).norm() < 1e-3, "{}", (x.p - y.p).norm());
                assert!((x.t - y.t).abs() < 1e-4);
                assert!((x.v - y.v).norm() < 1e-2);
            }
            (a, b) => assert_eq!(std::mem::discriminant(&a), std::mem::discriminant(&b)),
        }
    }
}

fn observe(s: &BallState, noise: f64, n: usize, outliers: bool, seed: u64) -> (Vec<f64>, Vec<[f64; 3]>, BallState) {
    let f = fine();
    let times: Vec<f64> = (0..n).map(|k| s.t + 0.02 + k as f64 * 0.005).collect();
    let truth = predict(&f, s, &times).unwrap();
    let mut rng = fastrand::Rng::with_seed(seed);
    let mut g = || {
        let (u, v) = (rng.f64().max(1e-300), rng.f64());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let mut p = truth.positions.clone();
    for (k, row) in p.iter_mut().enumerate() {
        for x in row.iter_mut() {
            *x += noise * g();
            if outliers && k % 10 == 3 {
                *x += 0.08;
            }
        }
    }
    let (last, _) = f.run(s, *times.last().unwrap(), None);
    (times, p, last)
}

#[test]
fn estimation_recovers_velocity_from_noisy_observations() {
    // Stated error: with σ = 2 mm, 41 observations at 200 Hz (0.2 s) and 10 % outliers of 8 cm,
    // the velocity at the last observation is within 0.15 m/s.
    let mut rng = fastrand::Rng::with_seed(3);
    let mut worst: f64 = 0.0;
    for seed in 0..30 {
        let s = rally::serve(&fine(), &mut rng, 40.0, 0.2);
        let (t, p, truth) = observe(&s, 0.002, 41, true, seed);
        let e = estimate(&t, &p, &EstimateOptions::default()).unwrap();
        assert!(e.outliers >= 3, "outliers found: {}", e.outliers);
        let err = (e.state.v - truth.v).norm();
        worst = worst.max(err);
        let sd = (e.covariance[3][3] + e.covariance[4][4] + e.covariance[5][5]).sqrt();
        assert!(err < 6.0 * sd + 0.02, "error {err} vs σ {sd}");
        assert!((e.state.t - truth.t).abs() < 1e-12);
    }
    assert!(worst < 0.15, "worst velocity error {worst} m/s");
}

#[test]
fn estimation_handles_a_bounce_inside_the_window() {
    let s = BallState::new(0.0, [-0.1, 0.0, 0.25], [-4.0, 0.1, -0.5], [0.0, 60.0, 0.0]);
    let (t, p, truth) = observe(&s, 0.001, 40, false, 1);
    let e = estimate(&t, &p, &EstimateOptions::default()).unwrap();
    assert!(e.bounce_time.is_some());
    assert_ne!(e.segment, Segment::Whole);
    assert!((e.state.v - truth.v).norm() < 0.2, "{}", (e.state.v - truth.v).norm());
}

#[test]
fn estimation_bad_input_gives_clear_errors() {
    let o = EstimateOptions::default();
    let s = BallState::new(0.0, [1.5, 0.0, 0.3], [-5.0, 0.0, 1.0], [0.0; 3]);
    let (t, mut p, _) = observe(&s, 0.001, 12, false, 2);
    assert!(matches!(
        estimate(&t[..3], &p[..3], &o),
        Err(EstimateError::TooFew { .. })
    ));
    assert!(matches!(estimate(&t, &p[..5], &o), Err(EstimateError::Shape { .. })));
    for row in p.iter_mut().take(9) {
        row[1] = f64::NAN;
    }
    assert!(matches!(
        estimate(&t, &p, &o),
        Err(EstimateError::TooFew { usable: 3, .. })
    ));
    p[0][1] = 0.0;
    p[1][1] = 0.0;
    let e = estimate(&t, &p, &o).unwrap();
    assert_eq!(e.nonfinite, 7);
    let mut t2 = t.clone();
    t2[10] = t2[9];
    assert!(matches!(estimate(&t2, &p, &o), Err(EstimateError::Times { .. })));
    for step in [0.0, -0.01, f64::NAN, 0.2] {
        let bad = EstimateOptions { step, ..o };
        assert!(matches!(
            estimate(&t, &p, &bad),
            Err(EstimateError::Option { what: "step", .. })
        ));
    }
}

#[test]
fn estimation_step_does_not_change_the_fit() {
    // The fit's integration step (20 ms by default) against a converged reference (1 ms step, up
    // to 30 iterations) on the same noisy data: the default fit lies within 1 % of its standard
    // deviation (σ = 2 mm noise; 0.12 % at most measured on 200 windows).
    let mut rng = fastrand::Rng::with_seed(11);
    let fine_opts = EstimateOptions {
        step: 0.001,
        iterations: 30,
        ..EstimateOptions::default()
    };
    for seed in 0..40 {
        let s = rally::serve(&fine(), &mut rng, 40.0, 0.2);
        let (t, p, _) = observe(&s, 0.002, 41, true, seed);
        let a = estimate(&t, &p, &EstimateOptions::default()).unwrap();
        let b = estimate(&t, &p, &fine_opts).unwrap();
        let sd_p = (b.covariance[0][0] + b.covariance[1][1] + b.covariance[2][2]).sqrt();
        let sd_v = (b.covariance[3][3] + b.covariance[4][4] + b.covariance[5][5]).sqrt();
        let (dp, dv) = ((a.state.p - b.state.p).norm(), (a.state.v - b.state.v).norm());
        assert!(dp < 0.01 * sd_p, "{dp} vs σ {sd_p}");
        assert!(dv < 0.01 * sd_v, "{dv} vs σ {sd_v}");
        assert_eq!(a.outliers, b.outliers);
        // The covariance from the coarser sensitivities: within 5 % of the reference's.
        let sd_a = (a.covariance[3][3] + a.covariance[4][4] + a.covariance[5][5]).sqrt();
        assert!((sd_a / sd_v - 1.0).abs() < 0.05, "velocity σ {sd_a} vs {sd_v}");
    }
}

#[test]
fn prediction_rejects_bad_times_and_states() {
    let f = Flight::default();
    let s = BallState::new(0.0, [1.5, 0.0, 0.3], [-5.0, 0.0, 1.0], [0.0; 3]);
    assert!(predict(&f, &s, &[0.2, 0.1]).is_err());
    assert!(predict(&f, &s, &[-0.1]).is_err());
    assert!(predict(&f, &s, &[f64::NAN]).is_err());
    let bad = BallState::new(0.0, [f64::NAN, 0.0, 0.3], [-5.0, 0.0, 1.0], [0.0; 3]);
    assert!(predict(&f, &bad, &[0.1]).is_err());
}

/// The rally of `planner()` with `config`.
fn gantry_rally(config: RallyConfig) -> Rally {
    Rally::with_planner(planner(), config).unwrap()
}

fn planner() -> ReturnPlanner {
    ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap()
}

#[test]
fn the_ball_planner_refuses_a_robot_it_cannot_plan_for_with_the_reason() {
    // ur5 has no analytic IK; arm4 has one, but its racket cannot reach the ready pose at the
    // rally's placement. Both are model errors naming the robot and what is missing.
    let err = ReturnPlanner::new(ttkin::robots::ur5(), Flight::default()).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, ttkin::Error::Model(_)), "{msg}");
    assert!(msg.contains("'ur5'") && msg.contains("analytic IK"), "{msg}");
    let err = ReturnPlanner::new(ttkin::robots::arm4(), Flight::default()).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, ttkin::Error::Model(_)), "{msg}");
    assert!(msg.contains("'arm4'") && msg.contains("ready racket pose"), "{msg}");
    // The chain given is the one planned for: a gantry6 with a longer first link has its own
    // ready configuration (the same racket pose by other joint values).
    let longer = ttkin::robots::gantry6_with(ttkin::robots::GantryLengths {
        l1: 0.14,
        ..Default::default()
    })
    .unwrap();
    let pl = ReturnPlanner::new(longer.clone(), Flight::default()).unwrap();
    assert_eq!(*pl.chain(), longer);
    assert_ne!(pl.ready, planner().ready);
}

#[test]
fn executed_hit_returns_the_ball_to_its_target() {
    let pl = planner();
    let mut rng = fastrand::Rng::with_seed(11);
    let mut planned = 0;
    let mut at_target = 0;
    for _ in 0..30 {
        let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
        let plan = pl.plan(&s, 0.2, [0.9, 0.2]).unwrap();
        let Some(hit) = plan.hit else { continue };
        planned += 1;
        // Execute the impact exactly with the planned racket and fly the ball.
        let (v, w) = pl.impact.hit(
            &pl.flight.model,
            &hit.ball.v,
            &hit.ball.w,
            &hit.racket.normal,
            &hit.racket.velocity,
        );
        let out = BallState { v, w, ..hit.ball };
        let (_, ev) = pl.flight.run(&out, out.t + 2.0, None);
        assert_eq!(ev[0].kind, EventKind::Table);
        // At the planned landing point: the target, or the nearest fallback target the planner
        // chose when no hit reaches the target (module doc of `hitplan`).
        let d = ((ev[0].before.p - hit.landing).xy()).norm();
        assert!(d < 5e-3, "landing error {d}");
        assert!(pl.flight.table.on_opponent_half(ev[0].before.p.x, ev[0].before.p.y));
        if (hit.landing.xy() - Vector3::new(0.9, 0.2, 0.0).xy()).norm() < 5e-3 {
            at_target += 1;
        }
        // The robot's racket is there at the hit: FK of q_hit is the planned pose.
        let fk = pl.chain().fk(&hit.branch.q).unwrap();
        assert!((fk.translation.vector - hit.hit.pose.translation.vector).norm() < 1e-9);
        // A late candidate (tried when no early one is feasible) may be exactly time-optimal.
        assert!(
            hit.branch.margin >= 0.0 && hit.hit.t > 0.0,
            "margin {}",
            hit.branch.margin
        );
    }
    assert!(planned >= 15, "only {planned} of 30 planned");
    assert!(
        4 * at_target >= 3 * planned,
        "{at_target} of {planned} at the target itself"
    );
}

#[test]
fn target_off_the_table_is_an_error_and_unreachable_balls_a_status() {
    let pl = planner();
    let s = BallState::new(0.0, [1.6, 0.0, 0.3], [-5.0, 0.0, 1.0], [0.0; 3]);
    for target in [[2.0, 0.0], [-0.5, 0.0], [0.9, 0.9], [f64::NAN, 0.0]] {
        assert!(pl.plan(&s, 0.2, target).is_err(), "{target:?}");
    }
    // Served into the net: no bounce on the robot's half.
    let net = BallState::new(0.0, [0.8, 0.0, 0.05], [-3.0, 0.0, 0.0], [0.0; 3]);
    assert_eq!(pl.plan(&net, 0.0, [0.9, 0.0]).unwrap().status, ReturnStatus::NoBounce);
    // Flying off to the side, far from the reach box.
    let wide = BallState::new(0.0, [1.6, 0.0, 0.3], [-4.0, 2.2, 1.0], [0.0; 3]);
    let st = pl.plan(&wide, 0.0, [0.9, 0.0]).unwrap().status;
    assert!(
        matches!(st, ReturnStatus::NoBounce | ReturnStatus::OutOfReach),
        "{st:?}"
    );
}

/// Smallest return rate of the balls in reach asserted on the 120-ball sample (docs/ball.md): it
/// returns 103 of 106 (97.2 %; 102 before the correction after the bounce); two binomial standard deviations of a 106-ball sample below the
/// 10 000-ball rates (94.9 % and 95.4 % on seeds 0 and 1) is 91 %.
const RALLY_RATE: f64 = 0.93;

#[test]
fn rally_returns_most_balls_in_reach() {
    let r = gantry_rally(RallyConfig {
        seed: 5,
        ..RallyConfig::default()
    });
    let out = r.play_range(0, 120, None, None, &|| false).unwrap();
    let in_reach = out.iter().filter(|o| o.in_reach).count();
    let returned = out.iter().filter(|o| o.in_reach && o.returned).count();
    let mut statuses: Vec<String> = out
        .iter()
        .filter(|o| o.in_reach && !o.returned)
        .map(|o| o.status.clone())
        .collect();
    statuses.sort();
    eprintln!("in reach {in_reach}/120, returned {returned}; failures {statuses:?}");
    // In reach when a return is possible by the robot's geometry, the physics and the joint limits
    // alone (`ttkin::ball::reach`), a bound no stroke meets for every ball (docs/ball.md); over
    // the earlier touch region, quintic strokes alone returned about 78 %, the planner before
    // fallback targets and off-centre contacts 83 %, with them 91 % of this sample.
    assert!(in_reach >= 95, "{in_reach}");
    assert!(returned as f64 >= RALLY_RATE * in_reach as f64, "{returned}/{in_reach}");
    // With the measured ball model (issue 28) and the drive-limited effort no stroke of this
    // sample needs a jerk-limited hit leg (before, some returns did); the jerk-limited planning and
    // execution of a ball beyond the quintic is tested in the next test.
}

/// A correction whose search near the hit under way finds no feasible hit searches in full from
/// the commanded state (`RallyConfig::widen_correction`, issue 28's eighth stop): balls of seed 0
/// where the near search fails (found in `rally_drives 1000 0`, missed without the wider search)
/// are corrected with it and returned at least as often.
#[test]
fn a_correction_the_near_search_cannot_make_is_searched_in_full() {
    let balls = [311, 401, 737, 925];
    let play = |widen: bool| -> Vec<BallOutcome> {
        let r = gantry_rally(RallyConfig {
            widen_correction: widen,
            paths: 0,
            ..RallyConfig::default()
        });
        balls
            .iter()
            .map(|&k| r.play_range(k, 1, None, None, &|| false).unwrap().remove(0))
            .collect()
    };
    let (narrow, wide) = (play(false), play(true));
    for ((k, n), w) in balls.iter().zip(&narrow).zip(&wide) {
        assert!(
            w.replans > n.replans,
            "ball {k}: {} corrections with the wider search, {} without",
            w.replans,
            n.replans
        );
    }
    let returned = |o: &[BallOutcome]| o.iter().filter(|o| o.returned).count();
    assert!(
        returned(&wide) >= returned(&narrow),
        "{} < {}",
        returned(&wide),
        returned(&narrow)
    );
}

/// The last resort of a plan with no feasible hit (`ReturnPlanner::last_resort_offsets`, issue
/// 28's ninth stop): balls of seed 0 no stroke reaches with the ball within 30 mm of the racket's
/// centre in time within the drives' torque (found in `rally_drives 1000 0`, `infeasible`
/// without it) are returned with the ball further off the centre, inside the face.
#[test]
fn balls_with_no_feasible_hit_are_returned_off_the_racket_centre() {
    let balls = [57, 106, 188, 247];
    let play = |last_resort: bool| -> Vec<BallOutcome> {
        let mut r = gantry_rally(RallyConfig {
            paths: 0,
            ..RallyConfig::default()
        });
        if !last_resort {
            r.planner.last_resort_offsets.clear();
        }
        balls
            .iter()
            .map(|&k| r.play_range(k, 1, None, None, &|| false).unwrap().remove(0))
            .collect()
    };
    let (without, with) = (play(false), play(true));
    for ((k, a), b) in balls.iter().zip(&without).zip(&with) {
        assert!(a.in_reach && b.in_reach, "ball {k}");
        assert_eq!(a.status, "infeasible", "ball {k} without the last resort");
        assert!(!a.returned, "ball {k}");
        assert_ne!(b.status, "infeasible", "ball {k} with the last resort");
        // The racket met the ball inside its face (the rally's contact test).
        if b.returned {
            assert!(b.racket_error < 0.075, "ball {k}: {}", b.racket_error);
        }
    }
    let returned = with.iter().filter(|o| o.returned).count();
    assert!(
        returned >= 3,
        "{returned} of {} returned with the last resort",
        balls.len()
    );
}

#[test]
fn ball_beyond_the_quintic_is_planned_and_executed_jerk_limited() {
    let pl = planner();
    let ready = JointState::rest(&pl.ready);
    let mut rng = fastrand::Rng::with_seed(3);
    let mut found = 0;
    for _ in 0..200 {
        let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
        let plan = pl.plan(&s, 0.2, [0.9, 0.0]).unwrap();
        let Some(hit) = plan.hit else { continue };
        if hit.branch.leg.profile != StrokeProfile::Jerk {
            continue;
        }
        assert_eq!(plan.status, ReturnStatus::Ok);
        let t = hit.hit.t;
        // The quintic the planner tries to this hit state (of q̈ = 0, ½ and 1 × the cubic's end
        // acceleration, the one of lowest exact ratio) breaks a limit: a speed, acceleration or
        // jerk limit, or a position limit between its ends (issue 28: the drives refuse those).
        let (ratio, end) = [0.0, 0.5, 1.0]
            .iter()
            .map(|alpha| {
                let qdd = (0..6)
                    .map(|i| alpha * (-6.0 * (hit.branch.q[i] - ready.q[i]) / (t * t) + 4.0 * hit.branch.qd[i] / t))
                    .collect();
                let end = JointState {
                    q: hit.branch.q.clone(),
                    qd: hit.branch.qd.clone(),
                    qdd,
                };
                (quintic_limit_ratio(&ready, &end, t, pl.limits()), end)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        let beyond_position = !JointTrajectory::quintic_between(&ready, &end, t)
            .unwrap()
            .position_violations(pl.limits(), 0.0)
            .is_empty();
        assert!(ratio > 1.0 || beyond_position, "ratio {ratio}");
        // The jerk-limited leg lasts exactly the hit time, within every limit, and the executed
        // stroke is that leg: at t_hit the racket is at the planned pose with the planned speeds.
        assert!((hit.branch.leg.trajectory.duration() - t).abs() < 1e-9);
        assert!(hit.branch.leg.trajectory.check_limits(pl.limits()).unwrap().is_empty());
        assert!(hit.branch.margin >= 0.0);
        let exec = rally::execution(&hit, &ready);
        let at = exec.state(t).unwrap();
        for j in 0..6 {
            assert!((at.q[j] - hit.branch.q[j]).abs() < 1e-7, "{at:?}");
            assert!((at.qd[j] - hit.branch.qd[j]).abs() < 1e-6, "{at:?}");
        }
        let fk = pl.chain().fk(&at.q).unwrap();
        assert!((fk.translation.vector - hit.hit.pose.translation.vector).norm() < 1e-6);
        assert!(exec.state(0.0).unwrap().q == ready.q);
        found += 1;
    }
    assert!(found >= 3, "only {found} jerk-limited hits in 200 balls");
}

#[test]
fn wide_balls_are_returned_to_another_target_or_off_the_racket_centre() {
    let pl = planner();
    let target = [0.9, 0.0];
    let mut rng = fastrand::Rng::with_seed(21);
    let (mut moved_target, mut off_centre) = (0, 0);
    for _ in 0..400 {
        let s = rally::serve(&pl.flight, &mut rng, 30.0, 0.2);
        let plan = pl.plan(&s, 0.2, target).unwrap();
        let Some(hit) = plan.hit else { continue };
        // Wherever it aims, the planned return lands on the opponent's half, and the contact point
        // (ball centre − r·n) is on the face within `contact_offset` of the racket centre, or
        // within the largest last-resort offset (still on the face) when nothing nearer is feasible.
        assert!(
            pl.flight.table.on_opponent_half(hit.landing.x, hit.landing.y),
            "{:?}",
            hit.landing
        );
        let world = pl.placement.world_from_base() * hit.hit.pose;
        let n = world.rotation * Vector3::z();
        assert!((n - hit.racket.normal).norm() < 1e-9);
        let contact = hit.ball.p - pl.flight.model.radius * n;
        let d = contact - world.translation.vector;
        let reach = pl.last_resort_offsets.iter().fold(pl.contact_offset, |a, &b| a.max(b));
        assert!(reach < pl.impact.radius);
        assert!(d.dot(&n).abs() < 1e-9 && d.norm() <= reach + 1e-9, "{d:?}");
        if (hit.landing.xy() - Vector3::new(target[0], target[1], 0.0).xy()).norm() > 0.1 {
            moved_target += 1;
        }
        if d.norm() > 1e-6 {
            off_centre += 1;
        }
    }
    eprintln!("{moved_target} returns to another target, {off_centre} off the racket centre");
    assert!(
        moved_target >= 2 && off_centre >= 2,
        "{moved_target} other targets, {off_centre} off centre"
    );
}

#[test]
fn mismatched_world_keeps_the_balls_and_draws_their_physics() {
    use ttkin::ball::rally::WorldSpread;
    let matched = gantry_rally(RallyConfig {
        paths: 0,
        ..RallyConfig::default()
    });
    let mismatched = gantry_rally(RallyConfig {
        world: Some(WorldSpread::measured()),
        ..matched.config
    });
    let a: Vec<_> = (0..12).map(|i| matched.play(i, None, None)).collect();
    let b: Vec<_> = (0..12).map(|i| mismatched.play(i, None, None)).collect();
    // The same incoming balls, another flight: the estimates differ.
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.incoming, y.incoming);
    }
    let differ = a.iter().zip(&b).filter(|(x, y)| x.estimate != y.estimate).count();
    assert!(differ >= 10, "{differ} of 12 estimates differ");
    // Given incoming balls are played as given.
    let given: Vec<BallState> = a.iter().map(|o| o.incoming).collect();
    let c = rally::rally_from(
        &matched.planner,
        &matched.region,
        &matched.truth,
        &matched.config,
        &given,
    );
    assert!(c
        .iter()
        .zip(&a)
        .all(|(x, y)| x.incoming == y.incoming && x.in_reach == y.in_reach));
    assert!(c.iter().filter(|o| o.returned).count() + 2 >= a.iter().filter(|o| o.returned).count());
    // The draws: spreads as stated (2000 draws, within 10 %).
    let w = WorldSpread::measured();
    let m = BallModel::default();
    let mut rng = fastrand::Rng::with_seed(1);
    let d: Vec<BallModel> = (0..2000).map(|_| w.draw(&m, &mut rng)).collect();
    let sd = |f: &dyn Fn(&BallModel) -> f64| {
        let mean = d.iter().map(f).sum::<f64>() / d.len() as f64;
        (d.iter().map(|x| (f(x) - mean).powi(2)).sum::<f64>() / d.len() as f64).sqrt()
    };
    assert!((sd(&|x| x.k_drag) / (w.k_drag * m.k_drag) - 1.0).abs() < 0.1);
    assert!((sd(&|x| x.table_restitution) / w.restitution - 1.0).abs() < 0.1);
    assert!(d
        .iter()
        .all(|x| x.k_magnus >= 0.0 && x.table_restitution <= 1.0 && x.table_friction >= 0.0));
}

/// An executor that does exactly what it is told (the reference at 1 ms): the rally with it
/// plays as without one, up to the linear interpolation between its samples.
struct Exact;

impl rally::Executor for Exact {
    fn execute(&self, times: &[f64], q: &[f64], qd: &[f64], _qdd: &[f64]) -> Option<rally::Executed> {
        Some(rally::Executed {
            dof: q.len() / times.len(),
            t: times.to_vec(),
            q: q.to_vec(),
            qd: qd.to_vec(),
        })
    }
}

#[test]
fn an_exact_executor_plays_as_the_ideal_execution() {
    let r = gantry_rally(RallyConfig {
        paths: 0,
        ..RallyConfig::default()
    });
    let mut same = 0;
    for i in 0..16 {
        let a = r.play(i, None, None);
        let b = r.play(i, None, Some(&Exact));
        assert_eq!(a.incoming, b.incoming);
        if a.returned == b.returned {
            same += 1;
        }
        if a.contact && b.contact {
            assert!(
                (a.racket_error - b.racket_error).abs() < 2e-3,
                "{} vs {}",
                a.racket_error,
                b.racket_error
            );
        }
    }
    assert!(same >= 15, "{same} of 16 alike");
}

// Issue 29: a flight's work is bounded before it starts, and its clock must advance.

#[test]
fn flights_far_from_t0_or_too_long_are_refused_not_run() {
    let f = Flight::default();
    // At t = 1e17 s, t + 2 ms == t: the flight loop never ended.
    let far = BallState::new(1e17, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0; 3]);
    let e = predict(&f, &far, &[1e17 + 1e3]).unwrap_err().to_string();
    assert!(e.contains("nearer origin"), "{e}");
    // A ball at z = 1e9 m for 1e7 s: 5e9 steps.
    let high = BallState::new(0.0, [0.0, 0.0, 1e9], [0.0; 3], [0.0; 3]);
    assert!(predict(&f, &high, &[1.0]).is_err());
    let high = BallState::new(0.0, [0.0, 0.0, 1e3], [0.0; 3], [0.0; 3]);
    let e = predict(&f, &high, &[1e7]).unwrap_err().to_string();
    assert!(e.contains("steps"), "{e}");
    let plane = Plane {
        point: Vector3::zeros(),
        normal: Vector3::x(),
    };
    assert!(crossing(&f, &far, &plane, 1e17 + 1.0).is_err());
    // 1e200 m/s gave NaN positions without an event.
    let fast = BallState::new(0.0, [0.0, 0.0, 1.0], [1e200, 0.0, 0.0], [0.0; 3]);
    let e = predict(&f, &fast, &[0.1]).unwrap_err().to_string();
    assert!(e.contains("velocity"), "{e}");
    // Unix-epoch times still fly.
    let unix = BallState::new(1.7e9, [-1.0, 0.0, 1.0], [5.0, 0.0, 0.0], [0.0; 3]);
    let p = predict(&f, &unix, &[1.7e9 + 0.1]).unwrap();
    assert!(p.positions[0].iter().all(|v| v.is_finite()));
}

/// `Rally::play_range`: the balls of `play` in ball order, its checks, and a caller's stop.
#[test]
fn a_rally_range_plays_the_balls_in_order_and_stops_when_asked() {
    let r = Rally::new(RallyConfig {
        paths: 1,
        ..RallyConfig::default()
    })
    .unwrap();
    let out = r.play_range(3, 2, None, None, &|| false).unwrap();
    for (o, i) in out.iter().zip(3..) {
        let p = r.play(i, None, None);
        assert_eq!(
            (&o.incoming, &o.status, o.returned),
            (&p.incoming, &p.status, p.returned)
        );
        assert!(o.landing_error == p.landing_error || (o.landing_error.is_nan() && p.landing_error.is_nan()));
    }
    let cols = rally::Outcomes::new(&out);
    assert_eq!(cols.incoming[10..20], out[1].incoming.to_array());
    assert_eq!(cols.paths.len(), out.iter().filter(|o| !o.path.is_empty()).count());
    let e = r
        .play_range(rally::MAX_BALLS, 1, None, None, &|| false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("go past"), "{e}");
    let given = [out[0].incoming];
    let e = r
        .play_range(0, 2, Some(&given), None, &|| false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("1 states"), "{e}");
    assert!(r.play_range(0, 4, None, None, &|| true).is_err());
    let bad = RallyConfig {
        max_spin_rps: f64::NAN,
        ..RallyConfig::default()
    };
    assert!(Rally::new(bad).unwrap_err().to_string().contains("max_spin_rps"));
}

#[test]
fn the_table_outline_is_drawn_from_its_geometry() {
    let t = Table {
        length: 3.0,
        width: 1.5,
        net_overhang: 0.1,
        ..Table::default()
    };
    let o = t.outline();
    assert_eq!(o.surface[0], o.surface[4]);
    for c in &o.surface[..4] {
        assert_eq!([c[0].abs(), c[1].abs(), c[2]], [1.5, 0.75, 0.0]);
        // every corner is on the surface's edge: on a half, and off it a hair further out
        assert!(t.on_opponent_half(c[0], c[1]) || t.on_robot_half(c[0], c[1]));
        assert!(!t.on_opponent_half(c[0] * (1.0 + 1e-12), c[1]) && !t.on_robot_half(c[0] * (1.0 + 1e-12), c[1]));
    }
    assert_eq!(o.centre_line, [[-1.5, 0.0, 0.0], [1.5, 0.0, 0.0]]);
    assert_eq!(o.net[0], o.net[4]);
    assert_eq!(o.net[2], [0.0, 0.85, t.net_height]);
}
