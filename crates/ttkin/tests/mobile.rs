//! Mobile manipulation: differential drive, whole-body Jacobian, weighted least norm, CLIK.
#![allow(clippy::needless_range_loop)]

mod common;

use common::config_from_unit;
#[path = "support/seed000.rs"]
mod seed000;
use nalgebra::{IsometryMatrix3, Matrix6xX, Translation3, Vector3};
use proptest::prelude::*;
use ttkin::clik::{track, ClikOptions, ClikStatus, TaskTrajectory};
use ttkin::diffdrive::{arc_step, DiffDrive, FourWheelBase, Odometry};
use ttkin::redundancy::{chan_dubey_weight, limit_criterion, limit_gradient, Damping, Weighting, WlsSolver, WlsStep};
use ttkin::task::{racket_angle_jacobian, racket_coordinates, Task};
use ttkin::wholebody::WholeBody;
use ttkin::Error;

/// Classical RK4 of the unicycle ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω, with compensated (Kahan)
/// accumulation so that rounding over many steps stays below the 1e-12 comparison.
fn rk4(pose: [f64; 3], v: f64, w: f64, dt: f64, steps: usize) -> [f64; 3] {
    let f = |p: [f64; 3]| [v * p[2].cos(), v * p[2].sin(), w];
    let h = dt / steps as f64;
    let mut p = pose;
    let mut comp = [0.0; 3];
    for _ in 0..steps {
        let k1 = f(p);
        let k2 = f([p[0] + 0.5 * h * k1[0], p[1] + 0.5 * h * k1[1], p[2] + 0.5 * h * k1[2]]);
        let k3 = f([p[0] + 0.5 * h * k2[0], p[1] + 0.5 * h * k2[1], p[2] + 0.5 * h * k2[2]]);
        let k4 = f([p[0] + h * k3[0], p[1] + h * k3[1], p[2] + h * k3[2]]);
        for i in 0..3 {
            let inc = h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) - comp[i];
            let next = p[i] + inc;
            comp[i] = (next - p[i]) - inc;
            p[i] = next;
        }
    }
    p
}

fn drive() -> DiffDrive {
    DiffDrive::new(0.075, 0.42).unwrap().with_limits(20.0, 40.0).unwrap()
}

fn mobile_arm() -> WholeBody {
    let mount = IsometryMatrix3::from_parts(Translation3::new(0.1, -0.05, 0.3), nalgebra::Rotation3::identity());
    WholeBody::on_diff_drive(drive(), mount, ttkin::robots::ur5())
}

