//! Process data objects: [`PdoMapping`], the mapping of one PDO (objects packed little endian in
//! order, whole bytes, at most 8), used by the drive node and the controller alike; and the
//! project's default mappings as the fixed [`Rpdo`]/[`Tpdo`] contents (one of each per axis per
//! cycle, 8 bytes):
//!
//! - RPDO1 (master → drive, COB-ID 0x200 + node): target 4 B (0x607A target position in CSP,
//!   0x60FF target velocity in CSV, 0x6071 target torque in CST; the slot is 4 bytes in every mode
//!   so the mapping never changes), torque offset 0x60B2 2 B, controlword 0x6040 2 B.
//! - TPDO1 (drive → master, COB-ID 0x180 + node): position actual 0x6064 4 B, current actual
//!   0x6078 2 B, statusword 0x6041 2 B.

use super::frame::{check_node, Cob, Frame};
use super::ProtocolError;

/// RPDO1 contents.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Rpdo {
    /// Target: position (increments), velocity (increments/s) or torque (‰ rated), by mode.
    pub target: i32,
    /// Torque offset 0x60B2, ‰ of the rated torque.
    pub torque_offset: i16,
    /// Controlword 0x6040.
    pub controlword: u16,
}

/// TPDO1 contents.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Tpdo {
    /// Position actual value 0x6064, increments.
    pub position: i32,
    /// Current actual value 0x6078, ‰ of the rated current.
    pub current: i16,
    /// Statusword 0x6041.
    pub statusword: u16,
}

fn pack(a: i32, b: i16, c: u16) -> [u8; 8] {
    let (a, b, c) = (a.to_le_bytes(), b.to_le_bytes(), c.to_le_bytes());
    [a[0], a[1], a[2], a[3], b[0], b[1], c[0], c[1]]
}

fn unpack(d: &[u8]) -> (i32, i16, u16) {
    (
        i32::from_le_bytes([d[0], d[1], d[2], d[3]]),
        i16::from_le_bytes([d[4], d[5]]),
        u16::from_le_bytes([d[6], d[7]]),
    )
}

impl Rpdo {
    /// Encodes the RPDO of `node`.
    pub fn encode(&self, node: u8) -> Result<Frame, ProtocolError> {
        let n = check_node(node)?;
        Ok(Frame::raw(
            Cob::Rpdo1(n).id(),
            8,
            pack(self.target, self.torque_offset, self.controlword),
        ))
    }

    /// Decodes an RPDO; returns (node, contents). Exactly 8 bytes (CiA 301: a PDO of the wrong
    /// length is not processed).
    pub fn decode(f: &Frame) -> Result<(u8, Rpdo), ProtocolError> {
        let Some(Cob::Rpdo1(node)) = Cob::classify(f.id()) else {
            return Err(ProtocolError::UnexpectedFrame(f.id()));
        };
        f.expect_len(8)?;
        let (target, torque_offset, controlword) = unpack(f.data());
        Ok((
            node,
            Rpdo {
                target,
                torque_offset,
                controlword,
            },
        ))
    }
}

impl Tpdo {
    /// Encodes the TPDO of `node`.
    pub fn encode(&self, node: u8) -> Result<Frame, ProtocolError> {
        let n = check_node(node)?;
        Ok(Frame::raw(
            Cob::Tpdo1(n).id(),
            8,
            pack(self.position, self.current, self.statusword),
        ))
    }

    /// Decodes a TPDO; returns (node, contents). Exactly 8 bytes.
    pub fn decode(f: &Frame) -> Result<(u8, Tpdo), ProtocolError> {
        let Some(Cob::Tpdo1(node)) = Cob::classify(f.id()) else {
            return Err(ProtocolError::UnexpectedFrame(f.id()));
        };
        f.expect_len(8)?;
        let (position, current, statusword) = unpack(f.data());
        Ok((
            node,
            Tpdo {
                position,
                current,
                statusword,
            },
        ))
    }
}

/// One entry of a PDO mapping: object, sub-index and length in bits (the CiA 301 mapping word
/// `index << 16 | sub << 8 | bits`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct MapEntry {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Length, bits.
    pub bits: u8,
}

