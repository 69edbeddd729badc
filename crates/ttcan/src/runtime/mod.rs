//! The controller runtime: the sans-I/O channel controller ([`master`]) and, on top of it, the
//! real-time pieces (threads, clocks, statistics) that drive it over a [`crate::bus::CanBus`].

pub mod master;

pub use master::{AxisSetpoint, ChannelMaster, LinkConfig, Phase, StopReason, WatchdogConfig};
pub mod channel;
pub mod config;
pub mod rt;
pub mod stats;
pub mod trajectory;
