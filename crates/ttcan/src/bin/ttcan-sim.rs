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
    let dt = 1.0 / s.axis.rates().position_hz();
    let n = (1.5 * tf / dt) as usize;
    let (mut q, mut qd, mut qdd) = (vec![], vec![], vec![]);
    for k in 0..n {
        let tau = (k as f64 * dt / tf).min(1.0);
        q.push(h * tau.powi(3) * (10.0 - 15.0 * tau + 6.0 * tau * tau));
        qd.push(h / tf * 30.0 * tau * tau * (1.0 - tau).powi(2));
        qdd.push(h / (tf * tf) * 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau));
    }
    s.run_position(&q, &qd, &qdd)
}

fn summary(name: &str, t: &[f64], y: &[f64], target: f64) {
    let t10 = t
        .iter()
        .zip(y)
        .find(|(_, v)| **v >= 0.1 * target)
        .map(|(t, _)| *t)
        .unwrap_or(f64::NAN);
    let t90 = t
        .iter()
        .zip(y)
        .find(|(_, v)| **v >= 0.9 * target)
        .map(|(t, _)| *t)
        .unwrap_or(f64::NAN);
    let peak = y.iter().cloned().fold(f64::MIN, f64::max);
    let tail = &y[y.len() * 4 / 5..];
    let mean = tail.iter().sum::<f64>() / tail.len() as f64;
    println!(
        "{name}: rise (10-90 %) {:.3} ms, overshoot {:.2} %, final mean {:.5}",
        (t90 - t10) * 1e3,
        (peak / target - 1.0) * 100.0,
        mean
    );
}
