//! The receiver thread: one UDP socket, every datagram decoded ([`super::wire::decode`]) and
//! screened ([`Screen`]: per-sender sequence, staleness, the kinds this mode takes), refusals
//! counted by class and dropped, the rest handed to the planning thread through a bounded queue.
//! A full queue answers a hit `rejected` at once (every hit gets a status). Nothing here can stop
//! the robot: the receiver never touches the cycle threads.

use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{SyncSender, TrySendError};
use std::time::Duration;

use super::counters::Counters;
use super::wire::{self, Datagram, HitMsg, Message, ObservationMsg, PlanStatus, StatusMsg};

/// Senders whose last sequence number is remembered; past that the table starts afresh (a flood
/// from many forged addresses cannot grow it).
pub const MAX_SENDERS: usize = 256;

/// What the receiver hands to the planning thread.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Inbound {
    /// A hit, received at controller time `arrival` (s) from `from`.
    Hit {
        /// The hit.
        hit: HitMsg,
        /// Controller clock at reception, s.
        arrival: f64,
    },
    /// A camera observation received at controller time `arrival` (s).
    Observation {
        /// The observation.
        obs: ObservationMsg,
        /// The header's send time on the camera's clock, s.
        sent: f64,
        /// Controller clock at reception, s.
        arrival: f64,
    },
}

/// Which kinds the controller's mode takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Hits from an upper computer.
    Hit,
    /// Ball observations from a camera process.
    Ball,
}

/// The sans-I/O screening of datagrams: decode, sequence per sender, staleness, kind.
#[derive(Debug)]
pub struct Screen {
    mode: Mode,
    latency_budget: f64,
    last_seq: HashMap<SocketAddr, u64>,
}

impl Screen {
    /// A screen for `mode`; a hit sent more than `latency_budget` s before its arrival (its send
    /// time on the controller clock) is stale.
    pub fn new(mode: Mode, latency_budget: f64) -> Self {
        Screen {
            mode,
            latency_budget,
            last_seq: HashMap::with_capacity(MAX_SENDERS),
        }
    }

    /// Screens `bytes` from `from` received at controller time `now` (s): the message to act on,
    /// or `None` (refused and counted in `counters`).
    pub fn screen(&mut self, bytes: &[u8], from: SocketAddr, now: f64, counters: &Counters) -> Option<Message> {
        Counters::bump(&counters.received);
        let d: Datagram = match wire::decode(bytes) {
            Ok(d) => d,
            Err(e) => {
                counters.refused(&e);
                return None;
            }
        };
        let wanted = matches!(
            (self.mode, &d.message),
            (Mode::Hit, Message::Hit(_)) | (Mode::Ball, Message::Observation(_))
        );
        if !wanted {
            Counters::bump(&counters.unexpected);
            return None;
        }
        match self.last_seq.get(&from) {
            Some(&last) if d.seq == last => {
                Counters::bump(&counters.duplicate);
                return None;
            }
            Some(&last) if d.seq < last => {
                Counters::bump(&counters.out_of_order);
                return None;
            }
            _ => {}
        }
        if matches!(d.message, Message::Hit(_)) && (now - d.sent).abs() > self.latency_budget {
            // the upper computer stamps hits on the controller clock (it gives the hit time on
            // it): a send time further than the budget from now is old, or from a wrong clock
            Counters::bump(&counters.stale);
            return None;
        }
        if self.last_seq.len() >= MAX_SENDERS && !self.last_seq.contains_key(&from) {
            self.last_seq.clear();
        }
        self.last_seq.insert(from, d.seq);
        Counters::bump(&counters.accepted);
        Some(d.message)
    }
}

/// Sends one status datagram to `to` from `socket`, counting it (or the send error).
pub fn send_status(socket: &UdpSocket, to: SocketAddr, seq: u64, now: f64, status: &StatusMsg, counters: &Counters) {
    let mut buf = [0u8; wire::MAX_LEN];
    let n = wire::encode(&Message::Status(*status), seq, now, &mut buf);
    match socket.send_to(&buf[..n], to) {
        Ok(_) => counters.status(status.status),
        Err(_) => Counters::bump(&counters.send_errors),
    }
}

/// The controller clock (s): `CLOCK_MONOTONIC` (Python's `time.monotonic()` on Linux).
pub fn controller_time() -> f64 {
    crate::runtime::rt::now_ns() as f64 * 1e-9
}

