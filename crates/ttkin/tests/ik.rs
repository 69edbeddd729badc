//! Inverse kinematics: analytic branches against FK, numeric IK against its reported tolerance,
//! differential IK against the Jacobian.

mod common;

use std::f64::consts::PI;

use common::*;
use nalgebra::{DMatrix, DVector, IsometryMatrix3};
use ttkin::ik::differential::{joint_limit_weights, DifferentialIk};
use ttkin::ik::numeric::measure;
use ttkin::ik::{joint_velocity, wrap, Analytic, IkSolver, LimitFilter};
use ttkin::task::Task;
use ttkin::transform::from_xyz_rpy;
use ttkin::{Chain, Error, JacobianFrame, JointType};

/// Random configurations within the limits, reproducible.
fn random_configs(chain: &Chain, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = fastrand::Rng::with_seed(seed);
    (0..count)
        .map(|_| {
            let u: Vec<f64> = (0..chain.dof()).map(|_| rng.f64()).collect();
            config_from_unit(chain, &u)
        })
        .collect()
}

/// Largest joint difference, revolute angles compared modulo 2π.
fn joint_diff(chain: &Chain, a: &[f64], b: &[f64]) -> f64 {
    chain
        .joints()
        .iter()
        .zip(a.iter().zip(b))
        .map(|(j, (x, y))| match j.kind() {
            JointType::Revolute => wrap(x - y).abs(),
            JointType::Prismatic => (x - y).abs(),
        })
        .fold(0.0, f64::max)
}

/// Gantries to test: the built-in and one with other lengths, joint offsets folded into a base
/// and tool transform.
fn gantries() -> Vec<Chain> {
    let other = ttkin::robots::gantry6_with(ttkin::robots::GantryLengths {
        l1: 0.2,
        l2: -0.07,
        l3: 0.45,
        l4: 0.12,
    })
    .unwrap()
    .with_base(from_xyz_rpy([0.3, -0.2, 1.1], [0.2, -0.1, 0.7]))
    .unwrap()
    .with_tool(from_xyz_rpy([0.01, 0.02, 0.05], [-0.3, 0.4, 0.1]))
    .unwrap();
    vec![ttkin::robots::gantry6(), other]
}

fn arms() -> Vec<Chain> {
    let other = ttkin::robots::arm4_with(ttkin::robots::Arm4Lengths {
        d1: 0.4,
        a1: 0.2,
        a2: 0.3,
        d4: 0.08,
    })
    .unwrap()
    .with_base(from_xyz_rpy([0.1, 0.0, 0.2], [0.0, 0.1, -0.4]))
    .unwrap()
    .with_tool(from_xyz_rpy([0.0, 0.03, 0.02], [0.2, 0.0, 0.3]))
    .unwrap();
    vec![ttkin::robots::arm4(), other]
}

/// Every branch reproduces the pose to 1e-12 and one of them is the configuration the pose came from.
fn check_analytic_round_trip(chain: &Chain, count: usize, seed: u64) {
    let ik = Analytic::for_chain(chain).expect("analytic solver");
    for q in random_configs(chain, count, seed) {
        let t = chain.fk(&q).unwrap();
        let sols = ik.solve(&t, None, LimitFilter::Off).unwrap();
        assert!(!sols.is_empty());
        for s in sols.iter() {
            let err = pose_diff(&chain.fk(s).unwrap(), &t);
            assert!(
                err < 1e-12,
                "{}: FK(IK(T)) off by {err:e} at q = {q:?}, branch {s:?}",
                chain.name()
            );
        }
        let nearest = sols
            .iter()
            .map(|s| joint_diff(chain, s, &q))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest < 1e-7,
            "{}: original q = {q:?} not among {sols:?}",
            chain.name()
        );
    }
}

#[test]
fn gantry6_every_branch_reproduces_10000_random_poses_and_contains_the_original() {
    for (k, chain) in gantries().iter().enumerate() {
        check_analytic_round_trip(chain, 10_000, 7 + k as u64);
    }
}

#[test]
fn arm4_every_branch_reproduces_10000_random_poses_and_contains_the_original() {
    for (k, chain) in arms().iter().enumerate() {
        check_analytic_round_trip(chain, 10_000, 11 + k as u64);
    }
}

