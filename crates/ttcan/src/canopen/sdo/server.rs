//! The SDO server of a node: the transfer state machine (expedited and segmented upload and
//! download) over any object dictionary ([`SdoTarget`]).

use super::*;
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
                        let seg = Segment::next(&data.bytes()[pos..], toggle);
                        let n = seg.len as usize;
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
