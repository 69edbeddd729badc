//! Trajectory generation: boundary conditions, via-point continuity, seed-001 values, task-space
//! geometry, IK hand-off, exact limit checks, minimal durations and the hitting stroke.

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector3};
use proptest::prelude::*;
use ttkin::traj::duration::{
    earliest_quintic_duration, minimal_duration_rest, minimal_quintic_duration, quintic_limit_ratio, SegmentKind,
};
use ttkin::traj::limits::LIMIT_TOLERANCE;
use ttkin::traj::via::{self, ViaKind};
use ttkin::traj::{stroke, CartesianTrajectory, JointState, JointTrajectory, KinematicLimits, Path, Quantity, TimeLaw};
use ttkin::{Chain, Error, Geometry, Joint, JointType};

const TOL: f64 = 1e-12;

fn state_at(traj: &JointTrajectory, t: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = traj.dof();
    let (mut q, mut qd, mut qdd, mut j) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    traj.sample(t, &mut q, &mut qd, &mut qdd).unwrap();
    traj.jerk(t, &mut j).unwrap();
    (q, qd, qdd, j)
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

fn vecs(n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(-2.0..2.0f64, n)
}

// ---------------------------------------------------------------- seed 001

#[test]
fn seed001_cubic_table_values() {
    // Joint 2: 0 → 1.6 rad, joint 4: 0 → −1.6 rad, rest to rest in 2 s.
    let traj = JointTrajectory::cubic(&[0.0, 0.0], &[1.6, -1.6], None, None, 2.0).unwrap();
    let expect = [
        (0.5, 0.25, 0.9, 1.2),
        (1.0, 0.8, 1.2, 0.0),
        (1.5, 1.35, 0.9, -1.2),
        (2.0, 1.6, 0.0, -2.4),
    ];
    for (t, q, qd, qdd) in expect {
        let (p, v, a, _) = state_at(&traj, t);
        assert!((p[0] - q).abs() < TOL && (p[1] + q).abs() < TOL, "q({t}) = {p:?}");
        assert!((v[0] - qd).abs() < TOL && (v[1] + qd).abs() < TOL, "qd({t}) = {v:?}");
        assert!((a[0] - qdd).abs() < TOL && (a[1] + qdd).abs() < TOL, "qdd({t}) = {a:?}");
    }
}

#[test]
fn cubic_with_velocities_uses_corrected_formulas() {
    // Seed 001 (24)–(25) would give a2 = 3h/tf², a3 = −2h/tf³ regardless of the velocities.
    let traj = JointTrajectory::cubic(&[0.3], &[1.1], Some(&[0.5]), Some(&[-0.25]), 1.5).unwrap();
    let c = traj.coefficients(0, 0).unwrap();
    let (h, tf, v0, v1) = (0.8f64, 1.5f64, 0.5, -0.25);
    assert!((c[2] - (3.0 * h / tf.powi(2) - (2.0 * v0 + v1) / tf)).abs() < TOL);
    assert!((c[3] - (-2.0 * h / tf.powi(3) + (v0 + v1) / tf.powi(2))).abs() < TOL);
}

// ---------------------------------------------------------------- boundary conditions

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn cubic_meets_boundary_conditions(q0 in vecs(8), q1 in vecs(8), v0 in vecs(8), v1 in vecs(8), tf in 0.2..3.0f64) {
        let traj = JointTrajectory::cubic(&q0, &q1, Some(&v0), Some(&v1), tf).unwrap();
        let (p0, d0, _, _) = state_at(&traj, 0.0);
        let (p1, d1, _, _) = state_at(&traj, tf);
        prop_assert!(max_diff(&p0, &q0) < TOL && max_diff(&d0, &v0) < TOL);
        prop_assert!(max_diff(&p1, &q1) < TOL && max_diff(&d1, &v1) < TOL, "{:?} {:?}", p1, d1);
    }

    #[test]
    fn quintic_meets_boundary_conditions(
        q0 in vecs(8), q1 in vecs(8), v0 in vecs(8), v1 in vecs(8), a0 in vecs(8), a1 in vecs(8), tf in 0.5..3.0f64
    ) {
        // Below 0.5 s the terms of q̈(tf) reach |h|·60/tf² ≈ 1e3 and their rounding alone is ~1e-13·1e1.
        let traj = JointTrajectory::quintic(&q0, &q1, Some(&v0), Some(&v1), Some(&a0), Some(&a1), tf).unwrap();
        let (p0, d0, dd0, _) = state_at(&traj, 0.0);
        let (p1, d1, dd1, _) = state_at(&traj, tf);
        prop_assert!(max_diff(&p0, &q0) < TOL && max_diff(&d0, &v0) < TOL && max_diff(&dd0, &a0) < TOL);
        prop_assert!(max_diff(&p1, &q1) < TOL && max_diff(&d1, &v1) < TOL && max_diff(&dd1, &a1) < TOL);
    }

    #[test]
    fn derivatives_match_central_differences(
        q0 in vecs(3), q1 in vecs(3), v0 in vecs(3), a1 in vecs(3), tf in 0.5..3.0f64, u in 0.05..0.95f64
    ) {
        let traj = JointTrajectory::quintic(&q0, &q1, Some(&v0), None, None, Some(&a1), tf).unwrap();
        let (t, h) = (u * tf, 1e-5);
        let (pp, vp, ap, _) = state_at(&traj, t + h);
        let (pm, vm, am, _) = state_at(&traj, t - h);
        let (_, v, a, j) = state_at(&traj, t);
        for i in 0..3 {
            prop_assert!(((pp[i] - pm[i]) / (2.0 * h) - v[i]).abs() < 1e-7);
            prop_assert!(((vp[i] - vm[i]) / (2.0 * h) - a[i]).abs() < 1e-6);
            prop_assert!(((ap[i] - am[i]) / (2.0 * h) - j[i]).abs() < 1e-5);
        }
    }
}

