//! One axis: the cascade of [`crate::loops`] for one motor, its sensing (position and speed from
//! the tracking observer of [`crate::observer`] on the encoder and the measured current), its
//! operating mode and its fault state machine.
//!
//! States: `Disabled` (duty 0) → `enable(mode)` → `Enabled` → on a fault → `Stopping` (speed loop
//! ramps the speed to zero at the quick-stop deceleration, current limited to the continuous
//! rating) → `Faulted` (duty 0) → `clear_fault()` → `Disabled`. A lost current reading (NaN) skips
//! the ramp: without it the current cannot be controlled, so the bridge goes to duty 0 at once
//! (both low sides on: the winding is shorted and brakes the motor).
//!
//! Everything that can be wrong with the configuration is checked by [`Axis::new`]; [`Axis::tick`]
//! never fails and never allocates.

mod build;
mod protection;

pub use protection::{Fault, Reaction};

pub use crate::axis_config::{AxisConfig, HoldingBrake};
use crate::error::{finite, non_negative, positive, Error, Result};
use crate::loops::{CurrentLoop, LowPass, Pi, PositionLoop, PositionOutput, SpeedLoop};
use crate::motor::Measurement;
use crate::observer::TrackingObserver;
use crate::schedule::{Due, Rates};
use crate::setpoint::SetpointInterpolator;
use crate::thermal::ThermalState;
use crate::tuning::{tune_cascade, CascadeTuning};

/// Operating mode (the CiA 402 cyclic synchronous modes: torque, velocity, position).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Current (torque) reference, A.
    Current,
    /// Output speed reference, rad/s.
    Velocity,
    /// Output position reference with velocity and acceleration, rad, rad/s, rad/s².
    Position,
}

impl std::str::FromStr for Mode {
    type Err = String;

    /// The names users type: `current`, `velocity` (or `speed`), `position`.
    fn from_str(s: &str) -> std::result::Result<Mode, String> {
        match s {
            "current" => Ok(Mode::Current),
            "velocity" | "speed" => Ok(Mode::Velocity),
            "position" => Ok(Mode::Position),
            other => Err(format!("expected 'current', 'velocity' or 'position', got '{other}'")),
        }
    }
}

/// State of the axis' power stage and fault machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisState {
    /// Bridge off (duty 0, open winding).
    Disabled,
    /// Loops running in the present mode.
    Enabled,
    /// Controlled stop after a fault.
    Stopping(Fault),
    /// Stopped after a fault, bridge off (open winding), waiting for `clear_fault`.
    Faulted(Fault),
}

/// One axis: configuration-derived constants, the three loops, sensing and state.
#[derive(Debug, Clone)]
pub struct Axis {
    config: AxisConfig,
    tuning: CascadeTuning,
    // Constants.
    rad_per_count: f64,
    speed_period: f64,
    current_period: f64,
    jump_limit: u64,
    standstill: f64,
    stop_timeout: f64,
    bus_nominal: f64,
    // Holding brake: engaged (true) or released, and the time left until a commanded change is done.
    brake_engaged: bool,
    brake_timer: f64,
    /// Disable requested with a brake: hold until it has engaged, then switch the bridge off.
    disable_pending: bool,
    /// Position held while the brake releases or engages, rad.
    q_hold: f64,
    // Loops.
    current_loop: CurrentLoop,
    thermal: ThermalState,
    emf_speed: LowPass,
    speed_loop: SpeedLoop,
    position_loop: PositionLoop,
    interpolator: SetpointInterpolator,
    interpolating: bool,
    amps_per_joint_torque: f64,
    // Sensing.
    primed: bool,
    count_offset: i64,
    last_counts: i64,
    /// Encoder position (mid-count), rad.
    encoder_position: f64,
    observer: TrackingObserver,
    /// Observer position and speed, sampled at the speed-loop rate, rad and rad/s.
    position: f64,
    speed: f64,
    // References and outputs.
    state: AxisState,
    mode: Mode,
    current_command: f64,
    speed_command: f64,
    q_ref: f64,
    qd_ref: f64,
    qdd_ref: f64,
    torque_feedforward: f64,
    /// Torque feed-forward before and after the latest cyclic setpoint (interpolated between).
    torque_segment: [f64; 2],
    host_torque: bool,
    position_output: PositionOutput,
    current_reference: f64,
    duty: f64,
    stop_reference: f64,
    stop_time: f64,
}

