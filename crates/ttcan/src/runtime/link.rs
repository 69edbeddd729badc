//! One axis as the channel controller sees it ([`super::master`]): its configuration
//! ([`LinkConfig`]), setpoint and feedback, the channel's counters, and the per-axis state with
//! the SDO configuration sequence. Plain data, no I/O.

use crate::canopen::cia402::{DriveState, OpMode};
use crate::canopen::nmt::HeartbeatConsumer;
use crate::canopen::pdo::PdoMapping;
use crate::canopen::sdo::{SdoClient, SdoData};
use crate::canopen::{ProtocolError, Units};

use super::watchdog::WatchdogConfig;

/// One axis as the controller sees it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkConfig {
    /// CANopen node id of the drive (1–127).
    pub node: u8,
    /// SI ↔ CiA 402 integer scaling.
    #[serde(default)]
    pub units: Units,
    /// Largest |target − position| before the watchdog stops, joint units (rad or m).
    #[serde(default = "default_following")]
    pub following_error_limit: f64,
    /// Largest |current| accepted from the drive, A (a larger value is an out-of-range frame).
    #[serde(default = "default_current")]
    pub max_current: f64,
}

/// Default following-error limit of an axis (joint units): [`LinkConfig`] and the configuration
/// file's axis entries.
pub(super) fn default_following() -> f64 {
    0.05
}

/// Default largest |current| accepted from a drive (A): [`LinkConfig`] and the configuration
/// file's axis entries.
pub(super) fn default_current() -> f64 {
    10.0
}

/// Joint setpoint of one axis, SI (rad or m, rad/s or m/s, N·m or N).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisSetpoint {
    /// Position.
    pub q: f64,
    /// Velocity (CSV target).
    pub qd: f64,
    /// Torque feed-forward (CSP/CSV torque offset) or torque target (CST).
    pub tau: f64,
}

/// Counters of one channel (all visible to the application).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ChannelCounters {
    /// Cycles run.
    pub cycles: u64,
    /// Frames received.
    pub rx: u64,
    /// Malformed frames from our drives.
    pub malformed: u64,
    /// Out-of-range values from our drives.
    pub out_of_range: u64,
    /// Cycles in which an axis had no fresh feedback.
    pub missed_feedback: u64,
    /// Second TPDO of a node within one cycle.
    pub duplicate_feedback: u64,
    /// Bus error frames.
    pub bus_faults: u64,
    /// SDO timeouts and aborts.
    pub sdo_failures: u64,
    /// Valid TPDOs received.
    pub tpdo_rx: u64,
    /// TPDOs due: one per SYNC sent per axis, counted from the axis' first TPDO.
    pub tpdo_expected: u64,
}

impl ChannelCounters {
    /// TPDOs lost on the way (due − received; call after the late ones were drained).
    pub fn tpdo_lost(&self) -> u64 {
        self.tpdo_expected.saturating_sub(self.tpdo_rx)
    }
}

/// Last feedback of one axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Feedback {
    /// Position, joint units.
    pub q: f64,
    /// Current, A.
    pub current: f64,
    /// Statusword.
    pub statusword: u16,
    /// Cycles the channel had completed when this feedback arrived (fresh for the cycle after).
    pub received_cycle: u64,
}

/// One axis' controller-side state: configuration, protocol clients, boot-up progress, last
/// feedback, hold.
#[derive(Debug, Clone, Copy)]
pub(super) struct Link {
    pub(super) cfg: LinkConfig,
    pub(super) heartbeat: HeartbeatConsumer,
    pub(super) sdo: SdoClient,
    /// Mode of operation and the PDO mappings the boot-up configures.
    pub(super) mode: OpMode,
    pub(super) rpdo: PdoMapping,
    pub(super) tpdo: PdoMapping,
    /// NMT Reset Communication sent; boot-up message seen; NMT Start sent.
    pub(super) reset_sent: bool,
    pub(super) booted: bool,
    pub(super) started: bool,
    /// Next step of the boot plan.
    pub(super) boot_step: usize,
    /// The device name 0x1008 read at boot-up.
    pub(super) device_name: Option<SdoData>,
    pub(super) sdo_retries: u8,
    pub(super) state: Option<DriveState>,
    pub(super) feedback: Option<Feedback>,
    pub(super) fresh: bool,
    /// This cycle's feedback answers the last SYNC: fresh, the stream continuous and no hold-off
    /// (what the following-error check compared).
    pub(super) in_step: bool,
    pub(super) missed_in_row: u32,
    pub(super) controlword: u16,
    pub(super) following_holdoff: u32,
    pub(super) hold: f64,
    pub(super) last_target: f64,
}

/// SDO timeouts tolerated per drive during configuration (frames can be lost: retry).
pub const SDO_RETRIES: u8 = 3;

impl Link {
    /// A link for axis `cfg` not yet configured, its clients timed by the watchdog `wd`.
    pub(super) fn new(
        cfg: LinkConfig,
        wd: &WatchdogConfig,
        mode: OpMode,
        rpdo: PdoMapping,
        tpdo: PdoMapping,
    ) -> Result<Link, ProtocolError> {
        cfg.units.validate()?;
        Ok(Link {
            cfg,
            heartbeat: HeartbeatConsumer::new(cfg.node, wd.heartbeat_cycles)?,
            sdo: SdoClient::new(cfg.node, wd.sdo_cycles)?,
            mode,
            rpdo,
            tpdo,
            reset_sent: false,
            booted: false,
            started: false,
            boot_step: 0,
            device_name: None,
            sdo_retries: 0,
            state: None,
            feedback: None,
            fresh: false,
            in_step: false,
            missed_in_row: 0,
            controlword: 0,
            following_holdoff: 0,
            hold: 0.0,
            last_target: 0.0,
        })
    }
}
