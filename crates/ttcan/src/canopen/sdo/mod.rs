//! SDO (CiA 301 §7.2.4): expedited transfers (up to 4 bytes) and segmented transfers (up to
//! [`SDO_BUFFER`] bytes: strings such as 0x1008, larger parameters), the frame codec of both
//! directions, the server's transfer state machine ([`SdoServer`], used by the drive node over
//! any [`SdoTarget`]) and the client ([`SdoClient`], in the controller: one transfer outstanding
//! per node, with a timeout). Block transfers are not supported: a block request is answered with
//! abort [`ABORT_COMMAND`] (CiA 301 §7.2.4.3.17: "client/server command specifier not valid or
//! unknown"), as is every command specifier outside the protocol.

mod client;
mod codec;
mod server;
#[cfg(test)]
mod tests;

pub use client::{SdoClient, SdoError, SdoJob, SdoOutcome};
pub use codec::{SdoRequest, SdoResponse, Segment};
pub use server::{SdoServer, SdoTarget};

/// Largest object a segmented transfer carries, bytes (fixed buffer, no allocation).
pub const SDO_BUFFER: usize = 64;

/// Abort code: toggle bit not alternated.
pub const ABORT_TOGGLE: u32 = 0x0503_0000;
/// Abort code: SDO protocol timed out.
pub const ABORT_TIMEOUT: u32 = 0x0504_0000;
/// Abort code: client/server command specifier not valid or unknown.
pub const ABORT_COMMAND: u32 = 0x0504_0001;
/// Abort code: out of memory (a segmented transfer longer than [`SDO_BUFFER`]).
pub const ABORT_MEMORY: u32 = 0x0504_0005;
/// Abort code: unsupported access to an object.
pub const ABORT_UNSUPPORTED: u32 = 0x0601_0000;
/// Abort code: attempt to read a write-only object.
pub const ABORT_WRITE_ONLY: u32 = 0x0601_0001;
/// Abort code: attempt to write a read-only object.
pub const ABORT_READ_ONLY: u32 = 0x0601_0002;
/// Abort code: object does not exist in the object dictionary.
pub const ABORT_NO_OBJECT: u32 = 0x0602_0000;
/// Abort code: object cannot be mapped to the PDO.
pub const ABORT_NOT_MAPPABLE: u32 = 0x0604_0041;
/// Abort code: the number and length of the objects to be mapped would exceed the PDO length.
pub const ABORT_PDO_LENGTH: u32 = 0x0604_0042;
/// Abort code: data type does not match, length of service parameter does not match.
pub const ABORT_LENGTH: u32 = 0x0607_0010;
/// Abort code: data type does not match, length of service parameter too high.
pub const ABORT_LENGTH_HIGH: u32 = 0x0607_0012;
/// Abort code: sub-index does not exist.
pub const ABORT_NO_SUBINDEX: u32 = 0x0609_0011;
/// Abort code: value range of parameter exceeded.
pub const ABORT_RANGE: u32 = 0x0609_0030;
/// Abort code: data cannot be transferred because of the present device state.
pub const ABORT_DEVICE_STATE: u32 = 0x0800_0022;

/// The text of a CiA 301 abort code (for messages).
pub fn abort_text(code: u32) -> &'static str {
    match code {
        ABORT_TOGGLE => "toggle bit not alternated",
        ABORT_TIMEOUT => "SDO protocol timed out",
        ABORT_COMMAND => "command specifier not valid or unknown",
        ABORT_MEMORY => "out of memory",
        ABORT_UNSUPPORTED => "unsupported access to an object",
        ABORT_WRITE_ONLY => "attempt to read a write-only object",
        ABORT_READ_ONLY => "attempt to write a read-only object",
        ABORT_NO_OBJECT => "object does not exist",
        ABORT_NOT_MAPPABLE => "object cannot be mapped to the PDO",
        ABORT_PDO_LENGTH => "mapping would exceed the PDO length",
        ABORT_LENGTH => "length of service parameter does not match",
        ABORT_LENGTH_HIGH => "length of service parameter too high",
        0x0607_0013 => "length of service parameter too low",
        ABORT_NO_SUBINDEX => "sub-index does not exist",
        ABORT_RANGE => "value range of parameter exceeded",
        0x0609_0031 => "value of parameter written too high",
        0x0609_0032 => "value of parameter written too low",
        0x0800_0000 => "general error",
        0x0800_0020 => "data cannot be transferred or stored to the application",
        ABORT_DEVICE_STATE => "data cannot be transferred because of the present device state",
        _ => "unknown abort code",
    }
}
/// The bytes of one object value (up to [`SDO_BUFFER`]), `Copy`, no allocation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdoData {
    buf: [u8; SDO_BUFFER],
    len: usize,
}

impl Default for SdoData {
    fn default() -> Self {
        SdoData {
            buf: [0; SDO_BUFFER],
            len: 0,
        }
    }
}

impl SdoData {
    /// The first `n` (≤ 8) little-endian bytes of `value`.
    pub fn int(value: u64, n: usize) -> Self {
        let mut d = SdoData::default();
        let n = n.min(8);
        d.buf[..n].copy_from_slice(&value.to_le_bytes()[..n]);
        d.len = n;
        d
    }

    /// A copy of `bytes`; `None` when longer than [`SDO_BUFFER`].
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let mut d = SdoData::default();
        d.buf.get_mut(..bytes.len())?.copy_from_slice(bytes);
        d.len = bytes.len();
        Some(d)
    }

    /// The bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Appends `b`; false when full.
    fn extend(&mut self, b: &[u8]) -> bool {
        let Some(dst) = self.buf.get_mut(self.len..self.len + b.len()) else {
            return false;
        };
        dst.copy_from_slice(b);
        self.len += b.len();
        true
    }

    /// The value as a little-endian unsigned integer (up to 8 bytes; longer: `None`).
    pub fn as_u64(&self) -> Option<u64> {
        if self.len > 8 {
            return None;
        }
        let mut b = [0u8; 8];
        b[..self.len].copy_from_slice(self.bytes());
        Some(u64::from_le_bytes(b))
    }
}
