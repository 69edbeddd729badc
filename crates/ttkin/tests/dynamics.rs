//! Dynamics: the identities that tie RNEA, CRBA and forward dynamics together, energy, finite
//! differences of the kinetic and potential energy, the tool wrench, file round trips and bad input.
//! (The comparison with Pinocchio is in the Python tests, tests/test_dynamics.py.)

mod common;

use common::*;
use nalgebra::{DMatrix, DVector, Rotation3, Vector3};
use proptest::prelude::*;
use ttkin::dynamics::EARTH_GRAVITY;
use ttkin::{Chain, Drive, Dynamics, DynamicsData, Error, Inertial, JacobianFrame, Wrench};

/// A physical inertial from eight numbers in [0, 1): mass 0.1–5 kg, com within ±0.2 m, principal
/// moments that satisfy the triangle inequality, random principal axes.
fn random_inertial(u: &[f64]) -> Inertial {
    let mass = 0.1 + 4.9 * u[0];
    let com = [0.4 * u[1] - 0.2, 0.4 * u[2] - 0.2, 0.4 * u[3] - 0.2];
    // Principal moments from positive "second moments" σ: I1 = σ2 + σ3 etc. is always triangle-valid.
    let s = [1e-3 + 0.05 * u[4], 1e-3 + 0.05 * u[5], 1e-3 + 0.05 * u[6]];
    let diag = nalgebra::Matrix3::from_diagonal(&Vector3::new(s[1] + s[2], s[0] + s[2], s[0] + s[1]));
    let r = Rotation3::from_euler_angles(6.0 * u[7], 3.0 * u[4] + 1.0, 5.0 * u[5]);
    Inertial {
        mass,
        com: com.into(),
        inertia: r.matrix() * diag * r.matrix().transpose(),
    }
}

/// The chain with random inertias (and random drives) from `u` (10 numbers per link).
fn randomised(chain: &Chain, u: &[f64]) -> Chain {
    let joints = chain
        .joints()
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let w = &u[10 * i..10 * i + 10];
            let drive = Drive {
                gear_ratio: 1.0 + 100.0 * w[8],
                rotor_inertia: 1e-5 * w[9],
                viscous: w[8],
                coulomb: w[9],
                torque_constant: Some(0.05),
                ..Drive::geared(1.0)
            };
            j.clone()
                .with_inertial(random_inertial(w))
                .unwrap()
                .with_drive(drive)
                .unwrap()
        })
        .collect();
    Chain::new(chain.name(), joints, *chain.base(), *chain.tool()).unwrap()
}

fn state(chain: &Chain, u: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = chain.dof();
    let q = config_from_unit(chain, &u[..n]);
    let qd = u[n..2 * n].iter().map(|x| 4.0 * x - 2.0).collect();
    let qdd = u[2 * n..3 * n].iter().map(|x| 10.0 * x - 5.0).collect();
    (q, qd, qdd)
}

fn models(u: &[f64]) -> Vec<Dynamics> {
    robots()
        .iter()
        .flat_map(|c| [c.clone(), randomised(c, u)])
        .map(|c| Dynamics::new(&c).unwrap())
        .collect()
}

/// `n` numbers in [0, 1), the proptests' raw draws.
fn unit(n: usize) -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec(0.0..1.0f64, n)
}

/// One model of `models(u)` with a fresh workspace and the joint state from `s` (rad, rad/s, rad/s²).
struct Case {
    dy: Dynamics,
    d: DynamicsData,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
}

/// Every model of `models(u)` at the state `state(chain, s)`.
fn cases(u: &[f64], s: &[f64]) -> Vec<Case> {
    models(u)
        .into_iter()
        .map(|dy| {
            let d = DynamicsData::new(&dy);
            let (q, qd, qdd) = state(dy.chain(), s);
            Case { dy, d, q, qd, qdd }
        })
        .collect()
}