/// Receives on `socket` until `stop` is set, screening every datagram; hits and observations go
/// to `to_planner`. A hit that finds the queue full is answered `rejected` to `reply`.
pub fn run_receiver(
    socket: &UdpSocket,
    mode: Mode,
    latency_budget: f64,
    reply: SocketAddr,
    to_planner: &SyncSender<Inbound>,
    counters: &Counters,
    stop: &AtomicBool,
) {
    let _ = socket.set_read_timeout(Some(Duration::from_millis(20)));
    let mut screen = Screen::new(mode, latency_budget);
    let mut buf = [0u8; 2048];
    let mut seq = 1u64 << 62; // the receiver's own statuses: a sequence apart from the planner's
    while !stop.load(Ordering::Relaxed) {
        let (len, from) = match socket.recv_from(&mut buf) {
            Ok(x) => x,
            Err(_) => continue,
        };
        let now = controller_time();
        let inbound = match screen.screen(&buf[..len], from, now, counters) {
            Some(Message::Hit(hit)) => Inbound::Hit { hit, arrival: now },
            Some(Message::Observation(obs)) => Inbound::Observation {
                obs,
                // The header's send time (camera clock), for the ball brain's clock relation.
                sent: wire::decode(&buf[..len]).map_or(f64::NAN, |d| d.sent),
                arrival: now,
            },
            _ => continue,
        };
        match to_planner.try_send(inbound) {
            Ok(()) => {}
            Err(TrySendError::Full(Inbound::Hit { hit, .. })) => {
                Counters::bump(&counters.overload);
                seq += 1;
                let status = StatusMsg {
                    id: hit.id,
                    status: PlanStatus::Rejected,
                    earliest_t_hit: f64::NAN,
                    t_hit: f64::NAN,
                    planning_time: 0.0,
                };
                send_status(socket, reply, seq, now, &status, counters);
            }
            Err(TrySendError::Full(_)) => Counters::bump(&counters.overload),
            Err(TrySendError::Disconnected(_)) => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(id: u32) -> Message {
        Message::Hit(HitMsg {
            id,
            stroke: id,
            t_hit: 10.0,
            rotation: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            centre: [0.3, -0.5, 0.1],
            twist: [0.0; 6],
        })
    }

    fn bytes(m: &Message, seq: u64, sent: f64) -> Vec<u8> {
        let mut buf = [0u8; wire::MAX_LEN];
        let n = wire::encode(m, seq, sent, &mut buf);
        buf[..n].to_vec()
    }

    #[test]
    fn each_refusal_class_is_counted_once() {
        let c = Counters::default();
        let mut s = Screen::new(Mode::Hit, 0.05);
        let a: SocketAddr = "127.0.0.1:9000".parse().unwrap();
        let b: SocketAddr = "127.0.0.1:9001".parse().unwrap();
        assert!(s.screen(&bytes(&hit(1), 5, 1.0), a, 1.0, &c).is_some());
        assert!(s.screen(&bytes(&hit(1), 5, 1.0), a, 1.0, &c).is_none());
        assert!(s.screen(&bytes(&hit(1), 4, 1.0), a, 1.0, &c).is_none());
        // another sender has its own sequence
        assert!(s.screen(&bytes(&hit(1), 1, 1.0), b, 1.0, &c).is_some());
        assert!(s.screen(&bytes(&hit(2), 6, 0.9), a, 1.0, &c).is_none());
        let good = bytes(&hit(3), 7, 1.0);
        assert!(s.screen(&good[..100], a, 1.0, &c).is_none());
        let mut long = good.clone();
        long.push(0);
        assert!(s.screen(&long, a, 1.0, &c).is_none());
        let mut v = good.clone();
        v[4] = 9;
        assert!(s.screen(&v, a, 1.0, &c).is_none());
        let mut m = good.clone();
        m[0] = 0;
        assert!(s.screen(&m, a, 1.0, &c).is_none());
        let mut nan = good.clone();
        nan[112..120].copy_from_slice(&f64::NAN.to_le_bytes());
        assert!(s.screen(&nan, a, 1.0, &c).is_none());
        let obs = Message::Observation(ObservationMsg {
            id: 1,
            camera_time: 0.0,
            position: [0.0; 3],
        });
        assert!(s.screen(&bytes(&obs, 8, 1.0), a, 1.0, &c).is_none());
        assert!(s.screen(&good, a, 1.0, &c).is_some());
        let k = c.snapshot();
        assert_eq!(
            (k.received, k.accepted, k.duplicate, k.out_of_order, k.stale),
            (12, 3, 1, 1, 1)
        );
        assert_eq!(
            (
                k.truncated,
                k.oversized,
                k.unknown_version,
                k.malformed,
                k.non_finite,
                k.unexpected
            ),
            (1, 1, 1, 1, 1, 1)
        );
        assert_eq!(k.refused() + k.accepted, k.received);
    }
}