#[test]
fn gantry6_has_four_distinct_branches_for_a_generic_pose() {
    let chain = ttkin::robots::gantry6();
    let t = chain.fk(&[0.1, -0.2, 0.3, 0.4, 0.5, 0.6]).unwrap();
    let sols = Analytic::for_chain(&chain)
        .unwrap()
        .solve(&t, None, LimitFilter::Off)
        .unwrap();
    assert_eq!(sols.len(), 4);
    assert!(!sols.family);
}

#[test]
fn gantry6_singular_and_near_singular_poses_are_reproduced() {
    let chain = ttkin::robots::gantry6();
    let ik = Analytic::for_chain(&chain).unwrap();
    // (θ4, θ5) with s45 = 0 exactly, s45 tiny, c4 = 0, both at once.
    let cases = [
        (0.3, -0.3, true),
        (0.3, PI - 0.3, true),
        (0.3, -0.3 + 1e-9, false),
        (0.3, -0.3 + 1e-14, true),
        (PI / 2.0, 0.4, false),
        (PI / 2.0 - 1e-10, 0.4, false),
        (PI / 2.0, -PI / 2.0, true),
    ];
    for (t4, t5, family) in cases {
        let q = [0.2, -0.1, 0.7, t4, t5, -1.1];
        let t = chain.fk(&q).unwrap();
        let sols = ik.solve(&t, Some(&q), LimitFilter::Off).unwrap();
        assert_eq!(sols.family, family, "θ4 = {t4}, θ5 = {t5}");
        for s in sols.iter() {
            let err = pose_diff(&chain.fk(s).unwrap(), &t);
            assert!(err < 1e-12, "θ4 = {t4}, θ5 = {t5}: FK(IK(T)) off by {err:e}");
        }
        // With the configuration as hint, the nearest branch is the configuration itself.
        let near = ik.nearest(&t, &q, LimitFilter::Off).unwrap();
        assert!(
            joint_diff(&chain, &near, &q) < 1e-4,
            "θ4 = {t4}, θ5 = {t5}: nearest {near:?}"
        );
    }
}

#[test]
fn gantry6_height_band_violation_is_a_clear_error() {
    let chain = ttkin::robots::gantry6();
    let ik = Analytic::for_chain(&chain).unwrap();
    let mut t = chain.fk(&[0.0, 0.0, 0.1, 0.2, 0.3, 0.4]).unwrap();
    t.translation.vector.z += 1.0;
    match ik.solve(&t, None, LimitFilter::Off) {
        Err(Error::Unreachable(msg)) => assert!(msg.contains("height band"), "{msg}"),
        other => panic!("expected Unreachable, got {other:?}"),
    }
}

#[test]
fn gantry6_limit_filter_keeps_only_branches_within_limits_and_names_the_stroke() {
    let chain = ttkin::robots::gantry6();
    let ik = Analytic::for_chain(&chain).unwrap();
    let limits = chain.limits();
    for q in random_configs(&chain, 500, 3) {
        let t = chain.fk(&q).unwrap();
        let sols = ik.solve(&t, None, LimitFilter::Enforce).unwrap();
        for s in sols.iter() {
            for (v, l) in s.iter().zip(&limits) {
                assert!(*v >= l.lower && *v <= l.upper);
            }
            assert!(pose_diff(&chain.fk(s).unwrap(), &t) < 1e-12);
        }
    }
    // Beyond the d1 stroke (±1 m): the pose exists mathematically, but no branch is within limits.
    let mut t = chain.fk(&[0.9, 0.0, 0.0, 0.2, 0.3, 0.4]).unwrap();
    t.translation.vector.y -= 2.0;
    assert!(ik.solve(&t, None, LimitFilter::Off).is_ok());
    match ik.solve(&t, None, LimitFilter::Enforce) {
        Err(Error::Unreachable(msg)) => assert!(msg.contains("d1 ="), "{msg}"),
        other => panic!("expected Unreachable, got {other:?}"),
    }
}

#[test]
fn nearest_branch_is_the_current_configuration_for_its_own_pose() {
    for chain in [ttkin::robots::gantry6(), ttkin::robots::arm4()] {
        let ik = Analytic::for_chain(&chain).unwrap();
        for q in random_configs(&chain, 1000, 5) {
            let near = ik.nearest(&chain.fk(&q).unwrap(), &q, LimitFilter::Enforce).unwrap();
            assert!(joint_diff(&chain, &near, &q) < 1e-7);
            let l = chain.limits();
            assert!(near.iter().zip(&l).all(|(v, l)| *v >= l.lower && *v <= l.upper));
        }
    }
}