impl MapEntry {
    /// The mapping word of object 0x1600+/0x1A00+ sub-indices 1–8.
    pub fn word(self) -> u32 {
        (self.index as u32) << 16 | (self.sub as u32) << 8 | self.bits as u32
    }

    /// The entry of a mapping word.
    pub fn from_word(w: u32) -> Self {
        MapEntry {
            index: (w >> 16) as u16,
            sub: (w >> 8) as u8,
            bits: w as u8,
        }
    }
}

impl std::fmt::Display for MapEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#06x}:{}", self.index, self.sub)
    }
}

/// Most entries of one PDO mapping (whole bytes: at most 8 in 8 bytes).
pub const MAX_MAP_ENTRIES: usize = 8;

/// Why a mapping was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum MappingError {
    /// More entries than [`MAX_MAP_ENTRIES`].
    #[error("{0} mapping entries, at most 8")]
    TooManyEntries(usize),
    /// The entries need more than 64 bits.
    #[error("the entries need {0} bits, a PDO carries at most 64")]
    TooLong(u32),
    /// An entry whose length is not a whole number of bytes (bit-wise mapping is not supported).
    #[error("object {0}: {1} bits is not a whole number of bytes 1..=8")]
    NotBytes(MapEntry, u8),
}

/// The mapping of one PDO: up to 8 byte-aligned entries in at most 8 bytes, little endian,
/// packed in order (CiA 301 §7.4.7). `Copy`, no allocation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PdoMapping {
    entries: [MapEntry; MAX_MAP_ENTRIES],
    n: u8,
}

impl PdoMapping {
    /// A mapping of `entries` (each 8, 16, 24, … 64 bits; 64 bits in all at most).
    pub fn new(entries: &[MapEntry]) -> Result<Self, MappingError> {
        if entries.len() > MAX_MAP_ENTRIES {
            return Err(MappingError::TooManyEntries(entries.len()));
        }
        let mut m = PdoMapping::default();
        let mut bits = 0u32;
        for (k, e) in entries.iter().enumerate() {
            if e.bits == 0 || e.bits % 8 != 0 || e.bits > 64 {
                return Err(MappingError::NotBytes(*e, e.bits));
            }
            bits += e.bits as u32;
            m.entries[k] = *e;
        }
        if bits > 64 {
            return Err(MappingError::TooLong(bits));
        }
        m.n = entries.len() as u8;
        Ok(m)
    }

    /// The project's RPDO1: target 0x607A (CSP) / 0x60FF (CSV) 4 B, or 0x6071 (CST) 2 B, torque
    /// offset 0x60B2 2 B, controlword 0x6040 2 B.
    pub fn default_rpdo(mode: super::OpMode) -> Self {
        let target = match mode {
            super::OpMode::Csp => MapEntry {
                index: 0x607A,
                sub: 0,
                bits: 32,
            },
            super::OpMode::Csv => MapEntry {
                index: 0x60FF,
                sub: 0,
                bits: 32,
            },
            super::OpMode::Cst => MapEntry {
                index: 0x6071,
                sub: 0,
                bits: 16,
            },
        };
        let rest = [
            MapEntry {
                index: 0x60B2,
                sub: 0,
                bits: 16,
            },
            MapEntry {
                index: 0x6040,
                sub: 0,
                bits: 16,
            },
        ];
        Self::new(&[target, rest[0], rest[1]]).unwrap_or_default()
    }

    /// The project's TPDO1: position actual 0x6064 4 B, current actual 0x6078 2 B, statusword
    /// 0x6041 2 B.
    pub fn default_tpdo() -> Self {
        Self::new(&[
            MapEntry {
                index: 0x6064,
                sub: 0,
                bits: 32,
            },
            MapEntry {
                index: 0x6078,
                sub: 0,
                bits: 16,
            },
            MapEntry {
                index: 0x6041,
                sub: 0,
                bits: 16,
            },
        ])
        .unwrap_or_default()
    }

    /// The entries in frame order.
    pub fn entries(&self) -> &[MapEntry] {
        &self.entries[..self.n as usize]
    }

    /// Length of the PDO, bytes.
    pub fn len(&self) -> usize {
        self.entries().iter().map(|e| e.bits as usize / 8).sum()
    }

