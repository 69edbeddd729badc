//! Fault reactions as drives do them (issue 10): every fault injected, its reaction asserted —
//! which outputs go to zero within how many ticks, what the joint does, nothing driven on a failed
//! sensor.

mod common;
use common::*;
use ttcan::axis::{HoldingBrake, Reaction};
use ttcan::{AxisState, Fault, Mode, Setpoint, Simulation};

/// Steps until the state is `Faulted(fault)` (at most `max` s); returns the time it took.
fn until_faulted(s: &mut Simulation, fault: Fault, max: f64) -> f64 {
    let t0 = s.time();
    while s.time() - t0 < max {
        if s.axis.state() == AxisState::Faulted(fault) {
            return s.time() - t0;
        }
        s.step();
    }
    panic!("not Faulted({fault:?}) within {max} s: {:?}", s.axis.state());
}

/// After a bridge-off fault: duty 0 on every later tick and an open winding (current 0 within a
/// few ticks, the joint coasting on with its speed only slowly decaying).
fn assert_bridge_off_and_coasting(s: &mut Simulation, fault: Fault) {
    assert_eq!(s.axis.state(), AxisState::Faulted(fault));
    assert!(!s.axis.bridge_on());
    let w0 = s.plant.output_speed();
    let tr = s.run(0.01, |_| Setpoint::Velocity(15.0)).unwrap();
    assert!(tr.duty.iter().all(|d| *d == 0.0), "duty must stay 0");
    assert!(tr.current_reference.iter().all(|i| *i == 0.0));
    // Open winding: the current is gone within 5 ticks (free-wheeling against the bus) ...
    assert!(
        tr.current[5..].iter().all(|i| *i == 0.0),
        "current {:?}",
        &tr.current[..8]
    );
    // ... and the joint coasts (no shorted-winding braking): after 10 ms it still runs at > 90 %.
    let w = s.plant.output_speed();
    assert!(w > 0.9 * w0 && w0 > 10.0, "speed {w0} → {w} rad/s: must coast");
}

#[test]
fn each_fault_has_one_reaction() {
    use Fault::*;
    for f in [OverCurrent, EncoderJump, InvalidMeasurement, OverVoltage] {
        assert_eq!(f.reaction(), Reaction::BridgeOff, "{f:?}");
    }
    for f in [
        FollowingError,
        InvalidReference,
        SetpointsLost,
        Overspeed,
        PositionLimit,
        UnderVoltage,
    ] {
        assert_eq!(f.reaction(), Reaction::QuickStop, "{f:?}");
    }
}

#[test]
fn over_current_switches_the_bridge_off_in_the_same_tick_and_the_joint_coasts() {
    let mut s = running();
    s.plant.set_current_sense_offset(8.0);
    s.step();
    s.plant.set_current_sense_offset(0.0);
    assert_eq!(s.axis.duty(), 0.0, "duty 0 on the tick that saw the over-current");
    assert_bridge_off_and_coasting(&mut s, Fault::OverCurrent);
}

#[test]
fn encoder_jump_switches_the_bridge_off_and_nothing_is_driven_on_the_encoder() {
    let mut s = running();
    s.plant.inject_encoder_jump(5000);
    s.step();
    assert_eq!(s.axis.duty(), 0.0);
    assert_bridge_off_and_coasting(&mut s, Fault::EncoderJump);
}

#[test]
fn nan_current_reading_switches_the_bridge_off_at_once() {
    let mut s = running();
    let m = ttcan::Measurement {
        current: f64::NAN,
        encoder_counts: s.plant.measure().encoder_counts,
        bus_voltage: Some(24.0),
    };
    assert_eq!(s.axis.tick(m, ttcan::Due::ALL), 0.0);
    assert_bridge_off_and_coasting(&mut s, Fault::InvalidMeasurement);
}

#[test]
fn bus_over_voltage_switches_the_bridge_off() {
    let mut s = running();
    s.plant.set_bus_voltage(31.0);
    s.step();
    assert_eq!(s.axis.duty(), 0.0);
    s.plant.set_bus_voltage(24.0);
    assert_bridge_off_and_coasting(&mut s, Fault::OverVoltage);
}

#[test]
fn bus_under_voltage_stops_the_axis_under_control() {
    let mut s = running();
    s.plant.set_bus_voltage(16.0);
    s.step();
    assert_eq!(s.axis.state(), AxisState::Stopping(Fault::UnderVoltage));
    until_faulted(&mut s, Fault::UnderVoltage, 0.5);
    assert!(
        s.plant.output_speed().abs() < 0.5,
        "stopped: {}",
        s.plant.output_speed()
    );
}