/// Scale of a vector for relative tolerances.
fn scale(v: &DVector<f64>) -> f64 {
    1.0 + v.amax()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn rnea_equals_mass_matrix_times_qdd_plus_nonlinear_effects(
        u in unit(80), s in unit(24)
    ) {
        for Case { dy, mut d, q, qd, qdd } in cases(&u, &s) {
            let tau = dy.rnea(&mut d, &q, &qd, &qdd, &EARTH_GRAVITY, None).unwrap().clone();
            let h = dy.nonlinear_effects(&mut d, &q, &qd, &EARTH_GRAVITY).unwrap().clone();
            let c = dy.coriolis(&mut d, &q, &qd).unwrap().clone();
            let g = dy.gravity(&mut d, &q, &EARTH_GRAVITY).unwrap().clone();
            let m = dy.mass_matrix(&mut d, &q).unwrap().clone();
            let rhs = &m * DVector::from_column_slice(&qdd) + &h;
            prop_assert!((&tau - &rhs).amax() < 1e-10 * scale(&tau), "{}: τ − (Mq̈ + h) = {:e}", dy.chain().name(), (&tau - &rhs).amax());
            prop_assert!((&h - (&c + &g)).amax() < 1e-10 * scale(&h));
        }
    }

    #[test]
    fn mass_matrix_is_symmetric_positive_definite(
        u in unit(80), s in unit(24)
    ) {
        for Case { dy, mut d, q, .. } in cases(&u, &s) {
            let m = dy.mass_matrix(&mut d, &q).unwrap().clone();
            prop_assert_eq!(&m, &m.transpose());
            let eig = m.clone().symmetric_eigenvalues();
            prop_assert!(eig.min() > 0.0, "{}: eigenvalues {}", dy.chain().name(), eig);
            // The armature sits on the diagonal on top of the rigid-body part.
            let rigid = {
                let joints = dy.chain().joints().iter().map(|j| {
                    let mut free = *j.drive().unwrap();
                    free.rotor_inertia = 0.0;
                    j.clone().with_drive(free).unwrap()
                }).collect();
                let c = Chain::new(dy.chain().name(), joints, *dy.chain().base(), *dy.chain().tool()).unwrap();
                Dynamics::new(&c).unwrap()
            };
            let mut dr = DynamicsData::new(&rigid);
            let mr = rigid.mass_matrix(&mut dr, &q).unwrap();
            let arm = DMatrix::from_diagonal(&DVector::from_column_slice(dy.armature()));
            prop_assert!((&m - mr - arm).amax() < 1e-12 * (1.0 + m.amax()));
        }
    }

    #[test]
    fn forward_dynamics_inverts_rnea(
        u in unit(80), s in unit(24),
        w in prop::collection::vec(-5.0..5.0f64, 6)
    ) {
        let wrench = Wrench { force: Vector3::new(w[0], w[1], w[2]), torque: Vector3::new(w[3], w[4], w[5]) };
        for Case { dy, mut d, q, qd, qdd } in cases(&u, &s) {
            let tau = dy.rnea(&mut d, &q, &qd, &qdd, &EARTH_GRAVITY, Some(&wrench)).unwrap().clone();
            let acc = dy.forward_dynamics(&mut d, &q, &qd, tau.as_slice(), &EARTH_GRAVITY, Some(&wrench)).unwrap();
            let err = (acc - DVector::from_column_slice(&qdd)).amax();
            prop_assert!(err < 1e-8, "{}: |FD(RNEA(q̈)) − q̈| = {:e}", dy.chain().name(), err);
        }
    }

    #[test]
    fn tool_wrench_maps_through_the_transposed_tool_jacobian(
        u in unit(80), s in unit(24),
        w in prop::collection::vec(-5.0..5.0f64, 6)
    ) {
        let wrench = Wrench { force: Vector3::new(w[0], w[1], w[2]), torque: Vector3::new(w[3], w[4], w[5]) };
        for dy in models(&u) {
            let chain = dy.chain().with_tool(ttkin::transform::from_xyz_rpy([0.01, -0.02, 0.12], [0.3, -0.1, 0.7])).unwrap();
            let dy = Dynamics::new(&chain).unwrap();
            let mut d = DynamicsData::new(&dy);
            let (q, qd, qdd) = state(&chain, &s);
            let with = dy.rnea(&mut d, &q, &qd, &qdd, &EARTH_GRAVITY, Some(&wrench)).unwrap().clone();
            let without = dy.rnea(&mut d, &q, &qd, &qdd, &EARTH_GRAVITY, None).unwrap().clone();
            let j = chain.jacobian(&q, JacobianFrame::Tool).unwrap();
            let f = nalgebra::Vector6::new(w[0], w[1], w[2], w[3], w[4], w[5]);
            let expected = -(j.transpose() * f);
            prop_assert!((with - without - expected).amax() < 1e-10);
        }
    }

    #[test]
    fn kinetic_energy_rate_is_power_of_non_gravity_torques(
        u in unit(80), s in unit(24)
    ) {
        // Along q(t) = q + t·q̇ + t²/2·q̈: dT/dt = q̇ᵀ(τ − g(q)) with τ = RNEA(q, q̇, q̈).
        let h = 1e-5;
        for Case { dy, mut d, q, qd, qdd } in cases(&u, &s) {
            let at = |t: f64| -> (Vec<f64>, Vec<f64>) {
                (
                    q.iter().zip(&qd).zip(&qdd).map(|((q, v), a)| q + t * v + 0.5 * t * t * a).collect(),
                    qd.iter().zip(&qdd).map(|(v, a)| v + t * a).collect(),
                )
            };
            let (qp, vp) = at(h);
            let (qm, vm) = at(-h);
            let rate = (dy.kinetic_energy(&mut d, &qp, &vp).unwrap() - dy.kinetic_energy(&mut d, &qm, &vm).unwrap()) / (2.0 * h);
            let tau = dy.rnea(&mut d, &q, &qd, &qdd, &EARTH_GRAVITY, None).unwrap().clone();
            let g = dy.gravity(&mut d, &q, &EARTH_GRAVITY).unwrap().clone();
            let power = DVector::from_column_slice(&qd).dot(&(tau - g));
            prop_assert!((rate - power).abs() < 1e-5 * (1.0 + power.abs()), "{}: dT/dt {} vs q̇ᵀ(τ − g) {}", dy.chain().name(), rate, power);
            // And T = ½ q̇ᵀ M q̇.
            let m = dy.mass_matrix(&mut d, &q).unwrap().clone();
            let v = DVector::from_column_slice(&qd);
            let t = dy.kinetic_energy(&mut d, &q, &qd).unwrap();
            prop_assert!((t - 0.5 * v.dot(&(&m * &v))).abs() < 1e-10 * (1.0 + t));
        }
    }

    #[test]
    fn gravity_torques_are_the_gradient_of_the_potential_energy(
        u in unit(80), s in unit(24),
        gdir in prop::collection::vec(-10.0..10.0f64, 3)
    ) {
        let grav = [gdir[0], gdir[1], gdir[2]];
        let h = 1e-6;
        for Case { dy, mut d, q, .. } in cases(&u, &s) {
            let g = dy.gravity(&mut d, &q, &grav).unwrap().clone();
            for i in 0..q.len() {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[i] += h;
                qm[i] -= h;
                let dv = (dy.potential_energy(&qp, &grav).unwrap() - dy.potential_energy(&qm, &grav).unwrap()) / (2.0 * h);
                prop_assert!((dv - g[i]).abs() < 1e-6 * (1.0 + g.amax()), "{} joint {}: ∂V/∂q {} vs g {}", dy.chain().name(), i, dv, g[i]);
            }
        }
    }

    #[test]
    fn batch_calls_match_single_calls(u in unit(80), s in unit(24 * 5)) {
        for dy in models(&u) {
            let n = dy.dof();
            let mut d = DynamicsData::new(&dy);
            let (mut qs, mut qds, mut qdds) = (vec![], vec![], vec![]);
            for k in 0..5 {
                let (q, qd, qdd) = state(dy.chain(), &s[24 * k..]);
                qs.extend(q);
                qds.extend(qd);
                qdds.extend(qdd);
            }
            let mut tau = vec![0.0; 5 * n];
            dy.rnea_batch(&qs, &qds, &qdds, &EARTH_GRAVITY, None, &mut tau).unwrap();
            let mut mass = vec![0.0; 5 * n * n];
            dy.mass_matrix_batch(&qs, &mut mass).unwrap();
            let mut acc = vec![0.0; 5 * n];
            dy.forward_dynamics_batch(&qs, &qds, &tau, &EARTH_GRAVITY, None, &mut acc).unwrap();
            for k in 0..5 {
                let r = k * n..(k + 1) * n;
                let t1 = dy.rnea(&mut d, &qs[r.clone()], &qds[r.clone()], &qdds[r.clone()], &EARTH_GRAVITY, None).unwrap();
                prop_assert_eq!(t1.as_slice(), &tau[r.clone()]);
                let m1 = dy.mass_matrix(&mut d, &qs[r.clone()]).unwrap();
                prop_assert_eq!(m1.as_slice(), &mass[k * n * n..(k + 1) * n * n]);
                let err = acc[r.clone()].iter().zip(&qdds[r]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                prop_assert!(err < 1e-8);
            }
        }
    }
}

/// Total energy along a torque-free, frictionless simulation from the seed-000 start with a
/// kick; returns the largest |E(t) − E(0)| over `duration` s.
fn energy_drift(dy: &Dynamics, q0: &[f64], qd0: &[f64], dt: f64, duration: f64) -> (f64, f64) {
    let n = dy.dof();
    let steps = (duration / dt).round() as usize;
    let taus = vec![0.0; steps * n];
    let (qs, qds) = dy.simulate(q0, qd0, &taus, dt, &EARTH_GRAVITY, false).unwrap();
    let mut d = DynamicsData::new(dy);
    let mut energy = |k: usize| {
        let (q, qd) = (&qs[k * n..(k + 1) * n], &qds[k * n..(k + 1) * n]);
        dy.kinetic_energy(&mut d, q, qd).unwrap() + dy.potential_energy(q, &EARTH_GRAVITY).unwrap()
    };
    let e0 = energy(0);
    let drift = (0..=steps).map(|k| (energy(k) - e0).abs()).fold(0.0, f64::max);
    (drift, e0)
}

#[test]
fn energy_is_conserved_to_first_order_in_the_step_without_torque_or_friction() {
    for chain in robots() {
        let dy = Dynamics::new(&chain).unwrap();
        let n = dy.dof();
        let q0 = config_from_unit(&chain, &vec![0.4; n]);
        let qd0: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { 0.8 } else { -0.6 }).collect();
        let (e1, e0) = energy_drift(&dy, &q0, &qd0, 2e-4, 0.5);
        let (e2, _) = energy_drift(&dy, &q0, &qd0, 1e-4, 0.5);
        let kinetic = dy.kinetic_energy(&mut DynamicsData::new(&dy), &q0, &qd0).unwrap();
        // Semi-implicit Euler: the energy error is O(dt) and bounded (no drift): halving the step
        // halves it, and it stays a small fraction of the energy in motion.
        assert!(
            e2 < 0.6 * e1,
            "{}: drift {e1:e} at dt = 2e-4, {e2:e} at dt = 1e-4",
            chain.name()
        );
        assert!(
            e2 > 0.4 * e1,
            "{}: drift {e1:e} at dt = 2e-4, {e2:e} at dt = 1e-4",
            chain.name()
        );
        assert!(e1 < 0.05 * (kinetic + e0.abs()), "{}: drift {e1:e} J", chain.name());
    }
}

