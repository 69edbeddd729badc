//! The robot's reachable region (`ttkin::ball::reach`): defined from geometry, physics and joint
//! limits, independently of the hit planner.

use nalgebra::{IsometryMatrix3, Translation3, Vector3};
use ttkin::ball::flight::{BallState, EventKind, Flight};
use ttkin::ball::hitplan::ReturnPlanner;
use ttkin::ball::rally;
use ttkin::ball::reach::{min_joint_time, racket_rotation, Placement, ReachRegion, Reachability};
use ttkin::chain::Chain;
use ttkin::ik::{Analytic, LimitFilter};

fn truth() -> Flight {
    Flight {
        step: 0.001,
        ..Flight::default()
    }
}

fn region() -> ReachRegion {
    let pl = ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap();
    ReachRegion::new(pl.chain(), pl.placement, pl.ready.clone(), pl.flight.model.radius).unwrap()
}

#[test]
fn the_rally_places_a_robot_by_its_structure_not_its_name() {
    let g6 = ttkin::robots::gantry6();
    assert_eq!(Placement::for_chain(&g6), Some(Placement::default()));
    // the same model under another name stands at the same place
    let renamed = Chain::new("not_gantry6", g6.joints().to_vec(), *g6.base(), *g6.tool()).unwrap();
    assert_eq!(Placement::for_chain(&renamed), Some(Placement::default()));
    // robots the ball planner cannot play (no analytic IK) have no place by the table
    for chain in [ttkin::robots::ur5(), ttkin::robots::mobile8()] {
        assert_eq!(Placement::for_chain(&chain), None, "{}", chain.name());
        assert!(ReturnPlanner::new(chain, Flight::default()).is_err());
    }
}

#[test]
fn minimum_joint_time_is_full_acceleration_then_full_speed() {
    // 0.1 m at 20 m/s² stays below 3 m/s: √(2·0.1/20) = 0.1 s.
    assert!((min_joint_time(0.1, 3.0, 20.0) - 0.1).abs() < 1e-12);
    assert!((min_joint_time(-0.1, 3.0, 20.0) - 0.1).abs() < 1e-12);
    // 1 m reaches 3 m/s after 0.225 m: 1/3 + 3/40 s.
    assert!((min_joint_time(1.0, 3.0, 20.0) - (1.0 / 3.0 + 0.075)).abs() < 1e-12);
    assert_eq!(min_joint_time(0.0, 3.0, 20.0), 0.0);
}

#[test]
fn a_point_inside_is_placeable_and_points_outside_the_strokes_or_band_are_not() {
    let r = region();
    // In front of the ready pose, at mid-height: placeable, quickly.
    let t = r.placement_time(&Vector3::new(-1.7, 0.1, 0.25)).expect("inside");
    assert!(t > 0.0 && t < 0.3, "{t}");
    // Beyond the d2 stroke (±0.6 m) plus the wrist's reach, though inside the volume's |y| ≤ 1.
    assert!(r.placement_time(&Vector3::new(-1.7, 0.98, 0.25)).is_none());
    // Behind the volume (the d1 stroke and the wrist reach about 3 m from the net's line).
    assert!(r.placement_time(&Vector3::new(-3.2, 0.0, 0.25)).is_none());
    // Above the height band, below it, and over the table.
    assert!(r.placement_time(&Vector3::new(-1.7, 0.0, 0.6)).is_none());
    assert!(r.placement_time(&Vector3::new(-1.7, 0.0, 0.02)).is_none());
    assert!(r.placement_time(&Vector3::new(-1.0, 0.0, 0.25)).is_none());
}

#[test]
fn classification_of_served_balls_and_of_balls_that_come_too_early() {
    let r = region();
    let truth = truth();
    let mut rng = fastrand::Rng::with_seed(3);
    let mut in_reach = 0;
    for _ in 0..40 {
        let s = rally::serve(&truth, &mut rng, 30.0, 0.2);
        let c = r.classify(&truth, &s, 0.23);
        if let Reachability::InReach { p, t, min_time } = c {
            in_reach += 1;
            assert!(r.volume.contains(&p) && min_time <= t - 0.23 + 1e-12, "{c:?}");
            // Planning only when the ball is already there leaves no time: too early for the joints
            // (every sample tried in full: checked on a few balls, the test also runs unoptimised).
            if in_reach <= 3 {
                assert_eq!(r.classify(&truth, &s, t + 1.0), Reachability::TooEarly);
                assert_eq!(r.classify_touch(&truth, &s, t + 1.0), Reachability::TooEarly);
            }
        }
    }
    assert!(in_reach >= 20, "{in_reach} of 40");
    // Into the net: no bounce on the robot's half.
    let net = BallState::new(0.0, [0.8, 0.0, 0.05], [-3.0, 0.0, 0.0], [0.0; 3]);
    assert_eq!(r.classify(&truth, &net, 0.0), Reachability::NoBounce);
    assert_eq!(r.classify_touch(&truth, &net, 0.0), Reachability::NoBounce);
    // A slow, flat ball that bounces and passes below the height band.
    let low = BallState::new(0.0, [-0.5, 0.0, 0.03], [-2.0, 0.0, 0.0], [0.0; 3]);
    assert!(matches!(
        r.classify(&truth, &low, 0.0),
        Reachability::OutsideVolume | Reachability::NoBounce
    ));
}

