//! The CiA 402 drive state machine (IEC 61800-7-201 §5.3): the states as the statusword 0x6041
//! shows them, the controlword 0x6040 commands, the drive's transitions, and the master's rule for
//! the next controlword towards Operation Enabled. Modes of operation 0x6060: CSP, CSV, CST.

use super::ProtocolError;

/// Statusword bit 4: voltage enabled.
pub const SW_VOLTAGE_ENABLED: u16 = 1 << 4;
/// Statusword bit 7: warning.
pub const SW_WARNING: u16 = 1 << 7;
/// Statusword bit 9: remote (the drive obeys the controlword).
pub const SW_REMOTE: u16 = 1 << 9;
/// Statusword bit 10: target reached.
pub const SW_TARGET_REACHED: u16 = 1 << 10;
/// Statusword bit 12 in CSP/CSV/CST: the drive follows the command value.
pub const SW_FOLLOWS_COMMAND: u16 = 1 << 12;
/// Statusword bit 13 in CSP: following error.
pub const SW_FOLLOWING_ERROR: u16 = 1 << 13;

/// Controlword: Shutdown (→ Ready to Switch On).
pub const CW_SHUTDOWN: u16 = 0x0006;
/// Controlword: Switch On / Disable Operation (→ Switched On).
pub const CW_SWITCH_ON: u16 = 0x0007;
/// Controlword: Enable Operation (→ Operation Enabled).
pub const CW_ENABLE_OPERATION: u16 = 0x000F;
/// Controlword: Disable Voltage (→ Switch On Disabled).
pub const CW_DISABLE_VOLTAGE: u16 = 0x0000;
/// Controlword: Quick Stop (Operation Enabled → Quick Stop Active).
pub const CW_QUICK_STOP: u16 = 0x0002;
/// Controlword: Fault Reset (rising edge of bit 7).
pub const CW_FAULT_RESET: u16 = 0x0080;

/// Mode of operation (object 0x6060 / 0x6061).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OpMode {
    /// Cyclic synchronous position (8), with torque offset 0x60B2.
    Csp,
    /// Cyclic synchronous velocity (9).
    Csv,
    /// Cyclic synchronous torque (10).
    Cst,
}

impl OpMode {
    /// The value of object 0x6060.
    pub fn code(self) -> i8 {
        match self {
            OpMode::Csp => 8,
            OpMode::Csv => 9,
            OpMode::Cst => 10,
        }
    }

    /// Mode from the value of 0x6060; other modes are not supported by this stack.
    pub fn from_code(c: i8) -> Result<Self, ProtocolError> {
        match c {
            8 => Ok(OpMode::Csp),
            9 => Ok(OpMode::Csv),
            10 => Ok(OpMode::Cst),
            c => Err(ProtocolError::OutOfRange {
                what: "mode of operation",
                value: c as i64,
            }),
        }
    }
}

/// State of a CiA 402 drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriveState {
    /// Not ready to switch on (initialising).
    NotReadyToSwitchOn,
    /// Switch on disabled (power stage off, waiting for Shutdown).
    SwitchOnDisabled,
    /// Ready to switch on.
    ReadyToSwitchOn,
    /// Switched on (power stage on, no torque).
    SwitchedOn,
    /// Operation enabled (following the command values).
    OperationEnabled,
    /// Quick stop active (decelerating with the quick-stop deceleration).
    QuickStopActive,
    /// Fault reaction active (braking after a fault).
    FaultReactionActive,
    /// Fault (power stage off, waiting for Fault Reset).
    Fault,
}

impl DriveState {
    /// Every state, in the order of the state machine's diagram.
    pub const ALL: [DriveState; 8] = [
        DriveState::NotReadyToSwitchOn,
        DriveState::SwitchOnDisabled,
        DriveState::ReadyToSwitchOn,
        DriveState::SwitchedOn,
        DriveState::OperationEnabled,
        DriveState::QuickStopActive,
        DriveState::FaultReactionActive,
        DriveState::Fault,
    ];