#[test]
fn viscous_friction_dissipates_energy() {
    let chain = ttkin::robots::ur5();
    let joints = chain
        .joints()
        .iter()
        .map(|j| {
            let mut d = *j.drive().unwrap();
            d.coulomb = 0.0;
            d.viscous = 2.0;
            j.clone().with_drive(d).unwrap()
        })
        .collect();
    let chain = Chain::new("ur5", joints, *chain.base(), *chain.tool()).unwrap();
    let dy = Dynamics::new(&chain).unwrap();
    let n = dy.dof();
    let dt = 1e-3;
    let (qs, qds) = dy
        .simulate(&[0.0; 6], &[1.0; 6], &vec![0.0; 500 * n], dt, &[0.0; 3], true)
        .unwrap();
    let mut d = DynamicsData::new(&dy);
    // Without gravity the energy is all kinetic and dE/dt = −b·|q̇|² < 0: it falls at every
    // sampled instant and by a large fraction over 0.5 s (time constant M/b of the order of 0.3 s).
    let t: Vec<f64> = (0..=10)
        .map(|k| {
            dy.kinetic_energy(
                &mut d,
                &qs[50 * k * n..(50 * k + 1) * n],
                &qds[50 * k * n..(50 * k + 1) * n],
            )
            .unwrap()
        })
        .collect();
    assert!(t.windows(2).all(|w| w[1] < w[0]), "kinetic energy {t:?}");
    assert!(t[10] < 0.8 * t[0], "kinetic energy {t:?}");
}

