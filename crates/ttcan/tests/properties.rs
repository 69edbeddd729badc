//! Properties of the plant discretisation, the current-loop design and the PI, over random
//! parameters (proptest).

use proptest::prelude::*;
use ttcan::loops::Pi;
use ttcan::tuning::current_gains;
use ttcan::{DcMotor, Gearbox, Load, MotorModel, Plant};

fn motor_model(r: f64, l: f64, kt: f64, j: f64) -> MotorModel {
    MotorModel {
        motor: DcMotor {
            resistance: r,
            inductance: l,
            torque_constant: kt,
            back_emf_constant: kt,
            rotor_inertia: j,
            viscous_friction: 1e-6,
            coulomb_friction: 0.0,
        },
        gearbox: Gearbox {
            ratio: 10.0,
            efficiency: 0.9,
            inertia: 0.0,
        },
        load: Load {
            inertia: 1e-4,
            viscous_friction: 0.0,
        },
        bus_voltage: 24.0,
        max_duty: 1.0,
        encoder_counts_per_rev: 4096,
        current_noise: 0.0,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Exact discretisation: one step of h equals k steps of h/k (the flow composes).
    #[test]
    fn plant_steps_compose(r in 0.5f64..10.0, l in 5e-5f64..5e-3, kt in 0.005f64..0.1, j in 1e-7f64..1e-5,
                           duty in -1.0f64..1.0, k in 2usize..20) {
        let m = motor_model(r, l, kt, j);
        let h = 1e-4;
        let mut coarse = Plant::new(&m, h).unwrap();
        let mut fine = Plant::new(&m, h / k as f64).unwrap();
        coarse.set_output_state(0.0, 1.0);
        fine.set_output_state(0.0, 1.0);
        for _ in 0..10 {
            coarse.step(duty);
            for _ in 0..k { fine.step(duty); }
        }
        let scale = 1.0 + coarse.current().abs();
        prop_assert!((coarse.current() - fine.current()).abs() < 1e-9 * scale);
        prop_assert!((coarse.motor_speed() - fine.motor_speed()).abs() < 1e-9 * (1.0 + coarse.motor_speed().abs()));
        prop_assert!((coarse.output_position() - fine.output_position()).abs() < 1e-9);
    }

    /// The steady state under a constant voltage is the analytic one: ω = Kt u / (Kt Ke + R b).
    #[test]
    fn plant_reaches_the_analytic_steady_speed(r in 0.5f64..10.0, kt in 0.01f64..0.1, duty in 0.1f64..1.0) {
        let m = motor_model(r, 2e-4, kt, 1e-6);
        let mut p = Plant::new(&m, 1e-3).unwrap();
        for _ in 0..20_000 { p.step(duty); }
        let b = m.motor_side_viscous();
        let u = duty * 24.0;
        let w = kt * u / (kt * kt + r * b);
        prop_assert!((p.motor_speed() - w).abs() < 1e-6 * w, "{} vs {}", p.motor_speed(), w);
        prop_assert!((p.current() - b * w / kt).abs() < 1e-6);
    }

    /// With the rotor held (huge load), the discrete current loop gives exactly the designed first
    /// order response i_k = 1 − e^{−ω_c k T}: pole-zero cancellation holds for any motor.
    #[test]
    fn current_loop_cancels_the_electrical_pole(r in 0.5f64..10.0, l in 5e-5f64..5e-3, bw in 100.0f64..3000.0) {
        let mut m = motor_model(r, l, 0.02, 1e-6);
        m.load.inertia = 1e9;
        m.bus_voltage = 1e4;
        let t = 5e-5;
        let (kp, ki) = current_gains(&m, t, bw).unwrap();
        let mut pi = Pi::new(kp, ki, t, true);
        let mut p = Plant::new(&m, t).unwrap();
        let pole = (-2.0 * std::f64::consts::PI * bw * t).exp();
        for k in 0..40 {
            let expected = 1.0 - pole.powi(k);
            prop_assert!((p.current() - expected).abs() < 1e-6, "k {}: {} vs {}", k, p.current(), expected);
            let u = pi.step(1.0 - p.current(), -1e4, 1e4);
            p.step(u / 1e4);
        }
    }

    /// With anti-windup the integrator never leaves the output range, whatever the errors.
    #[test]
    fn anti_windup_keeps_the_integrator_in_range(errors in proptest::collection::vec(-100.0f64..100.0, 1..200)) {
        let mut pi = Pi::new(0.5, 200.0, 1e-3, true);
        for e in errors {
            let u = pi.step(e, -2.0, 3.0);
            prop_assert!((-2.0..=3.0).contains(&u));
            prop_assert!((-2.0..=3.0).contains(&pi.integral()));
        }
    }
}

#[test]
fn tuning_reports_the_designed_bandwidths_and_margins() {
    let a = ttcan::Axis::new(&ttcan::AxisConfig::new(MotorModel::maxon_re25_gp26())).unwrap();
    let t = a.tuning();
    // Current loop: first order at 1 kHz, phase margin near 90° less the sampling.
    assert!((t.current.bandwidth_hz - 1000.0).abs() < 50.0, "{:?}", t.current);
    assert!(t.current.phase_margin_deg > 75.0);
    // Speed loop: symmetric optimum a = 3, crossover 1/(a T_σ), margin near atan(4/3) = 53.1°.
    let wc = 1.0 / (3.0 * t.t_sigma) / (2.0 * std::f64::consts::PI);
    assert!((t.speed.crossover_hz - wc).abs() < 0.15 * wc, "{:?} vs {wc}", t.speed);
    assert!((t.speed.phase_margin_deg - 53.1).abs() < 5.0, "{:?}", t.speed);
    // Position loop: well damped, crossover near Kp.
    assert!(t.position.phase_margin_deg > 45.0, "{:?}", t.position);
    let kp_hz = t.position.kp / (2.0 * std::f64::consts::PI);
    assert!(
        (t.position.crossover_hz - kp_hz).abs() < 0.3 * kp_hz,
        "{:?}",
        t.position
    );
}
