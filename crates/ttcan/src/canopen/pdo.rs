//! Process data objects with fixed mappings, one of each per axis per cycle (8 bytes, little
//! endian, as on every CiA 402 drive):
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

#[cfg(test)]
mod tests {
    use super::*;

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