/// The true ball of `s` at time `t` (s, absolute), through its bounce.
fn at(truth: &Flight, s: &BallState, t: f64) -> BallState {
    truth.run(s, t, None).0
}

/// Whether some IK branch within the position limits places the racket with normal `n` (world)
/// touching the ball centre `p` at one of the region's rolls: the region's own placement, redone.
fn placeable(r: &ReachRegion, ik: &Analytic, p: &Vector3<f64>, n: &Vector3<f64>) -> Option<Vec<f64>> {
    let base_from_world = r.placement.world_from_base().inverse();
    r.rolls.iter().find_map(|&roll| {
        let world = IsometryMatrix3::from_parts(Translation3::from(p - r.ball_radius * n), racket_rotation(n, roll));
        ik.solve(&(base_from_world * world), None, LimitFilter::Enforce)
            .ok()
            .and_then(|s| s.iter().next().map(|q| q.to_vec()))
    })
}

/// Served balls searched for ones the racket can touch but not return (about 8 % of them).
const N_TOUCH: usize = 80;

/// What the return-shot tests share: gantry6's region, the true flight, its analytic IK and a
/// seeded serve generator.
struct Rig {
    r: ReachRegion,
    truth: Flight,
    ik: Analytic,
    rng: fastrand::Rng,
}

impl Rig {
    fn new(seed: u64) -> Rig {
        Rig {
            r: region(),
            truth: truth(),
            ik: Analytic::for_chain(&ttkin::robots::gantry6()).unwrap(),
            rng: fastrand::Rng::with_seed(seed),
        }
    }

    /// The drag-free ball velocity (m/s) that leaves `p` and lands on `target` (x, y on the
    /// table, m) after `tf` s: the outgoing velocity each shot of the grid asks for.
    fn v_out(&self, p: &Vector3<f64>, target: &[f64; 2], tf: f64) -> Vector3<f64> {
        let g = Vector3::new(0.0, 0.0, -self.truth.model.gravity);
        let goal = Vector3::new(target[0], target[1], self.truth.model.radius);
        (goal - p - 0.5 * g * tf * tf) / tf
    }
}

#[test]
fn a_ball_the_racket_can_touch_but_not_return_is_out_with_no_return_pose() {
    let mut rig = Rig::new(11);
    let mut found = 0;
    for _ in 0..N_TOUCH {
        let s = rally::serve(&rig.truth, &mut rig.rng, 40.0, 0.2);
        let (r, truth, ik) = (&rig.r, &rig.truth, &rig.ik);
        let Reachability::InReach { p, t, .. } = r.classify_touch(truth, &s, 0.23) else {
            continue;
        };
        if r.classify(truth, &s, 0.23) != Reachability::NoReturnPose {
            continue;
        }
        found += 1;
        // Where the touch region places a racket, no shot of the grid has a racket pose: every
        // target and return time needs a face normal the joints cannot give there.
        let b = at(truth, &s, t);
        assert!((b.p - p).norm() < 1e-9);
        for target in &r.targets {
            for &tf in &r.return_times {
                let racket = r
                    .impact
                    .solve(&truth.model, &b.v, &b.w, &rig.v_out(&b.p, target, tf))
                    .unwrap();
                assert!(placeable(r, ik, &b.p, &racket.normal).is_none(), "{target:?} {tf}");
            }
        }
    }
    // Balls wide of the table: the carriage would pass its d2 stroke to turn them back over it.
    assert!(found >= 2, "{found} touched-only balls of {N_TOUCH}");
}

#[test]
fn a_ball_in_reach_is_returned_by_a_racket_the_joints_can_place_in_time() {
    let mut rig = Rig::new(12);
    let mut checked = 0;
    for _ in 0..30 {
        let s = rally::serve(&rig.truth, &mut rig.rng, 40.0, 0.2);
        let (r, truth, ik) = (&rig.r, &rig.truth, &rig.ik);
        let Reachability::InReach { p, t, min_time } = r.classify(truth, &s, 0.23) else {
            continue;
        };
        // Some shot of the grid at (p, t): its racket, hitting the true ball (forward impact
        // model), sends it onto the opponent's half, and the joints place that racket in time.
        let b = at(truth, &s, t);
        let ok = r.targets.iter().any(|target| {
            r.return_times.iter().any(|&tf| {
                let Ok(racket) = r.impact.solve(&truth.model, &b.v, &b.w, &rig.v_out(&p, target, tf)) else {
                    return false;
                };
                let (v, w) = r.impact.hit(&truth.model, &b.v, &b.w, &racket.normal, &racket.velocity);
                let (_, ev) = truth.run(&BallState { v, w, ..b }, t + 2.0, None);
                let lands = ev.first().is_some_and(|e| {
                    e.kind == EventKind::Table && truth.table.on_opponent_half(e.before.p.x, e.before.p.y)
                });
                lands && placeable(r, ik, &p, &racket.normal).is_some_and(|q| r.min_time(&q) <= t - 0.23)
            })
        });
        assert!(ok, "no checked return at {p:?}, t {t}");
        assert!(min_time <= t - 0.23 + 1e-12);
        checked += 1;
    }
    assert!(checked >= 15, "{checked} of 30");
}