#[test]
fn sample_rate_covers_the_duration() {
    let traj = JointTrajectory::quintic(&[0.0], &[1.0], None, None, None, None, 0.105).unwrap();
    let s = traj.sample_rate(100.0).unwrap();
    assert_eq!(s.t.len(), 12);
    assert_eq!(s.t[10], 0.1);
    assert_eq!(*s.t.last().unwrap(), 0.105);
    assert!((s.q[11] - 1.0).abs() < TOL);
    let mut t = vec![0.0; 101];
    let (mut q, mut qd, mut qdd) = (vec![0.0; 101], vec![0.0; 101], vec![0.0; 101]);
    traj.sample_uniform_into(&mut t, &mut q, &mut qd, &mut qdd).unwrap();
    assert_eq!(t[100], 0.105);
    assert!((q[50] - 0.5).abs() < TOL, "symmetric quintic is halfway at half time");
}

#[test]
fn column_sampling_equals_row_sampling() {
    let (points, times) = via_data();
    let trajs = [
        JointTrajectory::quintic(
            &[0.1, 0.2, 0.3],
            &[1.0, -1.0, 0.5],
            Some(&[0.3; 3]),
            None,
            None,
            None,
            0.7,
        )
        .unwrap(),
        via::through(&points, &times, 2, ViaKind::Quintic).unwrap(),
        via::through(&points, &times, 2, ViaKind::Spline).unwrap(),
    ];
    for traj in trajs {
        for n in [2, 7, 101] {
            let m = n * traj.dof();
            let (mut t, mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
            traj.sample_uniform_into(&mut t, &mut q, &mut qd, &mut qdd).unwrap();
            let (mut tc, mut qc, mut qdc, mut qddc) = (vec![0.0; n], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
            traj.sample_uniform_columns_into(&mut tc, &mut qc, &mut qdc, &mut qddc)
                .unwrap();
            assert_eq!(t, tc);
            for i in 0..n {
                for j in 0..traj.dof() {
                    let (r, c) = (i * traj.dof() + j, j * n + i);
                    assert_eq!((q[r], qd[r], qdd[r]), (qc[c], qdc[c], qddc[c]), "sample {i} joint {j}");
                }
            }
        }
    }
}

// ---------------------------------------------------------------- via points

fn via_data() -> (Vec<f64>, Vec<f64>) {
    // 5 via points of 2 joints, non-uniform times, one joint turning back at the middle point.
    let points = vec![0.0, 1.0, 0.4, 0.8, 1.0, 0.2, 1.3, 0.9, 1.5, 1.4];
    let times = vec![0.5, 1.0, 2.2, 2.7, 4.0];
    (points, times)
}

fn jump(traj: &JointTrajectory, t: f64, order: usize) -> f64 {
    let eps = 1e-9;
    let a = state_at(traj, t - eps);
    let b = state_at(traj, t + eps);
    let pick = |s: &(Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>)| match order {
        0 => s.0.clone(),
        1 => s.1.clone(),
        _ => s.2.clone(),
    };
    max_diff(&pick(&a), &pick(&b))
}

#[test]
fn via_trajectories_pass_through_points_with_promised_continuity() {
    let (points, times) = via_data();
    for (kind, smooth) in [(ViaKind::Cubic, 1), (ViaKind::Spline, 2), (ViaKind::Quintic, 2)] {
        let traj = via::through(&points, &times, 2, kind).unwrap();
        assert!((traj.duration() - 3.5).abs() < TOL);
        for (k, &tk) in times.iter().enumerate() {
            let (q, qd, _, _) = state_at(&traj, tk - times[0]);
            assert!(
                max_diff(&q, &points[2 * k..2 * k + 2]) < TOL,
                "{kind:?} misses point {k}"
            );
            if k == 0 || k == times.len() - 1 {
                assert!(max_diff(&qd, &[0.0, 0.0]) < TOL, "{kind:?} not at rest at the ends");
            }
        }
        for &tk in &times[1..times.len() - 1] {
            let t = tk - times[0];
            // A jump of a continuous quantity over 2e-9 s is at most |next derivative|·2e-9.
            assert!(jump(&traj, t, 0) < 1e-7);
            assert!(jump(&traj, t, 1) < 1e-7, "{kind:?} velocity jumps at {t}");
            if smooth == 2 {
                assert!(jump(&traj, t, 2) < 1e-6, "{kind:?} acceleration jumps at {t}");
            }
        }
    }
    // The cubic segments are not C²: the test above could fail.
    let cubic = via::through(&points, &times, 2, ViaKind::Cubic).unwrap();
    assert!(jump(&cubic, times[1] - times[0], 2) > 1e-3);
}

#[test]
fn heuristic_velocity_is_zero_where_the_joint_turns() {
    let (points, times) = via_data();
    let v = via::heuristic_velocities(&points, &times, 2).unwrap();
    // Joint 1 goes 1.0 → 0.8 → 0.2 → 0.9: falling then rising at point 2, so zero there.
    assert_eq!(v[2 * 2 + 1], 0.0);
    // Joint 0 rises throughout: mean of the adjacent slopes at point 1.
    let expect = 0.5 * (0.4 / 0.5 + 0.6 / 1.2);
    assert!((v[2] - expect).abs() < TOL);
}

#[test]
fn clamped_spline_reproduces_a_cubic_polynomial() {
    // A cubic polynomial is its own C² spline: sampling it at uneven knots and clamping with its
    // end velocities must give it back everywhere.
    let p = |t: f64| 0.3 - 0.7 * t + 0.4 * t * t - 0.15 * t * t * t;
    let dp = |t: f64| -0.7 + 0.8 * t - 0.45 * t * t;
    let times = [0.0, 0.4, 1.1, 1.5, 2.6, 3.0];
    let points: Vec<f64> = times.iter().map(|&t| p(t)).collect();
    let traj = via::spline(&points, &times, 1, Some(&[dp(0.0)]), Some(&[dp(3.0)])).unwrap();
    for i in 0..=60 {
        let t = 3.0 * i as f64 / 60.0;
        let (q, qd, _, _) = state_at(&traj, t);
        assert!((q[0] - p(t)).abs() < 1e-12 && (qd[0] - dp(t)).abs() < 1e-12, "t = {t}");
    }
}

// ---------------------------------------------------------------- task space

fn pose(xyz: [f64; 3], rpy: [f64; 3]) -> IsometryMatrix3<f64> {
    ttkin::transform::from_xyz_rpy(xyz, rpy)
}

fn laws() -> [TimeLaw; 4] {
    [
        TimeLaw::Cubic,
        TimeLaw::Quintic,
        TimeLaw::Trapezoid { blend: 0.2 },
        TimeLaw::Trapezoid { blend: 0.5 },
    ]
}

#[test]
fn time_laws_go_from_rest_to_rest() {
    for law in laws() {
        let [s0, v0, _, _] = law.eval(0.0, 1.7);
        let [s1, v1, _, _] = law.eval(1.7, 1.7);
        assert!(
            s0.abs() < TOL && (s1 - 1.0).abs() < TOL && v0.abs() < TOL && v1.abs() < TOL,
            "{law:?}"
        );
        // Monotone and matching its own derivative.
        let (t, h) = (0.61, 1e-6);
        let [sp, ..] = law.eval(t + h, 1.7);
        let [sm, ..] = law.eval(t - h, 1.7);
        let [_, v, _, _] = law.eval(t, 1.7);
        assert!(((sp - sm) / (2.0 * h) - v).abs() < 1e-8 && v > 0.0, "{law:?}");
    }
}

#[test]
fn line_samples_lie_on_the_segment() {
    let (a, b) = (
        pose([0.4, -0.2, 0.9], [0.1, 0.2, 0.3]),
        pose([0.7, 0.3, 1.2], [-0.5, 0.4, 2.0]),
    );
    for law in laws() {
        let traj = CartesianTrajectory::line(&a, &b, 0.8, law).unwrap();
        let (p0, p1) = (a.translation.vector, b.translation.vector);
        let dir = (p1 - p0).normalize();
        for s in traj.sample_rate(250.0).unwrap() {
            let d = s.pose.translation.vector - p0;
            let off = (d - dir * d.dot(&dir)).norm();
            let along = d.dot(&dir) / (p1 - p0).norm();
            assert!(off < TOL && (-TOL..=1.0 + TOL).contains(&along), "{law:?} t = {}", s.t);
            // The velocity is along the line.
            assert!(s.velocity.cross(&dir).norm() < TOL);
        }
        let end = traj.sample(0.8).unwrap().pose;
        assert!((end.to_homogeneous() - b.to_homogeneous()).abs().max() < TOL);
    }
}

#[test]
fn arc_through_three_points_lies_on_the_circle() {
    let (a, b) = (
        pose([0.5, 0.0, 1.0], [0.0, 0.0, 0.0]),
        pose([0.1, 0.45, 1.2], [0.3, -0.2, 1.0]),
    );
    let via_point = Vector3::new(0.45, 0.3, 1.15);
    let traj = CartesianTrajectory::arc_through(&a, &via_point, &b, 1.2, TimeLaw::Quintic).unwrap();
    let Path::Arc {
        centre, radius, axis, ..
    } = traj.path().clone()
    else {
        panic!("an arc");
    };
    // All three points are on the circle.
    for p in [a.translation.vector, via_point, b.translation.vector] {
        assert!(((p - centre).norm() - radius).abs() < TOL);
        assert!((p - centre).dot(&axis).abs() < TOL);
    }
    let mut closest_to_via = f64::INFINITY;
    for s in traj.sample_rate(1000.0).unwrap() {
        let d = s.pose.translation.vector - centre;
        assert!(
            (d.norm() - radius).abs() < TOL && d.dot(&axis).abs() < TOL,
            "t = {}",
            s.t
        );
        closest_to_via = closest_to_via.min((s.pose.translation.vector - via_point).norm());
    }
    assert!(
        closest_to_via < 2e-3,
        "the arc passes the via point ({closest_to_via} m)"
    );
    let end = traj.sample(1.2).unwrap().pose;
    assert!((end.to_homogeneous() - b.to_homogeneous()).abs().max() < TOL);
}

#[test]
fn arc_about_an_axis_turns_the_tool_with_it() {
    let start = pose([0.6, 0.1, 0.8], [0.2, -0.1, 0.4]);
    let (centre, axis) = (Vector3::new(0.2, 0.1, 0.5), Vector3::new(0.0, 0.3, 1.0));
    let angle = -4.0; // more than π, clockwise
    let traj =
        CartesianTrajectory::arc_about(&start, &centre, &axis, angle, 2.0, TimeLaw::Trapezoid { blend: 0.3 }).unwrap();
    let k = axis.normalize();
    for s in traj.sample_rate(200.0).unwrap() {
        // Rigid rotation of the start pose about the axis line by the swept angle.
        let [sv, ..] = traj.law().eval(s.t, 2.0);
        let rot = Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle * sv);
        let expect = IsometryMatrix3::from_parts(Translation3::from(centre), rot)
            * IsometryMatrix3::from_parts(Translation3::from(-centre), Rotation3::identity())
            * start;
        assert!(
            (s.pose.to_homogeneous() - expect.to_homogeneous()).abs().max() < TOL,
            "t = {}",
            s.t
        );
        assert!(s.angular_velocity.cross(&k).norm() < TOL);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(60))]

    #[test]
    fn twists_match_finite_differences_of_poses(
        xyz in prop::collection::vec(-1.0..1.0f64, 6), rpy in prop::collection::vec(-1.5..1.5f64, 6),
        u in 0.05..0.95f64, which in 0usize..3
    ) {
        let a = pose([xyz[0], xyz[1], xyz[2]], [rpy[0], rpy[1], rpy[2]]);
        let b = pose([xyz[3], xyz[4], xyz[5]], [rpy[3], rpy[4], rpy[5]]);
        let mid = Vector3::new(xyz[0] + xyz[5], xyz[1] - xyz[3], xyz[2] + 0.5);
        let traj = match which {
            0 => CartesianTrajectory::line(&a, &b, 1.3, TimeLaw::Quintic),
            1 => CartesianTrajectory::arc_through(&a, &mid, &b, 1.3, TimeLaw::Cubic),
            _ => CartesianTrajectory::arc_about(&a, &mid, &Vector3::new(0.2, 1.0, 0.1), 2.5, 1.3, TimeLaw::Quintic),
        };
        let Ok(traj) = traj else { return Ok(()) }; // collinear draws
        let (t, h) = (u * 1.3, 1e-6);
        let (sp, sm, s) = (traj.sample(t + h).unwrap(), traj.sample(t - h).unwrap(), traj.sample(t).unwrap());
        let v_fd = (sp.pose.translation.vector - sm.pose.translation.vector) / (2.0 * h);
        let a_fd = (sp.velocity - sm.velocity) / (2.0 * h);
        // ω from Ṙ·Rᵀ.
        let rdot = (sp.pose.rotation.matrix() - sm.pose.rotation.matrix()) / (2.0 * h);
        let w = rdot * s.pose.rotation.matrix().transpose();
        let w_fd = Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
        let al_fd = (sp.angular_velocity - sm.angular_velocity) / (2.0 * h);
        prop_assert!((v_fd - s.velocity).norm() < 1e-6);
        prop_assert!((a_fd - s.acceleration).norm() < 1e-5);
        prop_assert!((w_fd - s.angular_velocity).norm() < 1e-6);
        prop_assert!((al_fd - s.angular_acceleration).norm() < 1e-5);
    }
}

