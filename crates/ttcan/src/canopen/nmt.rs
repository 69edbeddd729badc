//! Network management (CiA 301 §7.2.8): NMT commands, the SYNC object, and heartbeat producer and
//! consumer. Times are counted in cycles of the channel (one cycle = one SYNC period).

use super::frame::{check_node, Cob, Frame};
use super::ProtocolError;

/// NMT command specifier (byte 0 of an NMT frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NmtCommand {
    /// Start remote node → Operational.
    Start,
    /// Stop remote node → Stopped.
    Stop,
    /// Enter Pre-operational.
    PreOperational,
    /// Reset node (application and communication).
    ResetNode,
    /// Reset communication.
    ResetCommunication,
}

impl NmtCommand {
    fn code(self) -> u8 {
        match self {
            NmtCommand::Start => 0x01,
            NmtCommand::Stop => 0x02,
            NmtCommand::PreOperational => 0x80,
            NmtCommand::ResetNode => 0x81,
            NmtCommand::ResetCommunication => 0x82,
        }
    }

    fn from_code(c: u8) -> Option<Self> {
        Some(match c {
            0x01 => NmtCommand::Start,
            0x02 => NmtCommand::Stop,
            0x80 => NmtCommand::PreOperational,
            0x81 => NmtCommand::ResetNode,
            0x82 => NmtCommand::ResetCommunication,
            _ => return None,
        })
    }
}

/// Encodes an NMT command for `node` (0 addresses every node).
pub fn encode_nmt(command: NmtCommand, node: u8) -> Result<Frame, ProtocolError> {
    if node > 127 {
        return Err(ProtocolError::BadNode(node));
    }
    Ok(Frame::raw(Cob::Nmt.id(), 2, [command.code(), node, 0, 0, 0, 0, 0, 0]))
}

/// Decodes an NMT frame into (command, addressed node; 0 = all).
pub fn decode_nmt(f: &Frame) -> Result<(NmtCommand, u8), ProtocolError> {
    if f.id() != Cob::Nmt.id() {
        return Err(ProtocolError::UnexpectedFrame(f.id()));
    }
    f.expect_len(2)?;
    let d = f.data();
    let cmd = NmtCommand::from_code(d[0]).ok_or(ProtocolError::BadCommand(d[0]))?;
    if d[1] > 127 {
        return Err(ProtocolError::BadNode(d[1]));
    }
    Ok((cmd, d[1]))
}

/// Encodes a SYNC without counter (0 data bytes, the 47–55-bit frame of the bus budget).
pub fn encode_sync() -> Frame {
    Frame::raw(Cob::Sync.id(), 0, [0; 8])
}

/// Decodes a SYNC: `Ok(None)` without counter, `Ok(Some(c))` with a counter 1–240.
pub fn decode_sync(f: &Frame) -> Result<Option<u8>, ProtocolError> {
    if f.id() != Cob::Sync.id() {
        return Err(ProtocolError::UnexpectedFrame(f.id()));
    }
    match f.data() {
        [] => Ok(None),
        [c @ 1..=240] => Ok(Some(*c)),
        [c] => Err(ProtocolError::OutOfRange {
            what: "SYNC counter",
            value: *c as i64,
        }),
        _ => Err(ProtocolError::BadLength {
            id: f.id(),
            expected: 0,
            got: f.len() as u8,
        }),
    }
}

/// NMT state of a node as its heartbeat reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NmtState {
    /// Boot-up message (sent once after reset).
    BootUp,
    /// Stopped.
    Stopped,
    /// Operational (PDOs exchanged).
    Operational,
    /// Pre-operational (SDO only).
    PreOperational,
}

impl NmtState {
    fn code(self) -> u8 {
        match self {
            NmtState::BootUp => 0x00,
            NmtState::Stopped => 0x04,
            NmtState::Operational => 0x05,
            NmtState::PreOperational => 0x7F,
        }
    }
}

/// Encodes the heartbeat (or boot-up) message of `node` in `state`.
pub fn encode_heartbeat(node: u8, state: NmtState) -> Result<Frame, ProtocolError> {
    let n = check_node(node)?;
    Ok(Frame::raw(
        Cob::Heartbeat(n).id(),
        1,
        [state.code(), 0, 0, 0, 0, 0, 0, 0],
    ))
}

/// Decodes a heartbeat into (node, state); the toggle bit 7 (node guarding) must be clear.
pub fn decode_heartbeat(f: &Frame) -> Result<(u8, NmtState), ProtocolError> {
    let Some(Cob::Heartbeat(node)) = Cob::classify(f.id()) else {
        return Err(ProtocolError::UnexpectedFrame(f.id()));
    };
    f.expect_len(1)?;
    let state = match f.data()[0] {
        0x00 => NmtState::BootUp,
        0x04 => NmtState::Stopped,
        0x05 => NmtState::Operational,
        0x7F => NmtState::PreOperational,
        s => {
            return Err(ProtocolError::OutOfRange {
                what: "heartbeat state",
                value: s as i64,
            })
        }
    };
    Ok((node, state))
}

