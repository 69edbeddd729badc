//! All axes together (issue 10): gantry6's six drives on its rigid-body dynamics with gravity.

use ttcan::cases::gantry6_demo_stroke;
use ttcan::{CoupledOptions, CoupledSim};
use ttkin::{Dynamics, DynamicsData, JointType};

const G: [f64; 3] = ttkin::dynamics::EARTH_GRAVITY;

/// The demo stroke sampled at 1 kHz with its inverse-dynamics torques (row-major).
fn stroke_samples() -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, f64) {
    let chain = ttkin::robots::gantry6();
    let s = gantry6_demo_stroke(&chain).unwrap();
    let d = Dynamics::new(&chain).unwrap();
    let mut data = DynamicsData::new(&d);
    let n = 6;
    let k = (s.trajectory.duration() * 1000.0).round() as usize + 1;
    let (mut t, mut q, mut qd, mut qdd, mut tau) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut a, mut b, mut c) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for i in 0..k {
        let ti = (i as f64 * 1e-3).min(s.trajectory.duration());
        s.trajectory.sample(ti, &mut a, &mut b, &mut c).unwrap();
        t.push(ti);
        q.extend_from_slice(&a);
        qd.extend_from_slice(&b);
        qdd.extend_from_slice(&c);
        tau.extend(d.inverse_dynamics(&mut data, &a, &b, &c, &G, None).unwrap().iter());
    }
    (t, q, qd, qdd, tau, s.t_hit)
}

#[test]
fn gantry6_tracks_the_demo_stroke_with_inverse_dynamics_feedforward() {
    let chain = ttkin::robots::gantry6();
    let (t, q, qd, qdd, tau, t_hit) = stroke_samples();
    let n = 6;
    let mut sim = CoupledSim::from_chain(&chain, &q[..n], CoupledOptions::default()).unwrap();
    // Settle on gravity first: hold the start with the gravity feed-forward.
    let g0: Vec<f64> = tau[..n].to_vec();
    sim.set_setpoint(&q[..n], &vec![0.0; n], &vec![0.0; n], Some(&g0))
        .unwrap();
    let tr = sim.run(&t, &q, &qd, &qdd, Some(&tau), 1e-3).unwrap();
    assert!(tr.faults.iter().all(|f| f.is_empty()), "faults {:?}", tr.faults);
    let k_hit = (t_hit / 5e-5).round() as usize;
    let kinds = sim.joint_types();
    for j in 0..n {
        let e = (tr.q[k_hit * n + j] - tr.q_ref[k_hit * n + j]).abs();
        let peak = (0..tr.len()).map(|k| tr.current[k * n + j].abs()).fold(0.0, f64::max);
        let rms = ((0..tr.len()).map(|k| tr.current[k * n + j].powi(2)).sum::<f64>() / tr.len() as f64).sqrt();
        let c = sim.axes()[j].config();
        println!("joint {j}: error at hit {e:.3e}, peak current {peak:.3} A (peak rating {:.2}), RMS {rms:.3} A (continuous {:.2})", c.peak_current, c.continuous_current);
        let bound = if kinds[j] == JointType::Revolute {
            0.5e-3
        } else {
            0.1e-3
        };
        assert!(e <= bound, "joint {j}: tracking error at the hit {e}");
        assert!(peak <= c.peak_current, "joint {j}: peak current {peak} A");
        assert!(rms <= c.continuous_current, "joint {j}: RMS current {rms} A");
    }
}