#[test]
fn arm4_vertical_approach_axis_has_two_elbow_branches() {
    let chain = ttkin::robots::arm4();
    let ik = Analytic::for_chain(&chain).unwrap();
    for t3 in [0.0, 1e-11, 1e-7] {
        let q = [0.4, 0.9, t3, -0.3];
        let t = chain.fk(&q).unwrap();
        let sols = ik.solve(&t, None, LimitFilter::Off).unwrap();
        if t3 == 0.0 {
            assert_eq!(sols.len(), 2);
        }
        for s in sols.iter() {
            assert!(pose_diff(&chain.fk(s).unwrap(), &t) < 1e-12, "θ3 = {t3}: {s:?}");
        }
        assert!(
            sols.iter().any(|s| joint_diff(&chain, s, &q) < 1e-6),
            "θ3 = {t3}: {sols:?}"
        );
    }
}

#[test]
fn arm4_unreachable_poses_name_the_failed_condition() {
    let chain = ttkin::robots::arm4();
    let ik = Analytic::for_chain(&chain).unwrap();
    let t = chain.fk(&[0.2, 0.5, 0.8, 0.3]).unwrap();
    let mut up = t;
    up.translation.vector.z += 0.01;
    let mut side = t;
    side.translation.vector.x += 0.01;
    let mut far = chain.fk(&[0.2, 0.5, 0.0, 0.3]).unwrap();
    far.translation.vector.x += 1.0;
    for (pose, needle) in [(up, "wrist height"), (side, "approach axis"), (far, "wrist distance")] {
        match ik.solve(&pose, None, LimitFilter::Off) {
            Err(Error::Unreachable(msg)) => assert!(msg.contains(needle), "{msg}"),
            other => panic!("expected Unreachable ({needle}), got {other:?}"),
        }
    }
}

#[test]
fn analytic_solver_is_found_by_structure_not_by_name() {
    assert!(matches!(
        Analytic::for_chain(&ttkin::robots::gantry6()),
        Some(Analytic::Gantry6(_))
    ));
    assert!(matches!(
        Analytic::for_chain(&ttkin::robots::arm4()),
        Some(Analytic::Arm4(_))
    ));
    assert!(Analytic::for_chain(&ttkin::robots::ur5()).is_none());
    assert!(Analytic::for_chain(&ttkin::robots::mobile8()).is_none());
    // A gantry read back from its robot file under another name keeps its solver.
    let text = ttkin::description::to_toml(&ttkin::robots::gantry6()).replace("gantry6", "my_gantry");
    let chain = ttkin::description::from_toml_str(&text, "<test>").unwrap();
    assert!(matches!(Analytic::for_chain(&chain), Some(Analytic::Gantry6(_))));
}

#[test]
fn analytic_ik_rejects_nan_targets() {
    let chain = ttkin::robots::gantry6();
    let ik = Analytic::for_chain(&chain).unwrap();
    let mut t = chain.fk(&[0.0; 6]).unwrap();
    t.translation.vector.x = f64::NAN;
    assert!(matches!(
        ik.solve(&t, None, LimitFilter::Off),
        Err(Error::NonFinite { .. })
    ));
}

fn tasks() -> [Task; 3] {
    [Task::Pose, Task::Racket { offset: 0.15 }, Task::Position]
}

#[test]
fn numeric_ik_reaches_random_targets_and_reports_true_errors() {
    for chain in robots() {
        let q0: Vec<f64> = chain.limits().iter().map(|l| 0.5 * (l.lower + l.upper)).collect();
        for task in tasks() {
            let solver = IkSolver {
                task,
                time_budget: None,
                max_restarts: 200,
                ..IkSolver::default()
            };
            let mut solved = 0;
            let configs = random_configs(&chain, 100, 21);
            for q in &configs {
                let target = chain.fk(q).unwrap();
                let r = solver.solve(&chain, &target, &q0).unwrap();
                // The reported errors are the errors of the returned q.
                let (p, o) = measure(&task, &chain.fk(&r.q).unwrap(), &target);
                assert!((p - r.position_error).abs() < 1e-15 && (o - r.orientation_error).abs() < 1e-15);
                assert_eq!(
                    r.success,
                    p <= solver.position_tolerance && (task == Task::Position || o <= solver.orientation_tolerance)
                );
                for (v, l) in r.q.iter().zip(chain.limits()) {
                    assert!(*v >= l.lower && *v <= l.upper, "{}: q outside limits", chain.name());
                }
                solved += r.success as usize;
            }
            // arm4 cannot follow a 6-D pose of another configuration's orientation only when unreachable;
            // targets here are FK of in-limit configurations, so every one is reachable.
            assert!(solved >= 99, "{} {:?}: {solved}/100 solved", chain.name(), task);
        }
    }
}