#[test]
fn torque_profile_reports_friction_motor_side_current_and_effort_violations() {
    let chain = ttkin::robots::mobile8();
    let dy = Dynamics::new(&chain).unwrap();
    let n = dy.dof();
    let q: Vec<f64> = ttkin::robots::mobile8_start().repeat(2);
    let mut qd = vec![0.3; 2 * n];
    qd[n..].fill(-0.2);
    let mut qdd = vec![0.0; 2 * n];
    qdd[n + 3] = 500.0; // far beyond what joint 4 can deliver
    let p = dy.torque_profile(&q, &qd, &qdd, &EARTH_GRAVITY, None).unwrap();
    let mut rigid = vec![0.0; 2 * n];
    dy.rnea_batch(&q, &qd, &qdd, &EARTH_GRAVITY, None, &mut rigid).unwrap();
    for k in 0..2 * n {
        let drive = chain.joints()[k % n].drive().unwrap();
        assert!((p.joint[k] - rigid[k] - drive.friction(qd[k])).abs() < 1e-12);
        assert!((p.motor[k] - p.joint[k] / drive.gear_ratio).abs() < 1e-12);
        assert!((p.current[k] - p.motor[k] / drive.torque_constant.unwrap()).abs() < 1e-12);
    }
    assert!(!p.within_limits());
    assert!(p.violations.iter().any(|v| v.sample == 1 && v.joint == 3));
    assert!(p.violations.iter().all(|v| v.torque.abs() > v.limit));
    assert_eq!(p.peak.len(), n);
    let still = dy
        .torque_profile(&q[..n], &[0.0; 8], &[0.0; 8], &EARTH_GRAVITY, None)
        .unwrap();
    assert!(still.within_limits(), "holding the start pose: {:?}", still.violations);
}

