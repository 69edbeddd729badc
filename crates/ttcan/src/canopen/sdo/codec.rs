//! The SDO frame codec: requests (client → server) and responses (server → client), expedited and
//! segmented, encoded to and decoded from 8-byte CAN frames (CiA 301 §7.2.4.3).

use super::super::frame::{check_node, Cob, Frame};
use super::super::ProtocolError;
/// Up to 7 data bytes of one segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Segment {
    /// Toggle bit (alternates from 0, per transfer).
    pub toggle: bool,
    /// Number of valid bytes, 0–7.
    pub len: u8,
    /// The bytes (beyond `len`: zero).
    pub data: [u8; 7],
    /// True for the last segment.
    pub last: bool,
}

impl Segment {
    /// The segment carrying the next (up to 7) bytes of `rest`, the last when they are all of it.
    pub(super) fn next(rest: &[u8], toggle: bool) -> Segment {
        let n = rest.len().min(7);
        let mut seg = Segment {
            toggle,
            len: n as u8,
            data: [0; 7],
            last: n == rest.len(),
        };
        seg.data[..n].copy_from_slice(&rest[..n]);
        seg
    }

    /// The valid bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data[..self.len as usize]
    }

    fn byte0(&self, base: u8) -> u8 {
        base | (u8::from(self.toggle) << 4) | ((7 - self.len) << 1) | u8::from(self.last)
    }

    fn parse(d: &[u8]) -> Segment {
        let len = 7 - ((d[0] >> 1) & 0x7);
        let mut data = [0u8; 7];
        data[..len as usize].copy_from_slice(&d[1..1 + len as usize]);
        Segment {
            toggle: d[0] & 0x10 != 0,
            len,
            data,
            last: d[0] & 1 != 0,
        }
    }

    fn put(&self, base: u8) -> [u8; 8] {
        let mut d = [0u8; 8];
        d[0] = self.byte0(base);
        d[1..8].copy_from_slice(&self.data);
        d
    }
}

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
    /// Initiation of a segmented download of `size` bytes (`None`: size not indicated).
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Number of bytes to follow.
        size: Option<u32>,
    },
    /// One segment of a segmented download.
    DownloadSegment(Segment),
    /// Upload (read) request of `index:sub`.
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// Request of the next segment of a segmented upload (with its toggle bit).
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
    },
    /// A block download or upload initiation (not supported: the server aborts).
    Block {
        /// True for a block upload, false for a block download.
        upload: bool,
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// The client aborts the transfer.
    Abort {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code.
        code: u32,
    },
}

impl SdoRequest {
    /// Object index and sub-index addressed (`None` for a segment, which names no object).
    pub fn address(&self) -> Option<(u16, u8)> {
        match *self {
            SdoRequest::Download { index, sub, .. }
            | SdoRequest::InitiateDownload { index, sub, .. }
            | SdoRequest::Upload { index, sub }
            | SdoRequest::Block { index, sub, .. }
            | SdoRequest::Abort { index, sub, .. } => Some((index, sub)),
            SdoRequest::DownloadSegment(_) | SdoRequest::UploadSegment { .. } => None,
        }
    }

    /// Encodes the request to `node` (COB-ID 0x600 + node).
    pub fn encode(&self, node: u8) -> Result<Frame, ProtocolError> {
        let n = check_node(node)?;
        let (index, sub) = self.address().unwrap_or((0, 0));
        let mut d = frame_data(index, sub);
        match *self {
            SdoRequest::Download { size, value, .. } => put_expedited(&mut d, 0x23, size, value)?,
            SdoRequest::InitiateDownload { size: Some(s), .. } => {
                d[0] = 0x21;
                d[4..8].copy_from_slice(&s.to_le_bytes());
            }
            SdoRequest::InitiateDownload { size: None, .. } => d[0] = 0x20,
            SdoRequest::DownloadSegment(s) => d = s.put(0x00),
            SdoRequest::Upload { .. } => d[0] = 0x40,
            SdoRequest::UploadSegment { toggle } => d = [0x60 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0],
            SdoRequest::Block { upload, .. } => d[0] = if upload { 0xA0 } else { 0xC0 },
            SdoRequest::Abort { code, .. } => {
                d[0] = 0x80;
                d[4..8].copy_from_slice(&code.to_le_bytes());
            }
        }
        Ok(Frame::raw(Cob::SdoRx(n).id(), 8, d))
    }

