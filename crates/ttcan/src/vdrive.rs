//! The virtual CiA 402 drive: the ONE adapter between the protocol node
//! ([`crate::canopen::node::DriveNode`]) and the drive layer ([`crate::sim::Simulation`]: the
//! axis cascade with its sensing and fault machine, against the motor model). Physics advance one
//! SYNC period per SYNC, so the drive is deterministic whatever the host's scheduling.
//!
//! - CSP: each fresh target goes to the axis' setpoint interpolator ([`crate::setpoint`], the
//!   SYNC period as interpolation time 0x60C2) with the velocity by differencing successive
//!   targets; the torque offset 0x60B2 is the axis' joint torque feed-forward (once the host has
//!   sent one it replaces the axis' own acceleration feed-forward). Without a fresh target the
//!   interpolator holds the last one at zero velocity (nothing moves on stale data), and its
//!   watchdog quick-stops the axis after `setpoint_max_missed` periods ([`Fault::SetpointsLost`],
//!   EMCY 0x8250). CSV: speed reference; CST: current τ/(k_t·n·η).
//! - Quick Stop and the protocol's fault reaction (an EMCY the adapter raises, a SYNC timeout):
//!   the position reference ramps the last speed to zero at the quick-stop deceleration, holds the
//!   stop position [`HOLD_S`] (the residual speed dies out under the position loop), then the
//!   axis is disabled (with a holding brake: engaged first, the bridge holds until it holds) and
//!   the node goes to Switch On Disabled / Fault. The axis has no public quick-stop entry, so the
//!   ramp is driven from here through its position mode.
//! - Drive-layer faults: each [`Fault`] maps to its EMCY code and the node to Fault; the axis
//!   runs its own reaction ([`crate::axis::Reaction`]: quick stop, or bridge off at once, after
//!   which the joint coasts on an open winding, as the hardware does).
//! - Watchdog: `missed_rpdo_limit` SYNCs without RPDO, or no SYNC for `sync_timeout_ms` while
//!   the power stage is on, is a fault (EMCY 0x8130) and brings the axis to a stop.
//! - [`Failure`] injects the faults of `ttdrive-sim --fail`.

use crate::axis::{Axis, AxisConfig, AxisState, Fault, Mode};
use crate::canopen::cia402::{DriveState, OpMode, SW_FOLLOWS_COMMAND, SW_TARGET_REACHED};
use crate::canopen::emcy;
use crate::canopen::frame::{Frame, Frames};
use crate::canopen::node::{DriveNode, NodeEvent};
use crate::canopen::od;
use crate::canopen::Units;
use crate::error::Result;
use crate::motor::MotorModel;
use crate::sim::{Setpoint, Simulation};

/// How long a controlled stop holds the stop position before the bridge goes off, s: the
/// bridge-off leaves the winding open (the joint coasts), so the speed the position loop still
/// corrects must have died out first.
pub const HOLD_S: f64 = 0.03;

/// Estimated speed below which a stop ramp that has reached zero counts as at rest, rad/s.
const AT_REST: f64 = 0.05;

/// A fault to inject into a virtual drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// The drive stops answering entirely (unplugged): no TPDO, heartbeat, SDO.
    Silent,
    /// The drive's current sensing reads an over-current: the axis switches the bridge off at
    /// once (its reaction to [`Fault::OverCurrent`], the joint coasts), the drive sends EMCY
    /// 0x2310 and goes to Fault.
    Emcy,
    /// The drive leaves Operation Enabled by itself (a local quick stop: Quick Stop Active, the
    /// controlled stop, then Switch On Disabled).
    LeaveEnabled,
    /// The drive's TPDOs are malformed (3 bytes).
    Malformed,
    /// The drive reports an impossible statusword.
    OutOfRange,
}

/// One virtual drive.
#[derive(Debug, Clone)]
pub struct VirtualDrive {
    node: DriveNode,
    sim: Simulation,
    units: Units,
    period: f64,
    ticks_per_cycle: u32,
    ticks_per_position: u32,
    /// RPDOs missing in a row before a fault.
    pub missed_rpdo_limit: u32,
    /// Milliseconds without SYNC (power stage on) before a fault.
    pub sync_timeout_ms: u32,
    ms_since_sync: u32,
    prev_target: Option<f64>,
    host_torque: bool,
    stop_speed: f64,
    stop_reference: f64,
    /// Time the stop position has been held, s.
    held: f64,
    failure: Option<Failure>,
    cycles: u64,
    max_tracking_error: f64,
    /// The node's state at the end of the last period (a change made over SDO in between, such
    /// as a quick stop by controlword, is seen at the next SYNC).
    last_state: DriveState,
    /// A SYNC arrived since the last reset (the SYNC watchdog is armed only then).
    sync_seen: bool,
}

