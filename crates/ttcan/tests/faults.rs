//! Each fault trips the axis and brings it to a controlled stop (issue 7 acceptance): over-current,
//! following error, encoder jump, NaN reference, NaN measurement.

mod common;
use common::*;
use ttcan::{AxisState, Fault, Mode, Setpoint, Simulation};

/// Runs at 15 rad/s for 200 ms in velocity mode.
fn running() -> Simulation {
    let mut s = sim();
    assert!(s.enable(Mode::Velocity));
    s.run(0.2, |_| Setpoint::Velocity(15.0)).unwrap();
    assert_eq!(s.axis.state(), AxisState::Enabled);
    assert!(
        (s.plant.output_speed() - 15.0).abs() < 0.5,
        "speed {}",
        s.plant.output_speed()
    );
    s
}

/// Runs until the axis leaves `Stopping` (at most 1 s); returns the stop duration.
fn run_until_stopped(s: &mut Simulation, fault: Fault) -> f64 {
    let t0 = s.time();
    let mut saw_stopping = false;
    while s.time() - t0 < 1.0 {
        s.step();
        match s.axis.state() {
            AxisState::Stopping(f) => {
                assert_eq!(f, fault);
                saw_stopping = true;
                // Controlled: the speed only falls while stopping.
                assert!(s.plant.output_speed() < 15.5);
            }
            AxisState::Faulted(f) => {
                assert_eq!(f, fault);
                assert!(saw_stopping || fault == Fault::InvalidMeasurement);
                return s.time() - t0;
            }
            other => panic!("unexpected state {other:?}"),
        }
    }
    panic!("axis did not stop within 1 s (state {:?})", s.axis.state());
}

/// After the stop: bridge off, axis at rest and it stays there.
fn assert_at_rest(s: &mut Simulation, fault: Fault) {
    let tr = s.run(0.1, |_| Setpoint::Velocity(15.0)).unwrap();
    assert_eq!(s.axis.state(), AxisState::Faulted(fault));
    assert!(tr.duty.iter().all(|d| *d == 0.0));
    assert!(
        s.plant.output_speed().abs() < 0.5,
        "speed {} rad/s after the stop",
        s.plant.output_speed()
    );
    assert!(
        !s.axis.enable(Mode::Velocity),
        "a faulted axis must not re-enable before clear_fault"
    );
}

#[test]
fn over_current_trips_and_stops_the_axis() {
    let mut s = running();
    // One sample of a shorted winding as the current sense sees it.
    s.plant.set_current_sense_offset(8.0);
    s.step();
    s.plant.set_current_sense_offset(0.0);
    assert_eq!(s.axis.state(), AxisState::Stopping(Fault::OverCurrent));
    let t = run_until_stopped(&mut s, Fault::OverCurrent);
    // 15 rad/s at 200 rad/s² is 75 ms, plus the settling of the speed estimate.
    assert!(t > 0.05 && t < 0.2, "stop took {t} s");
    assert_at_rest(&mut s, Fault::OverCurrent);
}

#[test]
fn following_error_trips_and_stops_the_axis() {
    let mut s = sim();
    assert!(s.enable(Mode::Position));
    let t0 = s.time();
    // A ramp at 40 rad/s: faster than the axis' 30 rad/s, so it must fall behind.
    let tr = s.run(0.1, |t| Setpoint::Position(40.0 * (t - t0), 40.0, 0.0)).unwrap();
    assert!(tr.state.contains(&2), "the axis must be stopping");
    let state = s.axis.state();
    assert!(matches!(
        state,
        AxisState::Stopping(Fault::FollowingError) | AxisState::Faulted(Fault::FollowingError)
    ));
    if let AxisState::Stopping(_) = state {
        run_until_stopped(&mut s, Fault::FollowingError);
    }
    assert!(s.axis.following_error().abs() > 0.1);
    assert_at_rest(&mut s, Fault::FollowingError);
}

#[test]
fn encoder_jump_trips_and_stops_the_axis() {
    let mut s = running();
    let before = s.axis.position();
    s.plant.inject_encoder_jump(5000);
    s.step();
    assert_eq!(s.axis.state(), AxisState::Stopping(Fault::EncoderJump));
    // The jump is not taken for motion: the position stays continuous.
    assert!((s.axis.position() - before).abs() < 0.01);
    run_until_stopped(&mut s, Fault::EncoderJump);
    assert_at_rest(&mut s, Fault::EncoderJump);
}

#[test]
fn nan_references_trip_and_stop_the_axis() {
    for bad in [
        Setpoint::Velocity(f64::NAN),
        Setpoint::Current(f64::INFINITY),
        Setpoint::Position(0.0, f64::NAN, 0.0),
    ] {
        let mut s = running();
        s.apply(bad);
        assert_eq!(s.axis.state(), AxisState::Stopping(Fault::InvalidReference), "{bad:?}");
        run_until_stopped(&mut s, Fault::InvalidReference);
        assert_at_rest(&mut s, Fault::InvalidReference);
    }
}

#[test]
fn nan_current_reading_switches_the_bridge_off_at_once() {
    let mut s = running();
    let m = ttcan::Measurement {
        current: f64::NAN,
        encoder_counts: s.plant.measure().encoder_counts,
    };
    let duty = s.axis.tick(m, ttcan::Due::default());
    assert_eq!(duty, 0.0);
    assert_eq!(s.axis.state(), AxisState::Faulted(Fault::InvalidMeasurement));
    // The shorted winding brakes the motor to rest.
    s.run(0.5, |_| Setpoint::Velocity(15.0)).unwrap();
    assert!(s.plant.output_speed().abs() < 0.5);
}

#[test]
fn cleared_fault_allows_a_fresh_start() {
    let mut s = running();
    s.apply(Setpoint::Velocity(f64::NAN));
    run_until_stopped(&mut s, Fault::InvalidReference);
    assert!(!s.axis.enable(Mode::Velocity));
    assert!(s.axis.clear_fault());
    assert_eq!(s.axis.state(), AxisState::Disabled);
    assert!(s.axis.enable(Mode::Velocity));
    s.run(0.1, |_| Setpoint::Velocity(10.0)).unwrap();
    assert_eq!(s.axis.state(), AxisState::Enabled);
    assert!((s.plant.output_speed() - 10.0).abs() < 0.5);
}
