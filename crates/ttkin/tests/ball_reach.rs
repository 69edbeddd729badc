//! The robot's reachable region (`ttkin::ball::reach`): defined from geometry and joint limits,
//! independently of the hit planner.

use nalgebra::Vector3;
use ttkin::ball::flight::{BallState, Flight};
use ttkin::ball::hitplan::HitPlanner;
use ttkin::ball::rally;
use ttkin::ball::reach::{min_joint_time, ReachRegion, Reachability};

fn region() -> ReachRegion {
    let pl = HitPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap();
    ReachRegion::new(&pl.chain, pl.placement, pl.ready.clone(), pl.flight.model.radius).unwrap()
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
    let truth = Flight {
        step: 0.001,
        ..Flight::default()
    };
    let mut rng = fastrand::Rng::with_seed(3);
    let mut in_reach = 0;
    for _ in 0..40 {
        let s = rally::serve(&truth, &mut rng, 30.0, 0.2);
        let c = r.classify(&truth, &s, 0.23);
        if let Reachability::InReach { p, t, min_time } = c {
            in_reach += 1;
            assert!(r.volume.contains(&p) && min_time <= t - 0.23 + 1e-12, "{c:?}");
            // Planning only when the ball is already there leaves no time: too early for the joints.
            assert_eq!(r.classify(&truth, &s, t + 1.0), Reachability::TooEarly);
        }
    }
    assert!(in_reach >= 20, "{in_reach} of 40");
    // Into the net: no bounce on the robot's half.
    let net = BallState::new(0.0, [0.8, 0.0, 0.05], [-3.0, 0.0, 0.0], [0.0; 3]);
    assert_eq!(r.classify(&truth, &net, 0.0), Reachability::NoBounce);
    // A slow, flat ball that bounces and passes below the height band.
    let low = BallState::new(0.0, [-0.5, 0.0, 0.03], [-2.0, 0.0, 0.0], [0.0; 3]);
    assert!(matches!(
        r.classify(&truth, &low, 0.0),
        Reachability::OutsideVolume | Reachability::NoBounce
    ));
}
