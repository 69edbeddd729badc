//! The virtual CiA 402 drive: the ONE adapter between the protocol node
//! ([`crate::canopen::node::DriveNode`]) and the drive layer ([`crate::sim::Simulation`]: the
//! axis cascade with its sensing and fault machine, against the motor model). Physics advance one
//! SYNC period per SYNC, so the drive is deterministic whatever the host's scheduling.
//!
//! - CSP: the target position comes with a velocity by differencing successive targets
//!   (setpoint interpolation of the position loop) and the torque offset 0x60B2 as an acceleration
//!   feed-forward τ/J (the axis turns J·q̈ into current through its torque constant and gearbox,
//!   which is exactly τ/(k_t·n)); CSV: speed reference; CST: current τ/(k_t·n·η).
//! - Quick Stop and fault reaction: the position reference ramps the last speed to zero at the
//!   quick-stop deceleration, then the bridge goes off (Switch On Disabled / Fault).
//! - Watchdog: `missed_rpdo_limit` SYNCs without RPDO, or no SYNC for `sync_timeout_ms` while
//!   the power stage is on, is a fault (EMCY 0x8130) and brings the axis to a stop.
//! - [`Failure`] injects the faults of `ttdrive-sim --fail`.

use crate::axis::{AxisConfig, AxisState, Fault, Mode};
use crate::canopen::cia402::{DriveState, OpMode, SW_FOLLOWS_COMMAND, SW_TARGET_REACHED};
use crate::canopen::emcy;
use crate::canopen::frame::{Frame, Frames};
use crate::canopen::node::{DriveNode, NodeEvent};
use crate::canopen::pdo::Tpdo;
use crate::canopen::Units;
use crate::error::Result;
use crate::motor::MotorModel;
use crate::sim::{Setpoint, Simulation};

/// A fault to inject into a virtual drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// The drive stops answering entirely (unplugged): no TPDO, heartbeat, SDO.
    Silent,
    /// The drive sends an EMCY (code 0x2310 over-current) and goes to Fault.
    Emcy,
    /// The drive leaves Operation Enabled by itself (Switch On Disabled).
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
    /// CSP setpoint interpolation over the SYNC period: (from, to, velocity, acceleration).
    interpolation: Option<(f64, f64, f64, f64)>,
    /// RPDOs missing in a row before a fault.
    pub missed_rpdo_limit: u32,
    /// Milliseconds without SYNC (power stage on) before a fault.
    pub sync_timeout_ms: u32,
    ms_since_sync: u32,
    prev_target: Option<f64>,
    stop_speed: f64,
    stop_reference: f64,
    failure: Option<Failure>,
    cycles: u64,
    max_tracking_error: f64,
}

impl VirtualDrive {
    /// A drive with node id `node`, the drive layer configured by `config` on a plant of
    /// `plant_model`, cycle period `period` s, scaling `units`. Boot-up message into `out`.
    pub fn new(
        node: u8,
        plant_model: &MotorModel,
        config: &AxisConfig,
        units: Units,
        period: f64,
        out: &mut Frames,
    ) -> Result<Self> {
        let sim = Simulation::new(plant_model, config)?;
        let ticks = (period * config.rates.current_hz()).round().max(1.0) as u32;
        let node = DriveNode::new(node, out).map_err(|e| crate::Error::Stepper(e.to_string()))?;
        Ok(VirtualDrive {
            node,
            sim,
            units,
            period,
            ticks_per_cycle: ticks,
            ticks_per_position: config.rates.position_ticks().max(1),
            interpolation: None,
            missed_rpdo_limit: 3,
            sync_timeout_ms: 20,
            ms_since_sync: 0,
            prev_target: None,
            stop_speed: 0.0,
            stop_reference: 0.0,
            failure: None,
            cycles: 0,
            max_tracking_error: 0.0,
        })
    }

    /// Injects `failure` from now on.
    pub fn inject(&mut self, failure: Failure, out: &mut Frames) {
        self.failure = Some(failure);
        match failure {
            Failure::Emcy => {
                self.node.emcy(emcy::OVER_CURRENT, out);
                self.node.cia402.fault();
            }
            Failure::LeaveEnabled => {
                self.node.cia402.on_controlword(0);
            }
            _ => {}
        }
    }

    /// The protocol node (state, counters, dictionary).
    pub fn node(&self) -> &DriveNode {
        &self.node
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
                self.period_step(out);
            }
            NodeEvent::Reset => {
                self.sim.axis.disable();
                self.prev_target = None;
                self.interpolation = None;
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
        if self.ms_since_sync > self.sync_timeout_ms && self.node.cia402.state().torque_on() {
            if self.node.cia402.state() == DriveState::OperationEnabled {
                self.node.emcy(emcy::SYNC_TIMEOUT, out);
                self.begin_stop();
                self.node.cia402.fault();
            }
            self.advance(out, false);
        }
    }