#[test]
fn numeric_ik_is_deterministic_for_a_seed() {
    let chain = ttkin::robots::mobile8();
    let solver = IkSolver {
        time_budget: None,
        seed: 99,
        ..IkSolver::default()
    };
    for q in random_configs(&chain, 50, 4) {
        let t = chain.fk(&q).unwrap();
        let a = solver.solve(&chain, &t, &ttkin::robots::mobile8_start()).unwrap();
        let b = solver.solve(&chain, &t, &ttkin::robots::mobile8_start()).unwrap();
        assert_eq!(a, b);
    }
}

#[test]
fn numeric_ik_reports_failure_with_its_best_error_for_unreachable_targets() {
    let chain = ttkin::robots::ur5();
    let target = from_xyz_rpy([3.0, 0.0, 0.5], [0.0, 0.0, 0.0]);
    let solver = IkSolver {
        time_budget: None,
        max_restarts: 5,
        ..IkSolver::default()
    };
    let r = solver.solve(&chain, &target, &[0.0; 6]).unwrap();
    assert!(!r.success);
    assert_eq!(r.restarts, 5);
    // The arm reaches about 1 m from its shoulder: the position error stays near 3 − 1 m.
    assert!(r.position_error > 2.0 && r.position_error < 2.5, "{}", r.position_error);
    let (p, _) = measure(&Task::Pose, &chain.fk(&r.q).unwrap(), &target);
    assert_eq!(p, r.position_error);
}

#[test]
fn numeric_ik_rejects_bad_input() {
    let chain = ttkin::robots::ur5();
    let solver = IkSolver::default();
    let t = chain.fk(&[0.1; 6]).unwrap();
    assert!(matches!(solver.solve(&chain, &t, &[0.0; 5]), Err(Error::Shape { .. })));
    assert!(matches!(
        solver.solve(&chain, &t, &[0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0]),
        Err(Error::NonFinite { .. })
    ));
    let mut bad = t;
    bad.translation.vector.y = f64::INFINITY;
    assert!(matches!(
        solver.solve(&chain, &bad, &[0.0; 6]),
        Err(Error::NonFinite { .. })
    ));
    let negative = IkSolver {
        position_tolerance: -1.0,
        ..IkSolver::default()
    };
    assert!(matches!(
        negative.solve(&chain, &t, &[0.0; 6]),
        Err(Error::InvalidArgument { .. })
    ));
    // Non-rigid user matrices are refused before any solver sees them.
    let mut m = t.to_homogeneous();
    m[(0, 0)] *= 1.001;
    assert!(ttkin::transform::isometry_from_matrix("T", &m).is_err());
}

#[test]
fn numeric_ik_batch_matches_single_solves() {
    let chain = ttkin::robots::ur5();
    let solver = IkSolver {
        time_budget: None,
        ..IkSolver::default()
    };
    let configs = random_configs(&chain, 40, 8);
    let targets: Vec<IsometryMatrix3<f64>> = configs.iter().map(|q| chain.fk(q).unwrap()).collect();
    let q0 = vec![vec![0.0, -1.0, 1.0, 0.0, 1.0, 0.0]];
    let batch = solver.solve_batch(&chain, &targets, &q0).unwrap();
    for (i, (t, r)) in targets.iter().zip(&batch).enumerate() {
        let single = IkSolver {
            seed: solver.seed + i as u64,
            ..solver.clone()
        }
        .solve(&chain, t, &q0[0])
        .unwrap();
        assert_eq!(&single, r);
    }
}

