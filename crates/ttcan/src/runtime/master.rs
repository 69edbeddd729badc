//! The controller's side of one channel, sans-I/O (read → update → write once per cycle, after
//! ros2_control): events in ([`ChannelMaster::on_event`]), then [`ChannelMaster::cycle`] with the
//! joint setpoints writes the RPDOs and the SYNC. It boots the drives as CiA 302 masters do (NMT
//! Reset Communication, boot-up message, then the SDO steps of each drive's
//! [`super::boot::BootPlan`]: identity and profile checked, SDO list, PDO remapping, 0x60C2,
//! 0x6060, 0x6065, 0x1017; then NMT Start), enables them through the CiA 402 state machine
//! holding their present position, and watches them: missing feedback for
//! k cycles, an EMCY, bus-off, a following error, heartbeat loss, a drive leaving Operation
//! Enabled, a malformed or out-of-range frame from a drive: each brings every axis to a controlled
//! stop (controlword Quick Stop), with the reason kept. Fixed capacity, no allocation.

use crate::bus::{BusEvent, BusFault};
use crate::canopen::cia402::{controlword_towards_enabled, DriveState, OpMode, CW_QUICK_STOP};
use crate::canopen::emcy::Emcy;
use crate::canopen::frame::{Cob, Frame, Frames};
use crate::canopen::nmt::{decode_heartbeat, encode_nmt, encode_sync, NmtCommand, NmtState};
use crate::canopen::od;
use crate::canopen::sdo::{SdoError, SdoOutcome};
use crate::canopen::ProtocolError;

use super::boot::{default_device, BootPlan, NodeSetup};
use super::link::Link;
pub use super::link::{AxisSetpoint, ChannelCounters, Feedback, LinkConfig, SDO_RETRIES};
pub use super::watchdog::{StopReason, WatchdogConfig};

/// Most axes on one channel (the bus budget allows 2 at 1 kHz and 1 Mbit/s).
pub const MAX_AXES_PER_CHANNEL: usize = 4;

/// Lifecycle of a channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Boot-up: NMT Reset Communication, boot-up messages, SDO steps, NMT Start, first feedback.
    Configure,
    /// Stepping the drives to Operation Enabled.
    Enable,
    /// Every axis in Operation Enabled: following the setpoints.
    Run,
    /// Controlled stop in progress.
    Stopping,
    /// Every axis stopped (or the stop timed out).
    Stopped,
}

/// The sans-I/O controller of one channel.
#[derive(Debug, Clone)]
pub struct ChannelMaster {
    links: [Option<Link>; MAX_AXES_PER_CHANNEL],
    plans: [Option<BootPlan>; MAX_AXES_PER_CHANNEL],
    n: usize,
    wd: WatchdogConfig,
    phase: Phase,
    phase_cycles: u32,
    stop: Option<StopReason>,
    stopped_after: Option<u32>,
    counters: ChannelCounters,
    /// SDO requests that answers called for (segments), sent with the next cycle.
    sdo_out: Frames,
}

impl ChannelMaster {
    /// A controller for `axes` (≤ [`MAX_AXES_PER_CHANNEL`]) in `mode`, each drive booted as
    /// `ttdrive-sim`'s device file describes it with the project's default PDO mappings (the
    /// interpolation period 0x60C2 set for a 1 kHz cycle; [`ChannelMaster::with_plans`] for
    /// other drives and cycles).
    pub fn new(axes: &[LinkConfig], mode: OpMode, wd: WatchdogConfig) -> Result<Self, ProtocolError> {
        let device = default_device();
        let mut plans = Vec::with_capacity(axes.len());
        for a in axes {
            let setup = NodeSetup {
                node: a.node,
                mode,
                rpdo: None,
                tpdo: None,
                sdo: Vec::new(),
                heartbeat_ms: wd.heartbeat_period_ms,
                following_window: following_window(a),
                cycle_s: 1e-3,
            };
            plans.push(BootPlan::build(&setup, &device).map_err(|_| ProtocolError::BadNode(a.node))?);
        }
        Self::with_plans(axes, &plans, wd)
    }

