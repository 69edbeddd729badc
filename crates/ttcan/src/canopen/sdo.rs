//! SDO (CiA 301 §7.2.4): expedited transfers (up to 4 bytes) and segmented transfers (up to
//! [`SDO_BUFFER`] bytes: strings such as 0x1008, larger parameters), the frame codec of both
//! directions, the server's transfer state machine ([`SdoServer`], used by the drive node over
//! any [`SdoTarget`]) and the client ([`SdoClient`], in the controller: one transfer outstanding
//! per node, with a timeout). Block transfers are not supported: a block request is answered with
//! abort [`ABORT_COMMAND`] (CiA 301 §7.2.4.3.17: "client/server command specifier not valid or
//! unknown"), as is every command specifier outside the protocol.

use super::frame::{check_node, Cob, Frame, Frames};
use super::ProtocolError;

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
    /// command specifier is [`ProtocolError::BadCommand`] (the server answers [`ABORT_COMMAND`]).
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

/// The object dictionary behind an [`SdoServer`]: whole-value reads and writes, refusals as
/// CiA 301 abort codes.
pub trait SdoTarget {
    /// Reads `index:sub` into `out`; returns the number of bytes or the abort code.
    fn sdo_read(&mut self, index: u16, sub: u8, out: &mut [u8; SDO_BUFFER]) -> Result<usize, u32>;
    /// Checks that `index:sub` exists and may be written (before a segmented download starts).
    fn sdo_check_write(&mut self, index: u16, sub: u8) -> Result<(), u32>;
    /// Writes the whole value `data` to `index:sub`.
    fn sdo_write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32>;
}

/// The server's transfer in progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum Transfer {
    #[default]
    Idle,
    Download {
        index: u16,
        sub: u8,
        size: Option<u32>,
        data: SdoData,
        toggle: bool,
    },
    Upload {
        index: u16,
        sub: u8,
        data: SdoData,
        pos: usize,
        toggle: bool,
    },
}

/// The SDO server of a node: expedited and segmented upload and download, aborts for everything
/// else. One transfer at a time; a new initiation ends the one in progress (CiA 301).
#[derive(Debug, Clone, Copy, Default)]
pub struct SdoServer {
    transfer: Transfer,
}

impl SdoServer {
    /// A server with no transfer in progress.
    pub fn new() -> Self {
        Self::default()
    }

    /// True while a segmented transfer is in progress.
    pub fn busy(&self) -> bool {
        self.transfer != Transfer::Idle
    }