    fn begin_stop(&mut self) {
        self.stop_speed = self.sim.axis.speed();
        self.stop_reference = self.sim.axis.position_reference();
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
        let mut local = Frames::new();
        let before = self.node.cia402.state();
        let cmd = self.node.on_sync(position, current, extra, max_step, &mut local);
        for f in local.as_slice() {
            out.push(self.tamper(*f));
        }
        let after = self.node.cia402.state();
        if after == DriveState::QuickStopActive && before != DriveState::QuickStopActive {
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
                self.interpolation = None;
            }
            if cmd.fresh {
                self.apply(cmd.mode, cmd.target, cmd.torque_offset);
            }
        }
        self.advance(out, true);
    }

    fn apply(&mut self, mode: OpMode, target: i32, torque_offset: i16) {
        let m = self.sim.axis.config().model;
        let joint_inertia = m.motor_side_inertia() * m.gearbox.ratio * m.gearbox.ratio;
        let tau = self.units.permille_to_torque(torque_offset);
        match mode {
            OpMode::Csp => {
                let q = self.units.increments_to_position(target);
                let from = self.prev_target.unwrap_or(q);
                let qd = (q - from) / self.period;
                self.prev_target = Some(q);
                // linear interpolation from the last target to this one at every position-loop
                // step of the period (the SYNC period may be longer than the position loop's)
                self.interpolation = Some((from, q, qd, tau / joint_inertia));
            }
            OpMode::Csv => self
                .sim
                .apply(Setpoint::Velocity(self.units.increments_to_velocity(target))),
            OpMode::Cst => {
                let t = self.units.permille_to_torque(target as i16) + tau;
                let amps = t / (m.motor.torque_constant * m.gearbox.ratio * m.gearbox.efficiency);
                self.sim.apply(Setpoint::Current(amps));
            }
        }
    }

    /// Runs the physics one period; handles stop ramps and axis faults.
    fn advance(&mut self, out: &mut Frames, _synced: bool) {
        self.cycles += 1;
        let state = self.node.cia402.state();
        if matches!(state, DriveState::QuickStopActive | DriveState::FaultReactionActive) {
            let a = self.sim.axis.config().quick_stop_deceleration;
            let dv = a * self.period;
            self.stop_speed = if self.stop_speed.abs() <= dv {
                0.0
            } else {
                self.stop_speed - dv * self.stop_speed.signum()
            };
            self.stop_reference += self.stop_speed * self.period;
            if self.sim.axis.state() == AxisState::Enabled {
                if self.sim.axis.mode() != Mode::Position {
                    self.sim.axis.set_mode(Mode::Position);
                }
                self.sim
                    .apply(Setpoint::Position(self.stop_reference, self.stop_speed, 0.0));
            }
            if self.stop_speed == 0.0 && self.sim.axis.speed().abs() < 0.05
                || !matches!(self.sim.axis.state(), AxisState::Enabled)
            {
                self.sim.axis.disable();
                self.node.cia402.stop_complete();
            }
        } else if !state.torque_on() && self.sim.axis.state() == AxisState::Enabled {
            self.sim.axis.disable();
        }
        let csp = self.node.cia402.state() == DriveState::OperationEnabled && self.sim.axis.mode() == Mode::Position;
        let steps = (self.ticks_per_cycle / self.ticks_per_position).max(1);
        for s in 0..self.ticks_per_cycle {
            if let (true, Some((from, to, qd, qdd))) = (csp, self.interpolation) {
                if s % self.ticks_per_position == 0 {
                    let k = (s / self.ticks_per_position + 1) as f64 / steps as f64;
                    self.sim
                        .apply(Setpoint::Position(from + (to - from) * k.min(1.0), qd, qdd));
                }
            }
            self.sim.step();
            if csp && (s + 1) % self.ticks_per_position == 0 {
                let e = (self.sim.axis.position_reference() - self.sim.axis.position()).abs();
                self.max_tracking_error = self.max_tracking_error.max(e);
            }
        }
        if let Some((_, to, _, _)) = self.interpolation {
            // hold the reached target until the next RPDO (no extrapolation on stale data)
            self.interpolation = Some((to, to, 0.0, 0.0));
        }
        if let AxisState::Stopping(f) | AxisState::Faulted(f) = self.sim.axis.state() {
            if self.node.cia402.state() != DriveState::Fault
                && self.node.cia402.state() != DriveState::FaultReactionActive
            {
                let code = match f {
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
                };
                self.node.emcy(code, out);
                self.node.cia402.fault();
            }
            if matches!(self.sim.axis.state(), AxisState::Faulted(_)) {
                self.node.cia402.stop_complete();
                self.sim.axis.clear_fault();
            }
        }
    }

    fn tamper(&self, f: Frame) -> Frame {
        let is_tpdo = (0x181..=0x1FF).contains(&f.id());
        match self.failure {
            Some(Failure::Malformed) if is_tpdo => Frame::new(f.id(), &f.data()[..3]).unwrap_or(f),
            Some(Failure::OutOfRange) if is_tpdo => match Tpdo::decode(&f) {
                Ok((n, t)) => Tpdo {
                    statusword: 0x0001,
                    ..t
                }
                .encode(n)
                .unwrap_or(f),
                Err(_) => f,
            },
            _ => f,
        }
    }
}
