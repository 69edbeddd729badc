//! The axis' protection: the fault → reaction table at work (bridge off at once, or quick stop
//! → brake → bridge off), escalation of a fault while stopping, and the holding-brake sequence.

use super::*;

/// Why an axis stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fault {
    /// The measured current exceeded the trip level.
    OverCurrent,
    /// |position reference − position| exceeded the following-error limit.
    FollowingError,
    /// The encoder moved further in one current-loop period than the axis can.
    EncoderJump,
    /// A reference was NaN or infinite.
    InvalidReference,
    /// The current reading was NaN or infinite.
    InvalidMeasurement,
    /// `setpoint_max_missed` cyclic position setpoints in a row did not arrive.
    SetpointsLost,
    /// The estimated speed exceeded the overspeed limit (checked in every mode).
    Overspeed,
    /// The position (or a position reference) left the software position limits.
    PositionLimit,
    /// The measured DC-bus voltage exceeded the over-voltage limit (regeneration).
    OverVoltage,
    /// The measured DC-bus voltage fell below the under-voltage limit.
    UnderVoltage,
}

/// What the axis does about a fault: each fault has exactly one reaction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reaction {
    /// Duty 0 and the bridge off at once (open winding: the joint coasts); used when the current
    /// cannot be controlled or a sensor the loops need has failed.
    BridgeOff,
    /// Controlled stop at the quick-stop deceleration, then (brake engaged) bridge off.
    QuickStop,
}

impl Fault {
    /// The one reaction to this fault. A fault while stopping always escalates to
    /// [`Reaction::BridgeOff`].
    pub fn reaction(self) -> Reaction {
        match self {
            Fault::OverCurrent | Fault::EncoderJump | Fault::InvalidMeasurement | Fault::OverVoltage => {
                Reaction::BridgeOff
            }
            Fault::FollowingError
            | Fault::InvalidReference
            | Fault::SetpointsLost
            | Fault::Overspeed
            | Fault::PositionLimit
            | Fault::UnderVoltage => Reaction::QuickStop,
        }
    }
}

impl Axis {
    /// Brake timing and the disable sequence: engage, hold until it holds, then bridge off.
    pub(super) fn run_brake(&mut self) {
        if self.brake_timer > 0.0 {
            self.brake_timer -= self.current_period;
        }
        if self.disable_pending && self.brake_timer <= 0.0 {
            self.disable_pending = false;
            self.state = AxisState::Disabled;
            self.current_reference = 0.0;
            self.current_loop.reset();
        }
    }

    /// True while the brake is being released (the axis holds its position meanwhile).
    pub(super) fn brake_releasing(&self) -> bool {
        !self.brake_engaged && self.brake_timer > 0.0 && self.config.holding_brake.is_some()
    }

    pub(super) fn engage_brake(&mut self) {
        if let Some(b) = self.config.holding_brake {
            if !self.brake_engaged {
                self.brake_engaged = true;
                self.brake_timer = b.engage_delay;
            }
        }
    }

    pub(super) fn run_stopping(&mut self, due: Due) {
        if !due.speed {
            return;
        }
        let fault = match self.state {
            AxisState::Stopping(f) => f,
            _ => return,
        };
        let dv = self.config.quick_stop_deceleration * self.speed_period;
        let r = self.stop_reference;
        self.stop_reference = if r > dv {
            r - dv
        } else if r < -dv {
            r + dv
        } else {
            0.0
        };
        let lim = self.config.continuous_current.min(self.current_loop.limit());
        self.current_reference = self.speed_loop.step(self.stop_reference, 0.0, self.speed, -lim, lim);
        self.stop_time += self.speed_period;
        let stopped = self.stop_reference == 0.0 && self.speed.abs() <= self.standstill;
        if stopped || self.stop_time > self.stop_timeout {
            if self.config.holding_brake.is_some() && !self.brake_engaged {
                // Engage the brake and keep holding (zero speed) until it holds.
                self.engage_brake();
            }
            if self.brake_timer <= 0.0 {
                self.bridge_off(fault);
            }
        }
    }

    /// Bridge off at once (duty 0, open winding) and the brake (if any) engaged.
    pub(super) fn bridge_off(&mut self, fault: Fault) {
        self.state = AxisState::Faulted(fault);
        self.current_reference = 0.0;
        self.duty = 0.0;
        self.current_loop.reset();
        self.disable_pending = false;
        if let Some(b) = self.config.holding_brake {
            if !self.brake_engaged {
                self.brake_engaged = true;
                self.brake_timer = b.engage_delay;
            }
        }
    }

    pub(super) fn trip(&mut self, fault: Fault) {
        match self.state {
            AxisState::Enabled => match fault.reaction() {
                Reaction::BridgeOff => self.bridge_off(fault),
                Reaction::QuickStop => {
                    self.state = AxisState::Stopping(fault);
                    self.disable_pending = false;
                    self.stop_reference = self.speed.max(-self.config.max_speed).min(self.config.max_speed);
                    self.stop_time = 0.0;
                    self.speed_loop.reset(self.speed, self.current_reference);
                }
            },
            // The condition being handled, still present: the stop goes on.
            AxisState::Stopping(f) if f == fault => {}
            // Another fault while stopping: the stop itself is in doubt, escalate.
            AxisState::Stopping(_) => self.bridge_off(fault),
            AxisState::Disabled => self.state = AxisState::Faulted(fault),
            AxisState::Faulted(_) => {}
        }
    }
}
