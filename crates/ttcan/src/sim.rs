//! Closed-loop simulation of one axis on a [`Plant`]: the plant steps once per current-loop period
//! with the duty the axis computed from the measurement taken at the start of that period.

use crate::axis::{Axis, AxisConfig, AxisState, Mode};
use crate::error::{finite, stopped, Error, Result};
use crate::motor::{MotorModel, Plant};
use crate::schedule::Scheduler;

/// Reference for one axis at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setpoint {
    /// Current, A.
    Current(f64),
    /// Output speed, rad/s.
    Velocity(f64),
    /// Output position, velocity, acceleration: rad, rad/s, rad/s².
    Position(f64, f64, f64),
}

impl Setpoint {
    /// The step of `amplitude` in `mode`: A, rad/s, or rad (with zero velocity and acceleration).
    pub fn step(mode: Mode, amplitude: f64) -> Setpoint {
        match mode {
            Mode::Current => Setpoint::Current(amplitude),
            Mode::Velocity => Setpoint::Velocity(amplitude),
            Mode::Position => Setpoint::Position(amplitude, 0.0, 0.0),
        }
    }
}

/// Recorded signals, one sample per current-loop period (before the step is applied).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trace {
    /// Time, s.
    pub time: Vec<f64>,
    /// True motor current, A.
    pub current: Vec<f64>,
    /// Current reference after limiting, A.
    pub current_reference: Vec<f64>,
    /// Duty cycle in [−1, 1].
    pub duty: Vec<f64>,
    /// True output speed, rad/s.
    pub speed: Vec<f64>,
    /// Speed reference after filtering and feedforward, rad/s.
    pub speed_reference: Vec<f64>,
    /// True output position, rad.
    pub position: Vec<f64>,
    /// Position reference, rad.
    pub position_reference: Vec<f64>,
    /// Following error q_ref − q_measured at the last position step, rad.
    pub following_error: Vec<f64>,
    /// Axis state code: 0 disabled, 1 enabled, 2 stopping, 3 faulted.
    pub state: Vec<u8>,
}

impl Trace {
    fn with_capacity(n: usize) -> Self {
        Trace {
            time: Vec::with_capacity(n),
            current: Vec::with_capacity(n),
            current_reference: Vec::with_capacity(n),
            duty: Vec::with_capacity(n),
            speed: Vec::with_capacity(n),
            speed_reference: Vec::with_capacity(n),
            position: Vec::with_capacity(n),
            position_reference: Vec::with_capacity(n),
            following_error: Vec::with_capacity(n),
            state: Vec::with_capacity(n),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True if nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Appends `tail`, recorded after this trace, to it.
    pub fn append(&mut self, tail: Trace) {
        self.time.extend(tail.time);
        self.current.extend(tail.current);
        self.current_reference.extend(tail.current_reference);
        self.duty.extend(tail.duty);
        self.speed.extend(tail.speed);
        self.speed_reference.extend(tail.speed_reference);
        self.position.extend(tail.position);
        self.position_reference.extend(tail.position_reference);
        self.following_error.extend(tail.following_error);
        self.state.extend(tail.state);
    }
}

/// 10 %–90 % rise time of `y` (sampled at times `t`, s) towards `target` (≠ 0): the time from the
/// first sample at or beyond 10 % of the target to the first at or beyond 90 %, s; infinite if
/// either is never reached. The one definition of rise time in ttmanip (Rust and Python).
pub fn rise_time(t: &[f64], y: &[f64], target: f64) -> f64 {
    let first = |level: f64| t.iter().zip(y).find(|(_, v)| **v / target >= level).map(|(t, _)| *t);
    match (first(0.1), first(0.9)) {
        (Some(a), Some(b)) => b - a,
        _ => f64::INFINITY,
    }
}

/// Largest excursion of `y` beyond `target` (≠ 0), as a fraction of `target` (0.05 = 5 %); NaN
/// for an empty signal. The one definition of overshoot in ttmanip (Rust and Python).
pub fn overshoot(y: &[f64], target: f64) -> f64 {
    y.iter().map(|v| v / target).fold(f64::NAN, f64::max) - 1.0
}

/// (10–90 % rise time in s, overshoot as a fraction) of `y` sampled at times `t` (s) towards
/// `target`: [`rise_time`] and [`overshoot`] with their arguments checked (equal lengths, a
/// finite target ≠ 0).
pub fn step_metrics(t: &[f64], y: &[f64], target: f64) -> Result<(f64, f64)> {
    if t.len() != y.len() {
        return Err(Error::InvalidParameter {
            what: "signal length".into(),
            value: y.len() as f64,
            reason: format!("t and y must have equal lengths (got {} and {})", t.len(), y.len()),
        });
    }
    if finite("step target", target)? == 0.0 {
        return Err(Error::InvalidParameter {
            what: "step target".into(),
            value: target,
            reason: "must be ≠ 0".into(),
        });
    }
    let o = overshoot(y, target);
    if o.is_infinite() {
        // |y / target| beyond the double range (a subnormal target): refused, not returned as inf.
        return Err(Error::InvalidParameter {
            what: "step target".into(),
            value: target,
            reason: "too small for the signal's scale: the overshoot ratio overflows".into(),
        });
    }
    Ok((rise_time(t, y, target), o))
}

/// One axis controlling one simulated actuator.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The simulated actuator (public for disturbances and fault injection).
    pub plant: Plant,
    /// The controller (public to read its state, enable it, clear faults).
    pub axis: Axis,
    scheduler: Scheduler,
    time: f64,
}

impl Simulation {
    /// Seed of the current-sense noise of a run whose caller names none (the Python
    /// `ServoSim.step` and `follow` default).
    pub const NOISE_SEED: u64 = 7;
    /// External torque at the output of a run without a load, N·m.
    pub const NO_LOAD: f64 = 0.0;
    /// Hold time after a followed trajectory when none is asked, s.
    pub const NO_SETTLE: f64 = 0.0;

