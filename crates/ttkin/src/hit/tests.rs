//! Tests of the hit pipeline: the plan meets the hit (pose, twist, time) exactly, stays within
//! every limit, reports infeasible requests with a status, and the batch equals single calls.

use nalgebra::Vector3;
use proptest::prelude::*;

use super::*;
use crate::robots;

/// The pipeline demo's hit: centre (0.35, −0.55, 0.05) m, normal (0.3, −1, −0.2), 3 m/s along
/// the normal (earliest feasible: 0.323 s jerk-limited, 0.503 s quintic).
fn demo_hit(t: f64) -> Hit {
    let n = Vector3::new(0.3, -1.0, -0.2).normalize() * 3.0;
    Hit::from_normal([0.35, -0.55, 0.05], [0.3, -1.0, -0.2], [n.x, n.y, n.z], t, None, None).unwrap()
}

fn planner() -> HitPlanner {
    HitPlanner::new(&robots::gantry6(), HitOptions::default()).unwrap()
}

/// Racket pose and twist reached by the plan at its hit time, against the request.
fn hit_errors(p: &HitPlanner, plan: &HitPlan) -> (f64, f64) {
    let traj = plan.trajectory.as_ref().unwrap();
    let s = traj.state(plan.t_hit).unwrap();
    let chain = p.chain();
    let tool = chain.fk(&s.q).unwrap();
    let racket = p.mount().racket_pose(&tool);
    let pose_err = (racket.to_homogeneous() - plan.hit.pose.to_homogeneous()).abs().max();
    let jac = chain.jacobian(&s.q, crate::JacobianFrame::Base).unwrap();
    let tw = jac * nalgebra::DVector::from_column_slice(&s.qd);
    let tw = p.mount().racket_twist(&tool, tw.as_slice());
    let twist_err = (0..6).map(|k| (tw[k] - plan.hit.twist[k]).abs()).fold(0.0, f64::max);
    (pose_err, twist_err)
}

#[test]
fn demo_hit_is_met_on_time_within_every_limit() {
    let p = planner();
    // 0.55 s: the stroke within gantry6's drives (its quintic needs 0.503 s; issue 28 moved the
    // demo from 0.35 s, which needs 1.01× d2's force limit and 1.3× θ3's drive peak).
    let plan = p.plan(&demo_hit(0.55), None, None).unwrap();
    assert!(plan.ok(), "{:?}: {}", plan.status, plan.message);
    assert_eq!(plan.t_hit, 0.55);
    assert!(plan.earliest_t_hit.is_nan());
    let late = p.plan(&demo_hit(0.35), None, None).unwrap();
    assert_eq!(late.status, HitStatus::TooEarly, "{}", late.message);
    assert!(
        late.t_hit > 0.5 && late.t_hit < 0.55 && late.effort_ratio <= 1.0,
        "{}",
        late.t_hit
    );
    // The earliest time of the ok plan counts the effort limits (it was the kinematic 0.29 s
    // while 0.35 s is refused for effort): a plan for it is accepted.
    let earliest = p.earliest_t_hit(&plan);
    assert!(earliest > 0.35 && earliest < 0.55, "{earliest}");
    let at = p.plan(&demo_hit(earliest), None, None).unwrap();
    assert!(at.ok(), "{earliest}: {:?} {}", at.status, at.message);
    let (pe, te) = hit_errors(&p, &plan);
    assert!(pe < 1e-9 && te < 1e-8, "pose {pe}, twist {te}");
    assert!(plan.violations.is_empty());
    assert!(plan.effort_ratio <= 1.0);
    let traj = plan.trajectory.as_ref().unwrap();
    let end = traj.state(traj.duration()).unwrap();
    for j in 0..6 {
        assert!((end.q[j] - plan.ready[j]).abs() < 1e-8 && end.qd[j].abs() < 1e-8);
    }
}

