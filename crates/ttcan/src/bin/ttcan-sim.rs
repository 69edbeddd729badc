//! `ttcan-sim`: prints the tuned cascade for the maxon RE 25 + GP 26 A axis and a summary of its
//! simulated current step, speed step and quintic move. No arguments.

use ttcan::{AxisConfig, Mode, MotorModel, Setpoint, Simulation, Trace};

fn main() -> Result<(), ttcan::Error> {
    let model = MotorModel::maxon_re25_gp26();
    let config = AxisConfig::new(model);
    let sim = Simulation::new(&model, &config)?;
    let t = sim.axis.tuning();
    println!(
        "T_sigma = {:.3} ms, speed reference filter {:.1} Hz",
        t.t_sigma * 1e3,
        t.speed_reference_filter_hz
    );
    for (name, r) in [("current", t.current), ("speed", t.speed), ("position", t.position)] {
        println!(
            "{name:>8} loop: kp {:.4e} ki {:.4e}  crossover {:.1} Hz  phase margin {:.1} deg  bandwidth {:.1} Hz",
            r.kp, r.ki, r.crossover_hz, r.phase_margin_deg, r.bandwidth_hz
        );
    }

    let mut s = Simulation::new(&model, &config)?;
    s.enable(Mode::Current);
    let tr = s.run(0.01, |_| Setpoint::Current(1.0))?;
    summary("current step 1 A", &tr.time, &tr.current, 1.0);

    let mut s = Simulation::new(&model, &config)?;
    s.enable(Mode::Velocity);
    let tr = s.run(0.1, |_| Setpoint::Velocity(20.0))?;
    summary("speed step 20 rad/s", &tr.time, &tr.speed, 20.0);

    let mut s = Simulation::new(&model, &config)?;
    s.enable(Mode::Position);
    let tr = quintic(&mut s, 3.0, 0.3)?;
    let max_e = tr.following_error.iter().fold(0.0f64, |m, e| m.max(e.abs()));
    println!(
        "quintic 3 rad in 0.3 s: max following error {max_e:.2e} rad (at the 1 kHz position steps), final state {:?}",
        s.axis.state()
    );
    Ok(())
}

fn quintic(s: &mut Simulation, h: f64, tf: f64) -> Result<Trace, ttcan::Error> {
    // The rest-to-rest quintic of ttkin's trajectory module (the one quintic of ttmanip).
    let c = ttkin::traj::poly::quintic(0.0, 0.0, 0.0, h, 0.0, 0.0, tf);
    let dt = 1.0 / s.axis.rates().position_hz();
    let n = (1.5 * tf / dt) as usize;
    let (mut q, mut qd, mut qdd) = (vec![], vec![], vec![]);
    for k in 0..n {
        let [a, b, d] = ttkin::traj::poly::eval3(&c, (k as f64 * dt).min(tf));
        q.push(a);
        qd.push(if k as f64 * dt >= tf { 0.0 } else { b });
        qdd.push(if k as f64 * dt >= tf { 0.0 } else { d });
    }
    s.run_position(&q, &qd, &qdd)
}

fn summary(name: &str, t: &[f64], y: &[f64], target: f64) {
    let tail = &y[y.len() * 4 / 5..];
    let mean = tail.iter().sum::<f64>() / tail.len() as f64;
    println!(
        "{name}: rise (10-90 %) {:.3} ms, overshoot {:.2} %, final mean {:.5}",
        ttcan::sim::rise_time(t, y, target) * 1e3,
        ttcan::sim::overshoot(y, target) * 100.0,
        mean
    );
}