/// A 6-joint gantry with a roll-pitch-yaw wrist at the tool point: x, y, z slides then rotations
/// about z, y, x, so FK(q) = Trans(q0, q1, q2)·Rz(q3)·Ry(q4)·Rx(q5) and IK is closed-form.
fn xyz_rpy_robot() -> Chain {
    let axes = [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()];
    let mut joints = Vec::new();
    for (i, a) in axes.iter().enumerate() {
        let g = Geometry::Origin {
            origin: IsometryMatrix3::identity(),
            axis: *a,
        };
        joints.push(Joint::new(format!("slide{i}"), JointType::Prismatic, g).unwrap());
    }
    for (i, a) in axes.iter().rev().enumerate() {
        let g = Geometry::Origin {
            origin: IsometryMatrix3::identity(),
            axis: *a,
        };
        joints.push(Joint::new(format!("wrist{i}"), JointType::Revolute, g).unwrap());
    }
    Chain::new(
        "xyz-rpy",
        joints,
        IsometryMatrix3::identity(),
        IsometryMatrix3::identity(),
    )
    .unwrap()
}

fn xyz_rpy_ik(t: &IsometryMatrix3<f64>, _seed: &[f64]) -> ttkin::Result<Vec<f64>> {
    let p = t.translation.vector;
    if p.x > 0.65 {
        return Err(Error::Unreachable(format!("x = {} m beyond the 0.65 m rail", p.x)));
    }
    let (roll, pitch, yaw) = t.rotation.euler_angles();
    Ok(vec![p.x, p.y, p.z, yaw, pitch, roll])
}