    /// The state bits of the statusword (bits 0–3, 5, 6).
    pub fn statusword_bits(self) -> u16 {
        match self {
            DriveState::NotReadyToSwitchOn => 0x0000,
            DriveState::SwitchOnDisabled => 0x0040,
            DriveState::ReadyToSwitchOn => 0x0021,
            DriveState::SwitchedOn => 0x0023,
            DriveState::OperationEnabled => 0x0027,
            DriveState::QuickStopActive => 0x0007,
            DriveState::FaultReactionActive => 0x000F,
            DriveState::Fault => 0x0008,
        }
    }

    /// Decodes the state from a statusword; a bit pattern no state has is an error.
    pub fn from_statusword(sw: u16) -> Result<Self, ProtocolError> {
        let s = match (sw & 0x4F, sw & 0x6F) {
            (0x00, _) => DriveState::NotReadyToSwitchOn,
            (0x40, _) => DriveState::SwitchOnDisabled,
            (_, 0x21) => DriveState::ReadyToSwitchOn,
            (_, 0x23) => DriveState::SwitchedOn,
            (_, 0x27) => DriveState::OperationEnabled,
            (_, 0x07) => DriveState::QuickStopActive,
            (0x0F, _) => DriveState::FaultReactionActive,
            (0x08, _) => DriveState::Fault,
            _ => {
                return Err(ProtocolError::OutOfRange {
                    what: "statusword",
                    value: sw as i64,
                })
            }
        };
        Ok(s)
    }

    /// True when the power stage may produce torque (Operation Enabled, Quick Stop, fault reaction).
    pub fn torque_on(self) -> bool {
        matches!(
            self,
            DriveState::OperationEnabled | DriveState::QuickStopActive | DriveState::FaultReactionActive
        )
    }
}

/// The master's next controlword to bring a drive from `state` towards Operation Enabled
/// (one transition per cycle; a fault is reset only when `reset_faults`).
pub fn controlword_towards_enabled(state: DriveState, reset_faults: bool, last: u16) -> u16 {
    match state {
        DriveState::SwitchOnDisabled | DriveState::NotReadyToSwitchOn => CW_SHUTDOWN,
        DriveState::ReadyToSwitchOn => CW_SWITCH_ON,
        DriveState::SwitchedOn | DriveState::OperationEnabled => CW_ENABLE_OPERATION,
        DriveState::QuickStopActive | DriveState::FaultReactionActive => CW_QUICK_STOP,
        // Fault reset acts on the rising edge of bit 7: alternate 0 and 0x80.
        DriveState::Fault if reset_faults && last & CW_FAULT_RESET == 0 => CW_FAULT_RESET,
        DriveState::Fault => CW_DISABLE_VOLTAGE,
    }
}

/// The drive's side of the state machine: transitions on controlwords and on internal events.
#[derive(Debug, Clone, Copy)]
pub struct Cia402 {
    state: DriveState,
    last_controlword: u16,
}

impl Default for Cia402 {
    fn default() -> Self {
        Self::new()
    }
}

impl Cia402 {
    /// A drive that has finished initialising (Switch On Disabled).
    pub fn new() -> Self {
        Cia402 {
            state: DriveState::SwitchOnDisabled,
            last_controlword: 0,
        }
    }

    /// Present state.
    pub fn state(&self) -> DriveState {
        self.state
    }

    /// Applies a controlword (transitions 2–12 and 15 of the standard); returns the new state.
    pub fn on_controlword(&mut self, cw: u16) -> DriveState {
        use DriveState::*;
        let rising_reset = cw & CW_FAULT_RESET != 0 && self.last_controlword & CW_FAULT_RESET == 0;
        self.last_controlword = cw;
        let ev = cw & 0x02 != 0; // enable voltage
        let qs = cw & 0x04 != 0; // quick stop (active low)
        let so = cw & 0x01 != 0; // switch on
        let eo = cw & 0x08 != 0; // enable operation
        self.state = match self.state {
            Fault if rising_reset => SwitchOnDisabled,
            s @ (Fault | FaultReactionActive | NotReadyToSwitchOn) => s,
            _ if !ev => SwitchOnDisabled,
            OperationEnabled if !qs => QuickStopActive,
            QuickStopActive => QuickStopActive, // left only by `stop_complete` or Disable Voltage
            _ if !qs => SwitchOnDisabled,
            SwitchOnDisabled if !so => ReadyToSwitchOn,
            SwitchOnDisabled => SwitchOnDisabled,
            ReadyToSwitchOn if so && !eo => SwitchedOn,
            ReadyToSwitchOn if so => SwitchedOn,
            ReadyToSwitchOn => ReadyToSwitchOn,
            SwitchedOn if !so => ReadyToSwitchOn,
            SwitchedOn if eo => OperationEnabled,
            SwitchedOn => SwitchedOn,
            OperationEnabled if !so => ReadyToSwitchOn,
            OperationEnabled if !eo => SwitchedOn,
            OperationEnabled => OperationEnabled,
        };
        self.state
    }