#[test]
fn built_in_gravity_torques_hold_within_effort_limits() {
    for chain in robots() {
        let dy = Dynamics::new(&chain).unwrap();
        let mut d = DynamicsData::new(&dy);
        // The robot's own gravity (mobile8: base x up, robots::MOBILE8_GRAVITY).
        let gravity = chain.gravity();
        for x in [0.1, 0.5, 0.9] {
            let q = config_from_unit(&chain, &vec![x; chain.dof()]);
            let g = dy.gravity(&mut d, &q, &gravity).unwrap();
            for (i, l) in chain.limits().iter().enumerate() {
                assert!(
                    g[i].abs() < l.effort.unwrap(),
                    "{} joint {i}: |g| = {} N·m",
                    chain.name(),
                    g[i]
                );
            }
        }
    }
}

#[test]
fn urdf_round_trip_keeps_the_rigid_body_dynamics_and_friction() {
    for chain in robots() {
        let text = ttkin::urdf::to_urdf_string(&chain);
        let back = ttkin::urdf::from_urdf_str(&text, "base_link", "tool").unwrap();
        let (a, b) = (Dynamics::new(&chain).unwrap(), Dynamics::new(&back).unwrap());
        let (mut da, mut db) = (DynamicsData::new(&a), DynamicsData::new(&b));
        let n = chain.dof();
        let q = config_from_unit(&chain, &vec![0.3; n]);
        let qd = vec![0.7; n];
        // q̈ = 0: the armature (not carried by URDF) plays no part.
        let ta = a.rnea(&mut da, &q, &qd, &vec![0.0; n], &EARTH_GRAVITY, None).unwrap();
        let tb = b.rnea(&mut db, &q, &qd, &vec![0.0; n], &EARTH_GRAVITY, None).unwrap();
        assert!((ta - tb).amax() < 1e-9, "{}", chain.name());
        assert_eq!(a.friction(&qd).unwrap(), b.friction(&qd).unwrap());
    }
}

