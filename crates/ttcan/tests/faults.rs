//! Faults whose reaction is a controlled stop (issue 7, kept for issue 10): following error and
//! NaN references. The bridge-off faults and the monitors of issue 10 are in `reactions.rs`.

mod common;
use common::*;
use ttcan::{AxisState, Fault, Mode, Setpoint, Simulation};

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