#[test]
fn too_early_hit_is_planned_at_the_earliest_feasible_time() {
    let p = planner();
    let plan = p.plan(&demo_hit(0.02), None, None).unwrap();
    assert_eq!(plan.status, HitStatus::TooEarly, "{}", plan.message);
    assert!(plan.t_hit > 0.02 && (plan.t_hit - plan.earliest_t_hit).abs() < 1e-9);
    let (pe, te) = hit_errors(&p, &plan);
    assert!(pe < 1e-9 && te < 1e-8, "pose {pe}, twist {te}");
    assert!(plan.violations.is_empty());
    // Asking for the earliest time itself is on time.
    let again = p
        .plan(&demo_hit(plan.earliest_t_hit * (1.0 + 1e-9)), None, None)
        .unwrap();
    assert!(again.ok(), "{:?} {}", again.status, again.message);
}

#[test]
fn auto_profile_prefers_the_quintic_when_it_is_on_time() {
    let p = planner();
    // A hit whose time-optimal stroke is within the drives (the demo's is not).
    let n = Vector3::new(0.3, -1.0, -0.2).normalize() * 3.0;
    let at = |t| Hit::from_normal([0.1, -0.5, 0.0], [0.3, -1.0, -0.2], [n.x, n.y, n.z], t, None, None).unwrap();
    let slow = p.plan(&at(1.0), None, None).unwrap();
    assert!(slow.ok());
    assert_eq!(slow.profile, StrokeProfile::Quintic);
    let earliest = p.plan(&at(0.01), None, None).unwrap().t_hit;
    let fast = p.plan(&at(earliest * 1.01), None, None).unwrap();
    assert!(fast.ok(), "{}", fast.message);
    assert_eq!(fast.profile, StrokeProfile::Jerk);
}

#[test]
fn unreachable_and_overspeed_hits_get_a_status() {
    let p = planner();
    let far = Hit::from_normal([0.3, -0.5, 2.0], [0.0, -1.0, 0.0], [0.0, -3.0, 0.0], 0.5, None, None).unwrap();
    let plan = p.plan(&far, None, None).unwrap();
    assert_eq!(plan.status, HitStatus::Unreachable);
    assert!(plan.trajectory.is_none() && !plan.message.is_empty());
    let n = Vector3::new(0.3, -1.0, -0.2).normalize() * 40.0;
    let fast = Hit::from_normal([0.35, -0.55, 0.05], [0.3, -1.0, -0.2], [n.x, n.y, n.z], 0.5, None, None).unwrap();
    let plan = p.plan(&fast, None, None).unwrap();
    assert_eq!(plan.status, HitStatus::HitSpeedLimit, "{}", plan.message);
}

#[test]
fn bad_hits_are_errors_naming_the_argument() {
    let e = Hit::from_normal([0.0; 3], [0.0; 3], [0.0; 3], 0.3, None, None).unwrap_err();
    assert!(e.to_string().contains("normal"), "{e}");
    let e = Hit::from_normal([0.0; 3], [0.0, 0.0, 1.0], [0.0; 3], -1.0, None, None).unwrap_err();
    assert!(e.to_string().starts_with("t:"), "{e}");
    let e = Hit::from_normal([f64::NAN, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0; 3], 1.0, None, None).unwrap_err();
    assert!(e.to_string().contains("centre"), "{e}");
}

#[test]
fn quintic_profile_without_jerk_limit_keeps_the_patent_stroke() {
    let opts = HitOptions {
        profile: StrokeProfile::Quintic,
        jerk: Some(vec![1e9; 6]),
        ..Default::default()
    };
    let p = HitPlanner::new(&robots::gantry6(), opts).unwrap();
    // The quintic needs 0.503 s for this hit (the jerk-limited stroke 0.323 s).
    let plan = p.plan(&demo_hit(0.6), None, None).unwrap();
    assert!(plan.ok(), "{}", plan.message);
    assert_eq!(plan.profile, StrokeProfile::Quintic);
    let (pe, te) = hit_errors(&p, &plan);
    assert!(pe < 1e-9 && te < 1e-8);
}

