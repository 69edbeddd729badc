//! Linux SocketCAN through the `socketcan` crate (4.x): a raw CAN socket in non-blocking mode,
//! socket receive timestamps (`SO_TIMESTAMPNS`), every error class accepted and decoded into a
//! [`BusFault`]; a send on a bus-off or down interface is [`BusError::Down`].

use super::{BusError, BusEvent, BusFault, CanBus};
use crate::canopen::Frame;
use socketcan::{
    CanError, CanFrame, CanSocket, EmbeddedFrame, ErrorCause, Frame as _, Socket, SocketOptions, StandardId,
};
use std::io;
use std::time::UNIX_EPOCH;

/// Receive buffer asked for on every socket, bytes (≈ 1500 frames).
pub const RECEIVE_BUFFER_BYTES: usize = 1 << 20;

/// One SocketCAN interface (e.g. `vcan0`, `can0`).
pub struct SocketCanBus {
    socket: CanSocket,
    timestamps: bool,
}

impl std::fmt::Debug for SocketCanBus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SocketCanBus")
            .field("timestamps", &self.timestamps)
            .finish()
    }
}

fn io_error(e: &io::Error) -> BusError {
    match e.raw_os_error() {
        Some(105) => BusError::Full,                      // ENOBUFS
        Some(100) | Some(19) | Some(6) => BusError::Down, // ENETDOWN, ENODEV, ENXIO
        _ if e.kind() == io::ErrorKind::WouldBlock => BusError::Full,
        _ => BusError::Io(e.kind()),
    }
}

impl SocketCanBus {
    /// Opens `interface` non-blocking, with error frames and receive timestamps enabled.
    pub fn open(interface: &str) -> io::Result<Self> {
        let socket = CanSocket::open(interface)?;
        socket.set_nonblocking(true)?;
        socket.set_error_filter_accept_all()?;
        let timestamps = socket.set_recv_timestamp(true).is_ok();
        // a larger receive buffer rides out scheduling stalls without dropping frames (the kernel
        // caps it at net.core.rmem_max)
        let _ = socket.as_raw_socket().set_recv_buffer_size(RECEIVE_BUFFER_BYTES);
        Ok(SocketCanBus { socket, timestamps })
    }

    /// Blocks until a frame is waiting or `timeout_ms` ms have passed (for the virtual drives,
    /// which have nothing to do between frames); true when readable.
    pub fn wait_readable(&self, timeout_ms: u16) -> bool {
        use nix::poll::{poll, PollFd, PollFlags};
        use std::os::fd::AsFd;
        let mut fds = [PollFd::new(self.socket.as_fd(), PollFlags::POLLIN)];
        matches!(poll(&mut fds, timeout_ms), Ok(n) if n > 0)
    }
}

fn decode_error(e: CanError) -> BusFault {
    let mut fault = BusFault::Other;
    for c in e.causes() {
        let f = match c {
            ErrorCause::BusOff => return BusFault::BusOff,
            ErrorCause::NoAck => BusFault::NoAck,
            ErrorCause::Restarted => BusFault::Restarted,
            ErrorCause::Controller(p) => {
                let s = format!("{p}");
                if s.contains("overflow") {
                    BusFault::Overflow
                } else {
                    BusFault::ErrorPassive
                }
            }
            _ => BusFault::Other,
        };
        if fault == BusFault::Other {
            fault = f;
        }
    }
    fault
}

impl CanBus for SocketCanBus {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        let id = StandardId::new(frame.id()).ok_or(BusError::Io(io::ErrorKind::InvalidInput))?;
        let f = CanFrame::new(id, frame.data()).ok_or(BusError::Io(io::ErrorKind::InvalidInput))?;
        self.socket.write_frame(&f).map_err(|e| io_error(&e))
    }

    fn poll(&mut self) -> Result<Option<BusEvent>, BusError> {
        let r = if self.timestamps {
            self.socket.read_frame_with_timestamp().map(|(f, t)| {
                (
                    f,
                    t.duration_since(UNIX_EPOCH).map(|d| d.as_nanos() as u64).unwrap_or(0),
                )
            })
        } else {
            self.socket.read_frame().map(|f| (f, 0))
        };
        match r {
            Ok((CanFrame::Data(d), ts)) => {
                if d.is_extended() {
                    return Ok(None); // 29-bit identifiers are not ours
                }
                match Frame::new(d.raw_id() as u16, d.data()) {
                    Ok(frame) => Ok(Some(BusEvent::Frame {
                        frame,
                        timestamp_ns: ts,
                    })),
                    Err(_) => Ok(None),
                }
            }
            Ok((CanFrame::Remote(_), _)) => Ok(None),
            Ok((CanFrame::Error(e), _)) => Ok(Some(BusEvent::Fault(decode_error(CanError::from(e))))),
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(None),
            Err(e) => Err(io_error(&e)),
        }
    }
}