impl VirtualDrive {
    /// A drive with node id `node`, the drive layer configured by `config` on a plant of
    /// `plant_model`, cycle period `period` s, scaling `units`. Boot-up message into `out`. The
    /// axis interpolates CSP targets over `period` (its `setpoint_period`) and watches their age.
    pub fn new(
        node: u8,
        plant_model: &MotorModel,
        config: &AxisConfig,
        units: Units,
        period: f64,
        out: &mut Frames,
    ) -> Result<Self> {
        let mut config = *config;
        config.setpoint_period = Some(period);
        let sim = Simulation::new(plant_model, &config)?;
        let ticks = (period * config.rates.current_hz()).round().max(1.0) as u32;
        let node = DriveNode::new(node, out).map_err(|e| crate::Error::Stepper(e.to_string()))?;
        Ok(VirtualDrive {
            node,
            sim,
            units,
            period,
            ticks_per_cycle: ticks,
            ticks_per_position: config.rates.position_ticks().max(1),
            missed_rpdo_limit: 3,
            sync_timeout_ms: 20,
            ms_since_sync: 0,
            prev_target: None,
            host_torque: false,
            stop_speed: 0.0,
            stop_reference: 0.0,
            held: 0.0,
            failure: None,
            cycles: 0,
            max_tracking_error: 0.0,
            last_state: DriveState::SwitchOnDisabled,
            sync_seen: false,
        })
    }

    /// Injects `failure` from now on.
    pub fn inject(&mut self, failure: Failure, _out: &mut Frames) {
        self.failure = Some(failure);
        if failure == Failure::OutOfRange {
            self.node.statusword_override = Some(0x0001);
        }
        if failure == Failure::Emcy {
            // Through the drive layer: the sensed current is beyond the trip level.
            let trip = self.sim.axis.config().overcurrent_trip;
            self.sim.plant.set_current_sense_offset(2.0 * trip);
        }
        // Enable voltage and switch on, quick stop (active low) requested: transition 11.
        if failure == Failure::LeaveEnabled && self.node.cia402.on_controlword(0x0003) == DriveState::QuickStopActive {
            self.begin_stop();
        }
    }

    /// The protocol node (state, counters, dictionary).
    pub fn node(&self) -> &DriveNode {
        &self.node
    }

    /// The protocol node, mutable (tests and tools that change the dictionary directly).
    pub fn node_mut(&mut self) -> &mut DriveNode {
        &mut self.node
    }

    /// The drive layer's axis (state, brake, references).
    pub fn axis(&self) -> &Axis {
        &self.sim.axis
    }

    /// True output position of the simulated joint, joint units.
    pub fn position(&self) -> f64 {
        self.sim.plant.output_position()
    }

    /// Largest |interpolated CSP target − measured position| at the position-loop steps while in
    /// Operation Enabled, joint units: the drive's own tracking, independent of bus timing.
    pub fn max_tracking_error(&self) -> f64 {
        self.max_tracking_error
    }

    /// SYNC periods simulated.
    pub fn cycles(&self) -> u64 {
        self.cycles
    }

    /// Handles one received frame (a SYNC advances the physics by one period).
    pub fn on_frame(&mut self, f: &Frame, out: &mut Frames) {
        if self.failure == Some(Failure::Silent) {
            return;
        }
        match self.node.on_frame(f, out) {
            NodeEvent::Sync => {
                self.ms_since_sync = 0;
                self.sync_seen = true;
                self.period_step(out);
            }
            NodeEvent::Reset => {
                self.sim.axis.disable();
                self.prev_target = None;
                self.sync_seen = false;
                self.last_state = self.node.cia402.state();
            }
            NodeEvent::None => {}
        }
    }

