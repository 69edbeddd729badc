//! The drive's protocol node (sans-I/O): NMT slave, heartbeat producer, SDO server on the object
//! dictionary, RPDO reception with validation, SYNC-triggered TPDO, EMCY producer and the CiA 402
//! state machine. The physics behind it (the drive layer) is not here: see `crate::vdrive`.

use super::cia402::{Cia402, DriveState, OpMode};
use super::emcy::{self, Emcy};
use super::frame::{Cob, Frame, Frames};
use super::nmt::{decode_nmt, decode_sync, HeartbeatProducer, NmtCommand, NmtState};
use super::od::{self, ObjectDictionary};
use super::pdo::{Rpdo, Tpdo};
use super::sdo::{SdoRequest, SdoResponse, ABORT_COMMAND};
use super::ProtocolError;

/// What a received frame meant to the node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeEvent {
    /// Nothing for the application (answered SDO, heartbeat of another node, ...).
    None,
    /// A SYNC: the application samples its feedback and calls [`DriveNode::on_sync`].
    Sync,
    /// A reset command: the application resets its drive.
    Reset,
}

/// The command the drive follows from one SYNC to the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriveCommand {
    /// Mode of operation.
    pub mode: OpMode,
    /// Target (increments, increments/s or ‰ rated torque, by mode).
    pub target: i32,
    /// Torque offset, ‰ rated torque.
    pub torque_offset: i16,
    /// True when the RPDO of this cycle arrived (false: the previous command is held).
    pub fresh: bool,
}

/// Counters of everything the node refused or missed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NodeCounters {
    /// Frames with a bad length, command or value.
    pub malformed: u32,
    /// SYNCs without a fresh RPDO before them.
    pub missed_rpdo: u32,
    /// RPDOs refused for an out-of-range target.
    pub out_of_range: u32,
    /// SDO requests served.
    pub sdo: u32,
}

/// Protocol state of one virtual drive.
#[derive(Debug, Clone)]
pub struct DriveNode {
    node: u8,
    nmt: NmtState,
    /// The CiA 402 state machine.
    pub cia402: Cia402,
    /// The object dictionary.
    pub od: ObjectDictionary,
    heartbeat: HeartbeatProducer,
    pending: Option<Rpdo>,
    command: DriveCommand,
    counters: NodeCounters,
    missed_in_row: u32,
}

impl DriveNode {
    /// A node with id `node` (1–127), in Pre-operational after sending its boot-up message.
    pub fn new(node: u8, out: &mut Frames) -> Result<Self, ProtocolError> {
        let od = ObjectDictionary::drive();
        let hb_ms = od.get(od::HEARTBEAT_TIME, 0).unwrap_or(0) as u32;
        let n = DriveNode {
            node,
            nmt: NmtState::PreOperational,
            cia402: Cia402::new(),
            od,
            heartbeat: HeartbeatProducer::new(node, hb_ms)?,
            pending: None,
            command: DriveCommand {
                mode: OpMode::Csp,
                target: 0,
                torque_offset: 0,
                fresh: false,
            },
            counters: NodeCounters::default(),
            missed_in_row: 0,
        };
        out.push(super::nmt::encode_heartbeat(node, NmtState::BootUp)?);
        Ok(n)
    }

    /// Node id.
    pub fn node(&self) -> u8 {
        self.node
    }

    /// NMT state.
    pub fn nmt_state(&self) -> NmtState {
        self.nmt
    }

    /// Counters of refused or missing input.
    pub fn counters(&self) -> NodeCounters {
        self.counters
    }

    /// SYNCs in a row without a fresh RPDO.
    pub fn missed_in_row(&self) -> u32 {
        self.missed_in_row
    }

    /// The command in force since the last SYNC.
    pub fn command(&self) -> DriveCommand {
        self.command
    }