/// mobile8 on a fixed base at the configuration `u` (in [0, 1) per joint, see
/// `config_from_unit`), the racket task and its 5 × 8 Jacobian there.
fn racket_task_at(u: &[f64]) -> (WholeBody, Vec<f64>, Task, nalgebra::DMatrix<f64>) {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q = config_from_unit(model.arm(), u);
    let task = Task::Racket { offset: 0.15 };
    let j6 = model.jacobian(&q).unwrap();
    let t = model.tool_pose(&q).unwrap();
    let je = task.jacobian(&j6, &t, &t);
    (model, q, task, je)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn diff_drive_exact_update_matches_rk4(
        wl in -15.0..15.0f64, wr in -15.0..15.0f64, th in -3.0..3.0f64, dt in 0.01..1.5f64,
    ) {
        let d = drive();
        let pose = [0.3, -1.2, th];
        let exact = d.integrate(pose, [wl, wr], dt);
        let (v, w) = d.body_velocity([wl, wr]);
        let num = rk4(pose, v, w, dt, 20_000);
        for i in 0..3 {
            prop_assert!((exact[i] - num[i]).abs() < 1e-12, "{:?} vs {:?}", exact, num);
        }
    }

    #[test]
    fn wheel_speeds_and_body_velocity_are_inverse(v in -2.0..2.0f64, w in -5.0..5.0f64) {
        let d = drive();
        let ws = d.wheel_speeds(v, w);
        let (v2, w2) = d.body_velocity(ws);
        prop_assert!((v - v2).abs() < 1e-12 && (w - w2).abs() < 1e-12);
    }

    #[test]
    fn whole_body_jacobian_matches_finite_differences(u in prop::collection::vec(0.0..1.0f64, 9)) {
        for model in [mobile_arm(), WholeBody::fixed(ttkin::robots::mobile8())] {
            let nb = model.base_coordinates();
            let mut q = vec![0.4, -0.3, u[0] * 6.0 - 3.0];
            q.truncate(nb);
            q.extend(config_from_unit(model.arm(), &u[1..]));
            let j = model.jacobian(&q).unwrap();
            let h = 1e-6;
            let mut jn = Matrix6xX::zeros(model.nu());
            for k in 0..model.nu() {
                let mut du = vec![0.0; model.nu()];
                du[k] = 1.0;
                let (mut qp, mut qm) = (q.clone(), q.clone());
                model.integrate(&mut qp, &du, h);
                model.integrate(&mut qm, &du, -h);
                let (tp, tm) = (model.tool_pose(&qp).unwrap(), model.tool_pose(&qm).unwrap());
                let v = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
                // vee of the skew part of the relative rotation (acos-based angles lose precision here)
                let r = (tp.rotation * tm.rotation.inverse()).into_inner();
                let w = Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]) / (4.0 * h);
                jn.column_mut(k).copy_from_slice(&[v.x, v.y, v.z, w.x, w.y, w.z]);
            }
            let err = (&j - &jn).abs().max();
            prop_assert!(err < 1e-8, "|J − J_fd| = {}", err);
        }
    }

    #[test]
    fn wls_solution_achieves_the_task_at_full_rank(u in prop::collection::vec(0.05..0.95f64, 8), x in prop::collection::vec(-1.0..1.0f64, 5)) {
        let (model, q, task, je) = racket_task_at(&u);
        for weighting in [Weighting::None, Weighting::ChanDubey] {
            let mut step = WlsStep::new(&model, task, weighting, Damping::none()).unwrap();
            let (qd, rep) = step.try_solve(&q, &x, &[0.0; 8]).unwrap();
            prop_assume!(rep.sigma_min > 1e-3);
            let r = &je * nalgebra::DVector::from_column_slice(&qd);
            for i in 0..5 {
                prop_assert!((r[i] - x[i]).abs() < 1e-10, "row {}: {} vs {}", i, r[i], x[i]);
            }
        }
    }

    #[test]
    fn null_space_motion_leaves_the_task_unchanged(u in prop::collection::vec(0.05..0.95f64, 8), z in prop::collection::vec(-1.0..1.0f64, 8)) {
        let (model, q, _, je) = racket_task_at(&u);
        let w: Vec<f64> = q.iter().zip(model.arm().limits()).map(|(&qi, l)| chan_dubey_weight(qi, l.lower, l.upper, 0.0)).collect();
        let mut solver = WlsSolver::new(5, 8, Damping::none()).unwrap();
        let inf = [f64::INFINITY; 8];
        let ninf = [f64::NEG_INFINITY; 8];
        let mut qd = [0.0; 8];
        let rep = solver.solve(je.as_slice(), &w, &[0.0; 5], Some(&z), &ninf, &inf, &mut qd);
        prop_assume!(rep.sigma_min > 1e-3);
        let r = &je * nalgebra::DVector::from_column_slice(&qd);
        prop_assert!(r.amax() < 1e-10, "J·N z = {}", r.amax());
        prop_assert!(qd.iter().any(|v| v.abs() > 1e-6), "the null-space motion is not trivial");
    }
}

#[test]
fn diff_drive_corrected_formulas_and_special_motions() {
    let d = drive();
    // (3) corrected: ω = (v_R − v_L)/l; (6) third row [r/l, −r/l] with wheels ordered (left, right).
    let (v, w) = d.body_velocity([2.0, 6.0]);
    assert!((v - 0.075 * 4.0).abs() < 1e-15);
    assert!((w - 0.075 * 4.0 / 0.42).abs() < 1e-15);
    // straight line: no 0/0
    let p = d.integrate([0.0, 0.0, 0.5], [4.0, 4.0], 2.0);
    assert!((p[0] - 0.6 * 0.5f64.cos()).abs() < 1e-15 && (p[1] - 0.6 * 0.5f64.sin()).abs() < 1e-15);
    assert_eq!(p[2], 0.5);
    // spinning in place: the position does not move
    let p = d.integrate([1.0, 2.0, 0.0], [-3.0, 3.0], 1.7);
    assert!((p[0] - 1.0).abs() < 1e-15 && (p[1] - 2.0).abs() < 1e-15);
    // a full circle of radius v/ω returns to the start
    let (v, w) = (0.5, 1.0);
    let p = arc_step([0.2, 0.1, 0.3], v, w, std::f64::consts::TAU / w);
    assert!((p[0] - 0.2).abs() < 1e-12 && (p[1] - 0.1).abs() < 1e-12);
}

