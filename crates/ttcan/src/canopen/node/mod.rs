//! The drive's protocol node (sans-I/O), a CiA 402 device as CiA 301 describes one: NMT slave
//! (boot-up in Pre-operational, the CiA 402 state machine already in Switch On Disabled),
//! heartbeat producer, SDO server (expedited and segmented) on the object dictionary with the
//! controlword and statusword reachable over SDO as over PDO, RPDO1/TPDO1 with mappings that a
//! master may change over SDO under the CiA 301 rules, SYNC-triggered TPDO, EMCY producer. The
//! physics behind it (the drive layer) is not here: see `crate::vdrive`.
//!
//! PDO rules (CiA 301 §7.5.2.35–38; the abort codes as CANopenNode's `CO_PDO.c` uses them): a
//! mapping entry or the number of entries may only be written while the PDO is invalid (COB-ID
//! bit 31 set), entries only while the number is 0 (else abort 0x06010000); an entry must name an
//! existing (0x06020000), mappable object of its direction and length (0x06040041); the number
//! of entries is checked against the 8 bytes of a PDO (0x06040042); the CAN identifier of a valid
//! PDO cannot change, 29-bit identifiers and the reserved identifiers of CiA 301 §7.3.5 are
//! refused (0x06090030). Transmission types: RPDO 0–240, 254, 255 (every received RPDO takes
//! effect at the next SYNC, as the cyclic synchronous modes require); TPDO 0–240 (synchronous,
//! every n-th SYNC; event-driven types are refused with 0x06090030). NMT Reset Communication
//! restores 0x1000–0x1FFF to their defaults, Reset Node the whole dictionary.

use super::cia402::{Cia402, DriveState, OpMode};
use super::emcy::{self, Emcy};
use super::frame::{Cob, Frame, Frames};
use super::nmt::{decode_nmt, decode_sync, HeartbeatProducer, NmtCommand, NmtState};
use super::od::{self, Access, ObjectDictionary};
use super::pdo::{MapEntry, PdoMapping, MAX_MAP_ENTRIES};
use super::sdo::{SdoRequest, SdoResponse, SdoServer, SdoTarget, ABORT_COMMAND, SDO_BUFFER};
use super::sdo::{ABORT_NOT_MAPPABLE, ABORT_NO_OBJECT, ABORT_PDO_LENGTH, ABORT_RANGE, ABORT_UNSUPPORTED};
use super::ProtocolError;

/// COB-ID bit 31: the PDO does not exist (is invalid).
pub const COB_INVALID: u32 = 1 << 31;
/// COB-ID bit 29: 29-bit identifier (not supported).
const COB_EXTENDED: u32 = 1 << 29;

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
    /// True when the RPDO of this cycle arrived (false: the previous command is held). Without a
    /// valid RPDO the targets come from SDO writes and every SYNC takes them.
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
    /// RPDOs replaced by a newer one before a SYNC took them (an RPDO that arrived after its
    /// SYNC: the SYNC before it counted as missed).
    pub replaced_rpdo: u32,
}

/// The identifiers CiA 301 §7.3.5 reserves (a PDO may not use them).
fn restricted_id(id: u32) -> bool {
    matches!(id, 0x000..=0x07F | 0x101..=0x180 | 0x581..=0x5FF | 0x601..=0x67F | 0x6E0..=0x6FF | 0x701..=0x77F | 0x780..=0x7FF)
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
    sdo: SdoServer,
    pending: Option<Frame>,
    command: DriveCommand,
    counters: NodeCounters,
    missed_in_row: u32,
    extra_status: u16,
    /// A statusword the TPDO carries instead of the true one (fault injection).
    pub statusword_override: Option<u16>,
    rpdo_map: PdoMapping,
    tpdo_map: PdoMapping,
    syncs_since_tpdo: u32,
}