    /// Handles one received frame; answers (SDO) go to `out`.
    pub fn on_frame(&mut self, f: &Frame, out: &mut Frames) -> NodeEvent {
        match Cob::classify(f.id()) {
            Some(Cob::Nmt) => match decode_nmt(f) {
                Ok((cmd, n)) if n == 0 || n == self.node => return self.on_nmt(cmd, out),
                Ok(_) => {}
                Err(_) => self.counters.malformed += 1,
            },
            Some(Cob::Sync) => match decode_sync(f) {
                Ok(_) => return NodeEvent::Sync,
                Err(_) => self.counters.malformed += 1,
            },
            Some(Cob::SdoRx(n)) if n == self.node => {
                let resp = match SdoRequest::decode(f) {
                    Ok((_, req)) => {
                        self.counters.sdo += 1;
                        let r = self.od.serve(&req);
                        if let SdoRequest::Download {
                            index: od::HEARTBEAT_TIME,
                            ..
                        } = req
                        {
                            let ms = self.od.get(od::HEARTBEAT_TIME, 0).unwrap_or(0) as u32;
                            self.heartbeat.set_period(ms);
                        }
                        r
                    }
                    Err(_) => {
                        self.counters.malformed += 1;
                        let d = f.data();
                        let (index, sub) = if d.len() >= 4 {
                            (u16::from_le_bytes([d[1], d[2]]), d[3])
                        } else {
                            (0, 0)
                        };
                        SdoResponse::Abort {
                            index,
                            sub,
                            code: ABORT_COMMAND,
                        }
                    }
                };
                if let Ok(fr) = resp.encode(self.node) {
                    out.push(fr);
                }
            }
            Some(Cob::Rpdo1(n)) if n == self.node && self.nmt == NmtState::Operational => match Rpdo::decode(f) {
                Ok((_, r)) => self.pending = Some(r),
                Err(_) => {
                    self.counters.malformed += 1;
                    self.emcy(emcy::PDO_LENGTH, out);
                }
            },
            _ => {}
        }
        NodeEvent::None
    }

    fn on_nmt(&mut self, cmd: NmtCommand, out: &mut Frames) -> NodeEvent {
        match cmd {
            NmtCommand::Start => self.nmt = NmtState::Operational,
            NmtCommand::Stop => self.nmt = NmtState::Stopped,
            NmtCommand::PreOperational => self.nmt = NmtState::PreOperational,
            NmtCommand::ResetNode | NmtCommand::ResetCommunication => {
                self.nmt = NmtState::PreOperational;
                self.cia402 = Cia402::new();
                self.pending = None;
                if let Ok(f) = super::nmt::encode_heartbeat(self.node, NmtState::BootUp) {
                    out.push(f);
                }
                return NodeEvent::Reset;
            }
        }
        NodeEvent::None
    }

    /// Sends an EMCY with `code` (error register bit 0 "generic error" set unless code is 0).
    pub fn emcy(&mut self, code: u16, out: &mut Frames) {
        let register = if code == emcy::NO_ERROR { 0 } else { 1 };
        self.od.set(od::ERROR_REGISTER, 0, register as i64);
        if let Ok(f) = (Emcy {
            node: self.node,
            code,
            register,
            info: [0; 5],
        })
        .encode()
        {
            out.push(f);
        }
    }

