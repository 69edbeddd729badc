//! Bad input is rejected with a clear error when something is built, never inside the loop.

mod common;
use common::*;
use ttcan::{Axis, AxisConfig, Error, MotorModel, Plant, Rates, Simulation, Stepper};

fn axis_error(f: impl FnOnce(&mut AxisConfig)) -> Error {
    let mut c = AxisConfig::new(model());
    f(&mut c);
    Axis::new(&c).expect_err("configuration must be rejected")
}

fn assert_names(e: &Error, what: &str) {
    let msg = e.to_string();
    assert!(msg.contains(what), "error `{msg}` should name `{what}`");
}

type Change = Box<dyn Fn(&mut MotorModel)>;

#[test]
fn non_physical_motor_parameters_are_rejected() {
    let cases: Vec<(&str, Change)> = vec![
        ("resistance", Box::new(|m| m.motor.resistance = -2.32)),
        ("inductance", Box::new(|m| m.motor.inductance = 0.0)),
        ("rotor inertia", Box::new(|m| m.motor.rotor_inertia = 0.0)),
        ("torque constant", Box::new(|m| m.motor.torque_constant = f64::NAN)),
        ("back-EMF", Box::new(|m| m.motor.back_emf_constant = -1.0)),
        ("Coulomb", Box::new(|m| m.motor.coulomb_friction = -1e-3)),
        ("gear ratio", Box::new(|m| m.gearbox.ratio = 0.0)),
        ("gear efficiency", Box::new(|m| m.gearbox.efficiency = 1.2)),
        ("load inertia", Box::new(|m| m.load.inertia = -1.0)),
        ("bus voltage", Box::new(|m| m.bus_voltage = 0.0)),
        ("max duty", Box::new(|m| m.max_duty = 0.0)),
        ("encoder", Box::new(|m| m.encoder_counts_per_rev = 2)),
    ];
    for (what, change) in cases {
        let mut m = model();
        change(&mut m);
        let e = m.validate().expect_err(what);
        assert_names(&e, what);
        assert_names(&Plant::new(&m, 5e-5).expect_err(what), what);
        assert_names(&axis_error(|c| c.model = m), what);
        assert_names(&Simulation::new(&m, &AxisConfig::new(model())).expect_err(what), what);
    }
}

#[test]
fn non_physical_limits_are_rejected() {
    assert_names(&axis_error(|c| c.continuous_current = 0.0), "continuous current");
    assert_names(&axis_error(|c| c.peak_current = 1.0), "peak current");
    assert_names(&axis_error(|c| c.overcurrent_trip = 3.0), "over-current trip");
    assert_names(&axis_error(|c| c.max_speed = f64::INFINITY), "max speed");
    // 40 rad/s at the output is 560 rad/s at the motor: 24.6 V of back-EMF, more than 22.8 V.
    assert_names(&axis_error(|c| c.max_speed = 40.0), "back-EMF");
    assert_names(&axis_error(|c| c.following_error_limit = -0.1), "following error");
    assert_names(&axis_error(|c| c.quick_stop_deceleration = 0.0), "quick-stop");
    assert_names(
        &axis_error(|c| c.speed_reference_filter_hz = Some(f64::NAN)),
        "speed reference filter",
    );
    assert_names(&axis_error(|c| c.emf_filter_hz = 0.0), "EMF filter");
}

#[test]
fn unreachable_tuning_targets_are_rejected() {
    assert_names(
        &axis_error(|c| c.tuning.current_bandwidth_hz = 5000.0),
        "sixth of the current loop rate",
    );
    assert_names(
        &axis_error(|c| c.tuning.current_bandwidth_hz = -1.0),
        "current loop bandwidth",
    );
    assert_names(
        &axis_error(|c| c.tuning.speed_symmetric_optimum = 1.5),
        "symmetric optimum",
    );
    assert_names(&axis_error(|c| c.tuning.position_ratio = f64::NAN), "position ratio");
    assert_names(
        &axis_error(|c| c.tuning.speed_output_filter_hz = 0.0),
        "speed output filter",
    );
    assert_names(
        &axis_error(|c| c.tuning.observer_bandwidth_hz = 0.0),
        "observer bandwidth",
    );
    assert_names(
        &axis_error(|c| c.tuning.observer_bandwidth_hz = 5000.0),
        "observer bandwidth",
    );
}