    /// A controller for `axes` booted by `plans` (one per axis, same order).
    pub fn with_plans(axes: &[LinkConfig], plans: &[BootPlan], wd: WatchdogConfig) -> Result<Self, ProtocolError> {
        if axes.len() > MAX_AXES_PER_CHANNEL || axes.is_empty() || plans.len() != axes.len() {
            return Err(ProtocolError::OutOfRange {
                what: "axes per channel",
                value: axes.len() as i64,
            });
        }
        let mut links = [None; MAX_AXES_PER_CHANNEL];
        let mut boot = [None; MAX_AXES_PER_CHANNEL];
        for (k, (a, p)) in axes.iter().zip(plans).enumerate() {
            links[k] = Some(Link::new(*a, &wd, p.mode, p.rpdo, p.tpdo)?);
            boot[k] = Some(*p);
        }
        Ok(ChannelMaster {
            links,
            plans: boot,
            n: axes.len(),
            wd,
            phase: Phase::Configure,
            phase_cycles: 0,
            stop: None,
            stopped_after: None,
            counters: ChannelCounters::default(),
            sdo_out: Frames::new(),
        })
    }

    fn links(&mut self) -> impl Iterator<Item = &mut Link> {
        self.links[..self.n].iter_mut().flatten()
    }

    /// Present phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Why the channel is stopping (`None` while fine).
    pub fn stop_reason(&self) -> Option<StopReason> {
        self.stop
    }

    /// Cycles from the stop decision to every axis stopped (`None` before).
    pub fn stopped_after(&self) -> Option<u32> {
        self.stopped_after
    }

    /// Counters.
    pub fn counters(&self) -> ChannelCounters {
        self.counters
    }

    /// Number of axes.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True without axes (never: [`ChannelMaster::new`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Last feedback of axis `k` (`None` before the first TPDO).
    pub fn feedback(&self, k: usize) -> Option<Feedback> {
        self.links.get(k).copied().flatten().and_then(|l| l.feedback)
    }

    /// Whether axis `k`'s feedback of this cycle answers the last SYNC (Run phase, fresh, the
    /// stream continuous and no hold-off after a gap, a burst or skipped deadlines): the
    /// feedback the following-error check compared with the target in force. Valid after
    /// [`ChannelMaster::cycle`].
    pub fn feedback_in_step(&self, k: usize) -> bool {
        self.links.get(k).copied().flatten().is_some_and(|l| l.in_step)
    }

    /// The device name (0x1008) axis `k`'s drive reported at boot-up.
    pub fn device_name(&self, k: usize) -> Option<String> {
        let l = self.links.get(k).copied().flatten()?;
        l.device_name.map(|d| String::from_utf8_lossy(d.bytes()).into_owned())
    }

    /// Drive state of axis `k` from its last statusword.
    pub fn drive_state(&self, k: usize) -> Option<DriveState> {
        self.links.get(k).copied().flatten().and_then(|l| l.state)
    }

    /// Position axis `k` held while enabling (the start of the motion), joint units.
    pub fn hold_position(&self, k: usize) -> f64 {
        self.links.get(k).copied().flatten().map(|l| l.hold).unwrap_or(0.0)
    }

    /// The cycle timing was disturbed (deadlines skipped): the following-error check pauses for
    /// `cycles` cycles, since feedback may then answer an older SYNC than the last one.
    pub fn hold_off_following_check(&mut self, cycles: u32) {
        for l in self.links() {
            l.following_holdoff = l.following_holdoff.max(cycles);
        }
    }

    /// Starts a controlled stop of every axis (the first reason is kept).
    pub fn request_stop(&mut self, reason: StopReason) {
        if self.stop.is_none() {
            self.stop = Some(reason);
        }
        if !matches!(self.phase, Phase::Stopping | Phase::Stopped) {
            self.phase = Phase::Stopping;
            self.phase_cycles = 0;
        }
    }

    /// Feeds one bus event (read phase of the cycle).
    pub fn on_event(&mut self, ev: &BusEvent) {
        match ev {
            BusEvent::Fault(f) => {
                self.counters.bus_faults += 1;
                if *f == BusFault::BusOff {
                    self.request_stop(StopReason::BusOff);
                }
            }
            BusEvent::Frame { frame, .. } => {
                self.counters.rx += 1;
                self.on_frame(frame);
            }
        }
    }

