//! Fixed-count loops of the operations the issue-16 refactor moved (fk, jacobian, rnea, ik), for
//! instruction counts under valgrind: `refactor_icount OP N`. Public API of main 40fcfd8 only, so
//! the same source builds on both sides of a before/after comparison.
use std::hint::black_box;
use ttkin::ik::{Analytic, IkSolver, LimitFilter};
use ttkin::{Dynamics, DynamicsData, JacobianFrame};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[2].parse().unwrap();
    let m8 = ttkin::robots::mobile8();
    let ur5 = ttkin::robots::ur5();
    let g6 = ttkin::robots::gantry6();
    let q8 = ttkin::robots::mobile8_start();
    let q6 = [0.3, -0.9, 1.1, -0.4, 0.8, 0.2];
    match args[1].as_str() {
        "fk" => (0..n).for_each(|_| {
            black_box(m8.fk(black_box(&q8)).unwrap());
        }),
        "jacobian" => {
            let mut j = nalgebra::Matrix6xX::zeros(m8.dof());
            (0..n).for_each(|_| {
                black_box(m8.jacobian_into(black_box(&q8), JacobianFrame::Base, &mut j));
            });
            black_box(j);
        }
        "rnea" => {
            let dy = Dynamics::new(&ur5).unwrap();
            let mut d = DynamicsData::new(&dy);
            let (qd, qdd) = ([0.3; 6], [1.0; 6]);
            (0..n).for_each(|_| {
                black_box(
                    dy.rnea(&mut d, black_box(&q6), &qd, &qdd, &[0.0, 0.0, -9.81], None)
                        .unwrap()[0],
                );
            });
        }
        "forward_dynamics" => {
            let dy = Dynamics::new(&ur5).unwrap();
            let mut d = DynamicsData::new(&dy);
            let (qd, tau) = ([0.3; 6], [1.0; 6]);
            (0..n).for_each(|_| {
                black_box(
                    dy.forward_dynamics(&mut d, black_box(&q6), &qd, &tau, &[0.0, 0.0, -9.81], None)
                        .unwrap()[0],
                );
            });
        }
        "ik_numeric" => {
            let t = ur5.fk(&q6).unwrap();
            let s = IkSolver {
                time_budget: None,
                ..IkSolver::default()
            };
            let q0 = [0.0, -1.5, 1.5, 0.0, 1.5, 0.0];
            (0..n).for_each(|_| {
                black_box(s.solve(&ur5, black_box(&t), &q0).unwrap());
            });
        }
        "ik_analytic" => {
            let ik = Analytic::for_chain(&g6).unwrap();
            let t = g6.fk(&[0.1, -0.1, 0.5, 0.4, -0.6, 0.9]).unwrap();
            (0..n).for_each(|_| {
                black_box(ik.solve(black_box(&t), None, LimitFilter::Off).unwrap());
            });
        }
        "stroke" => {
            // gantry6's hit stroke: the earliest feasible quintic to the hit, the minimal return
            let limits = ttkin::traj::KinematicLimits::from_chain(&g6, Some(&[2000.0; 6])).unwrap();
            let start = ttkin::traj::JointState::rest(&[0.0, 0.0, 0.5, 0.0, 0.0, 0.0]);
            let hit = ttkin::traj::JointState {
                q: vec![0.1, -0.1, 0.6, 0.4, -0.6, 0.9],
                qd: vec![0.5, 0.3, 0.2, 1.0, -1.0, 2.0],
                qdd: vec![0.0; 6],
            };
            let ready = [0.0, 0.0, 0.5, 0.0, 0.0, 0.0];
            (0..n).for_each(|_| {
                black_box(ttkin::traj::stroke(black_box(&start), &hit, 0.05, &ready, None, &limits).unwrap());
            });
        }
        "wls" => {
            // mobile8's base Jacobian: a fresh weighted least-norm solve, then a re-solve
            let dof = m8.dof();
            let jac = m8.jacobian(&q8, JacobianFrame::Base).unwrap();
            let damping = ttkin::redundancy::Damping::new(1e-3, 0.1).unwrap();
            let mut s = ttkin::redundancy::WlsSolver::new(6, dof, damping).unwrap();
            let (w, lo, hi, mut qdot) = (vec![1.0; dof], vec![-1.0; dof], vec![1.0; dof], vec![0.0; dof]);
            let xdot = [0.1, -0.2, 0.05, 0.0, 0.1, 0.0];
            (0..n).for_each(|_| {
                black_box(s.solve(jac.as_slice(), &w, black_box(&xdot), None, &lo, &hi, &mut qdot));
                black_box(s.resolve(jac.as_slice(), black_box(&xdot), None, &lo, &hi, &mut qdot));
            });
        }
        other => panic!("unknown op {other}"),
    }
}
