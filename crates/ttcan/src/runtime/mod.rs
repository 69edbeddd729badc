//! The controller runtime: the sans-I/O channel controller ([`master`]) with its axes ([`link`])
//! and its [`watchdog`],
//! and on top of it the real-time pieces: clocks and scheduling ([`rt`]), statistics ([`stats`]),
//! trajectories ([`trajectory`]), the configuration file ([`config`]) and the per-channel thread
//! ([`channel`]) that drives a controller over a [`crate::bus::CanBus`]; in-process virtual drives
//! for a machine without CAN ([`vdrives`]).

pub mod boot;
pub mod channel;
pub mod config;
pub mod exit;
pub mod link;
pub mod master;
pub mod rt;
pub mod stats;
pub mod trajectory;
pub mod vdrives;
pub mod watchdog;

pub use master::{AxisSetpoint, ChannelMaster, LinkConfig, Phase};
pub use watchdog::{StopReason, WatchdogConfig};