#[test]
fn mobile8_racket_task_hit_meets_centre_and_normal() {
    let chain = robots::mobile8();
    let p = HitPlanner::new(&chain, HitOptions::default()).unwrap();
    let q0 = p.default_ready().to_vec();
    let now = p.mount().racket_pose(&chain.fk(&q0).unwrap());
    // The demo's mobile8 hit (python/ttmanip/demo.py: mobile8_hit).
    let c = now.translation.vector + Vector3::new(0.02, -0.04, -0.07);
    let n = now.rotation.matrix().column(2).into_owned();
    let hit = Hit::from_normal([c.x, c.y, c.z], [n.x, n.y, n.z], [-0.29, 0.19, 0.25], 1.5, None, None).unwrap();
    let plan = p.plan(&hit, None, None).unwrap();
    assert!(
        matches!(plan.status, HitStatus::Ok | HitStatus::TooEarly),
        "{:?} {}",
        plan.status,
        plan.message
    );
    let traj = plan.trajectory.as_ref().unwrap();
    let s = traj.state(plan.t_hit).unwrap();
    let racket = p.mount().racket_pose(&chain.fk(&s.q).unwrap());
    assert!((racket.translation.vector - hit.centre()).norm() < 1e-6);
    let normal = racket.rotation.matrix().column(2).into_owned();
    assert!(normal.angle(&hit.normal()) < 1e-6);
    // Centre velocity as requested.
    let jac = chain.jacobian(&s.q, crate::JacobianFrame::Base).unwrap();
    let tw = jac * nalgebra::DVector::from_column_slice(&s.qd);
    let tw = p.mount().racket_twist(&chain.fk(&s.q).unwrap(), tw.as_slice());
    for k in 0..3 {
        assert!((tw[k] - hit.twist[k]).abs() < 1e-6, "{tw:?}");
    }
}

#[test]
fn batch_equals_single_calls() {
    let p = planner();
    let hits: Vec<Hit> = [0.02, 0.3, 0.5, 1.0].iter().map(|&t| demo_hit(t)).collect();
    let batch = p.plan_batch(&hits, None, None).unwrap();
    for (h, b) in hits.iter().zip(&batch) {
        let single = p.plan(h, None, None).unwrap();
        assert_eq!(single.status, b.status);
        assert_eq!(single.t_hit, b.t_hit, "{:?}", b.status);
        assert_eq!(single.q_hit, b.q_hit);
        assert_eq!(single.trajectory, b.trajectory);
    }
}

#[test]
fn batches_are_bounded_by_the_bytes_of_their_plans() {
    let p = planner();
    // the lower bound of a plan's bytes holds for quintic, jerk-limited and strokeless plans
    let floor = HitPlan::bytes_at_least(6);
    for (t, profile) in [
        (0.6, StrokeProfile::Quintic),
        (0.3, StrokeProfile::Jerk),
        (0.6, StrokeProfile::Auto),
    ] {
        let options = HitOptions {
            profile,
            ..Default::default()
        };
        let q = HitPlanner::new(&robots::gantry6(), options).unwrap();
        let plan = q.plan(&demo_hit(t), None, None).unwrap();
        assert!(
            plan.trajectory.is_some() && plan.bytes() >= floor,
            "{profile:?}: {} < {floor}",
            plan.bytes()
        );
    }
    // 10⁷ hits are refused before any is planned, with the number one call may take
    let most = crate::budget::MAX_BYTES / floor;
    assert!(HitPlanner::check_batch(6, most).is_ok());
    let e = HitPlanner::check_batch(6, 10_000_000).unwrap_err().to_string();
    assert!(
        e.starts_with("hits:") && e.contains(&format!("at most {most} hits")),
        "{e}"
    );
    assert!(p.plan_batch(&vec![demo_hit(0.6); most + 1], None, None).is_err());
}

/// A random reachable gantry6 hit: centre in the box x ∈ [−0.3, 0.3], y ∈ [−0.6, −0.2],
/// z ∈ [−0.15, 0.15] m, face normal within 45° of −y, racket speed 1–4 m/s along the normal, hit
/// time 0.15–0.6 s.
fn random_hit() -> impl Strategy<Value = Hit> {
    (
        -0.3..0.3f64,
        -0.6..-0.2f64,
        -0.15..0.15f64,
        -0.7..0.7f64,
        -0.7..0.7f64,
        1.0..4.0f64,
        0.15..0.6f64,
    )
        .prop_map(|(x, y, z, a, b, s, t)| {
            let n = Vector3::new(a.sin(), -a.cos() * b.cos(), b.sin()).normalize();
            let v = n * s;
            Hit::from_normal([x, y, z], [n.x, n.y, n.z], [v.x, v.y, v.z], t, None, None).unwrap()
        })
}