#[test]
fn robot_file_round_trip_keeps_inertias_and_drives() {
    for chain in robots() {
        let text = ttkin::description::to_toml(&chain);
        let back = ttkin::description::from_toml_str(&text, "<test>").unwrap();
        for (a, b) in chain.joints().iter().zip(back.joints()) {
            assert_eq!(a.drive(), b.drive());
            let (ia, ib) = (a.inertial().unwrap(), b.inertial().unwrap());
            assert!((ia.inertia - ib.inertia).amax() < 1e-15 && (ia.com - ib.com).amax() < 1e-15);
        }
    }
    let text = r#"
name = "one"
convention = "standard"
[[joint]]
name = "j"
type = "revolute"
dh = { a = 0.3 }
inertial = { mass = 1.0, com = [0.1, 0, 0], inertia = [1e-3, 1e-3, 1e-3, 0, 0, 0] }
drive = { gear_ratio = 50, rotor_inertia = 1e-5, viscous = 0.1, coulomb = 0.2, torque_constant = 0.04 }
"#;
    let c = ttkin::description::from_toml_str(text, "<test>").unwrap();
    let d = c.joints()[0].drive().unwrap();
    assert!((d.armature() - 2500.0 * 1e-5).abs() < 1e-15);
    let bad = text.replace("viscous = 0.1", "viscos = 0.1");
    assert!(ttkin::description::from_toml_str(&bad, "<test>").is_err());
}

#[test]
fn missing_inertia_is_an_error_naming_the_link() {
    let chain = ttkin::robots::arm4();
    let mut joints = chain.joints().to_vec();
    joints[2] = ttkin::Joint::new("theta3", joints[2].kind(), joints[2].geometry().clone()).unwrap();
    let bare = Chain::new("arm4", joints, *chain.base(), *chain.tool()).unwrap();
    let err = Dynamics::new(&bare).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, Error::Model(_)));
    assert!(
        msg.contains("'theta3'") && msg.contains("link3") && msg.contains("no inertial"),
        "{msg}"
    );
}

