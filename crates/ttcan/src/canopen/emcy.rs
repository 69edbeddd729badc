//! Emergency object (CiA 301 §7.2.7): error code (CiA 402 codes for drives), error register and
//! five manufacturer bytes; error code 0x0000 means "error reset / no error".

use super::frame::{check_node, Cob, Frame};
use super::ProtocolError;

/// Error code 0x0000: the node's errors were reset.
pub const NO_ERROR: u16 = 0x0000;
/// CiA 402 error code: continuous over-current.
pub const OVER_CURRENT: u16 = 0x2310;
/// CiA 402 error code: following error.
pub const FOLLOWING_ERROR: u16 = 0x8611;
/// CiA 402 error code: position sensor (encoder) fault.
pub const SENSOR: u16 = 0x7305;
/// CiA 301 error code: RPDO or SYNC timeout (life guard / communication).
pub const SYNC_TIMEOUT: u16 = 0x8130;
/// CiA 301 error code: PDO not processed due to length error.
pub const PDO_LENGTH: u16 = 0x8210;
/// CiA 402 error code: command value out of range (manufacturer specific group 0xFF00 used here).
pub const COMMAND_RANGE: u16 = 0xFF01;
/// CiA 301 error code: RPDO timeout (cyclic setpoints stopped arriving).
pub const RPDO_TIMEOUT: u16 = 0x8250;
/// CiA 402 error code: DC-link over-voltage.
pub const OVER_VOLTAGE: u16 = 0x3210;
/// CiA 402 error code: DC-link under-voltage.
pub const UNDER_VOLTAGE: u16 = 0x3220;
/// CiA 402 error code: velocity (speed controller) error, used for overspeed.
pub const OVERSPEED: u16 = 0x8400;
/// CiA 402 error code: reference limit (software position limit reached).
pub const POSITION_LIMIT: u16 = 0x8612;

/// A decoded emergency message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Emcy {
    /// Node that sent it.
    pub node: u8,
    /// Error code (0x0000 = reset).
    pub code: u16,
    /// Error register (object 0x1001).
    pub register: u8,
    /// Manufacturer-specific bytes.
    pub info: [u8; 5],
}

impl Emcy {
    /// Encodes the message as its 8-byte frame.
    pub fn encode(&self) -> Result<Frame, ProtocolError> {
        let n = check_node(self.node)?;
        let c = self.code.to_le_bytes();
        let i = self.info;
        Ok(Frame::raw(
            Cob::Emcy(n).id(),
            8,
            [c[0], c[1], self.register, i[0], i[1], i[2], i[3], i[4]],
        ))
    }

    /// Decodes an emergency frame (identifier 0x081–0x0FF, exactly 8 bytes).
    pub fn decode(f: &Frame) -> Result<Emcy, ProtocolError> {
        let Some(Cob::Emcy(node)) = Cob::classify(f.id()) else {
            return Err(ProtocolError::UnexpectedFrame(f.id()));
        };
        f.expect_len(8)?;
        let d = f.data();
        Ok(Emcy {
            node,
            code: u16::from_le_bytes([d[0], d[1]]),
            register: d[2],
            info: [d[3], d[4], d[5], d[6], d[7]],
        })
    }

    /// True for the "error reset" message.
    pub fn is_reset(&self) -> bool {
        self.code == NO_ERROR
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn emcy_round_trips_and_checks_length() {
        let e = Emcy {
            node: 9,
            code: FOLLOWING_ERROR,
            register: 0x81,
            info: [1, 2, 3, 4, 5],
        };
        let f = e.encode().unwrap();
        assert_eq!(f.id(), 0x89);
        assert_eq!(Emcy::decode(&f).unwrap(), e);
        assert!(Emcy::decode(&Frame::new(0x89, &[0, 0]).unwrap()).is_err());
        assert!(Emcy::decode(&Frame::new(0x80, &[0; 8]).unwrap()).is_err());
    }
}