#[test]
fn odometry_matches_the_exact_update_for_constant_speeds() {
    let d = drive();
    let mut odo = Odometry::new(d, [0.0, 0.0, 0.0]);
    let ws = [3.0, 5.0];
    let dt = 0.01;
    for _ in 0..300 {
        odo.update([ws[0] * dt, ws[1] * dt]).unwrap();
    }
    let exact = d.integrate([0.0, 0.0, 0.0], ws, 3.0);
    for i in 0..3 {
        assert!((odo.pose()[i] - exact[i]).abs() < 1e-12);
    }
    assert!(matches!(odo.update([f64::NAN, 0.0]), Err(Error::NonFinite { .. })));
}

#[test]
fn wheel_limits_keep_curvature_and_acceleration() {
    let d = drive();
    let (s, k) = d.saturate_speeds([30.0, 40.0]);
    assert!((s[1] - 20.0).abs() < 1e-12 && (s[0] / s[1] - 0.75).abs() < 1e-12 && k < 1.0);
    let next = d.limit_step([0.0, 0.0], [10.0, 5.0], 0.1);
    assert!((next[0] - 4.0).abs() < 1e-12 && (next[1] - 2.0).abs() < 1e-12);
    let (vmax, wmax) = d.body_velocity_box();
    for (v, w) in [(vmax, wmax), (-vmax, wmax), (vmax, -wmax)] {
        let ws = d.wheel_speeds(v, w);
        assert!(ws[0].abs() <= 20.0 + 1e-12 && ws[1].abs() <= 20.0 + 1e-12);
    }
    assert!(DiffDrive::new(-1.0, 0.4).is_err());
    assert!(DiffDrive::new(0.1, f64::NAN).is_err());
    assert!(d.try_integrate([0.0, 0.0, 0.0], [1.0, 1.0], -1.0).is_err());
}

#[test]
fn four_wheel_base_followers_roll_and_slip() {
    let base = FourWheelBase::new(drive(), 0.35, 0.05).unwrap();
    let ws = base.wheel_speeds(0.3, 0.0);
    assert!((ws[0] - 4.0).abs() < 1e-12 && (ws[2] - 6.0).abs() < 1e-12 && (ws[3] - 6.0).abs() < 1e-12);
    assert_eq!(base.follower_slip(0.0), 0.0);
    assert!((base.follower_slip(2.0) - 0.7).abs() < 1e-15);
}

#[test]
fn chan_dubey_weights_rise_toward_a_limit_and_stay_one_moving_away() {
    let (lo, hi) = (-1.0, 2.0);
    let mut previous = 0.0;
    for k in 1..40 {
        let q = 0.5 + 1.49 * k as f64 / 40.0; // toward the upper limit
        let w = chan_dubey_weight(q, lo, hi, 1.0);
        assert!(w > previous, "weight must rise toward the limit");
        previous = w;
        assert_eq!(chan_dubey_weight(q, lo, hi, -1.0), 1.0, "moving away: weight 1");
    }
    assert!(previous > 100.0);
    // below mid-range the approaching direction is negative
    assert!(chan_dubey_weight(-0.9, lo, hi, -1.0) > 10.0);
    assert_eq!(chan_dubey_weight(-0.9, lo, hi, 1.0), 1.0);
    // the gradient is the derivative of the criterion
    let (q, h) = (1.3, 1e-6);
    let fd = (limit_criterion(q + h, lo, hi) - limit_criterion(q - h, lo, hi)) / (2.0 * h);
    assert!((fd - limit_gradient(q, lo, hi)).abs() < 1e-6 * fd.abs().max(1.0));
    assert_eq!(limit_gradient(0.5, lo, hi), 0.0);
    assert_eq!(limit_gradient(3.0, f64::NEG_INFINITY, f64::INFINITY), 0.0);
    assert!(limit_gradient(2.5, lo, hi).is_finite());
}

