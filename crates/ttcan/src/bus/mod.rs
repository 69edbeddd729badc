//! CAN buses behind one small trait: send a frame, poll for the next event, never block. Three
//! implementations: [`memory`] (in-process, for tests, with fault injection), `socketcan`
//! (Linux SocketCAN via the `socketcan` crate, exercised in the VM test) and [`stdio`] (frames as
//! text lines, for bridges to other CAN stacks).

pub mod memory;
#[cfg(target_os = "linux")]
pub mod socketcan;
pub mod stdio;

use crate::canopen::Frame;

/// A bus-level problem reported by the controller (SocketCAN error frames, decoded).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusFault {
    /// The controller went bus-off (transmit error counter > 255): no traffic until restarted.
    BusOff,
    /// Error-passive or error-warning level reached.
    ErrorPassive,
    /// A transmitted frame was not acknowledged (nobody else on the bus).
    NoAck,
    /// Receive or transmit buffer overflow: frames were lost.
    Overflow,
    /// The controller was restarted after bus-off.
    Restarted,
    /// Any other error frame (protocol violation, transceiver, arbitration...).
    Other,
}

/// What a poll of the bus returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusEvent {
    /// A data frame, with its receive timestamp (ns, monotonic or wall clock of the bus).
    Frame {
        /// The frame.
        frame: Frame,
        /// Receive timestamp, ns.
        timestamp_ns: u64,
    },
    /// An error reported by the controller.
    Fault(BusFault),
}

/// Why a send or a poll failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum BusError {
    /// The transmit queue is full (the frame was not sent).
    #[error("transmit queue full")]
    Full,
    /// The interface is down or bus-off.
    #[error("CAN interface down or bus-off")]
    Down,
    /// Any other I/O error.
    #[error("CAN I/O error: {0:?}")]
    Io(std::io::ErrorKind),
}

/// One CAN channel: non-blocking send and poll.
pub trait CanBus: Send {
    /// Queues `frame` for transmission without blocking.
    fn send(&mut self, frame: &Frame) -> Result<(), BusError>;
    /// Returns the next received event, `None` when nothing is waiting. Never blocks.
    fn poll(&mut self) -> Result<Option<BusEvent>, BusError>;
}

impl<B: CanBus + ?Sized> CanBus for Box<B> {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        (**self).send(frame)
    }

    fn poll(&mut self) -> Result<Option<BusEvent>, BusError> {
        (**self).poll()
    }
}