/// The earliest feasible time a plan reports (`too_early`: its own; `ok`: the on-demand search
/// with the effort check) is a time at which planning is accepted, from rest and from moving
/// starts, every profile.
#[test]
fn the_earliest_time_reported_is_accepted() {
    let mut rng = fastrand::Rng::with_seed(30);
    let chain = robots::gantry6();
    let (mut early, mut ok) = (0, 0);
    for k in 0..120 {
        let profile = [StrokeProfile::Auto, StrokeProfile::Jerk, StrokeProfile::Quintic][k % 3];
        let p = HitPlanner::new(
            &chain,
            HitOptions {
                profile,
                ..HitOptions::default()
            },
        )
        .unwrap();
        let r = |rng: &mut fastrand::Rng, s: f64| (0..6).map(|_| s * (2.0 * rng.f64() - 1.0)).collect::<Vec<f64>>();
        let ready = p.default_ready().to_vec();
        let q: Vec<f64> = ready.iter().zip(r(&mut rng, 0.6)).map(|(a, b)| a + b).collect();
        let qd: Vec<f64> = r(&mut rng, 0.5)
            .iter()
            .zip(&p.limits().velocity)
            .map(|(a, v)| a * v)
            .collect();
        let tool = chain.fk(&q).unwrap();
        let jac = chain.jacobian(&q, crate::JacobianFrame::Base).unwrap();
        let tw = jac * nalgebra::DVector::from_column_slice(&qd);
        let twist = p.mount().racket_twist(&tool, tw.as_slice());
        let pose = p.mount().racket_pose(&tool);
        let start = (k % 2 == 1).then(|| crate::traj::JointState {
            q: ready.iter().zip(r(&mut rng, 0.2)).map(|(a, b)| a + b).collect(),
            qd: r(&mut rng, 0.3)
                .iter()
                .zip(&p.limits().velocity)
                .map(|(a, v)| a * v)
                .collect(),
            qdd: vec![0.0; 6],
        });
        let t = 0.15 + 0.6 * rng.f64();
        let plan = p
            .plan(&Hit::new(pose, twist, t).unwrap(), start.as_ref(), Some(&ready))
            .unwrap();
        if !matches!(plan.status, HitStatus::Ok | HitStatus::TooEarly) {
            continue;
        }
        let earliest = p.earliest_t_hit(&plan);
        assert!(
            earliest <= plan.t_hit * (1.0 + 1e-12),
            "{k}: {earliest} after {}",
            plan.t_hit
        );
        let again = p
            .plan(&Hit::new(pose, twist, earliest).unwrap(), start.as_ref(), Some(&ready))
            .unwrap();
        assert!(
            again.ok(),
            "{k} ({:?}, {:?}): at {earliest}: {:?} {}",
            plan.status,
            profile,
            again.status,
            again.message
        );
        if plan.ok() {
            ok += 1;
        } else {
            early += 1;
        }
    }
    assert!(ok >= 10 && early >= 10, "{ok} ok, {early} too early");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn every_planned_stroke_meets_its_hit_and_limits(hit in random_hit()) {
        let p = planner();
        let plan = p.plan(&hit, None, None).unwrap();
        if plan.trajectory.is_some() {
            let (pe, te) = hit_errors(&p, &plan);
            prop_assert!(pe < 1e-8 && te < 1e-6, "pose {} twist {}", pe, te);
            if matches!(plan.status, HitStatus::Ok | HitStatus::TooEarly) {
                prop_assert!(plan.violations.is_empty(), "{:?}", plan.violations);
                // Independent exact check of every kinematic limit (position, speed, acceleration, jerk).
                let all = plan.trajectory.as_ref().unwrap().check_limits(p.limits()).unwrap();
                prop_assert!(all.is_empty(), "{:?}", all);
                prop_assert!(plan.t_hit >= hit.t * (1.0 - 1e-12));
                prop_assert!(plan.t_hit >= p.earliest_t_hit(&plan) * (1.0 - 1e-9));
            }
            if plan.status == HitStatus::Ok {
                prop_assert_eq!(plan.t_hit, hit.t);
            }
        }
    }
}