#[test]
fn damped_solution_stays_bounded_through_a_singularity() {
    // UR5 wrist singularity at q5 = 0: sweep q5 through it with a fixed task velocity.
    let model = WholeBody::fixed(ttkin::robots::ur5());
    let xdot = [0.0, 0.0, 0.0, 0.3, 0.2, 0.1];
    let peak = |damping: Damping| {
        let mut step = WlsStep::new(&model, Task::Pose, Weighting::None, damping).unwrap();
        let mut peak: f64 = 0.0;
        for k in -50..=50 {
            let q = [0.3, -1.2, 1.4, -0.8, 1e-3 * k as f64 + 1e-9, 0.4];
            let (qd, _) = step.solve(&q, &xdot, &[0.0; 6]);
            peak = peak.max(qd.iter().map(|v| v.abs()).fold(0.0, f64::max));
        }
        peak
    };
    let damped = peak(Damping {
        epsilon: 0.05,
        lambda_max: 0.05,
    });
    let undamped = peak(Damping::none());
    assert!(damped.is_finite() && damped < 20.0, "damped peak {damped}");
    assert!(undamped > 50.0 * damped, "undamped {undamped} vs damped {damped}");
}

#[test]
fn velocity_boxes_are_respected_without_leaving_the_task() {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q = ttkin::robots::mobile8_start();
    let task = Task::Racket { offset: 0.15 };
    let j6 = model.jacobian(&q).unwrap();
    let t = model.tool_pose(&q).unwrap();
    let je = task.jacobian(&j6, &t, &t);
    let xdot = [0.1, 0.05, -0.08, 0.3, -0.2];
    let w = [1.0; 8];
    let mut solver = WlsSolver::new(5, 8, Damping::none()).unwrap();
    let mut free = [0.0; 8];
    solver.solve(
        je.as_slice(),
        &w,
        &xdot,
        None,
        &[f64::NEG_INFINITY; 8],
        &[f64::INFINITY; 8],
        &mut free,
    );
    // Box the largest joint rate at half its free value: the task must still hold.
    let big = (0..8).max_by(|&a, &b| free[a].abs().total_cmp(&free[b].abs())).unwrap();
    let mut lo = [f64::NEG_INFINITY; 8];
    let mut hi = [f64::INFINITY; 8];
    lo[big] = -0.5 * free[big].abs();
    hi[big] = 0.5 * free[big].abs();
    let mut qd = [0.0; 8];
    let rep = solver.solve(je.as_slice(), &w, &xdot, None, &lo, &hi, &mut qd);
    assert_eq!(rep.scale, 1.0);
    assert!(rep.saturated >= 1);
    assert!(qd[big].abs() <= 0.5 * free[big].abs() + 1e-12);
    let r = &je * nalgebra::DVector::from_column_slice(&qd);
    for i in 0..5 {
        assert!((r[i] - xdot[i]).abs() < 1e-10);
    }
    // An impossible box (every joint nearly frozen) scales the task instead of violating it.
    let rep = solver.solve(je.as_slice(), &w, &xdot, None, &[-1e-3; 8], &[1e-3; 8], &mut qd);
    assert!(rep.scale < 1.0);
    assert!(qd.iter().all(|v| v.abs() <= 1e-3 + 1e-15));
}

#[test]
fn racket_feedforward_matches_the_residual_rate_of_a_moving_target() {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q = ttkin::robots::mobile8_start();
    let t = model.tool_pose(&q).unwrap();
    let task = Task::Racket { offset: 0.15 };
    let x = racket_coordinates(&t, 0.15);
    let xdot = [0.1, -0.2, 0.05, 0.3, -0.4];
    let h = 1e-6;
    let moved = |s: f64| {
        let xs: Vec<f64> = (0..5).map(|i| x[i] + s * xdot[i]).collect();
        task.error(&t, &task.target_pose(&xs, &t))
    };
    let fd = (moved(h) - moved(-h)) / (2.0 * h);
    let mut ff = [0.0; 5];
    task.feedforward(&x, &xdot, &mut ff);
    for i in 0..5 {
        assert!((fd[i] - ff[i]).abs() < 1e-7, "row {i}: {} vs {}", fd[i], ff[i]);
    }
}

