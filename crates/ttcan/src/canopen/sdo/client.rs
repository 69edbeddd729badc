//! The SDO client of the controller: one transfer outstanding per node, segmented when the value
//! is longer than 4 bytes, with a timeout in cycles and counters of timeouts and aborts.

use super::super::frame::{check_node, Frame, Frames};
use super::super::ProtocolError;
use super::*;
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
        let seg = Segment::next(&data.bytes()[pos..], toggle);
        let n = seg.len as usize;
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
