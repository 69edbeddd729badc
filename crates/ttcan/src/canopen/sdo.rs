//! Expedited SDO (CiA 301 §7.2.4.3): read and write of objects of up to 4 bytes, a client (in the
//! controller, one request outstanding per node, with a timeout) and the frame codec the server in
//! the virtual drive uses. Segmented and block transfers are not needed for drive configuration
//! and are answered with an abort.

use super::frame::{check_node, Cob, Frame};
use super::ProtocolError;

/// Abort code: toggle bit not alternated.
pub const ABORT_TOGGLE: u32 = 0x0503_0000;
/// Abort code: SDO protocol timed out.
pub const ABORT_TIMEOUT: u32 = 0x0504_0000;
/// Abort code: client/server command specifier not valid or unknown.
pub const ABORT_COMMAND: u32 = 0x0504_0001;
/// Abort code: attempt to write a read-only object.
pub const ABORT_READ_ONLY: u32 = 0x0601_0002;
/// Abort code: object does not exist in the object dictionary.
pub const ABORT_NO_OBJECT: u32 = 0x0602_0000;
/// Abort code: data type does not match, length of service parameter does not match.
pub const ABORT_LENGTH: u32 = 0x0607_0010;
/// Abort code: sub-index does not exist.
pub const ABORT_NO_SUBINDEX: u32 = 0x0609_0011;
/// Abort code: value range of parameter exceeded.
pub const ABORT_RANGE: u32 = 0x0609_0030;

/// An SDO request from client to server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoRequest {
    /// Expedited download (write) of `size` (1–4) bytes of `value` to `index:sub`.
    Download {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Number of bytes, 1–4.
        size: u8,
        /// Value, little-endian in the frame.
        value: u32,
    },
    /// Upload (read) request of `index:sub`.
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
}

impl SdoRequest {
    /// Object index and sub-index addressed.
    pub fn address(&self) -> (u16, u8) {
        match *self {
            SdoRequest::Download { index, sub, .. } | SdoRequest::Upload { index, sub } => (index, sub),
        }
    }

    /// Encodes the request to `node` (COB-ID 0x600 + node).
    pub fn encode(&self, node: u8) -> Result<Frame, ProtocolError> {
        let n = check_node(node)?;
        let (index, sub) = self.address();
        let mut d = frame_data(index, sub);
        match *self {
            SdoRequest::Download { size, value, .. } => put_expedited(&mut d, 0x23, size, value)?,
            SdoRequest::Upload { .. } => d[0] = 0x40,
        }
        Ok(Frame::raw(Cob::SdoRx(n).id(), 8, d))
    }

    /// Decodes a request frame addressed to a server; returns (node, request). A segmented or
    /// block request is [`ProtocolError::BadCommand`] (the server answers with [`ABORT_COMMAND`]).
    pub fn decode(f: &Frame) -> Result<(u8, SdoRequest), ProtocolError> {
        let Some(Cob::SdoRx(node)) = Cob::classify(f.id()) else {
            return Err(ProtocolError::UnexpectedFrame(f.id()));
        };
        let (command, index, sub, word) = fields(f)?;
        let req = match command {
            c @ (0x23 | 0x27 | 0x2B | 0x2F) => {
                let (size, value) = expedited_value(c, word);
                SdoRequest::Download {
                    index,
                    sub,
                    size,
                    value,
                }
            }
            0x40 => SdoRequest::Upload { index, sub },
            c => return Err(ProtocolError::BadCommand(c)),
        };
        Ok((node, req))
    }
}

/// An SDO response from server to client.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoResponse {
    /// Download (write) confirmed.
    Downloaded {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// Expedited upload (read) answer.
    Uploaded {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Number of valid bytes, 1–4.
        size: u8,
        /// Value (zero-extended).
        value: u32,
    },
    /// Transfer aborted by the server.
    Abort {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code (`ABORT_*`).
        code: u32,
    },
}

impl SdoResponse {
    /// Object index and sub-index the response is about.
    pub fn address(&self) -> (u16, u8) {
        match *self {
            SdoResponse::Downloaded { index, sub }
            | SdoResponse::Uploaded { index, sub, .. }
            | SdoResponse::Abort { index, sub, .. } => (index, sub),
        }
    }