/// Heartbeat producer: emits the node's heartbeat every `period_cycles` cycles (0 = off).
#[derive(Debug, Clone, Copy)]
pub struct HeartbeatProducer {
    node: u8,
    period_cycles: u32,
    count: u32,
}

impl HeartbeatProducer {
    /// A producer for `node` with a period of `period_cycles` cycles.
    pub fn new(node: u8, period_cycles: u32) -> Result<Self, ProtocolError> {
        Ok(HeartbeatProducer {
            node: check_node(node)?,
            period_cycles,
            count: 0,
        })
    }

    /// Changes the period (object 0x1017 written), cycles; 0 switches the heartbeat off.
    pub fn set_period(&mut self, period_cycles: u32) {
        self.period_cycles = period_cycles;
        self.count = 0;
    }

    /// Advances one cycle; returns the heartbeat frame when one is due.
    pub fn tick(&mut self, state: NmtState) -> Option<Frame> {
        if self.period_cycles == 0 {
            return None;
        }
        self.count += 1;
        if self.count >= self.period_cycles {
            self.count = 0;
            encode_heartbeat(self.node, state).ok()
        } else {
            None
        }
    }
}

/// Heartbeat consumer for one node: expires when no heartbeat came for `timeout_cycles` cycles.
#[derive(Debug, Clone, Copy)]
pub struct HeartbeatConsumer {
    node: u8,
    timeout_cycles: u32,
    since_last: u32,
    state: Option<NmtState>,
    received: u64,
}

impl HeartbeatConsumer {
    /// A consumer watching `node` with a timeout of `timeout_cycles` cycles.
    pub fn new(node: u8, timeout_cycles: u32) -> Result<Self, ProtocolError> {
        Ok(HeartbeatConsumer {
            node: check_node(node)?,
            timeout_cycles,
            since_last: 0,
            state: None,
            received: 0,
        })
    }

    /// Feeds a heartbeat frame; returns true when it was this node's and valid.
    pub fn on_frame(&mut self, f: &Frame) -> bool {
        match decode_heartbeat(f) {
            Ok((n, s)) if n == self.node => {
                self.state = Some(s);
                self.since_last = 0;
                self.received += 1;
                true
            }
            _ => false,
        }
    }

    /// Advances one cycle; returns true once the heartbeat has expired.
    pub fn tick(&mut self) -> bool {
        self.since_last = self.since_last.saturating_add(1);
        self.expired()
    }

    /// True when the last heartbeat is older than the timeout.
    pub fn expired(&self) -> bool {
        self.since_last > self.timeout_cycles
    }

    /// Cycles since the last heartbeat.
    pub fn since_last(&self) -> u32 {
        self.since_last
    }

    /// The last reported NMT state (`None` before the first heartbeat).
    pub fn state(&self) -> Option<NmtState> {
        self.state
    }

    /// Heartbeats received so far.
    pub fn received(&self) -> u64 {
        self.received
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nmt_round_trips_and_rejects_unknown_command() {
        let f = encode_nmt(NmtCommand::Start, 0).unwrap();
        assert_eq!(f.data(), &[1, 0]);
        assert_eq!(decode_nmt(&f).unwrap(), (NmtCommand::Start, 0));
        let bad = Frame::new(0, &[0x33, 1]).unwrap();
        assert_eq!(decode_nmt(&bad), Err(ProtocolError::BadCommand(0x33)));
        assert!(decode_nmt(&Frame::new(0, &[1]).unwrap()).is_err());
    }

    #[test]
    fn sync_counter_range_is_checked() {
        assert_eq!(decode_sync(&encode_sync()), Ok(None));
        assert_eq!(decode_sync(&Frame::new(0x80, &[7]).unwrap()), Ok(Some(7)));
        assert!(decode_sync(&Frame::new(0x80, &[0]).unwrap()).is_err());
        assert!(decode_sync(&Frame::new(0x80, &[241]).unwrap()).is_err());
        assert!(decode_sync(&Frame::new(0x80, &[1, 2]).unwrap()).is_err());
    }

    #[test]
    fn heartbeat_consumer_expires_after_timeout_and_recovers() {
        let mut p = HeartbeatProducer::new(5, 3).unwrap();
        let mut c = HeartbeatConsumer::new(5, 4).unwrap();
        for _ in 0..30 {
            if let Some(f) = p.tick(NmtState::Operational) {
                assert!(c.on_frame(&f));
            }
            assert!(!c.tick());
        }
        assert_eq!(c.state(), Some(NmtState::Operational));
        assert!(c.on_frame(&encode_heartbeat(5, NmtState::Operational).unwrap()));
        for k in 0..5 {
            assert_eq!(c.tick(), k == 4);
        }
        let other = encode_heartbeat(6, NmtState::Operational).unwrap();
        assert!(!c.on_frame(&other));
        assert!(c.expired());
        assert!(decode_heartbeat(&Frame::new(0x705, &[0x85]).unwrap()).is_err());
    }
}
