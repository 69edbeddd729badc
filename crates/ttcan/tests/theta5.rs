//! The θ5 case of issue 10: gantry6's demo stroke on θ5, RE 25 + 14:1, 4096-count encoder.

use ttcan::cases::{gantry6_demo_stroke, mean_joint_inertia};
use ttcan::{AxisConfig, Load, Mode, MotorModel, Simulation};

#[test]
fn theta5_baseline() {
    let chain = ttkin::robots::gantry6();
    let s = gantry6_demo_stroke(&chain).unwrap();
    let j = mean_joint_inertia(&chain, &s.trajectory, 4, true).unwrap();
    let mut model = MotorModel::maxon_re25_gp26();
    model.load = Load { inertia: j, viscous_friction: 0.0 };
    let config = AxisConfig::new(model);
    let mut sim = Simulation::new(&model, &config).unwrap();
    sim.enable(Mode::Position);
    let rate = config.rates.position_hz();
    let dur = s.trajectory.duration() + 0.05;
    let k = (dur * rate).round() as usize;
    let n = 6;
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (mut a, mut b, mut c) = (vec![], vec![], vec![]);
    s.trajectory.sample(0.0, &mut q, &mut qd, &mut qdd).unwrap();
    let q0 = q[4];
    for i in 0..k {
        let t = (i as f64 / rate).min(s.trajectory.duration());
        s.trajectory.sample(t, &mut q, &mut qd, &mut qdd).unwrap();
        let hold = i as f64 / rate > s.trajectory.duration();
        a.push(q[4] - q0);
        b.push(if hold { 0.0 } else { qd[4] });
        c.push(if hold { 0.0 } else { qdd[4] });
    }
    let tr = sim.run_position(&a, &b, &c).unwrap();
    let rms = (tr.current.iter().zip(&tr.current_reference).map(|(i, r)| (i - r).powi(2)).sum::<f64>() / tr.len() as f64).sqrt();
    let fe = tr.following_error.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    println!("J = {j}, t_hit {}, dur {}, rms(i-iref) = {rms}, max following error {fe}", s.t_hit, s.trajectory.duration());
}