    /// True for a mapping without entries.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Byte offset and length of `index:sub` in the PDO (`None` when not mapped).
    pub fn position(&self, index: u16, sub: u8) -> Option<(usize, usize)> {
        let mut off = 0;
        for e in self.entries() {
            if e.index == index && e.sub == sub {
                return Some((off, e.bits as usize / 8));
            }
            off += e.bits as usize / 8;
        }
        None
    }

    /// Packs the values `value(entry)` (the low bytes of each, little endian) into a frame with
    /// identifier `id`.
    pub fn pack(&self, id: u16, mut value: impl FnMut(MapEntry) -> i64) -> Result<Frame, ProtocolError> {
        let mut d = [0u8; 8];
        let mut off = 0;
        for e in self.entries() {
            let n = e.bits as usize / 8;
            d[off..off + n].copy_from_slice(&value(*e).to_le_bytes()[..n]);
            off += n;
        }
        Frame::new(id, &d[..off])
    }

    /// The raw (zero-extended) value of every entry of a received PDO, in order; the frame must
    /// have exactly the mapped length (CiA 301: a PDO of the wrong length is not processed).
    pub fn unpack(&self, f: &Frame) -> Result<[(MapEntry, u64); MAX_MAP_ENTRIES], ProtocolError> {
        f.expect_len(self.len() as u8)?;
        let mut out = [(MapEntry::default(), 0u64); MAX_MAP_ENTRIES];
        let mut off = 0;
        for (k, e) in self.entries().iter().enumerate() {
            let n = e.bits as usize / 8;
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(&f.data()[off..off + n]);
            out[k] = (*e, u64::from_le_bytes(b));
            off += n;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_mappings_pack_as_the_fixed_pdos() {
        let r = Rpdo {
            target: -123_456,
            torque_offset: -250,
            controlword: 0x000F,
        };
        let m = PdoMapping::default_rpdo(super::super::OpMode::Csp);
        let f = m
            .pack(0x207, |e| match e.index {
                0x607A => r.target as i64,
                0x60B2 => r.torque_offset as i64,
                _ => r.controlword as i64,
            })
            .unwrap();
        assert_eq!(f, r.encode(7).unwrap());
        let t = PdoMapping::default_tpdo().unpack(&f).unwrap();
        assert_eq!(t[0].0.index, 0x6064);
        assert_eq!(t[2].1, 0x000F);
        assert_eq!(PdoMapping::default_rpdo(super::super::OpMode::Cst).len(), 6);
        assert_eq!(MapEntry::from_word(0x6041_0010).word(), 0x6041_0010);
        let e = |bits| MapEntry {
            index: 0x6064,
            sub: 0,
            bits,
        };
        assert_eq!(PdoMapping::new(&[e(32), e(32), e(8)]), Err(MappingError::TooLong(72)));
        assert!(matches!(PdoMapping::new(&[e(12)]), Err(MappingError::NotBytes(..))));
        assert_eq!(PdoMapping::new(&[e(8); 9]), Err(MappingError::TooManyEntries(9)));
    }

    #[test]
    fn pdos_round_trip_and_are_little_endian() {
        let r = Rpdo {
            target: -123_456,
            torque_offset: -250,
            controlword: 0x000F,
        };
        let f = r.encode(7).unwrap();
        assert_eq!(f.id(), 0x207);
        assert_eq!(f.data()[6..], [0x0F, 0x00]);
        assert_eq!(Rpdo::decode(&f).unwrap(), (7, r));
        let t = Tpdo {
            position: 1,
            current: 2,
            statusword: 0x0627,
        };
        let f = t.encode(7).unwrap();
        assert_eq!(f.data(), &[1, 0, 0, 0, 2, 0, 0x27, 0x06]);
        assert_eq!(Tpdo::decode(&f).unwrap(), (7, t));
    }

    #[test]
    fn short_pdo_and_foreign_identifier_are_rejected() {
        assert!(Tpdo::decode(&Frame::new(0x187, &[0; 7]).unwrap()).is_err());
        assert!(Tpdo::decode(&Frame::new(0x207, &[0; 8]).unwrap()).is_err());
        assert!(Rpdo::decode(&Frame::new(0x187, &[0; 8]).unwrap()).is_err());
    }
}
