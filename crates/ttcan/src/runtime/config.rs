//! The controller's configuration file (TOML): cycle rate, bit rate, mode, watchdog, and the
//! channels with their axes (node id, trajectory joint, scaling, limits) and each drive's bus
//! description (device file, mode, RPDO/TPDO mapping lists, SDO initialisation list, heartbeat;
//! the project's defaults when absent). Checked once at load, before the bus is touched: syntax
//! and unknown keys (the `toml` error names the line and the key), node ids, joint indices, the
//! device files (malformed lines named), every drive's boot-up plan
//! ([`super::boot::BootPlan`]: mapped objects exist, are mappable and fit 8 bytes; written
//! objects exist, are writable, values fit), and the bus budget of every channel from the real
//! mappings ([`crate::canopen::budget`]).

use super::boot::{default_device, BootError, BootPlan, NodeSetup, SdoInit};
use super::master::{following_window, LinkConfig, WatchdogConfig, MAX_AXES_PER_CHANNEL};
use crate::canopen::budget::{check_channel, BusLoad, ChannelTraffic};
use crate::canopen::cia402::OpMode;
use crate::canopen::eds::{DeviceFile, DeviceFileError};
use crate::canopen::Units;
use std::path::PathBuf;

/// `v` as typed by a person: 1e300 as `1e300`, not its 301 digits.
fn num(v: f64) -> String {
    if v.is_finite() && v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Longest approach from the present position to the trajectory's start, s (an hour).
pub const MAX_APPROACH_S: f64 = 3600.0;

/// Most joints a configuration may drive (`joints`, and every axis's `joint` index below it).
pub const MAX_JOINTS: usize = 1024;

/// One axis of a channel.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisEntry {
    /// CANopen node id (1–127).
    pub node: u8,
    /// Trajectory joint this axis follows (0-based); absent: the axis holds its position.
    pub joint: Option<usize>,
    /// SI ↔ CiA 402 scaling.
    #[serde(default)]
    pub units: Units,
    /// Following-error limit, joint units.
    #[serde(default = "super::link::default_following")]
    pub following_error_limit: f64,
    /// Largest plausible |current| from the drive, A.
    #[serde(default = "super::link::default_current")]
    pub max_current: f64,
    /// The drive's device file (EDS or DCF), relative to the configuration file; absent:
    /// `ttdrive-sim`'s (`crates/ttcan/devices/ttdrive-sim.eds`).
    #[serde(default)]
    pub device_file: Option<PathBuf>,
    /// Mode of this drive; absent: the configuration's `mode`.
    #[serde(default)]
    pub mode: Option<OpMode>,
    /// RPDO1 objects as `[index, sub-index]` pairs; absent: target, 0x60B2, 0x6040.
    #[serde(default)]
    pub rpdo: Option<Vec<(u16, u8)>>,
    /// TPDO1 objects; absent: 0x6064, 0x6078, 0x6041.
    #[serde(default)]
    pub tpdo: Option<Vec<(u16, u8)>>,
    /// SDO initialisation list (`{ index, sub, value }`, value a number or a text), written in
    /// order at boot-up after a DCF's parameter values.
    #[serde(default)]
    pub sdo: Vec<SdoInit>,
    /// Producer heartbeat time the drive is given (0x1017), ms; absent: the watchdog's
    /// `heartbeat_period_ms`.
    #[serde(default)]
    pub heartbeat_ms: Option<u16>,
}

impl AxisEntry {
    /// The controller's view of the axis.
    pub fn link(&self) -> LinkConfig {
        LinkConfig {
            node: self.node,
            units: self.units,
            following_error_limit: self.following_error_limit,
            max_current: self.max_current,
        }
    }
}

/// One CAN channel (interface) with its axes.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelEntry {
    /// Interface name (`vcan0`, `can0`, ...).
    pub interface: String,
    /// Axes on this channel.
    pub axis: Vec<AxisEntry>,
}

