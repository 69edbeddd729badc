//! All axes together (issue 10): gantry6's six drives on its rigid-body dynamics with gravity.
// Per-joint loops index several row-major arrays at once.
#![allow(clippy::needless_range_loop)]

use ttcan::cases::gantry6_demo_stroke;
use ttcan::{CoupledOptions, CoupledSim};
use ttkin::{Dynamics, DynamicsData, JointType};

const G: [f64; 3] = ttkin::dynamics::EARTH_GRAVITY;

/// t, q, qd, qdd, inverse-dynamics torques (row-major) and the hit time.
type Samples = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, f64);

/// The demo stroke sampled at 1 kHz with its inverse-dynamics torques (row-major).
fn stroke_samples() -> Samples {
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

/// gantry6's drives (default options) at the start of the demo stroke, and the stroke's samples.
fn at_stroke_start() -> (CoupledSim, Samples) {
    let samples = stroke_samples();
    let q0 = &samples.1[..6];
    let sim = CoupledSim::from_chain(&ttkin::robots::gantry6(), q0, CoupledOptions::default()).unwrap();
    (sim, samples)
}

#[test]
fn gantry6_tracks_the_demo_stroke_with_inverse_dynamics_feedforward() {
    let (mut sim, (t, q, qd, qdd, tau, t_hit)) = at_stroke_start();
    let n = 6;
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

#[test]
fn with_ideal_current_loops_the_mechanics_is_ttkins_forward_dynamics() {
    // Every tick's acceleration of the coupled simulation (M and h refreshed every 4 ticks)
    // against ttkin's `forward_dynamics` at the same state and drive torques minus the viscous
    // friction. Coulomb friction is the one documented model difference (saturated below the
    // speed it removes in one tick, against sign(q̇)): it is taken out of the drives here.
    // Stated tolerance, of the stroke's largest acceleration of each joint: 1e-9 with M and h
    // refreshed every tick (the same model), 0.5 % with the default refresh every 4 ticks
    // (measured: at most 0.17 %, on θ5).
    let g6 = ttkin::robots::gantry6();
    let joints: Vec<ttkin::Joint> = g6
        .joints()
        .iter()
        .map(|j| {
            let mut d = *j.drive().unwrap();
            d.coulomb = 0.0;
            j.clone().with_drive(d).unwrap()
        })
        .collect();
    let chain = ttkin::Chain::new("gantry6 without Coulomb friction", joints, *g6.base(), *g6.tool()).unwrap();
    for (refresh, tolerance) in [(1u32, 1e-9), (4, 5e-3)] {
        accelerations_agree(&chain, refresh, tolerance);
    }
}

fn accelerations_agree(chain: &ttkin::Chain, refresh: u32, tolerance: f64) {
    let (t, q, qd, qdd, tau, _) = stroke_samples();
    let n = 6;
    let options = CoupledOptions {
        ideal_current: true,
        refresh_ticks: refresh,
        ..CoupledOptions::default()
    };
    let mut sim = CoupledSim::from_chain(chain, &q[..n], options).unwrap();
    let tr = sim.run(&t, &q, &qd, &qdd, Some(&tau), 1e-3).unwrap();
    assert!(tr.faults.iter().all(|f| f.is_empty()));
    let d = Dynamics::new(chain).unwrap();
    let mut data = DynamicsData::new(&d);
    let dt = 5e-5;
    let (mut worst, mut peak) = (vec![0.0f64; n], vec![0.0f64; n]);
    for k in 1..tr.len() - 1 {
        let (qk, vk) = (&tr.q[k * n..(k + 1) * n], &tr.qd[k * n..(k + 1) * n]);
        let f = d.friction(vk).unwrap();
        // Row k holds the state before tick k and the torque of tick k − 1: tick k's is in row k + 1.
        let drive: Vec<f64> = (0..n).map(|j| tr.torque[(k + 1) * n + j] - f[j]).collect();
        let a = d.forward_dynamics(&mut data, qk, vk, &drive, &G, None).unwrap();
        for j in 0..n {
            let a_sim = (tr.qd[(k + 1) * n + j] - vk[j]) / dt;
            worst[j] = worst[j].max((a_sim - a[j]).abs());
            peak[j] = peak[j].max(a[j].abs());
        }
    }
    for j in 0..n {
        println!(
            "refresh {refresh}: joint {j}: largest |q̈_coupled − q̈_ttkin| {:.3e} of peak {:.3e}",
            worst[j], peak[j]
        );
        assert!(worst[j] <= tolerance * peak[j], "refresh {refresh}, joint {j}");
    }
}

#[test]
fn energy_bookkeeping_closes() {
    // Electrical input = copper loss + friction work + Δ(kinetic + potential + magnetic).
    let (mut sim, (t, q, qd, qdd, tau, _)) = at_stroke_start();
    let e0 = sim.stored_energy().unwrap();
    let before = sim.energy();
    sim.run(&t, &q, &qd, &qdd, Some(&tau), 1e-3).unwrap();
    let e1 = sim.stored_energy().unwrap();
    let after = sim.energy();
    let input = after.electrical_input - before.electrical_input;
    let copper = after.copper_loss - before.copper_loss;
    let friction = after.friction_loss - before.friction_loss;
    let residual = input - copper - friction - (e1 - e0);
    let scale = copper + friction.abs() + (e1 - e0).abs();
    println!(
        "input {input:.3} J = copper {copper:.3} + friction {friction:.3} + Δstored {:.3} + residual {residual:.2e}",
        e1 - e0
    );
    assert!(residual.abs() < 0.01 * scale, "residual {residual} J of {scale} J");
}

#[test]
fn the_demo_stroke_with_gravity_passes_the_sizing_of_gantry6s_drives() {
    let chain = ttkin::robots::gantry6();
    let (_t, q, qd, qdd, _tau, _) = stroke_samples();
    let configs = ttcan::coupled::axis_configs_from_chain(&chain, &q[..6], &CoupledOptions::default()).unwrap();
    let sizing = ttcan::sizing::size_drives(&chain, &configs, &q, &qd, &qdd, &G).unwrap();
    for s in &sizing {
        println!(
            "{}: RMS {:.3} A / {:.2} A, peak {:.3} A / {:.2} A, speed {:.3} / {:.3}",
            s.joint, s.rms_current, s.continuous_rating, s.peak_current, s.peak_rating, s.peak_speed, s.speed_limit
        );
        // the ratings are the robot file's datasheet values, not derived ones
        let d = chain
            .joints()
            .iter()
            .find(|j| j.name() == s.joint)
            .unwrap()
            .drive()
            .unwrap();
        assert_eq!(Some(s.continuous_rating), d.nominal_current);
        assert_eq!(Some(s.peak_rating), d.peak_current);
    }
    ttcan::sizing::check(&sizing).unwrap();
}

#[test]
fn an_undersized_motor_fails_the_sizing_with_its_joint_named() {
    // θ5 on the RE 25 + 14:1 (1.2 A continuous) with gravity: too small.
    let chain = ttkin::robots::gantry6();
    let mut drives: Vec<ttkin::Drive> = chain.joints().iter().map(|j| *j.drive().unwrap()).collect();
    drives[4] = ttkin::robots::drives::maxon_re25(
        14.0,
        0.81,
        ttkin::robots::drives::Friction {
            viscous: 0.02,
            coulomb: 0.1,
        },
    );
    let small = chain.with_drives(&drives).unwrap();
    let (_t, q, qd, qdd, _tau, _) = stroke_samples();
    let configs = ttcan::coupled::axis_configs_from_chain(&small, &q[..6], &CoupledOptions::default()).unwrap();
    let sizing = ttcan::sizing::size_drives(&small, &configs, &q, &qd, &qdd, &G).unwrap();
    let s = &sizing[4];
    println!("θ5 on the RE 25 + 14:1: {s:?}");
    assert!(s.rms_current > s.continuous_rating && !s.passes());
    assert!(sizing.iter().enumerate().all(|(k, s)| k == 4 || s.passes()));
    let e = ttcan::sizing::check(&sizing).unwrap_err().to_string();
    assert!(e.contains("'theta5'") && e.contains("continuous"), "{e}");
}

#[test]
fn a_current_noise_in_amps_reaches_every_axis_built_from_the_drive_sections() {
    let chain = ttkin::robots::gantry6();
    let q0 = vec![0.0; chain.dof()];
    for amps in [0.0, ttcan::motor::DEFAULT_CURRENT_NOISE, 0.012] {
        let options = CoupledOptions::default().with_current_noise(amps);
        let configs = ttcan::coupled::axis_configs_from_chain(&chain, &q0, &options).unwrap();
        for c in &configs {
            assert!(
                (c.model.current_noise - amps).abs() < 1e-15,
                "{} != {amps}",
                c.model.current_noise
            );
        }
    }
    let negative = CoupledOptions::default().with_current_noise(-0.001);
    assert!(ttcan::coupled::axis_configs_from_chain(&chain, &q0, &negative).is_err());
}

/// The rally's strokes through the drives (`ttcan::coupled::execute`): the racket still meets the
/// balls, near the planned contact point.
#[test]
fn rally_strokes_through_the_drives_return_the_balls() {
    use ttkin::ball::rally::{Rally, RallyConfig};
    let r = Rally::new(RallyConfig {
        paths: 0,
        ..RallyConfig::default()
    })
    .unwrap();
    let ex = ttcan::coupled::execute::DriveExecutor::with_defaults(r.planner.chain()).unwrap();
    let (mut ok, mut returned, mut ideal) = (0, 0, 0);
    for i in 0..8 {
        let a = r.play(i, None, None);
        let b = r.play(i, None, Some(&ex));
        assert_eq!(a.incoming, b.incoming);
        if a.status == "returned" {
            ideal += 1;
            ok += 1;
            returned += usize::from(b.returned);
            assert!(
                b.contact && b.racket_error < 0.05,
                "ball {i}: {} {}",
                b.status,
                b.racket_error
            );
        }
    }
    assert!(
        ok >= 4 && returned + 1 >= ideal,
        "{returned} of {ideal} returned through the drives"
    );
}