impl Axis {
    /// One base tick: the current loop always, the speed and position loops when `due`; returns the
    /// bridge duty cycle in [−1, 1]. Never fails, never allocates.
    #[inline]
    pub fn tick(&mut self, m: Measurement, due: Due) -> f64 {
        let duty = self.control(m, due);
        if self.interpolating {
            self.interpolator.advance(self.current_period);
        }
        duty
    }

    #[inline]
    fn control(&mut self, m: Measurement, due: Due) -> f64 {
        let current = if m.current.is_finite() {
            m.current
        } else {
            self.trip(Fault::InvalidMeasurement);
            0.0
        };
        self.sense(m.encoder_counts, current, due.speed);
        self.thermal.step(current, self.current_period);
        self.current_loop.set_limit(
            self.thermal
                .limit(self.config.peak_current, self.config.continuous_current),
        );
        if current.abs() > self.config.overcurrent_trip {
            self.trip(Fault::OverCurrent);
        }
        if let Some(v) = m.bus_voltage {
            if v.is_nan() || v > self.config.bus_overvoltage {
                self.trip(Fault::OverVoltage);
            } else if v < self.config.bus_undervoltage {
                self.trip(Fault::UnderVoltage);
            }
            // The duty that gives the commanded voltage on the bus as it is now.
            self.current_loop.set_bus_voltage(v.max(self.config.bus_undervoltage));
        } else {
            self.current_loop.set_bus_voltage(self.bus_nominal);
        }
        if due.speed && self.bridge_on() {
            if self.speed.abs() > self.config.overspeed_limit {
                self.trip(Fault::Overspeed);
            }
            if let Some((lo, hi)) = self.config.position_limits {
                if self.state == AxisState::Enabled && (self.position < lo || self.position > hi) {
                    self.trip(Fault::PositionLimit);
                }
            }
        }
        self.run_brake();
        match self.state {
            AxisState::Disabled | AxisState::Faulted(_) => {
                self.current_reference = 0.0;
                self.duty = 0.0;
                return 0.0;
            }
            AxisState::Enabled => self.run_enabled(due),
            AxisState::Stopping(_) => self.run_stopping(due),
        }
        if !self.bridge_on() {
            self.duty = 0.0;
            return 0.0;
        }
        self.duty = self
            .current_loop
            .step(self.current_reference, current, self.emf_speed.output());
        self.duty
    }

    fn sense(&mut self, raw_counts: i64, current: f64, speed_due: bool) {
        let mut counts = raw_counts.wrapping_add(self.count_offset);
        if self.primed {
            let delta = counts.wrapping_sub(self.last_counts);
            if delta.unsigned_abs() > self.jump_limit {
                // Keep the position continuous across the jump, then stop.
                self.count_offset = self.count_offset.wrapping_sub(delta);
                counts = self.last_counts;
                self.trip(Fault::EncoderJump);
            }
        } else {
            self.primed = true;
            let p = (counts as f64 + 0.5) * self.rad_per_count;
            self.observer.reset(p, 0.0);
            self.interpolator.reset(p);
            self.q_ref = p;
        }
        self.last_counts = counts;
        // The encoder reads floor(θ/Δ): the middle of the count is the unbiased position.
        self.encoder_position = (counts as f64 + 0.5) * self.rad_per_count;
        self.observer.step(self.encoder_position, current);
        if speed_due {
            self.position = self.observer.position();
            self.speed = self.observer.speed();
            self.emf_speed.step(self.speed);
        }
    }