/// The whole controller configuration.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerConfig {
    /// Robot the trajectory is for (a label checked against the trajectory's joint count).
    #[serde(default)]
    pub robot: Option<String>,
    /// Number of joints of the robot (checked against the trajectory).
    #[serde(default)]
    pub joints: Option<usize>,
    /// SYNC / cycle rate, Hz.
    #[serde(default = "hz")]
    pub cycle_hz: f64,
    /// Bit rate of every channel, bit/s.
    #[serde(default = "br")]
    pub bitrate: f64,
    /// Mode of operation of every drive.
    #[serde(default = "csp")]
    pub mode: OpMode,
    /// Duration of the approach from the present position to the trajectory's start, s.
    #[serde(default = "ap")]
    pub approach_s: f64,
    /// SCHED_FIFO priority of the channel threads.
    #[serde(default = "prio")]
    pub priority: u8,
    /// Watchdog timing.
    #[serde(default)]
    pub watchdog: WatchdogConfig,
    /// Online modes (`ttctl --online`): timeouts and budgets.
    #[serde(default)]
    pub online: crate::online::session::OnlineConfig,
    /// The channels.
    pub channel: Vec<ChannelEntry>,
    /// Directory that device files are relative to (the configuration file's).
    #[serde(skip)]
    pub base_dir: PathBuf,
}

fn hz() -> f64 {
    1000.0
}
fn br() -> f64 {
    1e6
}
fn csp() -> OpMode {
    OpMode::Csp
}
fn ap() -> f64 {
    1.0
}
fn prio() -> u8 {
    80
}

/// A refused configuration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    /// TOML syntax, an unknown key or a wrong type (the message names line and key).
    #[error("{source_name}: {message}")]
    Parse {
        /// File name.
        source_name: String,
        /// The `toml` message with line, column and key.
        message: String,
    },
    /// A value is not acceptable.
    #[error("{source_name}: {message}")]
    Invalid {
        /// File name.
        source_name: String,
        /// What and where.
        message: String,
    },
    /// A channel over the bus budget.
    #[error("{source_name}: {0}", source_name = .1)]
    Budget(crate::canopen::budget::OverBudget, String),
    /// A device file is missing or malformed (the message names file and line).
    #[error("{source_name}: channel {channel} {0}", source_name = .1, channel = .2)]
    DeviceFile(DeviceFileError, String, String),
    /// A drive's bus description does not fit its device file (node, object, reason).
    #[error("{source_name}: channel {channel}: {0}", source_name = .1, channel = .2)]
    Boot(BootError, String, String),
}

impl ControllerConfig {
    /// The default layout: 4 channels `vcan0..3` × 2 axes (nodes 1, 2), joints 0–7, 1 kHz, CSP.
    pub fn default_layout() -> Self {
        let channel = (0..4)
            .map(|c| ChannelEntry {
                interface: format!("vcan{c}"),
                axis: (0..2)
                    .map(|a| AxisEntry {
                        node: a as u8 + 1,
                        joint: Some(2 * c + a),
                        units: Units::default(),
                        following_error_limit: super::link::default_following(),
                        max_current: super::link::default_current(),
                        device_file: None,
                        mode: None,
                        rpdo: None,
                        tpdo: None,
                        sdo: Vec::new(),
                        heartbeat_ms: None,
                    })
                    .collect(),
            })
            .collect();
        ControllerConfig {
            robot: None,
            joints: None,
            cycle_hz: hz(),
            bitrate: br(),
            mode: OpMode::Csp,
            approach_s: ap(),
            priority: prio(),
            watchdog: WatchdogConfig::default(),
            online: Default::default(),
            channel,
            base_dir: PathBuf::new(),
        }
    }

    /// Parses and checks a configuration; `source_name` names the file in messages.
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self, ConfigError> {
        let mut c: ControllerConfig = toml::from_str(text).map_err(|e| ConfigError::Parse {
            source_name: source_name.to_string(),
            message: e.to_string(),
        })?;
        c.base_dir = std::path::Path::new(source_name)
            .parent()
            .map(|p| p.to_path_buf())
            .unwrap_or_default();
        c.check(source_name)?;
        Ok(c)
    }