    /// At a SYNC: sends the TPDO with the feedback sampled now (if Operational), then takes the
    /// RPDO received since the last SYNC: the controlword drives the state machine, the target is
    /// checked against the software position limits and `max_step` (largest change of a CSP
    /// target per cycle, increments) and refused (EMCY, previous command held) when out of range.
    pub fn on_sync(
        &mut self,
        position: i32,
        current: i16,
        extra_status: u16,
        max_step: i64,
        out: &mut Frames,
    ) -> DriveCommand {
        self.od.set(od::POSITION_ACTUAL, 0, position as i64);
        if self.nmt == NmtState::Operational {
            let sw = self.cia402.statusword(extra_status);
            self.od.set(od::STATUSWORD, 0, sw as i64);
            if let Ok(f) = (Tpdo {
                position,
                current,
                statusword: sw,
            })
            .encode(self.node)
            {
                out.push(f);
            }
        }
        let mode = OpMode::from_code(self.od.get(od::MODES_OF_OPERATION, 0).unwrap_or(8) as i8).unwrap_or(OpMode::Csp);
        self.od.set(od::MODES_DISPLAY, 0, mode.code() as i64);
        match self.pending.take() {
            Some(r) => {
                self.missed_in_row = 0;
                self.cia402.on_controlword(r.controlword);
                self.od.set(od::CONTROLWORD, 0, r.controlword as i64);
                let lo = self.od.get(od::SOFTWARE_POSITION_LIMIT, 1).unwrap_or(i32::MIN as i64);
                let hi = self.od.get(od::SOFTWARE_POSITION_LIMIT, 2).unwrap_or(i32::MAX as i64);
                let max_torque = self.od.get(od::MAX_TORQUE, 0).unwrap_or(0);
                let enabled = self.cia402.state() == DriveState::OperationEnabled;
                let in_range = match mode {
                    OpMode::Csp => {
                        let t = r.target as i64;
                        (lo..=hi).contains(&t) && (!enabled || (t - position as i64).abs() <= max_step)
                    }
                    OpMode::Csv => true,
                    OpMode::Cst => (r.target as i64).abs() <= max_torque,
                } && (r.torque_offset as i64).abs() <= max_torque;
                if in_range {
                    self.command = DriveCommand {
                        mode,
                        target: r.target,
                        torque_offset: r.torque_offset,
                        fresh: true,
                    };
                } else {
                    self.counters.out_of_range += 1;
                    self.command.fresh = false;
                    self.emcy(emcy::COMMAND_RANGE, out);
                }
            }
            None => {
                self.counters.missed_rpdo += 1;
                self.missed_in_row += 1;
                self.command.fresh = false;
            }
        }
        self.command.mode = mode;
        self.command
    }

    /// One heartbeat time base tick (1 ms); emits the heartbeat when due.
    pub fn tick_ms(&mut self, out: &mut Frames) {
        if let Some(f) = self.heartbeat.tick(self.nmt) {
            out.push(f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::cia402::{CW_ENABLE_OPERATION, CW_SHUTDOWN, CW_SWITCH_ON};
    use crate::canopen::nmt::{encode_nmt, encode_sync};

    #[test]
    fn node_boots_starts_enables_and_refuses_out_of_range_targets() {
        let mut out = Frames::new();
        let mut n = DriveNode::new(3, &mut out).unwrap();
        assert_eq!(out.as_slice()[0].id(), 0x703);
        out.clear();
        // RPDO before Start is ignored, no TPDO in Pre-operational
        n.on_frame(
            &Rpdo {
                target: 0,
                torque_offset: 0,
                controlword: CW_SHUTDOWN,
            }
            .encode(3)
            .unwrap(),
            &mut out,
        );
        assert_eq!(n.on_frame(&encode_sync(), &mut out), NodeEvent::Sync);
        n.on_sync(0, 0, 0, 100, &mut out);
        assert!(out.is_empty());
        n.on_frame(&encode_nmt(NmtCommand::Start, 0).unwrap(), &mut out);
        for cw in [CW_SHUTDOWN, CW_SWITCH_ON, CW_ENABLE_OPERATION] {
            n.on_frame(
                &Rpdo {
                    target: 10,
                    torque_offset: 0,
                    controlword: cw,
                }
                .encode(3)
                .unwrap(),
                &mut out,
            );
            let c = n.on_sync(0, 0, 0, 100, &mut out);
            assert!(c.fresh);
        }
        assert_eq!(n.cia402.state(), DriveState::OperationEnabled);
        out.clear();
        n.on_frame(
            &Rpdo {
                target: 1000,
                torque_offset: 0,
                controlword: CW_ENABLE_OPERATION,
            }
            .encode(3)
            .unwrap(),
            &mut out,
        );
        let c = n.on_sync(0, 0, 0, 100, &mut out);
        assert!(!c.fresh && c.target == 10, "jump refused, previous target held");
        assert_eq!(n.counters().out_of_range, 1);
        assert!(out.as_slice().iter().any(|f| f.id() == 0x83), "EMCY sent");
        // missing RPDO is counted
        n.on_sync(0, 0, 0, 100, &mut out);
        assert_eq!(n.missed_in_row(), 1);
        // malformed RPDO
        n.on_frame(&Frame::new(0x203, &[1, 2]).unwrap(), &mut out);
        assert_eq!(n.counters().malformed, 1);
    }
}