#[test]
fn joint_samples_from_ik_reproduce_the_poses() {
    let robot = xyz_rpy_robot();
    let (a, b) = (
        pose([0.4, -0.2, 0.9], [0.1, 0.2, 0.3]),
        pose([0.6, 0.3, 1.2], [-0.5, 0.4, 1.0]),
    );
    let via_point = Vector3::new(0.55, 0.1, 1.2);
    for traj in [
        CartesianTrajectory::line(&a, &b, 0.5, TimeLaw::Quintic).unwrap(),
        CartesianTrajectory::arc_through(&a, &via_point, &b, 0.5, TimeLaw::Cubic).unwrap(),
    ] {
        let samples = traj.to_joint(500.0, &[0.0; 6], xyz_rpy_ik).unwrap();
        assert_eq!(samples.t.len(), 251);
        for (i, &t) in samples.t.iter().enumerate() {
            let fk = robot.fk(&samples.q[6 * i..6 * i + 6]).unwrap();
            let want = traj.sample(t).unwrap().pose;
            assert!(
                (fk.to_homogeneous() - want.to_homogeneous()).abs().max() < TOL,
                "t = {t}"
            );
        }
        // Slide velocities are the tool velocity (the slides carry the wrist centre).
        let s = traj.sample(samples.t[100]).unwrap();
        let qd = &samples.qd[600..603];
        assert!((Vector3::new(qd[0], qd[1], qd[2]) - s.velocity).norm() < 1e-3);
    }
}