#[test]
fn mobile8_plans_under_its_own_gravity() {
    // mobile8's base frame has x up (robots::MOBILE8_GRAVITY): the planner's default gravity is
    // the robot's, and the hit's peak torques differ from the same plan under base-z-up gravity.
    let chain = robots::mobile8();
    assert_eq!(chain.gravity(), robots::MOBILE8_GRAVITY);
    let own = HitPlanner::new(&chain, HitOptions::default()).unwrap();
    assert_eq!(own.gravity(), robots::MOBILE8_GRAVITY);
    let z_up = HitPlanner::new(
        &chain,
        HitOptions {
            gravity: Some(crate::dynamics::EARTH_GRAVITY),
            ..HitOptions::default()
        },
    )
    .unwrap();
    let q0 = own.default_ready().to_vec();
    let now = own.mount().racket_pose(&chain.fk(&q0).unwrap());
    let c = now.translation.vector + Vector3::new(0.02, -0.04, -0.07);
    let n = now.rotation.matrix().column(2).into_owned();
    let hit = Hit::from_normal([c.x, c.y, c.z], [n.x, n.y, n.z], [-0.29, 0.19, 0.25], 1.5, None, None).unwrap();
    let a = own.plan(&hit, None, None).unwrap();
    let b = z_up.plan(&hit, None, None).unwrap();
    assert!(
        a.trajectory.is_some() && b.trajectory.is_some(),
        "{:?} {:?}",
        a.status,
        b.status
    );
    let differs = a
        .peak_effort
        .iter()
        .zip(&b.peak_effort)
        .any(|(x, y)| (x - y).abs() > 1e-3 * (1.0 + y.abs()));
    assert!(differs, "{:?} vs {:?}", a.peak_effort, b.peak_effort);
    // The held ready pose: the static torques are the RNEA's under the robot's gravity.
    let dy = crate::Dynamics::new(&chain).unwrap();
    let mut d = crate::DynamicsData::new(&dy);
    let g_own = dy.gravity(&mut d, &q0, &chain.gravity()).unwrap().clone();
    let g_z = dy
        .gravity(&mut d, &q0, &crate::dynamics::EARTH_GRAVITY)
        .unwrap()
        .clone();
    assert!(
        (g_own - g_z).norm() > 1.0,
        "gravity along x and along z load the joints differently"
    );
}

/// `Hit::batch` builds the hits `Hit::new` builds, and names the element and field of a bad one.
#[test]
fn hit_batch_matches_new_and_names_the_element() {
    let a = demo_hit(0.5);
    let b = demo_hit(0.6);
    let twists: Vec<f64> = a.twist.iter().chain(&b.twist).copied().collect();
    let hits = Hit::batch(&[a.pose, b.pose], &twists, &[0.5, 0.6]).unwrap();
    assert_eq!(hits, vec![a, b]);
    let e = Hit::batch(&[a.pose, b.pose], &twists, &[0.5, -1.0]).unwrap_err();
    assert!(e.to_string().starts_with("hits[1].t:"), "{e}");
    let mut bad = twists.clone();
    bad[7] = f64::NAN;
    let e = Hit::batch(&[a.pose, b.pose], &bad, &[0.5, 0.6]).unwrap_err();
    assert!(
        matches!(e, crate::Error::NonFinite { ref what, .. } if what == "hits[1].twist"),
        "{e}"
    );
    assert!(matches!(
        Hit::batch(&[a.pose], &twists, &[0.5]),
        Err(crate::Error::Shape { .. })
    ));
}

#[test]
fn task_and_profile_names_parse_back_and_a_bad_name_says_the_choices() {
    for task in [HitTask::Auto, HitTask::Pose, HitTask::Racket5] {
        assert_eq!(task.name().parse::<HitTask>().unwrap(), task);
    }
    for profile in [StrokeProfile::Auto, StrokeProfile::Quintic, StrokeProfile::Jerk] {
        assert_eq!(profile.name().parse::<StrokeProfile>().unwrap(), profile);
    }
    let err = "racket6".parse::<HitTask>().unwrap_err().to_string();
    assert!(
        err.contains("task") && err.contains("'racket5'") && err.contains("'racket6'"),
        "{err}"
    );
    assert!("Pose".parse::<HitTask>().is_err(), "names are exact");
    let err = "cubic".parse::<StrokeProfile>().unwrap_err().to_string();
    assert!(err.contains("profile") && err.contains("'quintic'"), "{err}");
}