#[test]
fn rates_that_are_not_integer_multiples_are_rejected() {
    assert!(Rates::new(20_000.0, 5_000.0, 1_000.0).is_ok());
    assert!(Rates::new(16_000.0, 16_000.0, 4_000.0).is_ok());
    for (c, s, p) in [
        (20_000.0, 6_000.0, 1_000.0),
        (20_000.0, 5_000.0, 1_500.0),
        (5_000.0, 20_000.0, 1_000.0),
        (20_000.0, 0.0, 1_000.0),
        (f64::NAN, 5_000.0, 1_000.0),
    ] {
        let e = Rates::new(c, s, p).expect_err("bad rates");
        assert!(
            matches!(
                e,
                Error::Rates(_) | Error::InvalidParameter { .. } | Error::NonFinite { .. }
            ),
            "{e}"
        );
    }
    let r = Rates::new(10_000.0, 2_500.0, 500.0).unwrap();
    assert_eq!(r.position_ticks(), 20);
    assert!((r.position_hz() - 500.0).abs() < 1e-9);
}

#[test]
fn a_stepper_rejects_axes_on_different_rates() {
    let a = Axis::new(&AxisConfig::new(model())).unwrap();
    let mut c = AxisConfig::new(model());
    c.rates = Rates::new(10_000.0, 2_500.0, 500.0).unwrap();
    let b = Axis::new(&c).unwrap();
    assert!(matches!(Stepper::new([a.clone(), b]), Err(Error::Stepper(_))));
    assert!(Stepper::new([a.clone(), a]).is_ok());
    assert!(matches!(Stepper::<0>::new([]), Err(Error::Stepper(_))));
}

#[test]
fn bad_trajectories_are_rejected_before_anything_runs() {
    let mut s = sim();
    assert!(s.enable(ttcan::Mode::Position));
    let t = s.time();
    let e = s.run_position(&[0.0, f64::NAN], &[0.0, 0.0], &[0.0, 0.0]).unwrap_err();
    assert_names(&e, "q[1]");
    let e = s.run_position(&[0.0, 0.0], &[0.0], &[0.0, 0.0]).unwrap_err();
    assert_names(&e, "equal lengths");
    assert!(s.run(f64::NAN, |_| ttcan::Setpoint::Current(0.0)).is_err());
    assert!(s.run(-1.0, |_| ttcan::Setpoint::Current(0.0)).is_err());
    assert_eq!(s.time(), t, "nothing ran");
}

#[test]
fn issue_10_bad_configurations_are_rejected_when_the_axis_is_built() {
    // Non-positive inductance, an encoder with zero counts, brake delays longer than the stop
    // time, thermal constants missing (see also tests/thermal.rs), bad monitors.
    assert_names(&axis_error(|c| c.model.motor.inductance = -1e-4), "motor inductance");
    assert_names(&axis_error(|c| c.model.encoder_counts_per_rev = 0), "encoder counts");
    let long = ttcan::HoldingBrake {
        release_delay: 0.01,
        engage_delay: 5.0,
    };
    assert_names(&axis_error(|c| c.holding_brake = Some(long)), "brake engage delay");
    let long = ttcan::HoldingBrake {
        release_delay: 5.0,
        engage_delay: 0.01,
    };
    assert_names(&axis_error(|c| c.holding_brake = Some(long)), "brake release delay");
    assert_names(
        &axis_error(|c| c.thermal.winding_time_constant = 0.0),
        "thermal time constant winding",
    );
    assert_names(&axis_error(|c| c.overspeed_limit = 10.0), "overspeed limit");
    assert_names(&axis_error(|c| c.bus_overvoltage = 20.0), "bus over-voltage");
    assert_names(&axis_error(|c| c.position_limits = Some((1.0, -1.0))), "position limit");
    assert_names(&axis_error(|c| c.setpoint_period = Some(0.0)), "setpoint period");
    assert_names(
        &axis_error(|c| c.tuning.observer_bandwidth_hz = 1000.0),
        "observer bandwidth",
    );
}

#[test]
fn the_axis_configuration_is_serde_described_and_round_trips_through_toml() {
    let mut c = AxisConfig::new(model());
    c.setpoint_period = Some(4e-3);
    c.holding_brake = Some(ttcan::HoldingBrake {
        release_delay: 0.02,
        engage_delay: 0.03,
    });
    c.position_limits = Some((-1.0, 2.0));
    let text = toml::to_string(&c).unwrap();
    let back: AxisConfig = toml::from_str(&text).unwrap();
    assert_eq!(back, c);
    assert!(Axis::new(&back).is_ok());
    // Rates are checked when read; unknown keys are refused.
    let bad = text.replace("speed_hz = 5000.0", "speed_hz = 3000.0");
    assert!(toml::from_str::<AxisConfig>(&bad)
        .unwrap_err()
        .to_string()
        .contains("not an integer"));
    let bad = text.replace("[model.motor]", "[model.motor]\nresistence = 1.0");
    assert!(toml::from_str::<AxisConfig>(&bad).is_err());
}