    fn index_of(&self, node: u8) -> Option<usize> {
        self.links[..self.n]
            .iter()
            .position(|l| l.map(|l| l.cfg.node) == Some(node))
    }

    fn on_frame(&mut self, f: &Frame) {
        let Some(cob) = Cob::classify(f.id()) else { return };
        let node = match cob {
            Cob::Tpdo1(n) | Cob::Emcy(n) | Cob::SdoTx(n) | Cob::Heartbeat(n) => n,
            _ => return,
        };
        let Some(k) = self.index_of(node) else { return };
        let mut stop = None;
        {
            let Some(l) = self.links[k].as_mut() else { return };
            match cob {
                Cob::Tpdo1(_) => match decode_feedback(l, f) {
                    Ok(t) => match DriveState::from_statusword(t.statusword) {
                        Ok(s) => {
                            let current = l.cfg.units.permille_to_current(t.current);
                            if current.abs() > l.cfg.max_current {
                                self.counters.out_of_range += 1;
                                stop = Some(StopReason::BadFrame(node));
                            } else {
                                if l.fresh {
                                    // two answers in one read: they came late, the newest may
                                    // answer an older SYNC than the last one
                                    self.counters.duplicate_feedback += 1;
                                    l.following_holdoff = l.following_holdoff.max(2);
                                }
                                l.fresh = true;
                                self.counters.tpdo_rx += 1;
                                l.state = Some(s);
                                l.feedback = Some(Feedback {
                                    q: l.cfg.units.increments_to_position(t.position),
                                    current,
                                    statusword: t.statusword,
                                    received_cycle: self.counters.cycles,
                                });
                            }
                        }
                        Err(_) => {
                            self.counters.out_of_range += 1;
                            stop = Some(StopReason::BadFrame(node));
                        }
                    },
                    Err(_) => {
                        self.counters.malformed += 1;
                        stop = Some(StopReason::BadFrame(node));
                    }
                },
                Cob::Emcy(_) => match Emcy::decode(f) {
                    Ok(e) if !e.is_reset() => stop = Some(StopReason::Emcy(node, e.code)),
                    Ok(_) => {}
                    Err(_) => {
                        self.counters.malformed += 1;
                        stop = Some(StopReason::BadFrame(node));
                    }
                },
                Cob::Heartbeat(_) => {
                    if let Ok((_, NmtState::BootUp)) = decode_heartbeat(f) {
                        if l.started {
                            stop = Some(StopReason::Rebooted(node));
                        } else if l.reset_sent {
                            l.booted = true;
                        }
                    }
                    self.counters.malformed += u64::from(!l.heartbeat.on_frame(f));
                }
                Cob::SdoTx(_) => match l.sdo.on_frame(f, &mut self.sdo_out) {
                    Some(Ok(outcome)) => {
                        let expect = self.plans[k].and_then(|p| p.step(l.boot_step)).and_then(|s| s.expect);
                        match (outcome, expect) {
                            (SdoOutcome::Read { index, sub, data }, Some(e))
                                if data.as_u64().unwrap_or(u64::MAX) as u32 & e.mask != e.value =>
                            {
                                stop = Some(StopReason::Mismatch {
                                    node,
                                    index,
                                    sub,
                                    got: data.as_u64().unwrap_or(0) as u32 & e.mask,
                                    expected: e.value,
                                });
                            }
                            (
                                SdoOutcome::Read {
                                    index: od::DEVICE_NAME,
                                    data,
                                    ..
                                },
                                _,
                            ) => {
                                l.device_name = Some(data);
                                l.boot_step += 1;
                            }
                            _ => l.boot_step += 1,
                        }
                    }
                    Some(Err(SdoError::Aborted { index, sub, code })) => {
                        self.counters.sdo_failures += 1;
                        stop = Some(StopReason::SdoAborted(node, index, sub, code));
                    }
                    Some(Err(_)) => {
                        self.counters.sdo_failures += 1;
                        stop = Some(StopReason::ConfigurationFailed(node));
                    }
                    None => {}
                },
                _ => {}
            }
        }
        if let Some(r) = stop {
            // before Run, a refused frame still stops: nothing may be enabled on bad data
            self.request_stop(r);
        }
    }

