//! Closed-loop simulation of one axis on a [`Plant`]: the plant steps once per current-loop period
//! with the duty the axis computed from the measurement taken at the start of that period.

use crate::axis::{Axis, AxisConfig, AxisState, Mode};
use crate::error::{Error, Result};
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
    pub fn run(&mut self, duration: f64, mut reference: impl FnMut(f64) -> Setpoint) -> Result<Trace> {
        let n = self.periods_in(duration)?;
        let mut trace = Trace::with_capacity(n);
        for _ in 0..n {
            self.apply(reference(self.time));
            self.record_into(&mut trace);
            self.step();
        }
        Ok(trace)
    }

    /// Runs a position trajectory given at the position-loop rate: sample k of (q, qd, qdd) (rad,
    /// rad/s, rad/s²) is handed to the axis just before its k-th position-loop step from now, and
    /// the run ends after the position period of the last sample. All three must have the same length and
    /// be finite (checked before anything runs).
    pub fn run_position(&mut self, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<Trace> {
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
        let per = self.axis.rates().position_ticks() as usize;
        let mut trace = Trace::with_capacity(q.len() * per);
        let mut k = 0;
        while k < q.len() || !self.scheduler.peek().position {
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
        Ok((duration / self.plant.dt()).round() as usize)
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