    /// Decodes a request frame addressed to a server; returns (node, request). An unknown
    /// command specifier is [`ProtocolError::BadCommand`] (the server answers [`ABORT_COMMAND`](super::ABORT_COMMAND)).
    pub fn decode(f: &Frame) -> Result<(u8, SdoRequest), ProtocolError> {
        let Some(Cob::SdoRx(node)) = Cob::classify(f.id()) else {
            return Err(ProtocolError::UnexpectedFrame(f.id()));
        };
        let (command, index, sub, word) = fields(f)?;
        let req = match command >> 5 {
            0 => SdoRequest::DownloadSegment(Segment::parse(f.data())),
            1 => match command & 0x03 {
                0x03 => {
                    let (size, value) = expedited_value(command, word);
                    SdoRequest::Download {
                        index,
                        sub,
                        size,
                        value,
                    }
                }
                0x01 => SdoRequest::InitiateDownload {
                    index,
                    sub,
                    size: Some(word),
                },
                0x00 => SdoRequest::InitiateDownload { index, sub, size: None },
                // expedited without size indication: 4 bytes (CiA 301 §7.2.4.3.3)
                _ => SdoRequest::Download {
                    index,
                    sub,
                    size: 4,
                    value: word,
                },
            },
            2 => SdoRequest::Upload { index, sub },
            3 => SdoRequest::UploadSegment {
                toggle: command & 0x10 != 0,
            },
            4 => SdoRequest::Abort { index, sub, code: word },
            5 => SdoRequest::Block {
                upload: true,
                index,
                sub,
            },
            6 => SdoRequest::Block {
                upload: false,
                index,
                sub,
            },
            _ => return Err(ProtocolError::BadCommand(command)),
        };
        Ok((node, req))
    }
}

/// An SDO response from server to client.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoResponse {
    /// Download (write) initiation confirmed (expedited: the write is done).
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
    /// Segmented upload initiated: `size` bytes follow in segments.
    UploadInitiated {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Number of bytes.
        size: u32,
    },
    /// One segment of a segmented upload.
    UploadSegment(Segment),
    /// A download segment confirmed (with its toggle bit).
    DownloadSegment {
        /// Toggle bit of the segment confirmed.
        toggle: bool,
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
    /// Object index and sub-index the response is about (`None` for a segment).
    pub fn address(&self) -> Option<(u16, u8)> {
        match *self {
            SdoResponse::Downloaded { index, sub }
            | SdoResponse::Uploaded { index, sub, .. }
            | SdoResponse::UploadInitiated { index, sub, .. }
            | SdoResponse::Abort { index, sub, .. } => Some((index, sub)),
            SdoResponse::UploadSegment(_) | SdoResponse::DownloadSegment { .. } => None,
        }
    }

    /// Encodes the response of `node` (COB-ID 0x580 + node).
    pub fn encode(&self, node: u8) -> Result<Frame, ProtocolError> {
        let n = check_node(node)?;
        let (index, sub) = self.address().unwrap_or((0, 0));
        let mut d = frame_data(index, sub);
        match *self {
            SdoResponse::Downloaded { .. } => d[0] = 0x60,
            SdoResponse::Uploaded { size, value, .. } => put_expedited(&mut d, 0x43, size, value)?,
            SdoResponse::UploadInitiated { size, .. } => {
                d[0] = 0x41;
                d[4..8].copy_from_slice(&size.to_le_bytes());
            }
            SdoResponse::UploadSegment(s) => d = s.put(0x00),
            SdoResponse::DownloadSegment { toggle } => d = [0x20 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0],
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
        let r = match command >> 5 {
            0 => SdoResponse::UploadSegment(Segment::parse(f.data())),
            1 => SdoResponse::DownloadSegment {
                toggle: command & 0x10 != 0,
            },
            2 => match command & 0x03 {
                0x03 => {
                    let (size, value) = expedited_value(command, word);
                    SdoResponse::Uploaded {
                        index,
                        sub,
                        size,
                        value,
                    }
                }
                0x01 => SdoResponse::UploadInitiated { index, sub, size: word },
                0x02 => SdoResponse::Uploaded {
                    index,
                    sub,
                    size: 4,
                    value: word,
                },
                _ => return Err(ProtocolError::BadCommand(command)),
            },
            3 => SdoResponse::Downloaded { index, sub },
            4 => SdoResponse::Abort { index, sub, code: word },
            _ => return Err(ProtocolError::BadCommand(command)),
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