    /// Checks values and the bus budget; returns the load of every channel.
    pub fn check(&self, source_name: &str) -> Result<Vec<BusLoad>, ConfigError> {
        let invalid = |message: String| ConfigError::Invalid {
            source_name: source_name.to_string(),
            message,
        };
        if !(self.cycle_hz.is_finite() && self.cycle_hz > 0.0 && self.cycle_hz <= 10_000.0) {
            return Err(invalid(format!(
                "cycle_hz = {}: must be in (0, 10000]",
                num(self.cycle_hz)
            )));
        }
        self.online.check().map_err(invalid)?;
        if let Some(n) = self.joints.filter(|&n| n == 0 || n > MAX_JOINTS) {
            return Err(invalid(format!("joints = {n}: must be in 1..={MAX_JOINTS}")));
        }
        if !(self.bitrate.is_finite() && self.bitrate >= 10_000.0 && self.bitrate <= 1e6) {
            return Err(invalid(format!(
                "bitrate = {}: must be in [10000, 1000000] (classical CAN)",
                num(self.bitrate)
            )));
        }
        if !(self.approach_s.is_finite() && (0.0..=MAX_APPROACH_S).contains(&self.approach_s)) {
            // 1e300 s passed: the axes crept to the start for ever (until --max-seconds)
            return Err(invalid(format!(
                "approach_s = {}: must be in [0, {MAX_APPROACH_S}] s",
                num(self.approach_s)
            )));
        }
        if self.channel.is_empty() {
            return Err(invalid("no [[channel]]".into()));
        }
        let mut loads = Vec::new();
        for (c, ch) in self.channel.iter().enumerate() {
            // One interface is one bus: its axes in one [[channel]] entry, so that the bus budget
            // counts all of them (split over two entries each half passed at 49–60 % where the
            // bus carried 94–114 %) and one thread owns the bus.
            if let Some(first) = self.channel[..c].iter().position(|o| o.interface == ch.interface) {
                return Err(invalid(format!(
                    "channel[{c}].interface = \"{}\": already channel[{first}]'s; give an interface's axes in one [[channel]]",
                    ch.interface
                )));
            }
            if ch.axis.is_empty() || ch.axis.len() > MAX_AXES_PER_CHANNEL {
                return Err(invalid(format!(
                    "channel[{c}] ({}): {} axes, 1..={MAX_AXES_PER_CHANNEL} allowed",
                    ch.interface,
                    ch.axis.len()
                )));
            }
            for (a, ax) in ch.axis.iter().enumerate() {
                if !(1..=127).contains(&ax.node) {
                    return Err(invalid(format!(
                        "channel[{c}].axis[{a}].node = {}: must be 1..=127",
                        ax.node
                    )));
                }
                if ch.axis[..a].iter().any(|o| o.node == ax.node) {
                    return Err(invalid(format!(
                        "channel[{c}].axis[{a}].node = {}: used twice on {}",
                        ax.node, ch.interface
                    )));
                }
                if ax.joint.is_some_and(|j| j >= MAX_JOINTS) {
                    // the demo motion and the trajectory's columns are sized by the largest index:
                    // joint = 10¹² aborted allocating them
                    return Err(invalid(format!(
                        "channel[{c}].axis[{a}].joint = {}: must be < {MAX_JOINTS}",
                        ax.joint.unwrap_or_default()
                    )));
                }
                if let (Some(j), Some(n)) = (ax.joint, self.joints) {
                    if j >= n {
                        return Err(invalid(format!(
                            "channel[{c}].axis[{a}].joint = {j}: the robot has {n} joints"
                        )));
                    }
                }
                if ax.units.validate().is_err() {
                    return Err(invalid(format!(
                        "channel[{c}].axis[{a}].units: every factor must be finite and > 0"
                    )));
                }
                if !(ax.max_current.is_finite() && ax.max_current > 0.0) {
                    // NaN compared false and disabled the run-time current check.
                    return Err(invalid(format!(
                        "channel[{c}].axis[{a}].max_current = {}: must be finite and > 0 A",
                        num(ax.max_current)
                    )));
                }
                if !(ax.following_error_limit.is_finite() && ax.following_error_limit > 0.0) {
                    return Err(invalid(format!(
                        "channel[{c}].axis[{a}].following_error_limit must be > 0"
                    )));
                }
            }
            let plans = self.channel_plans(c, source_name)?;
            let mut traffic = ChannelTraffic::eight_byte_pdos(ch.axis.len() as u32, self.cycle_hz, self.bitrate, 0.0);
            traffic.pdo_frames = [0; 9];
            for p in &plans {
                traffic.pdo_frames[p.rpdo.len()] += 1;
                traffic.pdo_frames[p.tpdo.len()] += 1;
            }
            // the fastest heartbeat of the channel, for every drive (conservative)
            let hb = ch
                .axis
                .iter()
                .map(|a| a.heartbeat_ms.unwrap_or(self.watchdog.heartbeat_period_ms))
                .filter(|&ms| ms > 0)
                .min()
                .unwrap_or(0);
            traffic.heartbeat_period = hb as f64 / 1000.0;
            loads.push(
                check_channel(&ch.interface, &traffic).map_err(|e| ConfigError::Budget(e, source_name.to_string()))?,
            );
        }
        Ok(loads)
    }