#[test]
fn racket_angle_jacobian_matches_finite_differences() {
    let chain = ttkin::robots::mobile8();
    let q = ttkin::robots::mobile8_start();
    let j = chain.jacobian(&q, ttkin::JacobianFrame::Base).unwrap();
    let t = chain.fk(&q).unwrap();
    let ja = racket_angle_jacobian(&j, &t, 0.15).unwrap();
    let h = 1e-6;
    for k in 0..8 {
        let (mut qp, mut qm) = (q, q);
        qp[k] += h;
        qm[k] -= h;
        let (xp, xm) = (
            racket_coordinates(&chain.fk(&qp).unwrap(), 0.15),
            racket_coordinates(&chain.fk(&qm).unwrap(), 0.15),
        );
        for i in 0..5 {
            assert!((ja[(i, k)] - (xp[i] - xm[i]) / (2.0 * h)).abs() < 1e-7);
        }
    }
    let up = IsometryMatrix3::from_parts(
        Translation3::identity(),
        nalgebra::Rotation3::rotation_between(&Vector3::x(), &Vector3::z()).unwrap(),
    );
    assert!(matches!(racket_angle_jacobian(&j, &up, 0.15), Err(Error::Singular(_))));
}

/// The seed000 motion over 4 s at 1 kHz: `fraction` of the way from our x(0) toward the seed's
/// x(4) (see `support/seed000.rs`).
fn seed000_trajectory(fraction: f64) -> (WholeBody, [f64; 8], TaskTrajectory) {
    let (model, q0, task, x0, x1) = seed000::seed000_line(fraction);
    let traj = TaskTrajectory::line(task, &x0, &x1, 4.0, 1000.0).unwrap();
    (model, q0, traj)
}

#[test]
fn seed000_weighted_tracking_is_accurate_and_within_limits() {
    let (model, q0, traj) = seed000_trajectory(0.15);
    let r = track(&model, &q0, &traj, ClikOptions::default()).unwrap();
    assert_eq!(r.status, ClikStatus::Completed);
    assert_eq!(r.len(), 4001);
    let max_err = r.error.iter().cloned().fold(0.0, f64::max);
    assert!(max_err <= 1e-6, "max tracking error {max_err}");
    let min_margin = r.margin.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(min_margin > 0.0, "a joint reached its limit: {min_margin}");
    let last = &r.x[(r.len() - 1) * 5..];
    for (a, b) in last.iter().zip(traj.x(traj.len() - 1)) {
        assert!((a - b).abs() < 1e-6);
    }
}

#[test]
fn seed000_unweighted_pseudo_inverse_crosses_a_limit() {
    let (model, q0, traj) = seed000_trajectory(0.15);
    let opts = ClikOptions {
        weighting: Weighting::None,
        respect_limits: false,
        ..ClikOptions::default()
    };
    let r = track(&model, &q0, &traj, opts).unwrap();
    let min_margin = r.margin.iter().cloned().fold(f64::INFINITY, f64::min);
    assert!(
        min_margin < 0.0,
        "expected the unweighted solution to cross a limit, margin {min_margin}"
    );
}

#[test]
fn unreachable_target_is_reported_not_garbage() {
    let (model, q0, traj) = seed000_trajectory(1.0);
    let r = track(&model, &q0, &traj, ClikOptions::default()).unwrap();
    assert!(!matches!(r.status, ClikStatus::Completed), "{:?}", r.status);
    assert!(r.q.iter().all(|v| v.is_finite()));
    assert!(
        r.margin.iter().all(|&m| m >= 0.0),
        "limits must hold even when the task fails"
    );
}

#[test]
fn bad_input_gives_clear_errors() {
    let (model, mut q0, traj) = seed000_trajectory(0.15);
    q0[2] = f64::NAN;
    assert!(track(&model, &q0, &traj, ClikOptions::default()).is_err());
    assert!(track(&model, &q0[..5], &traj, ClikOptions::default()).is_err());
    let mut outside = ttkin::robots::mobile8_start();
    outside[4] = 6.0;
    assert!(matches!(
        track(&model, &outside, &traj, ClikOptions::default()),
        Err(Error::InvalidArgument { .. })
    ));
    assert!(TaskTrajectory::new(Task::Position, 1000.0, vec![0.0; 4], vec![0.0; 4]).is_err());
    assert!(TaskTrajectory::from_samples(Task::Position, -1.0, vec![0.0; 6]).is_err());
    assert!(TaskTrajectory::from_samples(Task::Position, 100.0, vec![0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0]).is_err());
    assert!(WlsSolver::new(7, 8, Damping::default()).is_err());
    assert!(Weighting::from_name("inverse").is_err());
    let bad = ClikOptions {
        gain: Some(-1.0),
        ..ClikOptions::default()
    };
    assert!(track(&model, &ttkin::robots::mobile8_start(), &traj, bad).is_err());
}