    /// Serves one request frame's contents; returns the response (`None` after a client abort).
    pub fn serve(&mut self, req: &SdoRequest, od: &mut impl SdoTarget) -> Option<SdoResponse> {
        let abort = |index, sub, code| SdoResponse::Abort { index, sub, code };
        let r = match *req {
            SdoRequest::Download {
                index,
                sub,
                size,
                value,
            } => {
                self.transfer = Transfer::Idle;
                match od.sdo_write(index, sub, &value.to_le_bytes()[..size as usize]) {
                    Ok(()) => SdoResponse::Downloaded { index, sub },
                    Err(code) => abort(index, sub, code),
                }
            }
            SdoRequest::InitiateDownload { index, sub, size } => {
                self.transfer = Transfer::Idle;
                if size.is_some_and(|s| s as usize > SDO_BUFFER) {
                    abort(index, sub, ABORT_LENGTH_HIGH)
                } else {
                    match od.sdo_check_write(index, sub) {
                        Ok(()) => {
                            self.transfer = Transfer::Download {
                                index,
                                sub,
                                size,
                                data: SdoData::default(),
                                toggle: false,
                            };
                            SdoResponse::Downloaded { index, sub }
                        }
                        Err(code) => abort(index, sub, code),
                    }
                }
            }
            SdoRequest::DownloadSegment(seg) => match self.transfer {
                Transfer::Download {
                    index,
                    sub,
                    size,
                    mut data,
                    toggle,
                } => {
                    self.transfer = Transfer::Idle;
                    if seg.toggle != toggle {
                        abort(index, sub, ABORT_TOGGLE)
                    } else if !data.extend(seg.bytes()) {
                        abort(index, sub, ABORT_LENGTH_HIGH)
                    } else if !seg.last {
                        self.transfer = Transfer::Download {
                            index,
                            sub,
                            size,
                            data,
                            toggle: !toggle,
                        };
                        SdoResponse::DownloadSegment { toggle }
                    } else if size.is_some_and(|s| s as usize != data.len) {
                        abort(index, sub, ABORT_LENGTH)
                    } else {
                        match od.sdo_write(index, sub, data.bytes()) {
                            Ok(()) => SdoResponse::DownloadSegment { toggle },
                            Err(code) => abort(index, sub, code),
                        }
                    }
                }
                _ => abort(0, 0, ABORT_COMMAND),
            },
            SdoRequest::Upload { index, sub } => {
                self.transfer = Transfer::Idle;
                let mut buf = [0u8; SDO_BUFFER];
                match od.sdo_read(index, sub, &mut buf) {
                    Ok(n) if (1..=4).contains(&n) => {
                        let mut w = [0u8; 4];
                        w[..n].copy_from_slice(&buf[..n]);
                        SdoResponse::Uploaded {
                            index,
                            sub,
                            size: n as u8,
                            value: u32::from_le_bytes(w),
                        }
                    }
                    Ok(n) => {
                        self.transfer = Transfer::Upload {
                            index,
                            sub,
                            data: SdoData::from_bytes(&buf[..n]).unwrap_or_default(),
                            pos: 0,
                            toggle: false,
                        };
                        SdoResponse::UploadInitiated {
                            index,
                            sub,
                            size: n as u32,
                        }
                    }
                    Err(code) => abort(index, sub, code),
                }
            }
            SdoRequest::UploadSegment { toggle: t } => match self.transfer {
                Transfer::Upload {
                    index,
                    sub,
                    data,
                    pos,
                    toggle,
                } => {
                    self.transfer = Transfer::Idle;
                    if t != toggle {
                        abort(index, sub, ABORT_TOGGLE)
                    } else {
                        let rest = &data.bytes()[pos..];
                        let n = rest.len().min(7);
                        let mut seg = Segment {
                            toggle,
                            len: n as u8,
                            data: [0; 7],
                            last: n == rest.len(),
                        };
                        seg.data[..n].copy_from_slice(&rest[..n]);
                        if !seg.last {
                            self.transfer = Transfer::Upload {
                                index,
                                sub,
                                data,
                                pos: pos + n,
                                toggle: !toggle,
                            };
                        }
                        SdoResponse::UploadSegment(seg)
                    }
                }
                _ => abort(0, 0, ABORT_COMMAND),
            },
            SdoRequest::Block { index, sub, .. } => {
                self.transfer = Transfer::Idle;
                abort(index, sub, ABORT_COMMAND)
            }
            SdoRequest::Abort { .. } => {
                self.transfer = Transfer::Idle;
                return None;
            }
        };
        Some(r)
    }
}

/// Why an SDO transfer of the client failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SdoError {
    /// The server aborted with this code (or the client did, for an answer it cannot take).
    #[error("SDO {index:#06x}:{sub} aborted with code {code:#010x} ({})", abort_text(*code))]
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

/// One transfer the client performs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoJob {
    /// Read `index:sub`.
    Read {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// Write `data` to `index:sub` (expedited up to 4 bytes, segmented above).
    Write {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The value's bytes, little-endian.
        data: SdoData,
    },
}

impl SdoJob {
    /// A write of the `size` (1–4) low bytes of `value`.
    pub fn write_int(index: u16, sub: u8, size: u8, value: u32) -> Self {
        SdoJob::Write {
            index,
            sub,
            data: SdoData::int(value as u64, size as usize),
        }
    }