    /// One cycle (update and write): watchdog checks on this cycle's feedback, phase logic, then
    /// the RPDO of every axis and the SYNC into `out`. `setpoints[k]` is used in [`Phase::Run`].
    pub fn cycle(&mut self, setpoints: &[AxisSetpoint], out: &mut Frames) {
        self.counters.cycles += 1;
        self.phase_cycles = self.phase_cycles.saturating_add(1);
        for f in self.sdo_out.as_slice() {
            out.push(*f);
        }
        self.sdo_out.clear();
        self.watchdog();
        let phase = self.phase;
        let wd = self.wd;
        let mut all_configured = true;
        let mut all_enabled = true;
        let mut all_stopped = true;
        let mut bad_setpoint = None;
        for k in 0..self.n {
            let Some(mut l) = self.links[k] else { continue };
            let mode = l.mode;
            // boot-up: reset communication, boot-up message, SDO steps one at a time, NMT Start
            let steps = self.plans[k].map_or(0, |p| p.len());
            if phase == Phase::Configure {
                let cmd = if !l.reset_sent {
                    l.reset_sent = true;
                    Some(NmtCommand::ResetCommunication)
                } else if l.booted && l.boot_step >= steps && !l.started {
                    l.started = true;
                    Some(NmtCommand::Start)
                } else {
                    None
                };
                if let Some(Ok(f)) = cmd.map(|c| encode_nmt(c, l.cfg.node)) {
                    out.push(f);
                }
                if l.booted && l.boot_step < steps && !l.sdo.busy() {
                    if let Some(step) = self.plans[k].and_then(|p| p.step(l.boot_step)) {
                        if let Some(f) = l.sdo.start(step.job) {
                            out.push(f);
                        }
                    }
                }
            }
            if l.sdo.tick().is_some() {
                // a lost request or response: the next cycle sends the request again
                self.counters.sdo_failures += 1;
                l.sdo_retries += 1;
                if l.sdo_retries > SDO_RETRIES {
                    bad_setpoint.get_or_insert(StopReason::ConfigurationFailed(l.cfg.node));
                }
            }
            all_configured &= l.started && l.feedback.is_some();
            let state = l.state.unwrap_or(DriveState::NotReadyToSwitchOn);
            let (cw, target_q) = match phase {
                Phase::Configure => (0, l.feedback.map(|f| f.q).unwrap_or(0.0)),
                Phase::Enable => {
                    let q = l.feedback.map(|f| f.q).unwrap_or(0.0);
                    if state != DriveState::OperationEnabled {
                        l.hold = q;
                    }
                    all_enabled &= state == DriveState::OperationEnabled;
                    (controlword_towards_enabled(state, true, l.controlword), l.hold)
                }
                Phase::Run => (l.controlword, setpoints.get(k).map(|s| s.q).unwrap_or(l.hold)),
                Phase::Stopping | Phase::Stopped => {
                    all_stopped &= !state.torque_on() || !l.fresh && l.missed_in_row > 0;
                    (CW_QUICK_STOP, l.last_target)
                }
            };
            let sp = setpoints.get(k).copied().unwrap_or_default();
            let u = l.cfg.units;
            let encoded = match (phase, mode) {
                (Phase::Run, OpMode::Csv) => u.velocity_to_increments(sp.qd),
                (Phase::Run, OpMode::Cst) => u.torque_to_permille(sp.tau).map(|t| t as i32),
                (_, OpMode::Csv) | (_, OpMode::Cst) => Ok(0),
                _ => u.position_to_increments(target_q),
            };
            let offset = if phase == Phase::Run && mode != OpMode::Cst {
                u.torque_to_permille(sp.tau)
            } else {
                Ok(0)
            };
            match (encoded, offset) {
                (Ok(target), Ok(torque_offset)) => {
                    let packed = l.rpdo.pack(Cob::Rpdo1(l.cfg.node).id(), |e| match e.index {
                        od::CONTROLWORD => cw as i64,
                        od::TORQUE_OFFSET => torque_offset as i64,
                        od::MODES_OF_OPERATION => mode.code() as i64,
                        _ => target as i64,
                    });
                    if let Ok(f) = packed {
                        out.push(f);
                    }
                    l.last_target = target_q;
                }
                _ => {
                    bad_setpoint.get_or_insert(StopReason::BadSetpoint(l.cfg.node));
                    // the drive holds its last command (RPDO missing) and the stop follows
                }
            }
            l.controlword = cw;
            l.fresh = false;
            if l.feedback.is_some() {
                self.counters.tpdo_expected += 1;
            }
            self.links[k] = Some(l);
        }
        if let Some(r) = bad_setpoint {
            self.request_stop(r);
        }
        match self.phase {
            Phase::Configure if all_configured => {
                self.phase = Phase::Enable;
                self.phase_cycles = 0;
            }
            Phase::Enable if all_enabled => {
                self.phase = Phase::Run;
                self.phase_cycles = 0;
            }
            Phase::Configure | Phase::Enable if self.phase_cycles > wd.enable_cycles => {
                let silent = self.links[..self.n].iter().flatten().find(|l| !l.booted);
                let reason = match (self.phase, silent) {
                    (Phase::Configure, Some(l)) => StopReason::NoBootUp(l.cfg.node),
                    _ => StopReason::EnableTimeout,
                };
                self.request_stop(reason)
            }
            Phase::Stopping if all_stopped || self.phase_cycles > wd.stop_cycles => {
                self.stopped_after = Some(self.phase_cycles);
                self.phase = Phase::Stopped;
            }
            _ => {}
        }
        out.push(encode_sync());
    }

