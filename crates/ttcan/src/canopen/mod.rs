//! CANopen for CiA 402 drives, sans-I/O: frames in, frames out, a state machine per node, the
//! object dictionary as data, every timeout and error counted. Nothing here touches a socket, a
//! clock or the heap; the buses are in `crate::bus`, the controller threads in `crate::runtime`.
//!
//! - [`frame`]: the `Copy` frame, COB-IDs, fixed-capacity output lists;
//! - [`nmt`]: NMT commands, SYNC, heartbeat producer/consumer; [`emcy`]: emergency messages;
//! - [`sdo`]: expedited SDO client and codec; [`od`]: the drive's object dictionary (SDO server);
//! - [`pdo`]: the fixed RPDO/TPDO mappings; [`cia402`]: the drive state machine and modes;
//! - [`units`]: the one SI ↔ CiA 402 integer conversion; [`budget`]: bus load check;
//! - [`node`]: the drive-side node used by the virtual drive.

pub mod budget;
pub mod cia402;
pub mod eds;
pub mod emcy;
pub mod frame;
pub mod nmt;
pub mod node;
pub mod od;
pub mod pdo;
pub mod sdo;
pub mod units;

pub use cia402::{DriveState, OpMode};
pub use frame::{Cob, Frame, Frames};
pub use pdo::{Rpdo, Tpdo};
pub use units::Units;

/// Why a frame or a value was refused by the protocol layer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum ProtocolError {
    /// Identifier wider than 11 bits.
    #[error("CAN identifier {0:#x} is not an 11-bit identifier")]
    BadIdentifier(u16),
    /// A frame of the wrong length for its object.
    #[error("frame {id:#05x}: {got} data bytes, expected {expected}")]
    BadLength {
        /// Identifier.
        id: u16,
        /// Expected number of bytes.
        expected: u8,
        /// Received number of bytes.
        got: u8,
    },
    /// Node id outside 1–127.
    #[error("node id {0} outside 1..=127")]
    BadNode(u8),
    /// The frame is not of the object the decoder expects.
    #[error("frame {0:#05x} is not of the expected object")]
    UnexpectedFrame(u16),
    /// Unknown command specifier.
    #[error("unknown command specifier {0:#04x}")]
    BadCommand(u8),
    /// A value outside its range.
    #[error("{what} {value} out of range")]
    OutOfRange {
        /// Which value.
        what: &'static str,
        /// The value (rounded, saturated).
        value: i64,
    },
}

#[cfg(test)]
mod fuzz {
    //! Decoder fuzz: arbitrary identifiers and payloads never panic, and whatever decodes
    //! re-encodes to the same frame.
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        #[test]
        fn decoders_never_panic_and_round_trip(id in 0u16..0x800, data in proptest::collection::vec(any::<u8>(), 0..=8)) {
            let f = Frame::new(id, &data).unwrap();
            if let Ok((n, r)) = Rpdo::decode(&f) { prop_assert_eq!(r.encode(n).unwrap(), f); }
            if let Ok((n, t)) = Tpdo::decode(&f) { prop_assert_eq!(t.encode(n).unwrap(), f); }
            if let Ok(e) = emcy::Emcy::decode(&f) { prop_assert_eq!(e.encode().unwrap(), f); }
            if let Ok((n, s)) = nmt::decode_heartbeat(&f) { prop_assert_eq!(nmt::encode_heartbeat(n, s).unwrap(), f); }
            if let Ok((c, n)) = nmt::decode_nmt(&f) { prop_assert_eq!(nmt::encode_nmt(c, n).unwrap(), f); }
            if let Ok((n, r)) = sdo::SdoRequest::decode(&f) {
                // expedited download: the unused bytes need not be zero on the wire
                let g = r.encode(n).unwrap();
                prop_assert_eq!(sdo::SdoRequest::decode(&g).unwrap(), (n, r));
            }
            if let Ok((n, r)) = sdo::SdoResponse::decode(&f) {
                let g = r.encode(n).unwrap();
                prop_assert_eq!(sdo::SdoResponse::decode(&g).unwrap(), (n, r));
            }
            let _ = nmt::decode_sync(&f);
            if let Ok(Tpdo { statusword, .. }) = Tpdo::decode(&f).map(|x| x.1) {
                let _ = DriveState::from_statusword(statusword);
            }
            // a drive node fed arbitrary frames never panics
            let mut out = Frames::new();
            let mut node = node::DriveNode::new(1, &mut out).unwrap();
            node.on_frame(&f, &mut out);
            node.on_sync(0, 0, 0, 10, &mut out);
        }
    }
}