#[test]
fn mobile_base_clik_tracks_a_position_line() {
    let model = mobile_arm();
    let q0 = [0.0, 0.0, 0.2, 0.3, -1.2, 1.4, -0.8, 1.2, 0.4];
    let t = model.tool_pose(&q0).unwrap();
    let p = t.translation.vector;
    let x1 = [p.x + 0.4, p.y - 0.2, p.z + 0.05];
    let traj = TaskTrajectory::line(Task::Position, p.as_slice(), &x1, 2.0, 500.0).unwrap();
    let opts = ClikOptions {
        input_weights: Some(vec![10.0, 10.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
        ..ClikOptions::default()
    };
    let r = track(&model, &q0, &traj, opts).unwrap();
    assert_eq!(r.status, ClikStatus::Completed);
    assert!(r.error.iter().cloned().fold(0.0, f64::max) < 1e-6);
    // wheels within their limits at every sample
    let d = drive();
    for k in 0..r.len() {
        let u = &r.qd[k * 8..k * 8 + 2];
        let ws = d.wheel_speeds(u[0], u[1]);
        assert!(ws[0].abs() <= d.max_wheel_speed() + 1e-9 && ws[1].abs() <= d.max_wheel_speed() + 1e-9);
    }
}

#[test]
fn manipulability_is_the_root_of_the_gram_determinant() {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q = ttkin::robots::mobile8_start();
    let t = model.tool_pose(&q).unwrap();
    let je = Task::Racket { offset: 0.15 }.jacobian(&model.jacobian(&q).unwrap(), &t, &t);
    let expected = (&je * je.transpose()).determinant().sqrt();
    let w = ttkin::redundancy::manipulability(je.as_slice(), 5);
    assert!((w - expected).abs() < 1e-12 * expected.max(1.0), "{w} vs {expected}");
    assert_eq!(ttkin::redundancy::manipulability(&[1.0, 2.0, 2.0, 4.0], 2), 0.0);
}

#[test]
fn null_space_objectives_keep_the_task_and_do_their_job() {
    let (model, q0, traj) = seed000_trajectory(0.15);
    let task = Task::Racket { offset: 0.15 };
    let mean_manip = |r: &ttkin::clik::ClikResult| {
        let mut sum = 0.0;
        for k in 0..r.len() {
            let q = &r.q[k * 8..(k + 1) * 8];
            let t = model.tool_pose(q).unwrap();
            let je = task.jacobian(&model.jacobian(q).unwrap(), &t, &t);
            sum += ttkin::redundancy::manipulability(je.as_slice(), 5);
        }
        sum / r.len() as f64
    };
    let plain = track(&model, &q0, &traj, ClikOptions::default()).unwrap();
    let manip = track(
        &model,
        &q0,
        &traj,
        ClikOptions {
            manipulability_gain: 5.0,
            ..ClikOptions::default()
        },
    )
    .unwrap();
    let limits = track(
        &model,
        &q0,
        &traj,
        ClikOptions {
            limit_gain: 0.05,
            ..ClikOptions::default()
        },
    )
    .unwrap();
    for r in [&manip, &limits] {
        assert_eq!(r.status, ClikStatus::Completed);
        assert!(r.error.iter().cloned().fold(0.0, f64::max) <= 1e-6);
    }
    assert!(
        mean_manip(&manip) > mean_manip(&plain),
        "manipulability gradient must raise w"
    );
    let criterion = |r: &ttkin::clik::ClikResult| {
        let lims = model.arm().limits();
        let k = r.len() - 1;
        (0..8)
            .map(|i| limit_criterion(r.q[k * 8 + i], lims[i].lower, lims[i].upper))
            .sum::<f64>()
    };
    assert!(criterion(&limits) < criterion(&plain), "limit gradient must lower H");
}

/// FK along the quintic joint path from the seed000 start to the experiment's target
/// configuration: the racket normal's x component crosses 0.9, where the tangent basis switches.
#[test]
fn racket_tracking_is_accurate_where_the_tangent_basis_switches() {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let chain = ttkin::robots::mobile8();
    let q0 = ttkin::robots::mobile8_start();
    let q1 = [0.3998, 2.0706, 1.0711, 0.2618, 3.4214, 0.3513, 3.8653, 1.7117];
    let task = Task::Racket { offset: 0.15 };
    let (duration, rate) = (4.0, 1000.0);
    let coords = |t: f64| {
        let s = t / duration;
        let s = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
        let q: Vec<f64> = (0..8).map(|i| q0[i] + s * (q1[i] - q0[i])).collect();
        racket_coordinates(&chain.fk(&q).unwrap(), 0.15)
    };
    let (mut x, mut xdot) = (Vec::new(), Vec::new());
    let mut crossed = [false, false];
    for k in 0..=4000 {
        let t = k as f64 / rate;
        let c = coords(t);
        let nx = c[3].sin() * c[4].cos();
        crossed[usize::from(nx > 0.9)] = true;
        let h = 1e-5;
        let (p, m) = (coords(t + h), coords(t - h));
        x.extend_from_slice(&c);
        xdot.extend((0..5).map(|i| (p[i] - m[i]) / (2.0 * h)));
    }
    assert!(crossed[0] && crossed[1], "the normal does not cross n_x = 0.9");
    let traj = TaskTrajectory::new(task, rate, x, xdot).unwrap();
    let r = track(&model, &q0, &traj, ClikOptions::default()).unwrap();
    assert_eq!(r.status, ClikStatus::Completed);
    let max_err = r.error.iter().cloned().fold(0.0, f64::max);
    assert!(max_err <= 1e-7, "max tracking error {max_err}");
}

#[test]
fn racket_residual_and_feedforward_in_another_basis_are_the_same_vector() {
    let chain = ttkin::robots::mobile8();
    let q = ttkin::robots::mobile8_start();
    let t = chain.fk(&q).unwrap();
    let task = Task::Racket { offset: 0.15 };
    let x = racket_coordinates(&t, 0.15);
    // a basis on the other side of the helper switch (normal with n_x > 0.9)
    let xb: [f64; 5] = [0.0, 0.0, 0.0, 1.3, 0.1];
    let nb = Vector3::new(xb[3].sin() * xb[4].cos(), xb[3].sin() * xb[4].sin(), xb[3].cos());
    assert!(nb.x > 0.9);
    let basis = task.target_pose(&xb, &t);
    let (u1, u2) = ttkin::task::tangent_basis(&nb);
    let target = task.target_pose(&[x[0] + 0.01, x[1], x[2], x[3] + 0.02, x[4] - 0.03], &t);
    let mut e = [0.0; 5];
    task.error_in_basis_into(&t, &target, &basis, &mut e);
    let r = ttkin::task::racket_normal(&t).cross(&ttkin::task::racket_normal(&target));
    assert!((e[3] - u1.dot(&r)).abs() < 1e-15 && (e[4] - u2.dot(&r)).abs() < 1e-15);
    let mut same = [0.0; 5];
    task.error_in_basis_into(&t, &target, &target, &mut same);
    assert_eq!(same, task.error(&t, &target).as_slice());
    let xdot = [0.1, -0.2, 0.05, 0.3, -0.4];
    let (mut ff, mut fb) = ([0.0; 5], [0.0; 5]);
    task.feedforward(&x, &xdot, &mut ff);
    task.feedforward_in_basis(&x, &xdot, &xb, &mut fb);
    let (v1, v2) = ttkin::task::tangent_basis(&ttkin::task::racket_normal(&task.target_pose(&x, &t)));
    let w = v1 * ff[3] + v2 * ff[4]; // n × ṅ, perpendicular to n
    assert!((fb[3] - u1.dot(&w)).abs() < 1e-14 && (fb[4] - u2.dot(&w)).abs() < 1e-14);
    assert_eq!(ff[..3], fb[..3]);
}