    /// A fault was detected: Fault Reaction Active (from any state but Fault).
    pub fn fault(&mut self) {
        if self.state != DriveState::Fault {
            self.state = DriveState::FaultReactionActive;
        }
    }

    /// The braking of a quick stop or a fault reaction has finished (transitions 12 and 14).
    pub fn stop_complete(&mut self) {
        self.state = match self.state {
            DriveState::QuickStopActive => DriveState::SwitchOnDisabled,
            DriveState::FaultReactionActive => DriveState::Fault,
            s => s,
        };
    }

    /// The statusword: state bits, voltage enabled, remote, plus `extra` bits (10, 12, 13, 7).
    pub fn statusword(&self, extra: u16) -> u16 {
        let voltage = if matches!(
            self.state,
            DriveState::SwitchOnDisabled | DriveState::NotReadyToSwitchOn
        ) {
            0
        } else {
            SW_VOLTAGE_ENABLED
        };
        self.state.statusword_bits() | voltage | SW_REMOTE | extra
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use DriveState::*;

    #[test]
    fn every_state_round_trips_through_its_statusword() {
        for s in DriveState::ALL {
            let sw = s.statusword_bits() | SW_VOLTAGE_ENABLED | SW_REMOTE | SW_TARGET_REACHED;
            assert_eq!(DriveState::from_statusword(sw).unwrap(), s);
        }
        assert!(DriveState::from_statusword(0x0001).is_err());
    }

    #[test]
    fn master_rule_reaches_operation_enabled_in_three_cycles() {
        let mut d = Cia402::new();
        let mut cw = 0;
        for _ in 0..3 {
            cw = controlword_towards_enabled(d.state(), false, cw);
            d.on_controlword(cw);
        }
        assert_eq!(d.state(), OperationEnabled);
    }

    #[test]
    fn quick_stop_then_fault_and_reset_on_rising_edge_only() {
        let mut d = Cia402::new();
        for cw in [CW_SHUTDOWN, CW_SWITCH_ON, CW_ENABLE_OPERATION] {
            d.on_controlword(cw);
        }
        assert_eq!(d.on_controlword(CW_QUICK_STOP), QuickStopActive);
        assert_eq!(d.on_controlword(CW_ENABLE_OPERATION), QuickStopActive);
        d.stop_complete();
        assert_eq!(d.state(), SwitchOnDisabled);
        for cw in [CW_SHUTDOWN, CW_SWITCH_ON, CW_ENABLE_OPERATION] {
            d.on_controlword(cw);
        }
        d.fault();
        assert_eq!(d.state(), FaultReactionActive);
        assert_eq!(d.on_controlword(CW_FAULT_RESET), FaultReactionActive);
        d.stop_complete();
        assert_eq!(d.state(), Fault);
        // bit 7 still high from the last controlword: no edge, no reset
        assert_eq!(d.on_controlword(CW_FAULT_RESET), Fault);
        assert_eq!(d.on_controlword(0), Fault);
        assert_eq!(d.on_controlword(CW_FAULT_RESET), SwitchOnDisabled);
    }

    #[test]
    fn op_mode_codes() {
        for m in [OpMode::Csp, OpMode::Csv, OpMode::Cst] {
            assert_eq!(OpMode::from_code(m.code()).unwrap(), m);
        }
        assert!(OpMode::from_code(1).is_err());
    }
}