    fn watchdog(&mut self) {
        let phase = self.phase;
        let wd = self.wd;
        let mut stop = None;
        let mut missed = 0;
        for l in self.links() {
            l.in_step = false;
            if l.heartbeat.received() > 0 && l.heartbeat.tick() && phase != Phase::Stopped {
                stop.get_or_insert(StopReason::HeartbeatLost(l.cfg.node));
            }
            if l.fresh {
                // feedback after a gap may answer an older SYNC than the last one: the
                // following-error check waits until the stream is continuous again
                if l.missed_in_row > 0 {
                    l.following_holdoff = l.following_holdoff.max(2 * l.missed_in_row + 2);
                }
                l.missed_in_row = 0;
            } else if l.feedback.is_some() {
                l.missed_in_row += 1;
                missed += 1;
                // in Configure the SDO and enable timeouts watch the drives (start-up is slow)
                if l.missed_in_row > wd.feedback_cycles && !matches!(phase, Phase::Configure | Phase::Stopped) {
                    stop.get_or_insert(StopReason::MissingFeedback(l.cfg.node));
                }
            }
            if phase == Phase::Run {
                if let (true, Some(fb)) = (l.fresh, l.feedback) {
                    if l.state != Some(DriveState::OperationEnabled) {
                        stop.get_or_insert(StopReason::LeftOperationEnabled(l.cfg.node));
                    } else if l.following_holdoff > 0 {
                        l.following_holdoff -= 1;
                    } else {
                        l.in_step = true;
                        if (l.last_target - fb.q).abs() > l.cfg.following_error_limit {
                            stop.get_or_insert(StopReason::FollowingError(l.cfg.node));
                        }
                    }
                }
            }
        }
        self.counters.missed_feedback += missed;
        if let Some(r) = stop {
            self.request_stop(r);
        }
    }
}

/// Following-error window of an axis for 0x6065, increments.
pub fn following_window(a: &LinkConfig) -> u32 {
    (a.following_error_limit * a.units.increments_per_unit).clamp(1.0, i32::MAX as f64) as u32
}

/// The fields of a TPDO the controller uses, by the link's mapping (current 0 when not mapped).
struct TpdoFields {
    position: i32,
    current: i16,
    statusword: u16,
}

fn decode_feedback(l: &Link, f: &Frame) -> Result<TpdoFields, ProtocolError> {
    let values = l.tpdo.unpack(f)?;
    let mut t = TpdoFields {
        position: 0,
        current: 0,
        statusword: 0,
    };
    for (e, raw) in values.iter().take(l.tpdo.entries().len()) {
        match (e.index, e.sub) {
            (od::POSITION_ACTUAL, 0) => t.position = *raw as u32 as i32,
            (od::CURRENT_ACTUAL, 0) => t.current = *raw as u16 as i16,
            (od::STATUSWORD, 0) => t.statusword = *raw as u16,
            _ => {}
        }
    }
    Ok(t)
}