    /// Encodes the response of `node` (COB-ID 0x580 + node).
    pub fn encode(&self, node: u8) -> Result<Frame, ProtocolError> {
        let n = check_node(node)?;
        let (index, sub) = self.address();
        let mut d = frame_data(index, sub);
        match *self {
            SdoResponse::Downloaded { .. } => d[0] = 0x60,
            SdoResponse::Uploaded { size, value, .. } => put_expedited(&mut d, 0x43, size, value)?,
            SdoResponse::Abort { code, .. } => {
                d[0] = 0x80;
                d[4..8].copy_from_slice(&code.to_le_bytes());
            }
        }
        Ok(Frame::raw(Cob::SdoTx(n).id(), 8, d))
    }

    /// Decodes a response frame; returns (node, response).
    pub fn decode(f: &Frame) -> Result<(u8, SdoResponse), ProtocolError> {
        let Some(Cob::SdoTx(node)) = Cob::classify(f.id()) else {
            return Err(ProtocolError::UnexpectedFrame(f.id()));
        };
        let (command, index, sub, word) = fields(f)?;
        let r = match command {
            0x60 => SdoResponse::Downloaded { index, sub },
            c @ (0x43 | 0x47 | 0x4B | 0x4F) => {
                let (size, value) = expedited_value(c, word);
                SdoResponse::Uploaded {
                    index,
                    sub,
                    size,
                    value,
                }
            }
            0x80 => SdoResponse::Abort { index, sub, code: word },
            c => return Err(ProtocolError::BadCommand(c)),
        };
        Ok((node, r))
    }
}

/// The data bytes of an SDO frame about `index:sub`: the address in bytes 1–3, the rest zero.
fn frame_data(index: u16, sub: u8) -> [u8; 8] {
    let i = index.to_le_bytes();
    [0, i[0], i[1], sub, 0, 0, 0, 0]
}

/// An expedited transfer of `size` (1–4) bytes of `value` into `d`: the command specifier
/// `base` (0x23 download request, 0x43 upload answer) with the unused-byte count, the value
/// little-endian in bytes 4–7.
fn put_expedited(d: &mut [u8; 8], base: u8, size: u8, value: u32) -> Result<(), ProtocolError> {
    if !(1..=4).contains(&size) {
        return Err(ProtocolError::OutOfRange {
            what: "SDO size",
            value: size as i64,
        });
    }
    d[0] = base | ((4 - size) << 2);
    d[4..8].copy_from_slice(&value.to_le_bytes());
    Ok(())
}

/// (command byte, index, sub-index, data word) of an 8-byte SDO frame.
fn fields(f: &Frame) -> Result<(u8, u16, u8, u32), ProtocolError> {
    f.expect_len(8)?;
    let d = f.data();
    Ok((
        d[0],
        u16::from_le_bytes([d[1], d[2]]),
        d[3],
        u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
    ))
}

/// Size (1–4 bytes) and zero-extended value of the expedited command `c` carrying `word`.
fn expedited_value(c: u8, word: u32) -> (u8, u32) {
    let size = 4 - ((c >> 2) & 0x3);
    let mask = if size == 4 { u32::MAX } else { (1u32 << (8 * size)) - 1 };
    (size, word & mask)
}

/// Why an SDO transfer of the client failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SdoError {
    /// The server aborted with this code.
    #[error("SDO {index:#06x}:{sub} aborted by the drive with code {code:#010x}")]
    Aborted {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code.
        code: u32,
    },
    /// No response within the timeout.
    #[error("SDO {index:#06x}:{sub}: no response within {cycles} cycles")]
    Timeout {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Timeout, cycles.
        cycles: u32,
    },
    /// The response was for another object than the one requested, or of the wrong kind.
    #[error("SDO {index:#06x}:{sub}: response out of sequence")]
    OutOfSequence {
        /// Object index requested.
        index: u16,
        /// Sub-index requested.
        sub: u8,
    },
}

/// SDO client for one node: one request outstanding; counts timeouts and aborts.
#[derive(Debug, Clone, Copy)]
pub struct SdoClient {
    node: u8,
    timeout_cycles: u32,
    pending: Option<(SdoRequest, u32)>,
    /// Transfers that timed out.
    pub timeouts: u32,
    /// Transfers the server aborted.
    pub aborts: u32,
}

impl SdoClient {
    /// A client talking to `node`, giving up after `timeout_cycles` cycles.
    pub fn new(node: u8, timeout_cycles: u32) -> Result<Self, ProtocolError> {
        Ok(SdoClient {
            node: check_node(node)?,
            timeout_cycles,
            pending: None,
            timeouts: 0,
            aborts: 0,
        })
    }