#[test]
fn ik_failure_names_the_first_bad_sample() {
    let (a, b) = (pose([0.4, 0.0, 0.9], [0.0; 3]), pose([0.8, 0.0, 0.9], [0.0; 3]));
    let traj = CartesianTrajectory::line(&a, &b, 1.0, TimeLaw::Cubic).unwrap();
    let err = traj.to_joint(100.0, &[0.0; 6], xyz_rpy_ik).unwrap_err();
    // x(t) = 0.4 + 0.4·s(t) crosses 0.65 where s = 0.625.
    let first = (0..=100)
        .find(|&i| TimeLaw::Cubic.eval(i as f64 / 100.0, 1.0)[0] > 0.625)
        .unwrap();
    match err {
        Error::Unreachable(msg) => assert!(msg.starts_with(&format!("sample {first} at t = ")), "{msg}"),
        other => panic!("wrong error {other:?}"),
    }
}

// ---------------------------------------------------------------- limits

fn dense_peak(traj: &JointTrajectory, joint: usize, order: usize) -> f64 {
    let n = 20_000;
    (0..=n)
        .map(|i| {
            let s = state_at(traj, traj.duration() * i as f64 / n as f64);
            [s.1[joint], s.2[joint], s.3[joint]][order - 1].abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn exact_peaks_bound_dense_sampling() {
    let traj = JointTrajectory::quintic(
        &[0.1, -0.4],
        &[1.3, 0.2],
        Some(&[0.4, -1.0]),
        Some(&[1.5, 0.0]),
        None,
        None,
        0.7,
    )
    .unwrap();
    for order in 1..=3 {
        let peaks = traj.peaks(order).unwrap();
        for (j, p) in peaks.iter().enumerate() {
            let dense = dense_peak(&traj, j, order);
            assert!(p.value.abs() >= dense * (1.0 - 1e-12), "order {order} joint {j}");
            assert!(
                p.value.abs() <= dense * (1.0 + 1e-6),
                "order {order} joint {j}: {} vs {dense}",
                p.value
            );
        }
    }
}

#[test]
fn planted_limit_violations_are_found() {
    let traj = JointTrajectory::quintic(&[0.0, 0.0, 0.0], &[1.0, -0.5, 0.2], None, None, None, None, 1.0).unwrap();
    // Exact peaks for h over 1 s: 15h/8, 10h/√3, 60h.
    let (v, a, j) = (15.0 / 8.0, 10.0 / 3f64.sqrt(), 60.0);
    let limits = KinematicLimits::new(
        &[v * 1.001, v * 0.5 * 0.999, 10.0],
        &[a * 1.001, 10.0, a * 0.2 * 0.999],
        &[100.0; 3],
    )
    .unwrap()
    .with_position(&[-1.0, -0.45, -1.0], &[1.0, 1.0, 1.0])
    .unwrap();
    let found = traj.check_limits(&limits).unwrap();
    let mut got: Vec<(usize, Quantity)> = found.iter().map(|v| (v.joint, v.quantity)).collect();
    got.sort_by_key(|(j, q)| (*j, *q as u8));
    assert_eq!(
        got,
        vec![
            (1, Quantity::Position),
            (1, Quantity::Velocity),
            (2, Quantity::Acceleration)
        ]
    );
    let vel = found.iter().find(|v| v.quantity == Quantity::Velocity).unwrap();
    assert!((vel.value + 0.5 * v).abs() < TOL && (vel.time - 0.5).abs() < 1e-9);
    // Jerk 60 < 100 passes, while a jerk limit of 59.9 on joint 0 fails.
    let tight = KinematicLimits::new(&[10.0; 3], &[10.0; 3], &[j * 0.999, 100.0, 100.0]).unwrap();
    let found = traj.check_limits(&tight).unwrap();
    assert_eq!(found.len(), 1);
    assert_eq!((found[0].joint, found[0].quantity), (0, Quantity::Jerk));
}

#[test]
fn minimal_rest_duration_sits_exactly_at_the_limit() {
    let (q0, q1) = ([0.0, 0.5, -1.0], [1.6, -1.1, -0.2]);
    let cases = [
        ([2.0, 3.0, 1.5], [50.0; 3], [1e4; 3]),
        ([20.0; 3], [4.0, 9.0, 6.0], [1e4; 3]),
        ([20.0; 3], [90.0; 3], [30.0, 80.0, 50.0]),
    ];
    for kind in [SegmentKind::Cubic, SegmentKind::Quintic] {
        for (v, a, j) in cases {
            let limits = KinematicLimits::new(&v, &a, &j).unwrap();
            let t = minimal_duration_rest(&q0, &q1, &limits, kind).unwrap();
            let traj = match kind {
                SegmentKind::Cubic => JointTrajectory::cubic(&q0, &q1, None, None, t),
                SegmentKind::Quintic => JointTrajectory::quintic(&q0, &q1, None, None, None, None, t),
            }
            .unwrap();
            // The largest ratio peak/limit over joints and quantities is exactly 1.
            let mut worst: f64 = 0.0;
            for (order, lim) in [(1, &v), (2, &a), (3, &j)] {
                for (p, l) in traj.peaks(order).unwrap().iter().zip(lim.iter()) {
                    worst = worst.max(p.value.abs() / l);
                }
            }
            assert!((worst - 1.0).abs() < 1e-12, "{kind:?}: worst ratio {worst}");
            assert!(traj.check_limits(&limits).unwrap().is_empty());
            // The generic search (bisection on exact extrema) agrees for the quintic.
            if kind == SegmentKind::Quintic {
                let tb = minimal_quintic_duration(&JointState::rest(&q0), &JointState::rest(&q1), &limits).unwrap();
                assert!((tb - t).abs() < 1e-11 * t, "bisection {tb} vs closed form {t}");
            }
        }
    }
}

#[test]
fn earliest_duration_with_boundary_velocities_is_at_the_limit() {
    let start = JointState {
        q: vec![0.2, -0.3],
        qd: vec![0.5, 0.0],
        qdd: vec![1.0, 0.0],
    };
    let end = JointState {
        q: vec![1.0, 0.4],
        qd: vec![2.5, -1.0],
        qdd: vec![0.0, 0.0],
    };
    let limits = KinematicLimits::new(&[3.0, 3.0], &[15.0, 20.0], &[300.0, 300.0]).unwrap();
    let t = earliest_quintic_duration(&start, &end, &limits, 0.05).unwrap();
    let traj = JointTrajectory::quintic_between(&start, &end, t).unwrap();
    assert!(traj.check_limits(&limits).unwrap().is_empty());
    let slightly_less = JointTrajectory::quintic_between(&start, &end, t * (1.0 - 1e-9)).unwrap();
    assert!(!slightly_less.check_limits(&limits).unwrap().is_empty());
    let mut worst: f64 = 0.0;
    for (order, lim) in [(1, &limits.velocity), (2, &limits.acceleration), (3, &limits.jerk)] {
        for (p, l) in traj.peaks(order).unwrap().iter().zip(lim.iter()) {
            worst = worst.max(p.value.abs() / l);
        }
    }
    assert!((worst - 1.0).abs() < 1e-9 + LIMIT_TOLERANCE, "worst ratio {worst}");
}

// ---------------------------------------------------------------- stroke

fn stroke_problem() -> (JointState, JointState, Vec<f64>, KinematicLimits) {
    let start = JointState {
        q: vec![0.0, 0.3, -0.2, 0.1],
        qd: vec![0.2, 0.0, -0.1, 0.0],
        qdd: vec![0.0, 0.5, 0.0, 0.0],
    };
    let hit = JointState {
        q: vec![0.8, -0.4, 0.6, 1.0],
        qd: vec![2.0, -1.0, 1.5, 3.0],
        qdd: vec![0.0; 4],
    };
    let ready = vec![0.0, 0.0, 0.0, 0.0];
    let limits = KinematicLimits::new(&[4.0; 4], &[40.0; 4], &[800.0; 4]).unwrap();
    (start, hit, ready, limits)
}

#[test]
fn feasible_stroke_hits_on_time_and_returns_to_rest() {
    let (start, hit, ready, limits) = stroke_problem();
    let s = stroke(&start, &hit, 0.6, &ready, None, &limits).unwrap();
    assert!(s.on_time() && s.violations.is_empty());
    let (q, qd, qdd, _) = state_at(&s.trajectory, 0.0);
    assert!(max_diff(&q, &start.q) < TOL && max_diff(&qd, &start.qd) < TOL && max_diff(&qdd, &start.qdd) < TOL);
    let (q, qd, qdd, _) = state_at(&s.trajectory, 0.6);
    assert!(max_diff(&q, &hit.q) < TOL && max_diff(&qd, &hit.qd) < TOL && max_diff(&qdd, &hit.qdd) < TOL);
    let (q, qd, qdd, _) = state_at(&s.trajectory, s.trajectory.duration());
    assert!(max_diff(&q, &ready) < TOL && max_diff(&qd, &[0.0; 4]) < TOL && max_diff(&qdd, &[0.0; 4]) < TOL);
    assert!((s.trajectory.duration() - 0.6 - s.return_duration).abs() < TOL);
}

#[test]
fn infeasible_hit_time_moves_to_the_earliest_feasible_one() {
    let (start, hit, ready, limits) = stroke_problem();
    let s = stroke(&start, &hit, 0.1, &ready, None, &limits).unwrap();
    assert!(!s.on_time() && s.t_hit > 0.1, "t_hit {}", s.t_hit);
    assert!(s.trajectory.check_limits(&limits).unwrap().is_empty());
    // Earliest: the hit leg a hair shorter breaks a limit.
    assert!(quintic_limit_ratio(&start, &hit, s.t_hit * (1.0 - 1e-9), &limits) > 1.0);
    assert!(quintic_limit_ratio(&start, &hit, s.t_hit, &limits) <= 1.0);
    let (q, qd, _, _) = state_at(&s.trajectory, s.t_hit);
    assert!(max_diff(&q, &hit.q) < TOL && max_diff(&qd, &hit.qd) < TOL);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn random_strokes_are_feasible_exact_and_earliest(
        q0 in vecs(6), qd0 in prop::collection::vec(-1.0..1.0f64, 6), qdd0 in prop::collection::vec(-5.0..5.0f64, 6),
        qh in vecs(6), qdh in prop::collection::vec(-2.9..2.9f64, 6), t_hit in 0.05..1.0f64
    ) {
        let start = JointState { q: q0, qd: qd0, qdd: qdd0 };
        let hit = JointState { q: qh, qd: qdh, qdd: vec![0.0; 6] };
        let limits = KinematicLimits::new(&[3.0; 6], &[30.0; 6], &[500.0; 6]).unwrap();
        let s = match stroke(&start, &hit, t_hit, &[0.0; 6], None, &limits) {
            Ok(s) => s,
            Err(e) => {
                // Only when no quintic can do a leg: a dense log-spaced scan of durations finds none.
                let rest = JointState::rest(&[0.0; 6]);
                let scan = |a: &JointState, b: &JointState, from: f64| {
                    (0..4000)
                        .map(|i| from * 10f64.powf(i as f64 / 1000.0))
                        .find(|&t| quintic_limit_ratio(a, b, t, &limits) <= 1.0)
                };
                let (hit_leg, back_leg) = (scan(&start, &hit, t_hit), scan(&hit, &rest, 1e-3));
                prop_assert!(hit_leg.is_none() || back_leg.is_none(), "{e} but {hit_leg:?} / {back_leg:?} s work");
                return Ok(());
            }
        };
        prop_assert!(s.t_hit >= t_hit && s.violations.is_empty(), "{:?}", s.violations);
        let (q, qd, qdd, _) = state_at(&s.trajectory, s.t_hit);
        prop_assert!(max_diff(&q, &hit.q) < 1e-11 && max_diff(&qd, &hit.qd) < 1e-11 && max_diff(&qdd, &hit.qdd) < 1e-10);
        if !s.on_time() {
            prop_assert!(quintic_limit_ratio(&start, &hit, s.t_hit * (1.0 - 1e-9), &limits) > 1.0);
        }
        // The return leg is minimal too: a hair shorter breaks a limit.
        let rest = JointState::rest(&[0.0; 6]);
        prop_assert!(quintic_limit_ratio(&hit, &rest, s.return_duration * (1.0 - 1e-9), &limits) > 1.0);
    }
}

#[test]
fn stroke_rejects_a_hit_velocity_beyond_the_limit() {
    let (start, mut hit, ready, limits) = stroke_problem();
    hit.qd[3] = 4.5;
    assert!(matches!(
        stroke(&start, &hit, 0.5, &ready, None, &limits),
        Err(Error::InvalidArgument { .. })
    ));
}

// ---------------------------------------------------------------- bad input

#[test]
fn bad_input_gives_clear_errors() {
    let q = [0.0, 1.0];
    assert!(matches!(
        JointTrajectory::cubic(&q, &q, None, None, 0.0),
        Err(Error::InvalidArgument { .. })
    ));
    assert!(matches!(
        JointTrajectory::cubic(&q, &q, None, None, -1.0),
        Err(Error::InvalidArgument { .. })
    ));
    assert!(matches!(
        JointTrajectory::cubic(&q, &q, None, None, f64::NAN),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        JointTrajectory::cubic(&q, &[1.0], None, None, 1.0),
        Err(Error::Shape { .. })
    ));
    assert!(matches!(
        JointTrajectory::quintic(&q, &q, Some(&[1.0]), None, None, None, 1.0),
        Err(Error::Shape { .. })
    ));
    assert!(matches!(
        JointTrajectory::quintic(&q, &[0.0, f64::NAN], None, None, None, None, 1.0),
        Err(Error::NonFinite { index: 1, .. })
    ));
    let err = via::through(&[0.0, 1.0, 2.0], &[0.0, 1.0, 1.0], 1, ViaKind::Spline).unwrap_err();
    assert!(err.to_string().contains("strictly increasing"), "{err}");
    assert!(via::through(&[0.0, 1.0, 2.0], &[0.0, 2.0, 1.0], 1, ViaKind::Cubic).is_err());
    assert!(matches!(
        via::through(&[0.0, 1.0], &[0.0, 1.0, 2.0], 1, ViaKind::Quintic),
        Err(Error::Shape { .. })
    ));
    let traj = JointTrajectory::cubic(&q, &q, None, None, 1.0).unwrap();
    let (mut a, mut b, mut c) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    assert!(traj.sample(1.5, &mut a, &mut b, &mut c).is_err());
    assert!(traj.sample(f64::NAN, &mut a, &mut b, &mut c).is_err());
    assert!(traj.sample(0.5, &mut [0.0; 3], &mut b, &mut c).is_err());
    assert!(traj.sample_rate(0.0).is_err());
    let p = pose([0.0; 3], [0.0; 3]);
    assert!(CartesianTrajectory::line(&p, &p, -0.1, TimeLaw::Cubic).is_err());
    assert!(CartesianTrajectory::line(&p, &p, 1.0, TimeLaw::Trapezoid { blend: 0.7 }).is_err());
    let collinear = CartesianTrajectory::arc_through(
        &p,
        &Vector3::new(1.0, 0.0, 0.0),
        &pose([2.0, 0.0, 0.0], [0.0; 3]),
        1.0,
        TimeLaw::Cubic,
    );
    assert!(collinear.is_err());
    assert!(KinematicLimits::new(&[1.0, -1.0], &[1.0, 1.0], &[1.0, 1.0]).is_err());
    assert!(KinematicLimits::new(&[1.0, 1.0], &[1.0], &[1.0, 1.0]).is_err());
}

#[test]
fn stroke_finds_a_feasible_window_narrower_than_the_coarse_bracketing() {
    // Found by `random_strokes_are_feasible_exact_and_earliest`: the hit leg's feasible durations
    // are not one interval, and the ×1.5 bracketing alone stepped over them.
    let start = JointState {
        q: vec![0.0, 0.0, 1.7419366464886947, 0.0, 0.0, 1.8549145569782817],
        qd: vec![0.0, 0.0, 0.7891275682036328, 0.0, 0.0, -0.9374024515517073],
        qdd: vec![0.0, 0.0, 3.356450837953605, 0.0, 0.0, -4.647946526217632],
    };
    let hit = JointState {
        q: vec![0.0, 0.0, -1.5758944105970658, 0.0, 0.0, -1.3911186596207576],
        qd: vec![0.0, 0.0, 1.4128170182357596, 0.0, 0.0, 1.8663263247847237],
        qdd: vec![0.0; 6],
    };
    let limits = KinematicLimits::new(&[3.0; 6], &[30.0; 6], &[500.0; 6]).unwrap();
    let s = stroke(&start, &hit, 0.05, &[0.0; 6], None, &limits).expect("a feasible stroke exists");
    assert!(s.violations.is_empty());
    assert!(quintic_limit_ratio(&start, &hit, s.t_hit, &limits) <= 1.0 + 1e-9);
}

#[test]
fn the_overflow_bound_holds_for_ordinary_segments_and_refuses_overflowing_ones() {
    let q0 = [0.0, 1.0, -2.0];
    let q1 = [1.5, -1.0, 0.5];
    let ok = JointTrajectory::quintic(&q0, &q1, None, None, None, None, 0.8).unwrap();
    assert!(ok.samples_cannot_overflow());
    let slow = JointTrajectory::quintic(&q0, &q1, None, None, None, None, 50.0).unwrap();
    assert!(slow.samples_cannot_overflow());
    // 1/T⁵ overflows: the bound refuses, and sampling indeed gives non-finite values.
    let fast = JointTrajectory::quintic(&q0, &q1, None, None, None, None, 1e-70).unwrap();
    assert!(!fast.samples_cannot_overflow());
    let n = 11;
    let (mut t, mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; 3 * n], vec![0.0; 3 * n], vec![0.0; 3 * n]);
    fast.sample_uniform_columns_into(&mut t, &mut q, &mut qd, &mut qdd)
        .unwrap();
    assert!(qdd.iter().any(|v| !v.is_finite()));
    // Below the threshold the bound is a proof: every sample of a bounded trajectory is finite.
    let edge = JointTrajectory::quintic(&q0, &q1, None, None, None, None, 1e-50).unwrap();
    assert!(edge.samples_cannot_overflow());
    edge.sample_uniform_columns_into(&mut t, &mut q, &mut qd, &mut qdd)
        .unwrap();
    assert!(q.iter().chain(&qd).chain(&qdd).all(|v| v.is_finite()));
    assert!(
        qdd.iter().any(|v| v.abs() > 1e90),
        "the edge case does produce huge values"
    );
}

/// The coefficient table holds, for every segment and joint, what `coefficients` gives, and its
/// Quantity names serialise as the lower-case names the bindings hand to Python.
#[test]
fn coefficient_table_equals_per_segment_coefficients() {
    let (points, times) = via_data();
    let n = points.len() / times.len();
    let traj = via::cubic(&points, &times, n, None).unwrap();
    let table = traj.coefficient_table();
    assert_eq!(table.len(), traj.segments() * n * 6);
    for s in 0..traj.segments() {
        for j in 0..n {
            let c = traj.coefficients(s, j).unwrap();
            assert_eq!(&table[(s * n + j) * 6..(s * n + j + 1) * 6], &c[..]);
        }
    }
    assert_eq!(
        toml::Value::try_from(Quantity::Acceleration).unwrap().as_str(),
        Some(Quantity::Acceleration.name())
    );
}