impl DriveNode {
    /// A node with id `node` (1–127), in Pre-operational after sending its boot-up message, its
    /// state machine in Switch On Disabled.
    pub fn new(node: u8, out: &mut Frames) -> Result<Self, ProtocolError> {
        super::frame::check_node(node)?;
        let od = ObjectDictionary::drive(node);
        let hb_ms = od.get(od::HEARTBEAT_TIME, 0).unwrap_or(0) as u32;
        let mut n = DriveNode {
            node,
            nmt: NmtState::PreOperational,
            cia402: Cia402::new(),
            od,
            heartbeat: HeartbeatProducer::new(node, hb_ms)?,
            sdo: SdoServer::new(),
            pending: None,
            command: DriveCommand {
                mode: OpMode::Csp,
                target: 0,
                torque_offset: 0,
                fresh: false,
            },
            counters: NodeCounters::default(),
            missed_in_row: 0,
            extra_status: 0,
            statusword_override: None,
            rpdo_map: PdoMapping::default(),
            tpdo_map: PdoMapping::default(),
            syncs_since_tpdo: 0,
        };
        n.rpdo_map = n.mapping(od::RPDO1_MAP).unwrap_or_default();
        n.tpdo_map = n.mapping(od::TPDO1_MAP).unwrap_or_default();
        n.refresh_statusword();
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

    /// The RPDO1 mapping in force.
    pub fn rpdo_mapping(&self) -> PdoMapping {
        self.rpdo_map
    }

    /// The TPDO1 mapping in force.
    pub fn tpdo_mapping(&self) -> PdoMapping {
        self.tpdo_map
    }

    /// The COB-ID of the PDO whose communication object is `comm` when valid.
    fn pdo_id(&self, comm: u16) -> Option<u16> {
        let v = self.od.get(comm, 1)? as u32;
        (v & COB_INVALID == 0).then_some((v & 0x7FF) as u16)
    }

    /// True while RPDO1 is valid (commands come by PDO).
    pub fn rpdo_valid(&self) -> bool {
        self.pdo_id(od::RPDO1_COMM).is_some()
    }

    /// The mapping stored in mapping object `map` (entries 1..=sub 0).
    fn mapping(&self, map: u16) -> Result<PdoMapping, u32> {
        let n = self.od.get(map, 0).unwrap_or(0) as usize;
        self.mapping_of(map, n)
    }

    fn mapping_of(&self, map: u16, n: usize) -> Result<PdoMapping, u32> {
        if n > MAX_MAP_ENTRIES {
            return Err(ABORT_PDO_LENGTH);
        }
        let mut e = [MapEntry::default(); MAX_MAP_ENTRIES];
        for (k, slot) in e.iter_mut().enumerate().take(n) {
            let w = self.od.get(map, k as u8 + 1).unwrap_or(0) as u32;
            *slot = MapEntry::from_word(w);
            self.check_entry(map, *slot)?;
        }
        PdoMapping::new(&e[..n]).map_err(|_| ABORT_PDO_LENGTH)
    }

    /// Checks that `e` names an existing object mappable in the direction of `map`, of its length.
    fn check_entry(&self, map: u16, e: MapEntry) -> Result<(), u32> {
        let en = self.od.entry(e.index, e.sub).map_err(|_| ABORT_NO_OBJECT)?;
        let direction_ok = if map == od::RPDO1_MAP {
            en.access == Access::Rw
        } else {
            true
        };
        match en.data_type.size() {
            Some(n) if en.mappable && direction_ok && e.bits == 8 * n => Ok(()),
            _ => Err(ABORT_NOT_MAPPABLE),
        }
    }

    fn refresh_statusword(&mut self) {
        let sw = self.cia402.statusword(self.extra_status);
        self.od.set(od::STATUSWORD, 0, sw as i64);
    }

    /// Restores the communication area 0x1000–0x1FFF (`all`: the whole dictionary) to defaults.
    fn restore_defaults(&mut self, all: bool) {
        let fresh = ObjectDictionary::drive(self.node);
        if all {
            self.od = fresh;
        } else {
            for en in fresh.entries() {
                if en.index < 0x2000 {
                    if let Some(v) = fresh.get(en.index, en.sub) {
                        self.od.set(en.index, en.sub, v);
                    }
                }
            }
        }
        self.rpdo_map = self.mapping(od::RPDO1_MAP).unwrap_or_default();
        self.tpdo_map = self.mapping(od::TPDO1_MAP).unwrap_or_default();
        let ms = self.od.get(od::HEARTBEAT_TIME, 0).unwrap_or(0) as u32;
        self.heartbeat.set_period(ms);
    }

    /// Handles one received frame; answers (SDO) go to `out`.
    pub fn on_frame(&mut self, f: &Frame, out: &mut Frames) -> NodeEvent {
        if self.nmt == NmtState::Operational && self.pdo_id(od::RPDO1_COMM) == Some(f.id()) {
            if f.len() == self.rpdo_map.len() {
                if self.pending.is_some() {
                    self.counters.replaced_rpdo += 1;
                }
                self.pending = Some(*f);
            } else {
                self.counters.malformed += 1;
                self.emcy(emcy::PDO_LENGTH, out);
            }
            return NodeEvent::None;
        }
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
            Some(Cob::SdoRx(n)) if n == self.node && self.nmt != NmtState::Stopped => {
                let resp = match SdoRequest::decode(f) {
                    Ok((_, req)) => {
                        self.counters.sdo += 1;
                        let mut server = self.sdo;
                        let r = server.serve(&req, self);
                        self.sdo = server;
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
                        Some(SdoResponse::Abort {
                            index,
                            sub,
                            code: ABORT_COMMAND,
                        })
                    }
                };
                if let Some(Ok(fr)) = resp.map(|r| r.encode(self.node)) {
                    out.push(fr);
                }
            }
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
                self.sdo = SdoServer::new();
                self.syncs_since_tpdo = 0;
                self.missed_in_row = 0;
                self.restore_defaults(cmd == NmtCommand::ResetNode);
                self.refresh_statusword();
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

    /// At a SYNC: sends the TPDO (if Operational and due) with the feedback sampled now, then
    /// takes the RPDO received since the last SYNC (or, without a valid RPDO, the targets written
    /// over SDO): the controlword drives the state machine, the target of the mode is checked
    /// against the software position limits and `max_step` (largest change of a CSP target per
    /// cycle, increments) and refused (EMCY, previous command held) when out of range.
    pub fn on_sync(
        &mut self,
        position: i32,
        current: i16,
        extra_status: u16,
        max_step: i64,
        out: &mut Frames,
    ) -> DriveCommand {
        self.od.set(od::POSITION_ACTUAL, 0, position as i64);
        self.od.set(od::CURRENT_ACTUAL, 0, current as i64);
        self.extra_status = extra_status;
        let mode = OpMode::from_code(self.od.get(od::MODES_OF_OPERATION, 0).unwrap_or(8) as i8).unwrap_or(OpMode::Csp);
        self.od.set(od::MODES_DISPLAY, 0, mode.code() as i64);
        self.refresh_statusword();
        if self.nmt == NmtState::Operational {
            if let Some(id) = self.pdo_id(od::TPDO1_COMM) {
                self.syncs_since_tpdo += 1;
                let every = (self.od.get(od::TPDO1_COMM, 2).unwrap_or(1) as u32).max(1);
                if self.syncs_since_tpdo >= every {
                    self.syncs_since_tpdo = 0;
                    let (od_, sw) = (&self.od, self.statusword_override);
                    let packed = self.tpdo_map.pack(id, |e| match (e.index, sw) {
                        (od::STATUSWORD, Some(s)) => s as i64,
                        _ => od_.get(e.index, e.sub).unwrap_or(0),
                    });
                    if let Ok(f) = packed {
                        out.push(f);
                    }
                }
            }
        }
        let frame = self.pending.take();
        let by_pdo = self.rpdo_valid();
        let mut staged = [(MapEntry::default(), 0i64); MAX_MAP_ENTRIES];
        let mut n_staged = 0;
        if let Some(f) = frame {
            if let Ok(values) = self.rpdo_map.unpack(&f) {
                for (e, raw) in values.iter().take(self.rpdo_map.entries().len()) {
                    let Ok(en) = self.od.entry(e.index, e.sub) else {
                        continue;
                    };
                    let v = en.data_type.extend(*raw);
                    if e.index == od::CONTROLWORD && e.sub == 0 {
                        self.od.set(od::CONTROLWORD, 0, v);
                        self.cia402.on_controlword(v as u16);
                    } else {
                        staged[n_staged] = (*e, v);
                        n_staged += 1;
                    }
                }
            }
        }
        let value = |index: u16, staged: &[(MapEntry, i64)], od_: &ObjectDictionary| {
            staged
                .iter()
                .find(|(e, _)| e.index == index && e.sub == 0)
                .map(|x| x.1)
                .or_else(|| od_.get(index, 0))
                .unwrap_or(0)
        };
        if frame.is_some() || !by_pdo {
            self.missed_in_row = 0;
            let staged = &staged[..n_staged];
            let lo = self.od.get(od::SOFTWARE_POSITION_LIMIT, 1).unwrap_or(i32::MIN as i64);
            let hi = self.od.get(od::SOFTWARE_POSITION_LIMIT, 2).unwrap_or(i32::MAX as i64);
            let max_torque = self.od.get(od::MAX_TORQUE, 0).unwrap_or(0);
            let enabled = self.cia402.state() == DriveState::OperationEnabled;
            let target = match mode {
                OpMode::Csp => value(od::TARGET_POSITION, staged, &self.od),
                OpMode::Csv => value(od::TARGET_VELOCITY, staged, &self.od),
                OpMode::Cst => value(od::TARGET_TORQUE, staged, &self.od),
            };
            let offset = value(od::TORQUE_OFFSET, staged, &self.od);
            let in_range = match mode {
                OpMode::Csp => {
                    (lo..=hi).contains(&target) && (!enabled || (target - position as i64).abs() <= max_step)
                }
                OpMode::Csv => true,
                OpMode::Cst => target.abs() <= max_torque,
            } && offset.abs() <= max_torque
                && staged.iter().all(|(e, v)| {
                    self.od
                        .entry(e.index, e.sub)
                        .is_ok_and(|en| (en.min..=en.max).contains(v))
                });
            if in_range {
                for (e, v) in staged {
                    self.od.set(e.index, e.sub, *v);
                }
                self.command = DriveCommand {
                    mode,
                    target: target as i32,
                    torque_offset: offset as i16,
                    fresh: true,
                };
            } else {
                self.counters.out_of_range += 1;
                self.command.fresh = false;
                self.emcy(emcy::COMMAND_RANGE, out);
            }
        } else if self.nmt == NmtState::Operational {
            self.counters.missed_rpdo += 1;
            self.missed_in_row += 1;
            self.command.fresh = false;
        } else {
            // PDOs only flow in Operational: none is missing before
            self.command.fresh = false;
        }
        self.refresh_statusword();
        self.command.mode = mode;
        self.command
    }

    /// One heartbeat time base tick (1 ms); emits the heartbeat when due.
    pub fn tick_ms(&mut self, out: &mut Frames) {
        if let Some(f) = self.heartbeat.tick(self.nmt) {
            out.push(f);
        }
    }

    /// The CiA 301 rules of the PDO communication and mapping objects for a write of `v` to
    /// `index:sub`.
    fn check_pdo_write(&self, index: u16, sub: u8, v: i64) -> Result<(), u32> {
        let (comm, map) = match index {
            od::RPDO1_COMM | od::RPDO1_MAP => (od::RPDO1_COMM, od::RPDO1_MAP),
            od::TPDO1_COMM | od::TPDO1_MAP => (od::TPDO1_COMM, od::TPDO1_MAP),
            _ => return Ok(()),
        };
        let valid = self.pdo_id(comm).is_some();
        let v = v as u32;
        match (index == comm, sub) {
            (true, 1) => {
                let id = v & 0x7FF;
                if v & COB_EXTENDED != 0 || restricted_id(id) {
                    return Err(ABORT_RANGE);
                }
                let old = self.od.get(comm, 1).unwrap_or(0) as u32;
                if valid && v & COB_INVALID == 0 && id != old & 0x7FF {
                    return Err(ABORT_RANGE);
                }
                Ok(())
            }
            (true, 2) => {
                let ok = if comm == od::RPDO1_COMM {
                    v <= 240 || v >= 254
                } else {
                    v <= 240
                };
                if ok {
                    Ok(())
                } else {
                    Err(ABORT_RANGE)
                }
            }
            (true, _) => Ok(()),
            (false, 0) => {
                if valid {
                    return Err(ABORT_UNSUPPORTED);
                }
                self.mapping_of(map, v as usize).map(|_| ())
            }
            (false, _) => {
                if valid || self.od.get(map, 0).unwrap_or(0) != 0 {
                    return Err(ABORT_UNSUPPORTED);
                }
                if v != 0 {
                    self.check_entry(map, MapEntry::from_word(v))?;
                }
                Ok(())
            }
        }
    }
}

impl SdoTarget for DriveNode {
    fn sdo_read(&mut self, index: u16, sub: u8, out: &mut [u8; SDO_BUFFER]) -> Result<usize, u32> {
        if index == od::STATUSWORD {
            self.refresh_statusword();
        }
        self.od.read(index, sub, out)
    }

    fn sdo_check_write(&mut self, index: u16, sub: u8) -> Result<(), u32> {
        match self.od.entry(index, sub)?.access {
            Access::Rw => Ok(()),
            _ => Err(super::sdo::ABORT_READ_ONLY),
        }
    }

    fn sdo_write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let v = self.od.check_write(index, sub, data)?;
        self.check_pdo_write(index, sub, v)?;
        self.od.write(index, sub, data)?;
        match index {
            od::RPDO1_MAP if sub == 0 => self.rpdo_map = self.mapping(od::RPDO1_MAP).unwrap_or_default(),
            od::TPDO1_MAP if sub == 0 => self.tpdo_map = self.mapping(od::TPDO1_MAP).unwrap_or_default(),
            od::HEARTBEAT_TIME => self.heartbeat.set_period(v as u32),
            od::CONTROLWORD => {
                self.cia402.on_controlword(v as u16);
                self.refresh_statusword();
            }
            _ => {}
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