#[test]
fn differential_ik_reproduces_the_twist_away_from_singularities() {
    let twist = [0.3, -0.2, 0.5, 1.0, -0.7, 0.4];
    for chain in robots() {
        for q in random_configs(&chain, 300, 17) {
            let r = joint_velocity(&chain, &q, &twist).unwrap();
            if r.singular {
                continue;
            }
            let j = DMatrix::from_iterator(
                6,
                chain.dof(),
                chain.jacobian(&q, JacobianFrame::Base).unwrap().iter().copied(),
            );
            let qd = DVector::from_column_slice(&r.qd);
            let v = DVector::from_column_slice(&twist);
            let res = &j * &qd - &v;
            if chain.dof() >= 6 {
                assert!(res.amax() < 1e-10, "{}: |Jq̇ − V| = {:e}", chain.name(), res.amax());
            } else {
                // Fewer joints than twist components: the least-squares solution, Jᵀ(Jq̇ − V) = 0.
                assert!((j.transpose() * res).amax() < 1e-10, "{}", chain.name());
            }
        }
    }
}

#[test]
fn redundant_chain_gets_the_weighted_least_norm_solution() {
    let chain = ttkin::robots::mobile8();
    let twist = [0.1, 0.2, -0.1, 0.3, 0.0, -0.2];
    for q in random_configs(&chain, 100, 23) {
        let (w, _) = joint_limit_weights(&chain, &q, None).unwrap();
        let r = DifferentialIk::default().solve(&chain, &q, &twist, Some(&w)).unwrap();
        if r.singular {
            continue;
        }
        // q̇ = W⁻¹Jᵀ(JW⁻¹Jᵀ)⁻¹V (seed 000, eq. 20).
        let j = DMatrix::from_iterator(6, 8, chain.jacobian(&q, JacobianFrame::Base).unwrap().iter().copied());
        let winv = DMatrix::from_diagonal(&DVector::from_iterator(8, w.iter().map(|x| 1.0 / x)));
        let m = &j * &winv * j.transpose();
        let expected = &winv * j.transpose() * m.lu().solve(&DVector::from_column_slice(&twist)).unwrap();
        let diff = (expected - DVector::from_column_slice(&r.qd)).amax();
        assert!(
            diff < 1e-8 * (1.0 + r.qd.iter().map(|v| v.abs()).fold(0.0, f64::max)),
            "{diff:e}"
        );
    }
}

#[test]
fn gantry6_jacobian_determinant_is_minus_l3_c4_s45_and_singularities_stay_bounded() {
    let chain = ttkin::robots::gantry6();
    for q in random_configs(&chain, 500, 31) {
        let j = DMatrix::from_iterator(6, 6, chain.jacobian(&q, JacobianFrame::Base).unwrap().iter().copied());
        let expected = -0.30 * q[3].cos() * (q[3] + q[4]).sin();
        assert!(
            (j.determinant() - expected).abs() < 1e-12,
            "{} vs {}",
            j.determinant(),
            expected
        );
    }
    let twist = [0.5, -0.5, 0.5, 2.0, -1.0, 1.5];
    let norm = twist.iter().map(|v| v * v).sum::<f64>().sqrt();
    let settings = DifferentialIk::default();
    for (t4, t5) in [
        (PI / 2.0, 0.3),
        (0.3, -0.3),
        (0.3, -0.3 + 1e-6),
        (PI / 2.0 - 1e-7, 0.2),
        (PI / 2.0, -PI / 2.0),
    ] {
        let q = [0.1, 0.2, 0.3, t4, t5, 0.5];
        let r = settings.solve(&chain, &q, &twist, None).unwrap();
        assert!(r.singular, "θ4 = {t4}, θ5 = {t5}: σ_min = {}", r.sigma_min);
        let bound = norm * (1.0 / settings.epsilon).max(1.0 / (2.0 * r.damping));
        let qd = r.qd.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(
            qd.is_finite() && qd <= bound * (1.0 + 1e-9),
            "θ4 = {t4}, θ5 = {t5}: |q̇| = {qd}, bound {bound}"
        );
    }
}