#[test]
fn bad_inertias_and_drives_are_rejected() {
    let j = ttkin::robots::arm4().joints()[0].clone();
    let broken_triangle = Inertial::new(1.0, [0.0; 3], [1.0, 0.1, 0.1, 0.0, 0.0, 0.0]);
    assert!(j
        .clone()
        .with_inertial(broken_triangle)
        .unwrap_err()
        .to_string()
        .contains("triangle"));
    let not_pd = Inertial::new(1.0, [0.0; 3], [1.0, 1.0, -0.1, 0.0, 0.0, 0.0]);
    assert!(j
        .clone()
        .with_inertial(not_pd)
        .unwrap_err()
        .to_string()
        .contains("positive definite"));
    let nan = Inertial::new(f64::NAN, [0.0; 3], [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    assert!(matches!(j.clone().with_inertial(nan), Err(Error::NonFinite { .. })));
    assert!(j.clone().with_drive(Drive::geared(0.0)).is_err());
    assert!(j
        .clone()
        .with_drive(Drive {
            viscous: -1.0,
            ..Drive::geared(10.0)
        })
        .is_err());
    assert!(j
        .clone()
        .with_drive(Drive {
            torque_constant: Some(0.0),
            ..Drive::geared(10.0)
        })
        .is_err());
    assert!(j
        .with_drive(Drive {
            rotor_inertia: f64::NAN,
            ..Drive::geared(10.0)
        })
        .is_err());
}

#[test]
fn bad_arguments_are_errors_not_panics() {
    let dy = Dynamics::new(&ttkin::robots::ur5()).unwrap();
    let mut d = DynamicsData::new(&dy);
    let z = [0.0; 6];
    assert!(matches!(
        dy.rnea(&mut d, &[0.0; 5], &z, &z, &EARTH_GRAVITY, None),
        Err(Error::Shape { .. })
    ));
    let mut nan = z;
    nan[2] = f64::NAN;
    assert!(matches!(
        dy.rnea(&mut d, &z, &nan, &z, &EARTH_GRAVITY, None),
        Err(Error::NonFinite { .. })
    ));
    assert!(matches!(
        dy.gravity(&mut d, &z, &[0.0, f64::INFINITY, 0.0]),
        Err(Error::NonFinite { .. })
    ));
    assert!(dy.forward_dynamics(&mut d, &z, &z, &nan, &EARTH_GRAVITY, None).is_err());
    let w = Wrench {
        force: Vector3::new(f64::NAN, 0.0, 0.0),
        torque: Vector3::zeros(),
    };
    assert!(dy.rnea(&mut d, &z, &z, &z, &EARTH_GRAVITY, Some(&w)).is_err());
    // a non-finite wrench is an error wherever a wrench goes in, never a NaN result
    let nan_wrench = |r: ttkin::Result<()>| matches!(r, Err(Error::NonFinite { ref what, .. }) if what == "wrench");
    assert!(nan_wrench(
        dy.forward_dynamics(&mut d, &z, &z, &z, &EARTH_GRAVITY, Some(&w))
            .map(|_| ())
    ));
    type Batch = fn(&Dynamics, &[f64], &[f64], &[f64], &[f64; 3], Option<&Wrench>, &mut [f64]) -> ttkin::Result<()>;
    let batches: [(&str, Batch); 3] = [
        ("rnea_batch", Dynamics::rnea_batch),
        ("inverse_dynamics_batch", Dynamics::inverse_dynamics_batch),
        ("forward_dynamics_batch", Dynamics::forward_dynamics_batch),
    ];
    for (name, batch) in batches {
        let (x, mut out) = ([0.0; 12], [0.0; 12]);
        assert!(
            nan_wrench(batch(&dy, &x, &x, &x, &EARTH_GRAVITY, Some(&w), &mut out)),
            "{name}"
        );
    }
    let (mut q, mut qd) = (z, z);
    assert!(dy
        .step(&mut d, &mut q, &mut qd, &z, 0.0, &EARTH_GRAVITY, false)
        .is_err());
    assert!(dy
        .step(&mut d, &mut q, &mut qd, &z, f64::NAN, &EARTH_GRAVITY, false)
        .is_err());
    let other = Dynamics::new(&ttkin::robots::arm4()).unwrap();
    let mut small = DynamicsData::new(&other);
    assert!(matches!(dy.mass_matrix(&mut small, &z), Err(Error::Shape { .. })));
    let mut out = vec![0.0; 12];
    assert!(dy
        .rnea_batch(&[0.0; 12], &[0.0; 12], &[0.0; 6], &EARTH_GRAVITY, None, &mut out)
        .is_err());
    assert!(dy
        .rnea_batch(&[0.0; 11], &[0.0; 11], &[0.0; 11], &EARTH_GRAVITY, None, &mut out)
        .is_err());
    assert!(dy.simulate(&z, &z, &[0.0; 7], 1e-3, &EARTH_GRAVITY, false).is_err());
}

#[test]
fn a_hanging_pendulum_matches_its_closed_form() {
    // One revolute joint about the base y axis holding a 2 kg point-like ball 0.5 m away along x:
    // τ = (m·l² + I_c + armature)·q̈ + m·g·l·cos q.
    let m = 2.0;
    let l = 0.5;
    let ic = 1e-4;
    let joint = ttkin::Joint::revolute(
        "hinge",
        ttkin::DhConvention::Modified,
        ttkin::Dh {
            a: 0.0,
            alpha: std::f64::consts::FRAC_PI_2,
            d: 0.0,
            theta: 0.0,
        },
    )
    .unwrap()
    .with_inertial(Inertial::new(m, [l, 0.0, 0.0], [ic, ic, ic, 0.0, 0.0, 0.0]))
    .unwrap()
    .with_drive(Drive {
        rotor_inertia: 1e-4,
        ..Drive::geared(10.0)
    })
    .unwrap();
    let chain = Chain::new(
        "pendulum",
        vec![joint],
        nalgebra::IsometryMatrix3::identity(),
        nalgebra::IsometryMatrix3::identity(),
    )
    .unwrap();
    let dy = Dynamics::new(&chain).unwrap();
    let mut d = DynamicsData::new(&dy);
    for (q, qdd) in [(0.0, 0.0), (0.7, 3.0), (-2.0, -1.5)] {
        let tau = dy.rnea(&mut d, &[q], &[1.3], &[qdd], &EARTH_GRAVITY, None).unwrap()[0];
        let expected = (m * l * l + ic + 0.01) * qdd + m * 9.81 * l * f64::cos(q);
        assert!((tau - expected).abs() < 1e-12, "q = {q}: {tau} vs {expected}");
    }
}
