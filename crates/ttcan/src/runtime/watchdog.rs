//! What the controller watches and why it stops: the watchdog's timing (in cycles, from the
//! configuration file) and the stop reasons, each logged with the node it concerns.

/// Watchdog and protocol timing, in cycles.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WatchdogConfig {
    /// Cycles in a row without feedback (TPDO) before a stop.
    #[serde(default = "wd_feedback")]
    pub feedback_cycles: u32,
    /// Heartbeat consumer timeout, cycles.
    #[serde(default = "wd_heartbeat")]
    pub heartbeat_cycles: u32,
    /// Heartbeat period the drives are configured with, ms.
    #[serde(default = "wd_hb_period")]
    pub heartbeat_period_ms: u16,
    /// SDO response timeout, cycles.
    #[serde(default = "wd_sdo")]
    pub sdo_cycles: u32,
    /// Cycles allowed from start to every axis in Operation Enabled.
    #[serde(default = "wd_enable")]
    pub enable_cycles: u32,
    /// Cycles the controlled stop may take before the channel reports stopped anyway.
    #[serde(default = "wd_stop")]
    pub stop_cycles: u32,
}

fn wd_feedback() -> u32 {
    3
}
fn wd_heartbeat() -> u32 {
    250
}
fn wd_hb_period() -> u16 {
    100
}
fn wd_sdo() -> u32 {
    50
}
fn wd_enable() -> u32 {
    2000
}
fn wd_stop() -> u32 {
    1000
}

impl Default for WatchdogConfig {
    fn default() -> Self {
        WatchdogConfig {
            feedback_cycles: wd_feedback(),
            heartbeat_cycles: wd_heartbeat(),
            heartbeat_period_ms: wd_hb_period(),
            sdo_cycles: wd_sdo(),
            enable_cycles: wd_enable(),
            stop_cycles: wd_stop(),
        }
    }
}

/// Why the controller stopped the axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// Asked for (end of the motion, SIGINT/SIGTERM).
    Requested,
    /// Another channel stopped.
    OtherChannel,
    /// No TPDO from `node` for the configured number of cycles.
    MissingFeedback(u8),
    /// `node` sent an emergency with this error code.
    Emcy(u8, u16),
    /// The channel went bus-off or down.
    BusOff,
    /// The heartbeat of `node` expired.
    HeartbeatLost(u8),
    /// |target − position| of `node` exceeded its limit.
    FollowingError(u8),
    /// `node` left Operation Enabled while running.
    LeftOperationEnabled(u8),
    /// `node` sent a malformed or out-of-range frame.
    BadFrame(u8),
    /// Configuration of `node` over SDO failed (no answer after the retries, or out of sequence).
    ConfigurationFailed(u8),
    /// `node` aborted the boot-up SDO transfer of `index:sub` with this abort code.
    SdoAborted(u8, u16, u8, u32),
    /// `node` read `got` from `index:sub` where the device file or the profile says `expected`
    /// (identity 0x1018, device type 0x1000, supported modes 0x6502).
    Mismatch {
        /// Node.
        node: u8,
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Value read (the compared bits).
        got: u32,
        /// Value expected.
        expected: u32,
    },
    /// `node` sent no boot-up message after NMT Reset Communication.
    NoBootUp(u8),
    /// `node` sent a boot-up message after its configuration: it was reset and lost it.
    Rebooted(u8),
    /// The drives did not all reach Operation Enabled in time.
    EnableTimeout,
    /// A setpoint could not be encoded (NaN, or outside the integer range).
    BadSetpoint(u8),
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            StopReason::Requested => write!(f, "stop requested"),
            StopReason::OtherChannel => write!(f, "another channel stopped"),
            StopReason::MissingFeedback(n) => write!(f, "node {n}: feedback (TPDO) missing"),
            StopReason::Emcy(n, c) => write!(f, "node {n}: EMCY error code {c:#06x}"),
            StopReason::BusOff => write!(f, "bus-off / interface down"),
            StopReason::HeartbeatLost(n) => write!(f, "node {n}: heartbeat lost"),
            StopReason::FollowingError(n) => write!(f, "node {n}: following error over the limit"),
            StopReason::LeftOperationEnabled(n) => write!(f, "node {n}: left Operation Enabled"),
            StopReason::BadFrame(n) => write!(f, "node {n}: malformed or out-of-range frame"),
            StopReason::ConfigurationFailed(n) => write!(f, "node {n}: SDO configuration failed"),
            StopReason::SdoAborted(n, i, s, c) => write!(
                f,
                "node {n}: SDO {i:#06x}:{s} aborted at boot-up with code {c:#010x} ({})",
                crate::canopen::sdo::abort_text(c)
            ),
            StopReason::Mismatch {
                node,
                index,
                sub,
                got,
                expected,
            } => write!(
                f,
                "node {node}: {index:#06x}:{sub} reads {got:#x}, expected {expected:#x} (wrong drive or device file)"
            ),
            StopReason::NoBootUp(n) => write!(f, "node {n}: no boot-up message after NMT Reset Communication"),
            StopReason::Rebooted(n) => write!(f, "node {n}: boot-up message while running (the drive was reset)"),
            StopReason::EnableTimeout => write!(f, "drives not enabled in time"),
            StopReason::BadSetpoint(n) => write!(f, "node {n}: setpoint not encodable"),
        }
    }
}