    /// The boot-up plans of channel `c`'s drives (device files read, bus descriptions checked).
    pub fn channel_plans(&self, c: usize, source_name: &str) -> Result<Vec<BootPlan>, ConfigError> {
        let ch = &self.channel[c];
        let mut default = None;
        ch.axis
            .iter()
            .map(|a| {
                let device = match &a.device_file {
                    Some(p) => {
                        let path = self.base_dir.join(p);
                        DeviceFile::load(&path).map_err(|e| {
                            ConfigError::DeviceFile(
                                e,
                                source_name.to_string(),
                                format!("{} node {}:", ch.interface, a.node),
                            )
                        })?
                    }
                    None => default.get_or_insert_with(default_device).clone(),
                };
                let link = a.link();
                let setup = NodeSetup {
                    node: a.node,
                    mode: a.mode.unwrap_or(self.mode),
                    rpdo: a.rpdo.clone(),
                    tpdo: a.tpdo.clone(),
                    sdo: a.sdo.clone(),
                    heartbeat_ms: a.heartbeat_ms.unwrap_or(self.watchdog.heartbeat_period_ms),
                    following_window: following_window(&link),
                    cycle_s: 1.0 / self.cycle_hz,
                };
                BootPlan::build(&setup, &device)
                    .map_err(|e| ConfigError::Boot(e, source_name.to_string(), ch.interface.clone()))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_layout_passes_the_budget() {
        let loads = ControllerConfig::default_layout().check("default").unwrap();
        assert_eq!(loads.len(), 4);
        assert!(loads.iter().all(|l| l.worst < 0.6));
    }

    #[test]
    fn nan_or_negative_currents_and_a_split_interface_are_refused() {
        for v in ["nan", "-1.0", "0.0", "inf"] {
            let text = format!("[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\nmax_current = {v}\n");
            let e = ControllerConfig::from_toml(&text, "ctl.toml").unwrap_err().to_string();
            assert!(e.contains("max_current"), "{v}: {e}");
        }
        let split = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\n[[channel.axis]]\nnode = 2\n\
                     [[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 3\n";
        let e = ControllerConfig::from_toml(split, "ctl.toml").unwrap_err().to_string();
        assert!(e.contains("already channel[0]'s"), "{e}");
    }

    #[test]
    fn huge_joint_indices_and_endless_device_files_are_refused() {
        // joint = 10¹² aborted `ttctl --demo` allocating a demo motion of that many joints
        let text = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\njoint = 1000000000000\n";
        let e = ControllerConfig::from_toml(text, "ctl.toml").unwrap_err().to_string();
        assert!(e.contains("joint = 1000000000000") && e.contains("1024"), "{e}");
        for n in ["0", "100000"] {
            let text = format!("joints = {n}\n[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\n");
            let e = ControllerConfig::from_toml(&text, "ctl.toml").unwrap_err().to_string();
            assert!(e.contains(&format!("joints = {n}")), "{e}");
        }
        let text = "approach_s = 1e300\n[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\n";
        let e = ControllerConfig::from_toml(text, "ctl.toml").unwrap_err().to_string();
        assert!(e.contains("approach_s = 1e300"), "{e}");
        // a device file that never ends is read no further than 16 MiB
        let text = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\ndevice_file = \"/dev/zero\"\n";
        let e = ControllerConfig::from_toml(text, "/etc/ctl.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("16 MiB"), "{e}");
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let text = "cycle_hz = 1000\n[[channel]]\ninterface = \"vcan0\"\n[[channel.axis]]\nnode = 1\nfollowing_eror_limit = 0.1\n";
        let e = ControllerConfig::from_toml(text, "ctl.toml").unwrap_err().to_string();
        assert!(
            e.contains("ctl.toml") && e.contains("line 6") && e.contains("following_eror_limit"),
            "{e}"
        );
    }

    #[test]
    fn three_axes_per_channel_are_refused_with_the_numbers() {
        let text = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\n[[channel.axis]]\nnode = 2\n[[channel.axis]]\nnode = 3\n";
        let e = ControllerConfig::from_toml(text, "ctl.toml").unwrap_err().to_string();
        assert!(
            e.contains("can0") && e.contains("3 axes") && e.contains("71.") && e.contains("86."),
            "{e}"
        );
        let dup = "[[channel]]\ninterface = \"can0\"\n[[channel.axis]]\nnode = 1\n[[channel.axis]]\nnode = 1\n";
        assert!(ControllerConfig::from_toml(dup, "x")
            .unwrap_err()
            .to_string()
            .contains("used twice"));
    }
}