    fn run_enabled(&mut self, due: Due) {
        match self.mode {
            Mode::Current => self.current_reference = self.current_command,
            Mode::Velocity => {
                if due.speed {
                    let ff = self.torque_feedforward * self.amps_per_joint_torque;
                    self.current_reference = self.speed_step(self.speed_command, 0.0, ff);
                }
            }
            Mode::Position => {
                if self.brake_releasing() || self.disable_pending {
                    // Hold still until the brake is free (or while it engages before a disable).
                    self.q_ref = self.q_hold;
                    self.interpolator.reset(self.q_hold);
                    (self.qd_ref, self.qdd_ref) = (0.0, 0.0);
                } else if self.interpolating && due.speed {
                    let mid = self.interpolator.age() + 0.5 * self.speed_period;
                    let s = (mid / self.interpolator.period()).min(1.0);
                    let [t0, t1] = self.torque_segment;
                    self.torque_feedforward = t0 + s * (t1 - t0);
                    let [q, qd, qdd] = self.interpolator.sample(self.speed_period);
                    (self.q_ref, self.qd_ref, self.qdd_ref) = (q, qd, qdd);
                    if self.interpolator.lost() {
                        self.trip(Fault::SetpointsLost);
                        self.run_stopping(due);
                        return;
                    }
                }
                if due.position || (self.interpolating && due.speed) {
                    let o = self
                        .position_loop
                        .step(self.q_ref, self.qd_ref, self.qdd_ref, self.position);
                    self.position_output = o;
                    let limit =
                        self.config.following_error_limit + self.config.following_error_per_speed * self.qd_ref.abs();
                    if o.following_error.abs() > limit {
                        self.trip(Fault::FollowingError);
                        self.run_stopping(due);
                        return;
                    }
                }
                if due.speed {
                    let o = self.position_output;
                    // A host torque feed-forward holds the inertia torque already: not twice.
                    let own = if self.host_torque { 0.0 } else { o.current_feedforward };
                    let ff = own + self.torque_feedforward * self.amps_per_joint_torque;
                    self.current_reference = self.speed_step(o.speed_command, o.speed_feedforward, ff);
                }
            }
        }
    }

    #[inline]
    fn speed_step(&mut self, command: f64, feedforward: f64, current_feedforward: f64) -> f64 {
        let lim = self.current_loop.limit();
        let lo = -lim - current_feedforward;
        let hi = lim - current_feedforward;
        self.speed_loop.step(command, feedforward, self.speed, lo, hi) + current_feedforward
    }

    /// Switches the bridge on in `mode`, holding the present position (position mode) or zero speed
    /// or current; only from `Disabled`. Returns whether the axis is now enabled.
    pub fn enable(&mut self, mode: Mode) -> bool {
        if self.state != AxisState::Disabled {
            return false;
        }
        self.current_loop.reset();
        self.state = AxisState::Enabled;
        self.set_mode(mode);
        if let Some(b) = self.config.holding_brake {
            // Bridge on and holding first, then release the brake; motion after its delay.
            self.brake_engaged = false;
            self.brake_timer = b.release_delay;
            self.q_hold = self.position;
        }
        true
    }

    /// Changes the mode without a bump: the new mode starts from the present position, speed and current.
    pub fn set_mode(&mut self, mode: Mode) {
        self.mode = mode;
        self.current_command = 0.0;
        self.speed_command = 0.0;
        self.q_ref = self.position;
        self.qd_ref = 0.0;
        self.qdd_ref = 0.0;
        self.torque_feedforward = 0.0;
        self.torque_segment = [0.0; 2];
        self.host_torque = false;
        self.interpolator.reset(self.position);
        self.position_output = PositionOutput::default();
        self.speed_loop.reset(self.speed, self.current_reference);
    }

    /// Switches the bridge off (from any state but `Faulted`).
    pub fn disable(&mut self) {
        if self.state == AxisState::Enabled && self.config.holding_brake.is_some() {
            // Engage the brake first; the bridge stays on, holding, until it holds.
            self.engage_brake();
            self.disable_pending = true;
            self.q_hold = self.position;
            return;
        }
        if !matches!(self.state, AxisState::Faulted(_)) {
            self.state = AxisState::Disabled;
            self.current_reference = 0.0;
            self.current_loop.reset();
        }
    }

    /// True while the bridge drives the winding (enabled or stopping); false: open winding.
    pub fn bridge_on(&self) -> bool {
        matches!(self.state, AxisState::Enabled | AxisState::Stopping(_))
    }

    /// True when the holding brake is commanded engaged (always false without a brake).
    pub fn brake_engaged(&self) -> bool {
        self.brake_engaged
    }

    /// True when the brake is engaged and its engage delay has passed (it holds).
    pub fn brake_holding(&self) -> bool {
        self.brake_engaged && self.brake_timer <= 0.0
    }

    /// Acknowledges a fault after the stop: `Faulted` → `Disabled`. Returns whether it did.
    pub fn clear_fault(&mut self) -> bool {
        if let AxisState::Faulted(_) = self.state {
            self.state = AxisState::Disabled;
            true
        } else {
            false
        }
    }