    /// 1 ms time base: heartbeat, and the SYNC watchdog (which also keeps a stop ramp running
    /// when SYNCs have ceased).
    pub fn tick_ms(&mut self, out: &mut Frames) {
        if self.failure == Some(Failure::Silent) {
            return;
        }
        self.node.tick_ms(out);
        self.ms_since_sync = self.ms_since_sync.saturating_add(1);
        if self.sync_seen && self.ms_since_sync > self.sync_timeout_ms && self.node.cia402.state().torque_on() {
            if self.node.cia402.state() == DriveState::OperationEnabled {
                self.node.emcy(emcy::SYNC_TIMEOUT, out);
                self.begin_stop();
                self.node.cia402.fault();
            }
            self.advance(out);
        }
    }

    /// Starts the controlled stop from the present reference and speed.
    fn begin_stop(&mut self) {
        self.stop_speed = self.sim.axis.speed();
        self.stop_reference = self.sim.axis.position_reference();
        self.held = 0.0;
        self.prev_target = None;
        if self.sim.axis.state() == AxisState::Enabled && self.sim.axis.mode() != Mode::Position {
            // Bumpless: position mode from the present position, speed and current.
            self.sim.axis.set_mode(Mode::Position);
            self.stop_reference = self.sim.axis.position();
        }
    }

    fn period_step(&mut self, out: &mut Frames) {
        let q = self.sim.axis.position();
        let extra = if self.node.cia402.state() == DriveState::OperationEnabled {
            SW_FOLLOWS_COMMAND | SW_TARGET_REACHED
        } else {
            0
        };
        let position = self
            .units
            .position_to_increments(q)
            .unwrap_or(if q > 0.0 { i32::MAX } else { i32::MIN });
        let current = self.units.current_to_permille(self.sim.plant.current()).unwrap_or(0);
        let max_step = (self.sim.axis.config().max_speed * self.period * 2.0 * self.units.increments_per_unit) as i64;
        let speed = self.units.velocity_to_increments(self.sim.axis.speed()).unwrap_or(0);
        self.node.od.set(od::VELOCITY_ACTUAL, 0, speed as i64);
        let mut local = Frames::new();
        let before = self.last_state;
        let cmd = self.node.on_sync(position, current, extra, max_step, &mut local);
        for f in local.as_slice() {
            out.push(self.tamper(*f));
        }
        let after = self.node.cia402.state();
        if matches!(after, DriveState::QuickStopActive | DriveState::FaultReactionActive)
            && !matches!(before, DriveState::QuickStopActive | DriveState::FaultReactionActive)
        {
            self.begin_stop();
        }
        if after == DriveState::OperationEnabled && self.node.missed_in_row() > self.missed_rpdo_limit {
            self.node.emcy(emcy::SYNC_TIMEOUT, out);
            self.begin_stop();
            self.node.cia402.fault();
        }
        if self.node.cia402.state() == DriveState::OperationEnabled {
            let mode = match cmd.mode {
                OpMode::Csp => Mode::Position,
                OpMode::Csv => Mode::Velocity,
                OpMode::Cst => Mode::Current,
            };
            if self.sim.axis.state() == AxisState::Disabled {
                self.sim.enable(mode);
                self.prev_target = None;
                self.host_torque = false;
            }
            if self.sim.axis.state() == AxisState::Enabled && cmd.fresh {
                self.apply(cmd.mode, cmd.target, cmd.torque_offset);
            }
        }
        self.advance(out);
        self.last_state = self.node.cia402.state();
    }

    fn apply(&mut self, mode: OpMode, target: i32, torque_offset: i16) {
        let m = self.sim.axis.config().model;
        let tau = self.units.permille_to_torque(torque_offset);
        match mode {
            OpMode::Csp => {
                let q = self.units.increments_to_position(target);
                let qd = self.prev_target.map_or(0.0, |p| (q - p) / self.period);
                self.prev_target = Some(q);
                if torque_offset != 0 || self.host_torque {
                    self.host_torque = true;
                    self.sim.axis.set_torque_feedforward(tau);
                }
                self.sim.apply(Setpoint::Position(q, qd, 0.0));
            }
            OpMode::Csv => {
                if torque_offset != 0 || self.host_torque {
                    self.host_torque = true;
                    self.sim.axis.set_torque_feedforward(tau);
                }
                self.sim
                    .apply(Setpoint::Velocity(self.units.increments_to_velocity(target)))
            }
            OpMode::Cst => {
                let t = self.units.permille_to_torque(target as i16) + tau;
                let amps = t / (m.motor.torque_constant * m.gearbox.ratio * m.gearbox.efficiency);
                self.sim.apply(Setpoint::Current(amps));
            }
        }
    }

