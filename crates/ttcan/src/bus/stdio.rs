//! A CAN bus carried as text lines on standard input and output, for bridges to CAN stacks that
//! run elsewhere (the interoperability test with python-canopen on python-can's virtual bus, on a
//! host without vcan). A frame is one line `CAN <id>#<data>` (identifier and data in hex, as
//! can-utils' `cansend` writes them); other lines on standard output are the program's own
//! messages and are ignored by the bridge. A reader thread parses standard input; `poll` never
//! blocks. Malformed input lines are counted and skipped.

use super::{BusError, BusEvent, CanBus};
use crate::canopen::Frame;
use std::io::{BufRead, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::sync::Arc;
use std::time::Duration;

/// The bus on standard input/output.
#[derive(Debug)]
pub struct StdioBus {
    rx: Receiver<Frame>,
    pending: Option<Frame>,
    malformed: Arc<AtomicU64>,
    closed: bool,
}

/// Parses `CAN 181#0102` (the prefix optional); `None` when malformed.
pub fn parse_line(line: &str) -> Option<Frame> {
    let l = line.trim();
    let l = l.strip_prefix("CAN ").unwrap_or(l);
    let (id, data) = l.split_once('#')?;
    let id = u16::from_str_radix(id, 16).ok()?;
    if data.len() % 2 != 0 || data.len() > 16 {
        return None;
    }
    let mut bytes = [0u8; 8];
    for (k, b) in bytes.iter_mut().enumerate().take(data.len() / 2) {
        *b = u8::from_str_radix(data.get(2 * k..2 * k + 2)?, 16).ok()?;
    }
    Frame::new(id, &bytes[..data.len() / 2]).ok()
}

/// The line of `f`: `CAN <id>#<data>`.
pub fn format_line(f: &Frame) -> String {
    let mut s = format!("CAN {:03X}#", f.id());
    for b in f.data() {
        s.push_str(&format!("{b:02X}"));
    }
    s
}

impl StdioBus {
    /// Starts reading frames from standard input.
    pub fn open() -> Self {
        let (tx, rx) = std::sync::mpsc::channel();
        let malformed = Arc::new(AtomicU64::new(0));
        let bad = malformed.clone();
        std::thread::spawn(move || {
            for line in std::io::stdin().lock().lines() {
                let Ok(line) = line else { break };
                match parse_line(&line) {
                    Some(f) => {
                        if tx.send(f).is_err() {
                            break;
                        }
                    }
                    None => {
                        bad.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
        });
        StdioBus {
            rx,
            pending: None,
            malformed,
            closed: false,
        }
    }

    /// True once standard input has ended (the bridge closed it).
    pub fn closed(&self) -> bool {
        self.closed && self.pending.is_none()
    }

    /// Input lines that were not frames.
    pub fn malformed(&self) -> u64 {
        self.malformed.load(Ordering::Relaxed)
    }

    /// Waits up to `timeout_ms` for a frame; true when one is waiting.
    pub fn wait_readable(&mut self, timeout_ms: u16) -> bool {
        if self.pending.is_some() {
            return true;
        }
        match self.rx.recv_timeout(Duration::from_millis(timeout_ms as u64)) {
            Ok(f) => {
                self.pending = Some(f);
                true
            }
            Err(RecvTimeoutError::Timeout) => false,
            Err(RecvTimeoutError::Disconnected) => {
                self.closed = true;
                std::thread::sleep(Duration::from_millis(timeout_ms as u64));
                false
            }
        }
    }
}

impl CanBus for StdioBus {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{}", format_line(frame))
            .and_then(|_| out.flush())
            .map_err(|e| BusError::Io(e.kind()))
    }

    fn poll(&mut self) -> Result<Option<BusEvent>, BusError> {
        let frame = match self.pending.take() {
            Some(f) => f,
            None => match self.rx.try_recv() {
                Ok(f) => f,
                Err(TryRecvError::Empty) => return Ok(None),
                Err(TryRecvError::Disconnected) => {
                    self.closed = true;
                    return Ok(None);
                }
            },
        };
        Ok(Some(BusEvent::Frame {
            frame,
            timestamp_ns: crate::runtime::rt::now_ns(),
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_round_trip_and_malformed_lines_are_refused() {
        for data in [&[][..], &[1, 2, 3], &[0xFF; 8]] {
            let f = Frame::new(0x605, data).unwrap();
            assert_eq!(parse_line(&format_line(&f)), Some(f));
        }
        assert_eq!(format_line(&Frame::new(0x80, &[]).unwrap()), "CAN 080#");
        assert_eq!(parse_line("181#0102").unwrap().data(), &[1, 2]);
        for bad in [
            "",
            "CAN 181",
            "CAN 800#",
            "CAN 181#123",
            "CAN 181#0011223344556677889",
            "CAN xyz#00",
            "ttctl: hello",
        ] {
            assert_eq!(parse_line(bad), None, "{bad}");
        }
    }
}