    /// Simulates `plant_model` controlled by an axis built from `config` (whose own model may differ,
    /// to test robustness). The plant steps at the current-loop period.
    pub fn new(plant_model: &MotorModel, config: &AxisConfig) -> Result<Self> {
        let axis = Axis::new(config)?;
        let plant = Plant::new(plant_model, config.rates.periods()[0])?;
        Ok(Simulation {
            plant,
            axis,
            scheduler: Scheduler::new(&config.rates),
            time: 0.0,
        })
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Which loops run on the next [`Simulation::step`].
    pub fn next_due(&self) -> crate::schedule::Due {
        self.scheduler.peek()
    }

    /// Enables the axis in `mode` (after one disabled tick so that the encoder origin is known).
    pub fn enable(&mut self, mode: Mode) -> bool {
        if self.scheduler.ticks() == 0 {
            self.step();
        }
        self.axis.enable(mode)
    }

    /// Hands `setpoint` to the axis (a mode it is not in is stored for later, as on a real drive).
    pub fn apply(&mut self, setpoint: Setpoint) {
        match setpoint {
            Setpoint::Current(i) => self.axis.set_current(i),
            Setpoint::Velocity(w) => self.axis.set_velocity(w),
            Setpoint::Position(q, qd, qdd) => self.axis.set_position(q, qd, qdd),
        }
    }

    /// One current-loop period: measure, control, apply the duty over the period.
    pub fn step(&mut self) {
        let m = self.plant.measure();
        let due = self.scheduler.next_tick();
        let duty = self.axis.tick(m, due);
        if self.axis.bridge_on() {
            self.plant.step(duty);
        } else {
            self.plant.step_open();
        }
        self.time += self.plant.dt();
    }

    /// Runs for `duration` seconds, asking `reference(t)` for the setpoint every period, recording
    /// every period. A non-finite or negative duration is an error.
    pub fn run(&mut self, duration: f64, reference: impl FnMut(f64) -> Setpoint) -> Result<Trace> {
        self.run_until(duration, reference, &|| false)
    }

    /// [`Simulation::run`] that ends early with an error when `stop()` turns true (a caller's
    /// cancellation, e.g. Ctrl-C seen by the Python binding; polled every
    /// [`ttkin::budget::STOP_POLL_STEPS`] periods).
    pub fn run_until(
        &mut self,
        duration: f64,
        mut reference: impl FnMut(f64) -> Setpoint,
        stop: ttkin::budget::Stop<'_>,
    ) -> Result<Trace> {
        let n = self.periods_in(duration)?;
        let mut trace = Trace::with_capacity(n);
        for k in 0..n {
            if (k as u64 + 1).is_multiple_of(ttkin::budget::STOP_POLL_STEPS) && stop() {
                return Err(stopped());
            }
            self.apply(reference(self.time));
            self.record_into(&mut trace);
            self.step();
        }
        Ok(trace)
    }

    /// Step response: enables the axis in `mode` and holds [`Setpoint::step`] of `amplitude` for
    /// `duration` s, with `external_torque` (N·m at the output) acting throughout. Every argument
    /// is checked (finite, duration ≥ 0) before anything runs.
    pub fn step_response(&mut self, mode: Mode, amplitude: f64, duration: f64, external_torque: f64) -> Result<Trace> {
        self.step_response_until(mode, amplitude, duration, external_torque, &|| false)
    }

    /// [`Simulation::step_response`] that ends early with an error when `stop()` turns true.
    pub fn step_response_until(
        &mut self,
        mode: Mode,
        amplitude: f64,
        duration: f64,
        external_torque: f64,
        stop: ttkin::budget::Stop<'_>,
    ) -> Result<Trace> {
        finite("step amplitude", amplitude)?;
        finite("external torque (N·m)", external_torque)?;
        self.periods_in(duration)?;
        self.plant.set_external_torque(external_torque);
        self.enable(mode);
        let setpoint = Setpoint::step(mode, amplitude);
        self.run_until(duration, |_| setpoint, stop)
    }

    /// Follows a position trajectory (q, qd, qdd: rad, rad/s, rad/s², at least one sample, given
    /// at the position-loop rate as in [`Simulation::run_position`]) from rest at q\[0\] in position
    /// mode, then holds its last sample for `settle` s; `external_torque` (N·m at the output) acts
    /// throughout. Every argument is checked before anything runs.
    pub fn follow(&mut self, q: &[f64], qd: &[f64], qdd: &[f64], settle: f64, external_torque: f64) -> Result<Trace> {
        self.follow_until(q, qd, qdd, settle, external_torque, &|| false)
    }

    /// [`Simulation::follow`] that ends early with an error when `stop()` turns true.
    pub fn follow_until(
        &mut self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        settle: f64,
        external_torque: f64,
        stop: ttkin::budget::Stop<'_>,
    ) -> Result<Trace> {
        check_trajectory(q, qd, qdd)?;
        let (Some(&q0), Some(&q_end), Some(&qd_end), Some(&qdd_end)) = (q.first(), q.last(), qd.last(), qdd.last())
        else {
            return Err(Error::InvalidParameter {
                what: "trajectory length".into(),
                value: 0.0,
                reason: "must hold at least one sample".into(),
            });
        };
        finite("external torque (N·m)", external_torque)?;
        self.periods_in(settle)?;
        self.plant.set_external_torque(external_torque);
        self.plant.set_output_state(q0, 0.0);
        self.enable(Mode::Position);
        let mut trace = self.run_position_until(q, qd, qdd, stop)?;
        trace.append(self.run_until(settle, |_| Setpoint::Position(q_end, qd_end, qdd_end), stop)?);
        Ok(trace)
    }

    /// Runs a position trajectory given at the position-loop rate: sample k of (q, qd, qdd) (rad,
    /// rad/s, rad/s²) is handed to the axis just before its k-th position-loop step from now, and
    /// the run ends after the position period of the last sample. All three must have the same length and
    /// be finite (checked before anything runs).
    pub fn run_position(&mut self, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<Trace> {
        self.run_position_until(q, qd, qdd, &|| false)
    }

    /// [`Simulation::run_position`] that ends early with an error when `stop()` turns true.
    pub fn run_position_until(
        &mut self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        stop: ttkin::budget::Stop<'_>,
    ) -> Result<Trace> {
        check_trajectory(q, qd, qdd)?;
        let per = self.axis.rates().position_ticks() as usize;
        let mut trace = Trace::with_capacity(q.len() * per);
        let mut k = 0;
        let mut steps = 0u64;
        while k < q.len() || !self.scheduler.peek().position {
            steps += 1;
            if steps.is_multiple_of(ttkin::budget::STOP_POLL_STEPS) && stop() {
                return Err(stopped());
            }
            if self.scheduler.peek().position {
                self.axis.set_position(q[k], qd[k], qdd[k]);
                k += 1;
            }
            self.record_into(&mut trace);
            self.step();
        }
        Ok(trace)
    }

    fn periods_in(&self, duration: f64) -> Result<usize> {
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(Error::InvalidParameter {
                what: "duration (s)".into(),
                value: duration,
                reason: "must be finite and >= 0".into(),
            });
        }
        // Bounded before anything is allocated or run: the trace keeps nine f64 signals and a
        // state byte a period, within `ttkin::budget::MAX_BYTES` and `MAX_STEPS` (a 1e4 s step
        // response at 20 kHz asked for 16 GB and aborted the process; so did a 1e12 Hz loop).
        let periods = (duration / self.plant.dt()).round();
        let limit = |reason: String| Error::InvalidParameter {
            what: "duration (s)".into(),
            value: duration,
            reason,
        };
        ttkin::budget::check_bytes("duration", periods, 9 * 8 + 1).map_err(|e| limit(crate::error::ttkin_reason(e)))?;
        ttkin::budget::check_steps("duration", duration, self.plant.dt())
            .map_err(|e| limit(crate::error::ttkin_reason(e)))?;
        Ok(periods as usize)
    }

    /// Appends the present signals to `t` (what [`Simulation::run`] records every period).
    pub fn record_into(&self, t: &mut Trace) {
        let a = &self.axis;
        t.time.push(self.time);
        t.current.push(self.plant.current());
        t.current_reference.push(a.current_reference());
        t.duty.push(a.duty());
        t.speed.push(self.plant.output_speed());
        t.speed_reference.push(a.speed_reference());
        t.position.push(self.plant.output_position());
        t.position_reference.push(a.position_reference());
        t.following_error.push(a.following_error());
        t.state.push(match a.state() {
            AxisState::Disabled => 0,
            AxisState::Enabled => 1,
            AxisState::Stopping(_) => 2,
            AxisState::Faulted(_) => 3,
        });
    }
}

/// Checks a position trajectory (q, qd, qdd): equal lengths, every sample finite.
fn check_trajectory(q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<()> {
    if qd.len() != q.len() || qdd.len() != q.len() {
        return Err(Error::InvalidParameter {
            what: "trajectory length".into(),
            value: q.len() as f64,
            reason: format!(
                "q, qd, qdd must have equal lengths (got {}, {}, {})",
                q.len(),
                qd.len(),
                qdd.len()
            ),
        });
    }
    for (name, v) in [("q", q), ("qd", qd), ("qdd", qdd)] {
        if let Some(k) = v.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                what: format!("trajectory {name}[{k}]"),
                value: v[k],
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sim() -> Simulation {
        let config = AxisConfig::new(MotorModel::maxon_re25_gp26());
        Simulation::new(&config.model, &config).unwrap()
    }

    fn ramp(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let q = (0..n).map(|k| 0.2 + 1e-3 * k as f64).collect();
        (q, vec![1.0; n], vec![0.0; n])
    }

    /// A run asked to stop ends with an error after its first poll; one never asked is the
    /// plain run, bit for bit.
    #[test]
    fn runs_stop_on_request_and_are_unchanged_otherwise() {
        let err = sim()
            .step_response_until(Mode::Position, 0.1, 1.0, 0.0, &|| true)
            .unwrap_err();
        assert!(err.to_string().contains("stopped by the caller"), "{err}");
        let a = sim().step_response(Mode::Position, 0.1, 0.2, 0.0).unwrap();
        let b = sim()
            .step_response_until(Mode::Position, 0.1, 0.2, 0.0, &|| false)
            .unwrap();
        assert_eq!(a, b);
        let (q, qd, qdd) = ramp(2000);
        assert!(sim().follow_until(&q, &qd, &qdd, 0.0, 0.0, &|| true).is_err());
    }

    #[test]
    fn follow_is_the_trajectory_from_rest_then_the_held_last_sample() {
        let (q, qd, qdd) = ramp(50);
        let got = sim().follow(&q, &qd, &qdd, 0.02, 0.01).unwrap();
        let mut s = sim();
        s.plant.set_external_torque(0.01);
        s.plant.set_output_state(q[0], 0.0);
        s.enable(Mode::Position);
        let mut want = s.run_position(&q, &qd, &qdd).unwrap();
        let n_path = want.len();
        want.append(s.run(0.02, |_| Setpoint::Position(q[49], 1.0, 0.0)).unwrap());
        assert_eq!(got, want);
        assert_eq!(got.len(), n_path + 400, "20 ms of hold at 20 kHz");
        assert_eq!(got.position_reference.last(), Some(&q[49]));
    }

    #[test]
    fn follow_checks_everything_before_it_runs() {
        let (q, qd, qdd) = ramp(5);
        let mut s = sim();
        assert!(matches!(
            s.follow(&[], &[], &[], 0.0, 0.0),
            Err(Error::InvalidParameter { .. })
        ));
        assert!(matches!(
            s.follow(&q, &qd[..4], &qdd, 0.0, 0.0),
            Err(Error::InvalidParameter { .. })
        ));
        let mut bad = qd.clone();
        bad[3] = f64::NAN;
        let e = s.follow(&q, &bad, &qdd, 0.0, 0.0).unwrap_err();
        assert!(e.to_string().contains("qd[3]"), "{e}");
        assert!(matches!(
            s.follow(&q, &qd, &qdd, -1.0, 0.0),
            Err(Error::InvalidParameter { .. })
        ));
        assert!(matches!(
            s.follow(&q, &qd, &qdd, 0.0, f64::INFINITY),
            Err(Error::NonFinite { .. })
        ));
        assert_eq!(s.time(), 0.0, "nothing ran");
    }

    #[test]
    fn step_response_holds_the_step_of_its_mode() {
        let got = sim().step_response(Mode::Velocity, 5.0, 0.01, 0.0).unwrap();
        let mut s = sim();
        s.enable(Mode::Velocity);
        assert_eq!(got, s.run(0.01, |_| Setpoint::Velocity(5.0)).unwrap());
        assert_eq!(Setpoint::step(Mode::Position, 0.3), Setpoint::Position(0.3, 0.0, 0.0));
        assert_eq!(Setpoint::step(Mode::Current, 0.3), Setpoint::Current(0.3));
        let mut s = sim();
        assert!(matches!(
            s.step_response(Mode::Current, f64::NAN, 0.01, 0.0),
            Err(Error::NonFinite { .. })
        ));
        assert!(matches!(
            s.step_response(Mode::Current, 1.0, -0.01, 0.0),
            Err(Error::InvalidParameter { .. })
        ));
        assert_eq!(s.time(), 0.0, "nothing ran");
    }

    #[test]
    fn step_metrics_checks_its_arguments() {
        let t = [0.0, 1.0, 2.0, 3.0];
        let y = [0.0, 0.5, 1.0, 1.1];
        let (rise, over) = step_metrics(&t, &y, 1.0).unwrap();
        assert_eq!(rise, rise_time(&t, &y, 1.0));
        assert!((over - 0.1).abs() < 1e-12);
        assert!(step_metrics(&t, &y[..3], 1.0).is_err());
        assert!(step_metrics(&t, &y, 0.0).is_err());
        assert!(matches!(step_metrics(&t, &y, f64::NAN), Err(Error::NonFinite { .. })));
    }

    #[test]
    fn modes_parse_from_the_names_users_type() {
        assert_eq!("speed".parse::<Mode>(), Ok(Mode::Velocity));
        assert_eq!("position".parse::<Mode>(), Ok(Mode::Position));
        assert!("torque".parse::<Mode>().unwrap_err().contains("'torque'"));
    }
}