    /// True while a request waits for its response.
    pub fn busy(&self) -> bool {
        self.pending.is_some()
    }

    /// Starts `req`; returns its frame, or `None` while another request is outstanding.
    pub fn start(&mut self, req: SdoRequest) -> Option<Frame> {
        if self.pending.is_some() {
            return None;
        }
        let f = req.encode(self.node).ok()?;
        self.pending = Some((req, 0));
        Some(f)
    }

    /// Feeds a received frame; returns the outcome when it completes the pending transfer.
    /// Frames of other nodes and responses nobody asked for return `None`.
    pub fn on_frame(&mut self, f: &Frame) -> Option<Result<SdoResponse, SdoError>> {
        let (req, _) = self.pending?;
        let Ok((node, resp)) = SdoResponse::decode(f) else {
            return None;
        };
        if node != self.node {
            return None;
        }
        self.pending = None;
        let (index, sub) = req.address();
        if resp.address() != (index, sub) {
            return Some(Err(SdoError::OutOfSequence { index, sub }));
        }
        Some(match (req, resp) {
            (_, SdoResponse::Abort { code, .. }) => {
                self.aborts += 1;
                Err(SdoError::Aborted { index, sub, code })
            }
            (SdoRequest::Download { .. }, r @ SdoResponse::Downloaded { .. })
            | (SdoRequest::Upload { .. }, r @ SdoResponse::Uploaded { .. }) => Ok(r),
            _ => Err(SdoError::OutOfSequence { index, sub }),
        })
    }

    /// Advances one cycle; returns the timeout error when the pending request expired.
    pub fn tick(&mut self) -> Option<SdoError> {
        let (req, waited) = self.pending.as_mut()?;
        *waited += 1;
        if *waited > self.timeout_cycles {
            let (index, sub) = req.address();
            self.pending = None;
            self.timeouts += 1;
            return Some(SdoError::Timeout {
                index,
                sub,
                cycles: self.timeout_cycles,
            });
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_and_responses_round_trip_for_every_size() {
        for size in 1..=4u8 {
            let value = 0xA1B2_C3D4u32 & if size == 4 { u32::MAX } else { (1 << (8 * size)) - 1 };
            let req = SdoRequest::Download {
                index: 0x6060,
                sub: 0,
                size,
                value,
            };
            let f = req.encode(3).unwrap();
            assert_eq!(f.id(), 0x603);
            assert_eq!(SdoRequest::decode(&f).unwrap(), (3, req));
            let resp = SdoResponse::Uploaded {
                index: 0x6064,
                sub: 0,
                size,
                value,
            };
            assert_eq!(SdoResponse::decode(&resp.encode(3).unwrap()).unwrap(), (3, resp));
        }
        // The well-known command bytes: 4-byte write 0x23, 1-byte write 0x2F, 2-byte upload 0x4B.
        let f = SdoRequest::Download {
            index: 0x1017,
            sub: 0,
            size: 1,
            value: 5,
        }
        .encode(1)
        .unwrap();
        assert_eq!(f.data()[..4], [0x2F, 0x17, 0x10, 0x00]);
    }

    #[test]
    fn client_matches_response_to_request_and_times_out() {
        let mut c = SdoClient::new(2, 3).unwrap();
        let req = SdoRequest::Upload { index: 0x6041, sub: 0 };
        assert!(c.start(req).is_some());
        assert!(c.start(req).is_none(), "one transfer at a time");
        let wrong = SdoResponse::Downloaded { index: 0x6040, sub: 0 }.encode(2).unwrap();
        assert_eq!(
            c.on_frame(&wrong),
            Some(Err(SdoError::OutOfSequence { index: 0x6041, sub: 0 }))
        );
        assert!(c.start(req).is_some());
        let other_node = SdoResponse::Downloaded { index: 0x6041, sub: 0 }.encode(4).unwrap();
        assert_eq!(c.on_frame(&other_node), None);
        for _ in 0..3 {
            assert_eq!(c.tick(), None);
        }
        assert!(matches!(c.tick(), Some(SdoError::Timeout { .. })));
        assert_eq!(c.timeouts, 1);
        assert!(!c.busy());
    }

    #[test]
    fn segmented_commands_are_rejected() {
        let f = Frame::new(0x601, &[0x21, 0, 0x10, 0, 8, 0, 0, 0]).unwrap();
        assert_eq!(SdoRequest::decode(&f), Err(ProtocolError::BadCommand(0x21)));
    }
}