    /// Object index and sub-index.
    pub fn address(&self) -> (u16, u8) {
        match *self {
            SdoJob::Read { index, sub } | SdoJob::Write { index, sub, .. } => (index, sub),
        }
    }
}

/// A completed transfer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SdoOutcome {
    /// The value read.
    Read {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The bytes.
        data: SdoData,
    },
    /// The write was confirmed.
    Written {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stage {
    Initiated,
    Uploading { data: SdoData, size: u32, toggle: bool },
    Downloading { pos: usize, toggle: bool },
}

/// SDO client for one node: one transfer outstanding; counts timeouts and aborts.
#[derive(Debug, Clone, Copy)]
pub struct SdoClient {
    node: u8,
    timeout_cycles: u32,
    pending: Option<(SdoJob, Stage, u32)>,
    /// Transfers that timed out.
    pub timeouts: u32,
    /// Transfers aborted (by the server or by the client).
    pub aborts: u32,
}

impl SdoClient {
    /// A client talking to `node`, giving up after `timeout_cycles` cycles without an answer.
    pub fn new(node: u8, timeout_cycles: u32) -> Result<Self, ProtocolError> {
        Ok(SdoClient {
            node: check_node(node)?,
            timeout_cycles,
            pending: None,
            timeouts: 0,
            aborts: 0,
        })
    }

    /// True while a transfer waits for its response.
    pub fn busy(&self) -> bool {
        self.pending.is_some()
    }

    /// Starts `job`; returns its first frame, or `None` while another transfer is outstanding
    /// (or for an empty write).
    pub fn start(&mut self, job: SdoJob) -> Option<Frame> {
        if self.pending.is_some() {
            return None;
        }
        let req = match job {
            SdoJob::Read { index, sub } => SdoRequest::Upload { index, sub },
            SdoJob::Write { index, sub, data } => match data.len {
                0 => return None,
                n @ 1..=4 => SdoRequest::Download {
                    index,
                    sub,
                    size: n as u8,
                    value: data.as_u64().unwrap_or(0) as u32,
                },
                n => SdoRequest::InitiateDownload {
                    index,
                    sub,
                    size: Some(n as u32),
                },
            },
        };
        let f = req.encode(self.node).ok()?;
        self.pending = Some((job, Stage::Initiated, 0));
        Some(f)
    }

    fn send(&self, req: SdoRequest, out: &mut Frames) {
        if let Ok(f) = req.encode(self.node) {
            out.push(f);
        }
    }

    fn client_abort(&mut self, index: u16, sub: u8, code: u32, out: &mut Frames) -> Result<SdoOutcome, SdoError> {
        self.send(SdoRequest::Abort { index, sub, code }, out);
        self.aborts += 1;
        Err(SdoError::Aborted { index, sub, code })
    }

    /// Feeds a received frame: the next request of a segmented transfer goes to `out`; returns
    /// the outcome when the transfer completes. Frames of other nodes and responses nobody asked
    /// for return `None`.
    pub fn on_frame(&mut self, f: &Frame, out: &mut Frames) -> Option<Result<SdoOutcome, SdoError>> {
        let (job, stage, _) = self.pending?;
        let Ok((node, resp)) = SdoResponse::decode(f) else {
            return None;
        };
        if node != self.node {
            return None;
        }
        self.pending = None;
        let (index, sub) = job.address();
        if let SdoResponse::Abort { code, .. } = resp {
            self.aborts += 1;
            return Some(Err(SdoError::Aborted { index, sub, code }));
        }
        if resp.address().is_some_and(|a| a != (index, sub)) {
            return Some(Err(SdoError::OutOfSequence { index, sub }));
        }
        let seq = Some(Err(SdoError::OutOfSequence { index, sub }));
        match (job, stage, resp) {
            (SdoJob::Read { .. }, Stage::Initiated, SdoResponse::Uploaded { size, value, .. }) => {
                Some(Ok(SdoOutcome::Read {
                    index,
                    sub,
                    data: SdoData::int(value as u64, size as usize),
                }))
            }
            (SdoJob::Read { .. }, Stage::Initiated, SdoResponse::UploadInitiated { size, .. }) => {
                if size as usize > SDO_BUFFER {
                    return Some(self.client_abort(index, sub, ABORT_MEMORY, out));
                }
                self.send(SdoRequest::UploadSegment { toggle: false }, out);
                self.pending = Some((
                    job,
                    Stage::Uploading {
                        data: SdoData::default(),
                        size,
                        toggle: false,
                    },
                    0,
                ));
                None
            }
            (SdoJob::Read { .. }, Stage::Uploading { mut data, size, toggle }, SdoResponse::UploadSegment(seg)) => {
                if seg.toggle != toggle {
                    return Some(self.client_abort(index, sub, ABORT_TOGGLE, out));
                }
                if !data.extend(seg.bytes()) {
                    return Some(self.client_abort(index, sub, ABORT_MEMORY, out));
                }
                if seg.last {
                    if data.len != size as usize {
                        return Some(self.client_abort(index, sub, ABORT_LENGTH, out));
                    }
                    return Some(Ok(SdoOutcome::Read { index, sub, data }));
                }
                self.send(SdoRequest::UploadSegment { toggle: !toggle }, out);
                self.pending = Some((
                    job,
                    Stage::Uploading {
                        data,
                        size,
                        toggle: !toggle,
                    },
                    0,
                ));
                None
            }
            (SdoJob::Write { data, .. }, Stage::Initiated, SdoResponse::Downloaded { .. }) => {
                if data.len <= 4 {
                    return Some(Ok(SdoOutcome::Written { index, sub }));
                }
                self.next_segment(job, data, 0, false, out);
                None
            }
            (
                SdoJob::Write { data, .. },
                Stage::Downloading { pos, toggle },
                SdoResponse::DownloadSegment { toggle: t },
            ) => {
                if t != toggle {
                    return Some(self.client_abort(index, sub, ABORT_TOGGLE, out));
                }
                if pos >= data.len {
                    return Some(Ok(SdoOutcome::Written { index, sub }));
                }
                self.next_segment(job, data, pos, !toggle, out);
                None
            }
            _ => seq,
        }
    }

    fn next_segment(&mut self, job: SdoJob, data: SdoData, pos: usize, toggle: bool, out: &mut Frames) {
        let rest = &data.bytes()[pos..];
        let n = rest.len().min(7);
        let mut seg = Segment {
            toggle,
            len: n as u8,
            data: [0; 7],
            last: n == rest.len(),
        };
        seg.data[..n].copy_from_slice(&rest[..n]);
        self.send(SdoRequest::DownloadSegment(seg), out);
        self.pending = Some((job, Stage::Downloading { pos: pos + n, toggle }, 0));
    }

    /// Advances one cycle; returns the timeout error when the pending transfer expired (the
    /// waiting time restarts at every segment).
    pub fn tick(&mut self) -> Option<SdoError> {
        let (job, _, waited) = self.pending.as_mut()?;
        *waited += 1;
        if *waited > self.timeout_cycles {
            let (index, sub) = job.address();
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

    /// A dictionary of one 4-byte value 0x2000:0 and one string 0x1008:0 (up to 40 bytes).
    struct Dict {
        word: u32,
        text: SdoData,
    }

    impl SdoTarget for Dict {
        fn sdo_read(&mut self, index: u16, sub: u8, out: &mut [u8; SDO_BUFFER]) -> Result<usize, u32> {
            match (index, sub) {
                (0x2000, 0) => {
                    out[..4].copy_from_slice(&self.word.to_le_bytes());
                    Ok(4)
                }
                (0x1008, 0) => {
                    out[..self.text.len].copy_from_slice(self.text.bytes());
                    Ok(self.text.len)
                }
                (0x2000 | 0x1008, _) => Err(ABORT_NO_SUBINDEX),
                _ => Err(ABORT_NO_OBJECT),
            }
        }
        fn sdo_check_write(&mut self, index: u16, sub: u8) -> Result<(), u32> {
            match (index, sub) {
                (0x2000 | 0x1008, 0) => Ok(()),
                _ => Err(ABORT_NO_OBJECT),
            }
        }
        fn sdo_write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
            match (index, sub) {
                (0x2000, 0) if data.len() == 4 => {
                    self.word = u32::from_le_bytes([data[0], data[1], data[2], data[3]]);
                    Ok(())
                }
                (0x2000, 0) => Err(ABORT_LENGTH),
                (0x1008, 0) if data.len() <= 40 => {
                    self.text = SdoData::from_bytes(data).unwrap();
                    Ok(())
                }
                (0x1008, 0) => Err(ABORT_LENGTH_HIGH),
                _ => Err(ABORT_NO_OBJECT),
            }
        }
    }

    /// Runs `job` from a client against a server until it completes.
    fn run(job: SdoJob, dict: &mut Dict) -> Result<SdoOutcome, SdoError> {
        let mut c = SdoClient::new(5, 3).unwrap();
        let mut s = SdoServer::new();
        let mut f = c.start(job).unwrap();
        for _ in 0..100 {
            let (_, req) = SdoRequest::decode(&f).unwrap();
            let resp = s.serve(&req, dict).unwrap().encode(5).unwrap();
            let mut out = Frames::new();
            if let Some(r) = c.on_frame(&resp, &mut out) {
                assert!(!s.busy() || r.is_err());
                return r;
            }
            f = out.as_slice()[0];
        }
        panic!("transfer did not end");
    }

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
        // segmented: initiate 0x21 with the size, last segment of 3 bytes 0x09 | toggle 0x10
        let f = SdoRequest::InitiateDownload {
            index: 0x1008,
            sub: 0,
            size: Some(10),
        }
        .encode(1)
        .unwrap();
        assert_eq!(f.data(), &[0x21, 0x08, 0x10, 0, 10, 0, 0, 0]);
        let seg = Segment {
            toggle: true,
            len: 3,
            data: [1, 2, 3, 0, 0, 0, 0],
            last: true,
        };
        let f = SdoRequest::DownloadSegment(seg).encode(1).unwrap();
        assert_eq!(f.data(), &[0x19, 1, 2, 3, 0, 0, 0, 0]);
        assert_eq!(SdoRequest::decode(&f).unwrap().1, SdoRequest::DownloadSegment(seg));
        let f = SdoResponse::UploadSegment(seg).encode(1).unwrap();
        assert_eq!(SdoResponse::decode(&f).unwrap().1, SdoResponse::UploadSegment(seg));
    }

    #[test]
    fn segmented_upload_and_download_of_a_string_through_client_and_server() {
        let mut d = Dict {
            word: 7,
            text: SdoData::from_bytes(b"ttdrive-sim virtual CiA 402 drive").unwrap(),
        };
        let r = run(SdoJob::Read { index: 0x1008, sub: 0 }, &mut d).unwrap();
        let SdoOutcome::Read { data, .. } = r else { panic!() };
        assert_eq!(data.bytes(), b"ttdrive-sim virtual CiA 402 drive");
        // lengths around the segment size, 5..=40 bytes
        for n in [5usize, 7, 8, 14, 15, 40] {
            let text: Vec<u8> = (0..n as u8).map(|k| b'a' + k % 26).collect();
            let job = SdoJob::Write {
                index: 0x1008,
                sub: 0,
                data: SdoData::from_bytes(&text).unwrap(),
            };
            assert_eq!(run(job, &mut d).unwrap(), SdoOutcome::Written { index: 0x1008, sub: 0 });
            assert_eq!(d.text.bytes(), &text[..]);
            let SdoOutcome::Read { data, .. } = run(SdoJob::Read { index: 0x1008, sub: 0 }, &mut d).unwrap() else {
                panic!()
            };
            assert_eq!(data.bytes(), &text[..]);
        }
        let long = SdoJob::Write {
            index: 0x1008,
            sub: 0,
            data: SdoData::from_bytes(&[b'x'; 41]).unwrap(),
        };
        assert_eq!(
            run(long, &mut d),
            Err(SdoError::Aborted {
                index: 0x1008,
                sub: 0,
                code: ABORT_LENGTH_HIGH
            })
        );
        assert_eq!(
            run(SdoJob::write_int(0x2000, 0, 4, 0xDEAD_BEEF), &mut d).unwrap(),
            SdoOutcome::Written { index: 0x2000, sub: 0 }
        );
        assert_eq!(d.word, 0xDEAD_BEEF);
        assert!(matches!(
            run(SdoJob::Read { index: 0x3000, sub: 0 }, &mut d),
            Err(SdoError::Aborted {
                code: ABORT_NO_OBJECT,
                ..
            })
        ));
    }

    #[test]
    fn server_aborts_block_transfers_wrong_toggles_and_stray_segments() {
        let mut d = Dict {
            word: 0,
            text: SdoData::default(),
        };
        let mut s = SdoServer::new();
        for upload in [true, false] {
            let r = s.serve(
                &SdoRequest::Block {
                    upload,
                    index: 0x1008,
                    sub: 0,
                },
                &mut d,
            );
            assert_eq!(
                r,
                Some(SdoResponse::Abort {
                    index: 0x1008,
                    sub: 0,
                    code: ABORT_COMMAND
                })
            );
        }
        // a block download request as python-canopen sends it: 0xC6
        let f = Frame::new(0x605, &[0xC6, 0x08, 0x10, 0, 20, 0, 0, 0]).unwrap();
        assert!(matches!(
            SdoRequest::decode(&f).unwrap().1,
            SdoRequest::Block { upload: false, .. }
        ));
        // segment without initiation
        let r = s.serve(&SdoRequest::UploadSegment { toggle: false }, &mut d);
        assert!(matches!(
            r,
            Some(SdoResponse::Abort {
                code: ABORT_COMMAND,
                ..
            })
        ));
        // toggle error
        s.serve(
            &SdoRequest::InitiateDownload {
                index: 0x1008,
                sub: 0,
                size: Some(10),
            },
            &mut d,
        );
        let seg = Segment {
            toggle: true,
            len: 7,
            ..Segment::default()
        };
        let r = s.serve(&SdoRequest::DownloadSegment(seg), &mut d);
        assert!(matches!(r, Some(SdoResponse::Abort { code: ABORT_TOGGLE, .. })));
        assert!(!s.busy());
        // a command specifier 7 is not SDO
        let f = Frame::new(0x605, &[0xE0, 0, 0, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!(SdoRequest::decode(&f), Err(ProtocolError::BadCommand(0xE0)));
    }

    #[test]
    fn client_matches_response_to_request_and_times_out() {
        let mut out = Frames::new();
        let mut c = SdoClient::new(2, 3).unwrap();
        let job = SdoJob::Read { index: 0x6041, sub: 0 };
        assert!(c.start(job).is_some());
        assert!(c.start(job).is_none(), "one transfer at a time");
        let wrong = SdoResponse::Downloaded { index: 0x6040, sub: 0 }.encode(2).unwrap();
        assert_eq!(
            c.on_frame(&wrong, &mut out),
            Some(Err(SdoError::OutOfSequence { index: 0x6041, sub: 0 }))
        );
        assert!(c.start(job).is_some());
        let other_node = SdoResponse::Downloaded { index: 0x6041, sub: 0 }.encode(4).unwrap();
        assert_eq!(c.on_frame(&other_node, &mut out), None);
        for _ in 0..3 {
            assert_eq!(c.tick(), None);
        }
        assert!(matches!(c.tick(), Some(SdoError::Timeout { .. })));
        assert_eq!(c.timeouts, 1);
        assert!(!c.busy());
    }
}
