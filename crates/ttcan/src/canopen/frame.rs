//! A classical CAN data frame as a small `Copy` value (11-bit identifier, 0–8 data bytes), the
//! CANopen communication objects it can carry (CiA 301 pre-defined connection set), and the
//! fixed-capacity frame list that protocol code writes its output into (no allocation).

use super::ProtocolError;

/// Largest 11-bit identifier.
pub const MAX_STANDARD_ID: u16 = 0x7FF;

/// A classical CAN 2.0A data frame: 11-bit identifier and up to 8 data bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Frame {
    id: u16,
    len: u8,
    data: [u8; 8],
}

impl Frame {
    /// A frame with identifier `id` (≤ 0x7FF) and payload `data` (≤ 8 bytes).
    pub fn new(id: u16, data: &[u8]) -> Result<Self, ProtocolError> {
        if id > MAX_STANDARD_ID {
            return Err(ProtocolError::BadIdentifier(id));
        }
        if data.len() > 8 {
            return Err(ProtocolError::BadLength {
                id,
                expected: 8,
                got: data.len().min(255) as u8,
            });
        }
        let mut d = [0u8; 8];
        d[..data.len()].copy_from_slice(data);
        Ok(Frame {
            id,
            len: data.len() as u8,
            data: d,
        })
    }

    /// Internal constructor for encoders whose identifier and length are correct by construction.
    pub(crate) const fn raw(id: u16, len: u8, data: [u8; 8]) -> Self {
        Frame { id, len, data }
    }

    /// The 11-bit identifier (COB-ID).
    pub fn id(&self) -> u16 {
        self.id
    }

    /// The payload, 0–8 bytes.
    pub fn data(&self) -> &[u8] {
        &self.data[..self.len as usize]
    }

    /// Number of data bytes (the DLC of a classical frame).
    pub fn len(&self) -> usize {
        self.len as usize
    }

    /// True for a frame without data bytes (SYNC without counter).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Checks that the payload is exactly `n` bytes long.
    pub(crate) fn expect_len(&self, n: u8) -> Result<(), ProtocolError> {
        if self.len == n {
            Ok(())
        } else {
            Err(ProtocolError::BadLength {
                id: self.id,
                expected: n,
                got: self.len,
            })
        }
    }
}

/// The CANopen communication object a frame belongs to (pre-defined connection set, node 1–127).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cob {
    /// Network management command from the master (COB-ID 0x000).
    Nmt,
    /// SYNC (0x080).
    Sync,
    /// Emergency of a node (0x080 + node).
    Emcy(u8),
    /// TPDO1 of a node, drive → master (0x180 + node).
    Tpdo1(u8),
    /// RPDO1 of a node, master → drive (0x200 + node).
    Rpdo1(u8),
    /// SDO response, server (drive) → client (0x580 + node).
    SdoTx(u8),
    /// SDO request, client → server (drive) (0x600 + node).
    SdoRx(u8),
    /// Heartbeat / boot-up of a node (0x700 + node).
    Heartbeat(u8),
}

impl Cob {
    /// The 11-bit identifier of this object.
    pub fn id(self) -> u16 {
        match self {
            Cob::Nmt => 0x000,
            Cob::Sync => 0x080,
            Cob::Emcy(n) => 0x080 + n as u16,
            Cob::Tpdo1(n) => 0x180 + n as u16,
            Cob::Rpdo1(n) => 0x200 + n as u16,
            Cob::SdoTx(n) => 0x580 + n as u16,
            Cob::SdoRx(n) => 0x600 + n as u16,
            Cob::Heartbeat(n) => 0x700 + n as u16,
        }
    }

    /// Classifies an identifier; `None` for identifiers outside the objects this stack uses.
    pub fn classify(id: u16) -> Option<Cob> {
        let node = (id & 0x7F) as u8;
        let function = id & 0x780;
        match (function, node) {
            (0x000, 0) => Some(Cob::Nmt),
            (0x080, 0) => Some(Cob::Sync),
            (_, 0) => None,
            (0x080, n) => Some(Cob::Emcy(n)),
            (0x180, n) => Some(Cob::Tpdo1(n)),
            (0x200, n) => Some(Cob::Rpdo1(n)),
            (0x580, n) => Some(Cob::SdoTx(n)),
            (0x600, n) => Some(Cob::SdoRx(n)),
            (0x700, n) => Some(Cob::Heartbeat(n)),
            _ => None,
        }
    }
}

/// Checks a CANopen node id (1–127).
pub fn check_node(node: u8) -> Result<u8, ProtocolError> {
    if (1..=127).contains(&node) {
        Ok(node)
    } else {
        Err(ProtocolError::BadNode(node))
    }
}

/// Capacity of a [`Frames`] list: one cycle of a channel (SYNC, an RPDO per axis, SDO, NMT, EMCY).
pub const FRAMES_CAPACITY: usize = 16;

/// A fixed-capacity list of frames that protocol code appends its output to (never allocates).
#[derive(Debug, Clone, Copy, Default)]
pub struct Frames {
    frames: [Frame; FRAMES_CAPACITY],
    len: usize,
    overflowed: u32,
}

impl Frames {
    /// An empty list.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends `frame`; when full the frame is dropped and counted in [`Frames::overflowed`].
    pub fn push(&mut self, frame: Frame) {
        if self.len < FRAMES_CAPACITY {
            self.frames[self.len] = frame;
            self.len += 1;
        } else {
            self.overflowed += 1;
        }
    }

    /// The frames appended since the last [`Frames::clear`].
    pub fn as_slice(&self) -> &[Frame] {
        &self.frames[..self.len]
    }

    /// Empties the list (the overflow counter is kept).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Frames dropped because the list was full (a configuration error: too many axes).
    pub fn overflowed(&self) -> u32 {
        self.overflowed
    }

    /// Number of frames in the list.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the list holds no frame.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cob_ids_round_trip_for_every_node() {
        for n in 1..=127u8 {
            for cob in [
                Cob::Emcy(n),
                Cob::Tpdo1(n),
                Cob::Rpdo1(n),
                Cob::SdoTx(n),
                Cob::SdoRx(n),
                Cob::Heartbeat(n),
            ] {
                assert_eq!(Cob::classify(cob.id()), Some(cob));
            }
        }
        assert_eq!(Cob::classify(0), Some(Cob::Nmt));
        assert_eq!(Cob::classify(0x80), Some(Cob::Sync));
        assert_eq!(Cob::classify(0x100), None);
        assert_eq!(Cob::classify(0x280 + 3), None);
    }

    #[test]
    fn frame_rejects_long_payload_and_wide_identifier() {
        assert!(Frame::new(0x800, &[]).is_err());
        assert!(Frame::new(0x100, &[0; 9]).is_err());
        let f = Frame::new(0x181, &[1, 2, 3]).unwrap();
        assert_eq!(f.data(), &[1, 2, 3]);
        assert_eq!(f.len(), 3);
    }

    #[test]
    fn frames_list_counts_overflow_instead_of_growing() {
        let mut l = Frames::new();
        for _ in 0..FRAMES_CAPACITY + 3 {
            l.push(Frame::default());
        }
        assert_eq!(l.len(), FRAMES_CAPACITY);
        assert_eq!(l.overflowed(), 3);
    }
}