    /// Current reference for current mode, A (limited by the loop; NaN trips a fault).
    pub fn set_current(&mut self, amps: f64) {
        if amps.is_finite() {
            self.current_command = amps;
        } else {
            self.trip(Fault::InvalidReference);
        }
    }

    /// Speed reference for velocity mode, output rad/s (limited to the max speed; NaN trips a fault).
    pub fn set_velocity(&mut self, speed: f64) {
        if speed.is_finite() {
            self.speed_command = speed;
        } else {
            self.trip(Fault::InvalidReference);
        }
    }

    /// Position reference for position mode: rad, rad/s, rad/s² at the output (NaN trips a fault).
    pub fn set_position(&mut self, q: f64, qd: f64, qdd: f64) {
        if !(q.is_finite() && qd.is_finite() && qdd.is_finite()) {
            self.trip(Fault::InvalidReference);
        } else if self.interpolating {
            self.interpolator.push(q, qd, qdd);
        } else {
            self.q_ref = q;
            self.qd_ref = qd;
            self.qdd_ref = qdd;
        }
    }

    /// Joint-side torque feed-forward, N·m (N for a linear axis): the host's inverse dynamics,
    /// turned into a current through the gear ratio and k_t and added after the speed PI in
    /// velocity and position mode (the analogue of CiA 402 0x60B2); with cyclic setpoints it is
    /// interpolated like them (it belongs to the setpoint that came with it). From the first call until the
    /// next mode change it replaces the axis' own acceleration feed-forward (the host's inverse
    /// dynamics holds the inertia torque, with the coupling the axis cannot know). NaN trips a fault.
    pub fn set_torque_feedforward(&mut self, torque: f64) {
        if torque.is_finite() {
            if self.interpolating && self.mode == Mode::Position {
                // Ramp from where the torque is now to the new value over one setpoint period,
                // in step with the position segment.
                self.torque_segment = [self.torque_feedforward, torque];
            } else {
                self.torque_feedforward = torque;
            }
            self.host_torque = true;
        } else {
            self.trip(Fault::InvalidReference);
        }
    }

    /// The configuration the axis was built from.
    pub fn config(&self) -> &AxisConfig {
        &self.config
    }

    /// Loop rates.
    pub fn rates(&self) -> &Rates {
        &self.config.rates
    }

    /// Gains and achieved bandwidths and margins.
    pub fn tuning(&self) -> &CascadeTuning {
        &self.tuning
    }

    /// State of the fault machine.
    pub fn state(&self) -> AxisState {
        self.state
    }

    /// The fault being handled or waiting to be cleared, if any.
    pub fn fault(&self) -> Option<Fault> {
        match self.state {
            AxisState::Stopping(f) | AxisState::Faulted(f) => Some(f),
            _ => None,
        }
    }

    /// Operating mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Estimated output position (tracking observer, sampled at the speed-loop rate), rad.
    pub fn position(&self) -> f64 {
        self.position
    }

    /// Estimated output speed (tracking observer, sampled at the speed-loop rate), rad/s.
    pub fn speed(&self) -> f64 {
        self.speed
    }

    /// Position reference, rad.
    pub fn position_reference(&self) -> f64 {
        self.q_ref
    }

    /// Speed reference after limiting, filtering and feedforward, rad/s.
    pub fn speed_reference(&self) -> f64 {
        self.speed_loop.reference()
    }

    /// Current reference after limiting, A.
    pub fn current_reference(&self) -> f64 {
        self.current_loop.reference()
    }

    /// Last duty cycle, in [−1, 1].
    pub fn duty(&self) -> f64 {
        self.duty
    }

    /// Position error at the last position-loop step, rad.
    pub fn following_error(&self) -> f64 {
        self.position_output.following_error
    }

    /// Present current limit (the peak current, derated with the winding temperature), A.
    pub fn current_limit(&self) -> f64 {
        self.current_loop.limit()
    }

    /// True while the thermal derating holds the current limit below the peak current.
    pub fn thermal_limit_active(&self) -> bool {
        self.current_loop.limit() < self.config.peak_current
    }

    /// Winding and housing temperatures, °C (for a planner: how much peak current is left).
    pub fn thermal_state(&self) -> &ThermalState {
        &self.thermal
    }

    /// Mutable thermal state (to start from a warm motor).
    pub fn thermal_state_mut(&mut self) -> &mut ThermalState {
        &mut self.thermal
    }
}