    /// One period of the controlled stop: ramp the speed to zero, hold [`HOLD_S`], disable.
    fn stop_step(&mut self) {
        let a = self.sim.axis.config().quick_stop_deceleration;
        let dv = a * self.period;
        let (speed, accel) = if self.stop_speed.abs() <= dv {
            (0.0, 0.0)
        } else {
            (
                self.stop_speed - dv * self.stop_speed.signum(),
                -a * self.stop_speed.signum(),
            )
        };
        self.stop_reference += 0.5 * (self.stop_speed + speed) * self.period;
        self.stop_speed = speed;
        if self.stop_speed == 0.0 && self.sim.axis.speed().abs() < AT_REST {
            self.held += self.period;
        }
        if self.held >= HOLD_S {
            // With a brake the axis engages it and holds until it holds; then the bridge goes off.
            if !self.sim.axis.brake_engaged() {
                self.sim.axis.disable();
            }
        } else {
            self.sim
                .apply(Setpoint::Position(self.stop_reference, self.stop_speed, accel));
        }
    }

    /// Runs the physics one period; handles stop ramps and axis faults.
    fn advance(&mut self, out: &mut Frames) {
        self.cycles += 1;
        let state = self.node.cia402.state();
        let stopping = matches!(state, DriveState::QuickStopActive | DriveState::FaultReactionActive);
        if self.sim.axis.state() == AxisState::Enabled {
            if stopping {
                self.stop_step();
            } else if !state.torque_on() && !self.sim.axis.brake_engaged() {
                // Disable Voltage / Shutdown: the power stage goes off (after the brake, if any).
                self.sim.axis.disable();
            }
        }
        let csp = state == DriveState::OperationEnabled && self.sim.axis.mode() == Mode::Position;
        for s in 0..self.ticks_per_cycle {
            self.sim.step();
            if csp && self.sim.axis.state() == AxisState::Enabled && (s + 1) % self.ticks_per_position == 0 {
                let e = (self.sim.axis.position_reference() - self.sim.axis.position()).abs();
                self.max_tracking_error = self.max_tracking_error.max(e);
            }
        }
        if let AxisState::Stopping(f) | AxisState::Faulted(f) = self.sim.axis.state() {
            if !matches!(
                self.node.cia402.state(),
                DriveState::Fault | DriveState::FaultReactionActive
            ) {
                self.node.emcy(emcy_code(f), out);
                self.node.cia402.fault();
            }
            if matches!(self.sim.axis.state(), AxisState::Faulted(_)) {
                // The axis' own reaction (quick stop or bridge off) is over.
                self.node.cia402.stop_complete();
                self.sim.axis.clear_fault();
            }
        } else if self.sim.axis.state() == AxisState::Disabled
            && matches!(
                self.node.cia402.state(),
                DriveState::QuickStopActive | DriveState::FaultReactionActive
            )
        {
            self.node.cia402.stop_complete();
        }
    }

    fn tamper(&self, f: Frame) -> Frame {
        let tpdo_id = self.node.od.get(od::TPDO1_COMM, 1).unwrap_or(0) & 0x7FF;
        match self.failure {
            Some(Failure::Malformed) if i64::from(f.id()) == tpdo_id => {
                Frame::new(f.id(), &f.data()[..3.min(f.len())]).unwrap_or(f)
            }
            _ => f,
        }
    }
}

/// The EMCY error code of a drive-layer fault.
pub fn emcy_code(f: Fault) -> u16 {
    match f {
        Fault::OverCurrent => emcy::OVER_CURRENT,
        Fault::FollowingError => emcy::FOLLOWING_ERROR,
        Fault::EncoderJump => emcy::SENSOR,
        Fault::InvalidReference => emcy::COMMAND_RANGE,
        Fault::InvalidMeasurement => emcy::SENSOR,
        Fault::SetpointsLost => emcy::RPDO_TIMEOUT,
        Fault::Overspeed => emcy::OVERSPEED,
        Fault::PositionLimit => emcy::POSITION_LIMIT,
        Fault::OverVoltage => emcy::OVER_VOLTAGE,
        Fault::UnderVoltage => emcy::UNDER_VOLTAGE,
    }
}