/// gantry6 with every joint's velocity limit scaled by `k`.
fn slow_gantry(k: f64) -> Chain {
    let c = ttkin::robots::gantry6();
    let joints = c
        .joints()
        .iter()
        .map(|j| {
            let mut l = *j.limits();
            l.velocity = l.velocity.map(|v| v * k);
            j.clone().with_limits(l).unwrap()
        })
        .collect();
    Chain::new(c.name(), joints, *c.base(), *c.tool()).unwrap()
}

#[test]
fn joints_too_slow_for_the_racket_speed_put_a_ball_out_with_return_speed() {
    let fast = region();
    let truth = truth();
    let chain = slow_gantry(0.01);
    let mut slow = ReachRegion::new(&chain, fast.placement, fast.ready.clone(), truth.model.radius).unwrap();
    // Every sample of a ball out of reach is tried in full: a 20 ms sampling keeps the test short
    // (it also runs unoptimised).
    slow.step = 0.02;
    let mut rng = fastrand::Rng::with_seed(3);
    let (mut compared, mut speed) = (0, 0);
    for _ in 0..12 {
        let s = rally::serve(&truth, &mut rng, 30.0, 0.2);
        if !fast.classify(&truth, &s, 0.23).in_reach() {
            continue;
        }
        compared += 1;
        // Planned long before the ball arrives (the time bound is no obstacle), with joint speeds
        // a hundredth of gantry6's (3 cm/s on the carriages): every pose is where it was, but the
        // joints cannot move the racket at the speed of a return, except for a block (a racket
        // almost at rest), which needs luck with the incoming spin.
        let c = slow.classify(&truth, &s, -1e6);
        assert!(
            matches!(c, Reachability::ReturnSpeed | Reachability::InReach { .. }),
            "{c:?}"
        );
        speed += usize::from(c == Reachability::ReturnSpeed);
    }
    assert!(compared >= 6 && speed * 4 >= compared * 3, "{speed} of {compared}");
    // The names of the verdicts, as counted in `summary.json`'s `reach`.
    assert_eq!(Reachability::ReturnSpeed.name(), "return_speed");
    assert_eq!(Reachability::NoReturnPose.name(), "no_return_pose");
    assert!(Reachability::NAMES.contains(&"return_speed") && !Reachability::NAMES.contains(&"no_pose"));
}

#[test]
fn racket_rotation_at_roll_zero_is_the_full_turn_and_rolls_about_the_normal() {
    let tau = std::f64::consts::TAU;
    for n in [
        Vector3::new(1.0, 0.2, 0.3),
        Vector3::new(0.1, -0.9, 0.2),
        Vector3::new(0.05, 0.02, 1.0),
    ] {
        let r0 = racket_rotation(&n, 0.0);
        // Roll 0 takes a path without sin/cos: it must agree with the general one (a full turn).
        assert!((r0.matrix() - racket_rotation(&n, tau).matrix()).norm() < 1e-14);
        assert!((r0.matrix().column(2) - n.normalize()).norm() < 1e-15);
        // Handle x: as close to world up as possible at roll 0, turned by the roll about n.
        let r = racket_rotation(&n, 0.5);
        assert!((r.matrix().column(0).dot(&r0.matrix().column(0)) - 0.5f64.cos()).abs() < 1e-14);
        assert!((r0.matrix() * r0.matrix().transpose() - nalgebra::Matrix3::identity()).norm() < 1e-14);
    }
}

#[test]
fn the_definition_is_written_from_the_region_s_own_grids() {
    let mut r = region();
    let text = r.definition();
    for part in [
        "x in {0.4, 0.8, 1.2} m, y in {-0.5, 0, 0.5} m in 0.45 to 1.05 s",
        "(roll 0, +-30, +-60 deg)",
        "(ttkin::ball::reach)",
    ] {
        assert!(text.contains(part), "{part} not in: {text}");
    }
    // Another grid, another sentence: the numbers are read, not restated.
    r.targets = vec![[0.5, 0.25], [1.0, 0.25]];
    r.return_times = vec![0.7, 0.5];
    r.rolls = vec![0.0, 45f64.to_radians()];
    let text = r.definition();
    assert!(
        text.contains("x in {0.5, 1} m, y in {0.25} m in 0.5 to 0.7 s"),
        "{text}"
    );
    assert!(text.contains("(roll 0, 45 deg)"), "{text}");
}
