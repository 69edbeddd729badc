//! Forward kinematics and Jacobian: closed forms, finite differences, convention equivalence.

mod common;

use common::*;
use nalgebra::Vector3;
use proptest::prelude::*;
use ttkin::{Chain, Dh, DhConvention, Error, JacobianFrame, Joint};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn jacobian_matches_central_differences(u in prop::collection::vec(0.0..1.0f64, 8)) {
        for chain in robots() {
            let q = config_from_unit(&chain, &u);
            for frame in [JacobianFrame::Base, JacobianFrame::Tool] {
                let j = chain.jacobian(&q, frame).unwrap();
                let jn = numeric_jacobian(&chain, &q, frame);
                let err = (j - jn).abs().max();
                prop_assert!(err < 1e-8, "{} {:?}: |J − J_fd| = {}", chain.name(), frame, err);
            }
        }
    }

    #[test]
    fn gantry6_fk_matches_seed_closed_form(u in prop::collection::vec(0.0..1.0f64, 6)) {
        let chain = ttkin::robots::gantry6();
        let q = config_from_unit(&chain, &u);
        let (l1, l2, l3, l4) = (0.10, 0.05, 0.30, 0.15);
        let (d1, d2, t3, t4, t5) = (q[0], q[1], q[2], q[3], q[4]);
        let (s3, c3, c4, s4) = (t3.sin(), t3.cos(), t4.cos(), t4.sin());
        let (s45, c45) = ((t4 + t5).sin(), (t4 + t5).cos());
        let a = Vector3::new(s3 * s45, -c3 * s45, -c45);
        let p = Vector3::new(
            d2 - l2 * c3 + s3 * (l3 * c4 + l4 * s45),
            -d1 - l2 * s3 - c3 * (l3 * c4 + l4 * s45),
            l1 + l3 * s4 - l4 * c45,
        );
        let t = chain.fk(&q).unwrap();
        prop_assert!((t.rotation.matrix().column(2) - a).abs().max() < 1e-12);
        prop_assert!((t.translation.vector - p).abs().max() < 1e-12);
    }

    #[test]
    fn standard_and_modified_dh_agree(u in prop::collection::vec(0.0..1.0f64, 6)) {
        let std_chain = ttkin::robots::ur5();
        let modified = to_modified(&std_chain);
        let q = config_from_unit(&std_chain, &u);
        prop_assert!(pose_diff(&std_chain.fk(&q).unwrap(), &modified.fk(&q).unwrap()) < 1e-12);
        let d = (std_chain.jacobian(&q, JacobianFrame::Base).unwrap() - modified.jacobian(&q, JacobianFrame::Base).unwrap()).abs().max();
        prop_assert!(d < 1e-12);
    }

    #[test]
    fn last_link_frame_times_tool_is_fk(u in prop::collection::vec(0.0..1.0f64, 8)) {
        for chain in robots() {
            let chain = chain.with_tool(ttkin::transform::from_xyz_rpy([0.01, 0.02, 0.15], [0.1, -0.2, 0.3])).unwrap();
            let q = config_from_unit(&chain, &u);
            let all = chain.fk_all(&q).unwrap();
            prop_assert_eq!(all.len(), chain.dof());
            prop_assert!(pose_diff(&(all[chain.dof() - 1] * chain.tool()), &chain.fk(&q).unwrap()) < 1e-12);
            // Each frame is the previous one times the joint's own transform.
            let mut t = *chain.base();
            for (k, j) in chain.joints().iter().enumerate() {
                t *= j.transform(q[k]);
                prop_assert!(pose_diff(&t, &all[k]) < 1e-12);
            }
        }
    }
}

/// Rewrites a standard-DH chain in the modified convention: row i's (a, α) moves to row i+1,
/// the last one into the tool transform.
fn to_modified(chain: &Chain) -> Chain {
    let mut prev = (0.0, 0.0);
    let mut joints = Vec::new();
    for j in chain.joints() {
        let ttkin::Geometry::Dh(DhConvention::Standard, dh) = j.geometry() else {
            panic!("standard DH expected")
        };
        let row = Dh {
            a: prev.0,
            alpha: prev.1,
            d: dh.d,
            theta: dh.theta,
        };
        joints.push(Joint::new(j.name(), j.kind(), ttkin::Geometry::Dh(DhConvention::Modified, row)).unwrap());
        prev = (dh.a, dh.alpha);
    }
    let tool = ttkin::transform::trans(prev.0, 0.0, 0.0) * ttkin::transform::rot_x(prev.1) * chain.tool();
    Chain::new("modified", joints, *chain.base(), tool).unwrap()
}

#[test]
fn gantry6_determinant_matches_seed() {
    // det J = −L3·c4·s45 (seeds README), for the 6×6 geometric Jacobian at the tool point.
    let chain = ttkin::robots::gantry6();
    for q in [[0.1, -0.2, 0.3, 0.4, 0.5, 0.6], [0.0, 0.0, -1.0, 1.2, -0.3, 2.0]] {
        let j = chain.jacobian(&q, JacobianFrame::Base).unwrap();
        let det = nalgebra::Matrix6::from_iterator(j.iter().copied()).determinant();
        let expected = -0.30 * q[3].cos() * (q[3] + q[4]).sin();
        assert!((det.abs() - expected.abs()).abs() < 1e-12, "det {det} vs {expected}");
    }
}

#[test]
fn fk_evaluates_outside_limits() {
    let chain = ttkin::robots::mobile8();
    let q = [5.0, 10.0, -10.0, 7.0, 100.0, -50.0, 3.0, 4.0];
    assert!(chain.fk(&q).is_ok());
    assert!(chain.jacobian(&q, JacobianFrame::Tool).is_ok());
}