#[test]
fn joint_limit_gradient_matches_finite_differences() {
    let chain = ttkin::robots::mobile8();
    let h_of = |q: &[f64]| -> f64 {
        chain
            .limits()
            .iter()
            .zip(q)
            .map(|(l, &x)| (l.upper - l.lower).powi(2) / (4.0 * (l.upper - x) * (x - l.lower)))
            .sum()
    };
    for q in random_configs(&chain, 50, 41) {
        let (w, g) = joint_limit_weights(&chain, &q, None).unwrap();
        for i in 0..8 {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += 1e-7;
            qm[i] -= 1e-7;
            let fd = (h_of(&qp) - h_of(&qm)) / 2e-7;
            assert!(
                (fd - g[i]).abs() < 1e-4 * (1.0 + g[i].abs()),
                "joint {i}: {fd} vs {}",
                g[i]
            );
            assert!((w[i] - (1.0 + g[i].abs())).abs() < 1e-12);
        }
        // Moving away from the limits (|∂H/∂q| shrinking) gives weight 1.
        let bigger: Vec<f64> = g.iter().map(|v| 2.0 * v.abs() + 1.0).collect();
        let (w2, _) = joint_limit_weights(&chain, &q, Some(&bigger)).unwrap();
        assert!(w2.iter().all(|v| *v == 1.0));
    }
}

#[test]
fn rotation_log_inverts_the_exponential_from_zero_to_pi() {
    use nalgebra::{Rotation3, Vector3};
    let mut rng = fastrand::Rng::with_seed(5);
    for k in 0..20_000 {
        let axis = Vector3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5).normalize();
        let angle = match k % 4 {
            0 => PI * rng.f64(),
            1 => 1e-9 * rng.f64(),
            2 => PI - 1e-7 * rng.f64(),
            _ => PI - 1e-2 * rng.f64(),
        };
        let r = Rotation3::from_scaled_axis(axis * angle);
        let v = ttkin::task::rotation_log(r.matrix());
        assert!(v.iter().all(|x| x.is_finite()));
        // Compare as rotations (at π the sign of the axis is a matter of convention).
        let back = Rotation3::from_scaled_axis(v);
        let err = (back.matrix() - r.matrix()).amax();
        assert!(err < 1e-12, "angle {angle}: {err:e}");
        assert!((v.norm() - angle).abs() < 1e-12, "angle {angle}: |log| = {}", v.norm());
    }
}

/// `solve_matrices` gives the same branches on the float64 fast path and on the pose path (a
/// looser tolerance or a hint), and the loose path accepts poses rounded to float32.
#[test]
fn solve_matrices_paths_agree_and_float32_needs_its_tolerance() {
    use ttkin::ik::MAX_BRANCHES;
    let chain = ttkin::robots::gantry6();
    let ik = Analytic::for_chain(&chain).unwrap();
    let n = chain.dof();
    let q = chain.mid_range();
    let mut data = Vec::new();
    for k in 0..3 {
        let mut qk = q.clone();
        qk[1] += 0.05 * k as f64;
        let mut m = [0.0; 16];
        ttkin::transform::write_row_major(&chain.fk(&qk).unwrap(), &mut m);
        data.extend_from_slice(&m);
    }
    let run = |data: &[f64], tol: f64, hint: Option<&[f64]>| {
        let mut out = vec![0.0; 3 * MAX_BRANCHES * n];
        let mut counts = vec![0; 3];
        ik.solve_matrices(data, tol, hint, LimitFilter::Off, &mut out, &mut counts)
            .map(|_| (out, counts))
    };
    let (fast, c_fast) = run(&data, ttkin::transform::RIGID_TOLERANCE, None).unwrap();
    let (slow, c_slow) = run(&data, 1e-6, None).unwrap();
    assert_eq!(c_fast, c_slow);
    assert!(c_fast.iter().all(|&c| c > 0));
    for (a, b) in fast.iter().zip(&slow) {
        assert!((a.is_nan() && b.is_nan()) || (a - b).abs() < 1e-12);
    }
    let rounded: Vec<f64> = data.iter().map(|&v| f64::from(v as f32)).collect();
    let (_, c32) = run(&rounded, 16.0 * f64::from(f32::EPSILON), None).unwrap();
    assert!(c32.iter().all(|&c| c > 0));
    assert!(run(&data[..20], 1e-6, None).is_err());
    // the single-pose branches, flat, are the rows of the batch's first pose
    let mut m = [0.0; 16];
    m.copy_from_slice(&data[..16]);
    let t = ttkin::transform::isometry_from_matrix("T", &nalgebra::Matrix4::from_row_slice(&m)).unwrap();
    let sols = ik.solve(&t, None, LimitFilter::Off).unwrap();
    let flat = sols.flat();
    assert_eq!(flat.len(), sols.len() * n);
    assert_eq!(&flat[..], &fast[..sols.len() * n]);
}