#[test]
fn measured_bus_voltage_scales_the_duty() {
    let mut s = running();
    let (d24, _) = (s.axis.duty(), ());
    // Same motion on a 20 V bus: the same voltage needs 24/20 of the duty.
    s.plant.set_bus_voltage(20.0);
    s.run(0.05, |_| Setpoint::Velocity(15.0)).unwrap();
    assert_eq!(s.axis.state(), AxisState::Enabled);
    assert!((s.plant.output_speed() - 15.0).abs() < 0.5);
    let d20 = s.axis.duty();
    assert!((d20 / d24 - 1.2).abs() < 0.1, "duty {d24} on 24 V, {d20} on 20 V");
}

#[test]
fn a_fault_while_stopping_escalates_to_bridge_off() {
    let mut s = running();
    s.apply(Setpoint::Velocity(f64::NAN));
    assert_eq!(s.axis.state(), AxisState::Stopping(Fault::InvalidReference));
    for _ in 0..40 {
        s.step();
    }
    assert!(matches!(s.axis.state(), AxisState::Stopping(_)));
    // A second fault during the stop (the speed loop now needs a current it cannot get).
    s.plant.set_current_sense_offset(8.0);
    s.step();
    s.plant.set_current_sense_offset(0.0);
    assert_bridge_off_and_coasting(&mut s, Fault::OverCurrent);
}

#[test]
fn overspeed_trips_in_current_mode_and_the_axis_stops() {
    let mut s = sim();
    assert!(s.enable(Mode::Current));
    let tr = s.run(0.5, |_| Setpoint::Current(1.0)).unwrap();
    let k = tr.state.iter().position(|st| *st == 2).expect("must stop");
    let limit = s.axis.config().overspeed_limit;
    assert!(tr.speed[k] > 0.95 * limit, "tripped at {} rad/s", tr.speed[k]);
    until_faulted(&mut s, Fault::Overspeed, 0.5);
    assert!(s.plant.output_speed().abs() < 0.5);
}

#[test]
fn quick_stop_ends_at_a_speed_that_means_stopped() {
    let mut s = running();
    s.apply(Setpoint::Velocity(f64::NAN));
    let mut last_stopping_speed = f64::NAN;
    while let AxisState::Stopping(_) = s.axis.state() {
        last_stopping_speed = s.plant.output_speed();
        s.step();
    }
    let max = s.axis.config().max_speed;
    // Below 1 % of the largest speed, or three counts per speed period (the estimate's floor).
    let counts = 3.0 * s.plant.model().radians_per_count() * s.axis.rates().speed_hz();
    assert!(
        last_stopping_speed.abs() <= (0.01 * max).max(counts) + 0.05,
        "left the stop at {last_stopping_speed} rad/s"
    );
}

#[test]
fn lost_setpoints_quick_stop_near_the_last_setpoint() {
    let mut s = sim_with(|c| c.setpoint_period = Some(1e-3));
    assert!(s.enable(Mode::Position));
    while !s.next_due().position {
        s.step();
    }
    // A ramp at 5 rad/s for 50 ms, setpoints every millisecond, then nothing.
    let q0 = s.axis.position();
    let mut last = q0;
    for k in 0..50 {
        last = q0 + 5.0 * (k as f64 + 1.0) * 1e-3;
        s.axis.set_position(last, 5.0, 0.0);
        for _ in 0..20 {
            s.step();
        }
    }
    let t_lost = s.time();
    let mut tripped = None;
    while s.time() - t_lost < 0.5 {
        s.step();
        if tripped.is_none() && s.axis.state() == AxisState::Stopping(Fault::SetpointsLost) {
            tripped = Some(s.time() - t_lost);
        }
        if let AxisState::Faulted(_) = s.axis.state() {
            break;
        }
    }
    let t = tripped.expect("the watchdog must trip");
    // Three missed 1 ms setpoints (+ half a period of jitter allowance).
    assert!(t > 2.4e-3 && t < 3.6e-3, "tripped after {t} s");
    assert_eq!(s.axis.state(), AxisState::Faulted(Fault::SetpointsLost));
    // Stale setpoints move nothing: the reference stops at the last setpoint with zero
    // feed-forward, then the watchdog stops the axis; what remains is the braking distance from
    // 5 rad/s (before issue 10: 24.5 mrad past it and no fault).
    let past = s.plant.output_position() - last;
    assert!(past.abs() < 15e-3, "ended {past} rad past the last setpoint");
}