#[test]
fn bad_joint_vectors_are_typed_errors() {
    let chain = ttkin::robots::gantry6();
    assert!(matches!(chain.fk(&[0.0; 5]), Err(Error::Shape { .. })));
    let msg = chain.fk(&[0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0]).unwrap_err().to_string();
    assert!(msg.contains("element 2") && msg.contains("NaN"), "{msg}");
    assert!(matches!(
        chain.jacobian(&[f64::INFINITY; 6], JacobianFrame::Base),
        Err(Error::NonFinite { .. })
    ));
    let mut out = vec![0.0; 16];
    assert!(chain.fk_batch(&[0.0; 7], &mut out).is_err());
}

#[test]
fn batches_equal_single_calls() {
    for chain in robots() {
        let n = chain.dof();
        let count = 1000;
        let qs: Vec<f64> = (0..count * n)
            .map(|k| ((k * 7919) % 1000) as f64 / 300.0 - 1.5)
            .collect();
        let mut fk = vec![0.0; count * 16];
        let mut jac = vec![0.0; count * 6 * n];
        let mut all = vec![0.0; count * n * 16];
        chain.fk_batch(&qs, &mut fk).unwrap();
        chain.jacobian_batch(&qs, JacobianFrame::Base, &mut jac).unwrap();
        chain.fk_all_batch(&qs, &mut all).unwrap();
        for k in [0, 1, 255, 256, 999] {
            let q = &qs[k * n..(k + 1) * n];
            let t = chain.fk(q).unwrap().to_homogeneous();
            let j = chain.jacobian(q, JacobianFrame::Base).unwrap();
            for r in 0..4 {
                for c in 0..4 {
                    assert_eq!(fk[k * 16 + r * 4 + c], t[(r, c)]);
                }
            }
            for r in 0..6 {
                for c in 0..n {
                    assert_eq!(jac[k * 6 * n + r * n + c], j[(r, c)]);
                }
            }
            let last = chain.fk_all(q).unwrap()[n - 1].to_homogeneous();
            assert_eq!(all[(k * n + n - 1) * 16 + 3], last[(0, 3)]);
        }
    }
}

#[test]
fn prismatic_column_is_its_axis() {
    let chain = ttkin::robots::mobile8();
    let q = ttkin::robots::mobile8_start();
    let j = chain.jacobian(&q, JacobianFrame::Base).unwrap();
    // Joint 1 of mobile8 moves along the base z axis (α0 = 0, θ1 = 90°): column [0 0 1 0 0 0].
    let expected = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
    for r in 0..6 {
        assert!((j[(r, 0)] - expected[r]).abs() < 1e-15);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    #[test]
    fn task_jacobians_match_finite_differences_of_the_residual(u in prop::collection::vec(0.0..1.0f64, 8), v in prop::collection::vec(0.0..1.0f64, 8)) {
        use ttkin::task::Task;
        for chain in robots() {
            let q = config_from_unit(&chain, &u);
            let target = chain.fk(&config_from_unit(&chain, &v)).unwrap();
            for task in [Task::Pose, Task::Position, Task::Racket { offset: 0.15 }] {
                let t = chain.fk(&q).unwrap();
                let j = chain.jacobian(&q, JacobianFrame::Base).unwrap();
                let je = task.jacobian(&j, &t, &target);
                let h = 1e-6;
                for i in 0..chain.dof() {
                    let (mut qp, mut qm) = (q.clone(), q.clone());
                    qp[i] += h;
                    qm[i] -= h;
                    let de = (task.error(&chain.fk(&qp).unwrap(), &target) - task.error(&chain.fk(&qm).unwrap(), &target)) / (2.0 * h);
                    // ė = −J_e q̇; the pose task's rotation rows are exact only near the target.
                    let rows = if task == Task::Pose { 3 } else { task.dim() };
                    for r in 0..rows {
                        prop_assert!((de[r] + je[(r, i)]).abs() < 1e-6, "{} {:?} row {} col {}: {} vs {}", chain.name(), task, r, i, -de[r], je[(r, i)]);
                    }
                }
            }
        }
    }
}

#[test]
fn racket_pose_reproduces_its_coordinates() {
    let x = [0.4, 0.8, 0.3, 1.1, -2.0];
    let t = ttkin::task::racket_pose(&x, 0.15, &Vector3::z());
    let back = ttkin::task::racket_coordinates(&t, 0.15);
    for k in 0..5 {
        assert!((back[k] - x[k]).abs() < 1e-12);
    }
    let task = ttkin::task::Task::Racket { offset: 0.15 };
    assert!(task.error(&t, &t).norm() < 1e-15);
}

/// The per-joint tables the bindings hand over: names, type names and letters, position limits
/// as (n, 2), and joint types read back from their names or letters.
#[test]
fn joint_tables_follow_the_joints() {
    let chain = ttkin::robots::gantry6();
    let n = chain.dof();
    let kinds: String = chain.joints().iter().map(|j| j.kind().letter()).collect();
    assert_eq!(chain.joint_letters(), kinds);
    assert_eq!(chain.joint_letters().len(), n);
    let letters = ttkin::JointType::from_letters(&chain.joint_letters()).unwrap();
    assert_eq!(
        ttkin::JointType::from_names(&chain.joint_type_names()).unwrap(),
        letters
    );
    assert_eq!(chain.joint_type_names()[0], chain.joints()[0].kind().name());
    assert!(ttkin::JointType::from_names(&["revolute", "hinge"]).is_err());
    let names = chain.joint_names();
    assert_eq!(names.len(), n);
    assert_eq!(names[2], chain.joints()[2].name());
    let table = chain.position_limit_table();
    for (k, l) in chain.limits().iter().enumerate() {
        assert_eq!((table[2 * k], table[2 * k + 1]), (l.lower, l.upper));
    }
}