#[test]
fn software_position_limit_stops_the_axis() {
    let mut s = sim_with(|c| c.position_limits = Some((-0.5, 0.2)));
    assert!(s.enable(Mode::Position));
    let t0 = s.time();
    let tr = s.run(0.3, |t| Setpoint::Position(2.0 * (t - t0), 2.0, 0.0)).unwrap();
    assert!(tr.state.contains(&2));
    until_faulted(&mut s, Fault::PositionLimit, 0.5);
    let q = s.plant.output_position();
    assert!(q > 0.2 && q < 0.25, "stopped at {q} rad, limit 0.2 rad");
}

#[test]
fn following_error_limit_grows_with_speed() {
    // 2 mrad at rest + 5 ms of lag: a 10 rad/s ramp with a 20 mrad lag is allowed, at rest it is not.
    let mut s = sim_with(|c| {
        c.following_error_limit = 2e-3;
        c.following_error_per_speed = 5e-3;
    });
    assert!(s.enable(Mode::Position));
    let t0 = s.time();
    let q0 = s.axis.position();
    s.run(0.1, |t| Setpoint::Position(q0 + 10.0 * (t - t0) - 0.02, 10.0, 0.0))
        .unwrap();
    assert_eq!(
        s.axis.state(),
        AxisState::Enabled,
        "20 mrad behind at 10 rad/s is within 52 mrad"
    );
    let q = s.axis.position();
    s.apply(Setpoint::Position(q - 0.01, 0.0, 0.0));
    s.run(0.05, |_| Setpoint::Position(q + 0.5, 0.0, 0.0)).unwrap();
    assert!(matches!(
        s.axis.state(),
        AxisState::Stopping(Fault::FollowingError) | AxisState::Faulted(Fault::FollowingError)
    ));
}

#[test]
fn brake_is_released_after_the_bridge_holds_and_engaged_before_the_bridge_is_released() {
    let brake = HoldingBrake {
        release_delay: 0.02,
        engage_delay: 0.03,
    };
    let mut s = sim_with(|c| c.holding_brake = Some(brake));
    assert!(s.axis.brake_engaged());
    assert!(s.enable(Mode::Position));
    assert!(s.axis.bridge_on() && !s.axis.brake_engaged());
    // While the brake releases, a setpoint does not move the axis.
    let q0 = s.axis.position();
    let tr = s.run(0.015, |_| Setpoint::Position(q0 + 0.3, 0.0, 0.0)).unwrap();
    assert!(tr.position.iter().all(|q| (q - q0).abs() < 1e-3));
    // Disable: the brake engages first, the bridge stays on (holding) until it holds.
    s.run(0.02, |_| Setpoint::Position(q0, 0.0, 0.0)).unwrap();
    s.axis.disable();
    assert!(s.axis.brake_engaged() && s.axis.bridge_on());
    let t0 = s.time();
    while s.axis.bridge_on() {
        s.step();
        assert!(s.time() - t0 < 0.1);
    }
    let held = s.time() - t0;
    assert!(
        held >= brake.engage_delay - 1e-9,
        "bridge released {held} s after the brake command"
    );
    assert!(s.axis.brake_holding());
    assert_eq!(s.axis.state(), AxisState::Disabled);
}

#[test]
fn a_quick_stop_engages_the_brake_before_the_bridge_goes_off() {
    let brake = HoldingBrake {
        release_delay: 0.01,
        engage_delay: 0.03,
    };
    let mut s = running_with(|c| c.holding_brake = Some(brake));
    s.apply(Setpoint::Velocity(f64::NAN));
    let mut t_engage = None;
    while s.axis.bridge_on() {
        s.step();
        if t_engage.is_none() && s.axis.brake_engaged() {
            t_engage = Some(s.time());
        }
    }
    let t_off = s.time();
    let t_engage = t_engage.expect("the brake must engage while the bridge is on");
    assert!(t_off - t_engage >= brake.engage_delay - 1e-4, "{t_engage} → {t_off}");
}

#[test]
fn a_gravity_loaded_joint_falls_when_the_bridge_goes_off() {
    let mut s = sim();
    assert!(s.enable(Mode::Position));
    s.plant.set_external_torque(-0.3);
    s.run(0.2, |_| Setpoint::Position(0.0, 0.0, 0.0)).unwrap();
    assert!(s.plant.output_speed().abs() < 0.05, "held against the load");
    s.plant.set_current_sense_offset(8.0);
    s.step();
    s.plant.set_current_sense_offset(0.0);
    assert_eq!(s.axis.state(), AxisState::Faulted(Fault::OverCurrent));
    s.run(0.1, |_| Setpoint::Position(0.0, 0.0, 0.0)).unwrap();
    assert!(s.plant.output_speed() < -0.5, "falls: {} rad/s", s.plant.output_speed());
}
