//! The controller's datagram format, version 1: hits from an upper computer, ball observations
//! from a camera process, plan status and joint telemetry back. Every datagram is a fixed-size,
//! little-endian record: a 24-byte header, then the payload of its kind. Encoding and decoding
//! are sans-I/O and allocation-free (a buffer of [`MAX_LEN`] bytes on the stack); a datagram that
//! is truncated, oversized, of another magic, version or kind, or that carries a non-finite
//! number is refused with a [`WireError`] that says which, so that a receiver can count and drop
//! it. `docs/online.md` is the same table for the people who write the other side.
//!
//! | offset | type | header field |
//! |---|---|---|
//! | 0 | `[u8; 4]` | magic `TTMW` |
//! | 4 | u16 | version (1) |
//! | 6 | u16 | kind: 1 hit, 2 observation, 3 status, 4 telemetry |
//! | 8 | u64 | sequence number of the sender (strictly increasing per sender) |
//! | 16 | f64 | send time on the sender's clock (s) |

use std::fmt;

/// The four bytes every datagram starts with.
pub const MAGIC: [u8; 4] = *b"TTMW";
/// The version of this format.
pub const VERSION: u16 = 1;
/// Header length (bytes).
pub const HEADER_LEN: usize = 24;
/// Joints a telemetry datagram carries at most (unused slots are 0).
pub const MAX_JOINTS: usize = 8;
/// The longest datagram (bytes): a receive buffer of this size holds any of them.
pub const MAX_LEN: usize = HEADER_LEN
    + max(
        max(HIT_PAYLOAD, OBSERVATION_PAYLOAD),
        max(STATUS_PAYLOAD, TELEMETRY_PAYLOAD),
    );

const fn max(a: usize, b: usize) -> usize {
    if a > b {
        a
    } else {
        b
    }
}

const HIT_PAYLOAD: usize = 4 + 4 + 8 + 12 * 8 + 6 * 8;
const OBSERVATION_PAYLOAD: usize = 4 + 4 + 8 + 3 * 8;
const STATUS_PAYLOAD: usize = 4 + 2 + 2 + 8 + 8 + 8;
const TELEMETRY_PAYLOAD: usize = 8 + 8 + 4 + 2 + 2 + 2 * MAX_JOINTS * 8;

/// A hit for the robot (upper computer → controller): the racket pose and racket-centre twist
/// at the hit time, as `ttkin::hit::Hit` takes them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitMsg {
    /// The sender's id of this hit (echoed in its status).
    pub id: u32,
    /// Which stroke the hit is for: a newer hit with the same stroke replaces an older one.
    pub stroke: u32,
    /// Hit time on the controller's clock (s).
    pub t_hit: f64,
    /// Racket orientation, row-major 3×3 (racket frame in the base frame).
    pub rotation: [f64; 9],
    /// Racket centre (m, base frame).
    pub centre: [f64; 3],
    /// Racket-centre twist [v (m/s); ω (rad/s)], base axes.
    pub twist: [f64; 6],
}

impl HitMsg {
    /// The hit `id` for `stroke` at `t_hit` (s, controller clock) with the racket at `pose`
    /// (racket frame in the base frame, m) and the racket-centre `twist` [v (m/s); ω (rad/s)]
    /// (base axes): the rotation written row-major, the one conversion of a pose to the wire.
    pub fn from_pose(
        id: u32,
        stroke: u32,
        t_hit: f64,
        pose: &nalgebra::IsometryMatrix3<f64>,
        twist: [f64; 6],
    ) -> HitMsg {
        let r = pose.rotation.matrix();
        HitMsg {
            id,
            stroke,
            t_hit,
            rotation: std::array::from_fn(|k| r[(k / 3, k % 3)]),
            centre: pose.translation.vector.into(),
            twist,
        }
    }
}

/// A ball observation (camera → controller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObservationMsg {
    /// The camera's id of the ball (a new id: a new incoming ball).
    pub id: u32,
    /// Time stamp of the camera frame on the camera's clock (s).
    pub camera_time: f64,
    /// Ball centre (m, world frame of the table).
    pub position: [f64; 3],
}

/// How a hit came out (controller → upper computer); the codes are the wire's, stable across
/// versions of the planner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanStatus {
    /// Planned and spliced into the setpoint stream.
    Accepted = 0,
    /// Not feasible at its time; `earliest_t_hit` says when it would be.
    TooEarly = 1,
    /// No joint configuration puts the racket there.
    Unreachable = 2,
    /// A limit (velocity, acceleration, jerk, effort) cannot be met.
    Infeasible = 3,
    /// Replaced by a newer hit for the same stroke.
    Replaced = 4,
    /// Refused: in the past, malformed values, or the robot not ready.
    Rejected = 5,
    /// A second status of an accepted hit, before its time: a channel thread's stall left the
    /// channels apart and no re-plan brings them back in step before the hit (too close to it,
    /// or no feasible leg): the hit will be executed out of step, off the racket pose.
    OutOfStep = 6,
}

impl PlanStatus {
    fn from_code(c: u16) -> Option<Self> {
        Some(match c {
            0 => PlanStatus::Accepted,
            1 => PlanStatus::TooEarly,
            2 => PlanStatus::Unreachable,
            3 => PlanStatus::Infeasible,
            4 => PlanStatus::Replaced,
            5 => PlanStatus::Rejected,
            6 => PlanStatus::OutOfStep,
            _ => return None,
        })
    }
}

/// The status of one hit (controller → upper computer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StatusMsg {
    /// The hit's id.
    pub id: u32,
    /// How it came out.
    pub status: PlanStatus,
    /// The earliest feasible hit time on the controller's clock (s); NaN when unknown.
    pub earliest_t_hit: f64,
    /// The planned hit time (s, controller clock); NaN when not planned.
    pub t_hit: f64,
    /// Planning time (s) from the datagram's arrival to the stroke's handover.
    pub planning_time: f64,
}

/// Measured joint state at one cycle (controller → upper computer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TelemetryMsg {
    /// Controller clock (s) at the cycle.
    pub time: f64,
    /// Cycle number.
    pub cycle: u64,
    /// Fault bits of the axes (bit i: axis i stopped).
    pub faults: u32,
    /// Number of joints in use (≤ [`MAX_JOINTS`]).
    pub joints: u16,
    /// Measured joint positions (m or rad); slots past `joints` are 0.
    pub q: [f64; MAX_JOINTS],
    /// Measured joint velocities (m/s or rad/s).
    pub qd: [f64; MAX_JOINTS],
}

/// One datagram's content.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// Kind 1.
    Hit(HitMsg),
    /// Kind 2.
    Observation(ObservationMsg),
    /// Kind 3.
    Status(StatusMsg),
    /// Kind 4.
    Telemetry(TelemetryMsg),
}

/// A decoded datagram: the sender's sequence number and send time, and its message.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Datagram {
    /// The sender's sequence number.
    pub seq: u64,
    /// Send time on the sender's clock (s).
    pub sent: f64,
    /// The message.
    pub message: Message,
}

/// Why a datagram was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireError {
    /// Shorter than its header or than its kind's length.
    Truncated {
        /// Bytes received.
        len: usize,
        /// Bytes the header or the kind needs.
        expected: usize,
    },
    /// Longer than its kind's length.
    Oversized {
        /// Bytes received.
        len: usize,
        /// Bytes of the kind.
        expected: usize,
    },
    /// Not `TTMW`.
    BadMagic,
    /// A version this controller does not speak.
    UnsupportedVersion(u16),
    /// A kind this version does not define.
    UnknownKind(u16),
    /// A NaN or infinite number in the named field.
    NonFinite(&'static str),
    /// A value out of its range in the named field (a status code, a joint count).
    BadValue(&'static str),
}

impl fmt::Display for WireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WireError::Truncated { len, expected } => write!(f, "truncated datagram: {len} bytes, expected {expected}"),
            WireError::Oversized { len, expected } => write!(f, "oversized datagram: {len} bytes, expected {expected}"),
            WireError::BadMagic => write!(f, "not a ttmanip datagram (magic is not TTMW)"),
            WireError::UnsupportedVersion(v) => write!(f, "datagram version {v}, this controller speaks {VERSION}"),
            WireError::UnknownKind(k) => write!(f, "unknown datagram kind {k}"),
            WireError::NonFinite(w) => write!(f, "non-finite value in {w}"),
            WireError::BadValue(w) => write!(f, "value out of range in {w}"),
        }
    }
}

impl std::error::Error for WireError {}

fn payload_len(kind: u16) -> Option<usize> {
    Some(match kind {
        1 => HIT_PAYLOAD,
        2 => OBSERVATION_PAYLOAD,
        3 => STATUS_PAYLOAD,
        4 => TELEMETRY_PAYLOAD,
        _ => return None,
    })
}

/// Writes little-endian fields one after another into a byte buffer.
struct Writer<'a> {
    buf: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        self.buf[self.at..self.at + b.len()].copy_from_slice(b);
        self.at += b.len();
    }
    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    fn f64s(&mut self, v: &[f64]) {
        for x in v {
            self.bytes(&x.to_le_bytes());
        }
    }
}

/// Reads little-endian fields one after another; lengths are checked before it is made.
struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        out.copy_from_slice(&self.buf[self.at..self.at + N]);
        self.at += N;
        out
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    fn f64(&mut self, what: &'static str) -> Result<f64, WireError> {
        let v = f64::from_le_bytes(self.take());
        if v.is_finite() {
            Ok(v)
        } else {
            Err(WireError::NonFinite(what))
        }
    }
    /// A number that may be NaN by definition ("unknown"), never infinite.
    fn f64_or_nan(&mut self, what: &'static str) -> Result<f64, WireError> {
        let v = f64::from_le_bytes(self.take());
        if v.is_infinite() {
            Err(WireError::NonFinite(what))
        } else {
            Ok(v)
        }
    }
    fn f64s<const N: usize>(&mut self, what: &'static str) -> Result<[f64; N], WireError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(what)?;
        }
        Ok(out)
    }
}

/// Encodes `message` with sequence number `seq` and send time `sent` (s) into `buf`; returns the
/// datagram's length. The values are written as given (a sender that puts NaN in a hit has its
/// datagram refused by the receiver).
pub fn encode(message: &Message, seq: u64, sent: f64, buf: &mut [u8; MAX_LEN]) -> usize {
    let kind: u16 = match message {
        Message::Hit(_) => 1,
        Message::Observation(_) => 2,
        Message::Status(_) => 3,
        Message::Telemetry(_) => 4,
    };
    let len = HEADER_LEN + payload_len(kind).unwrap_or(0);
    let mut w = Writer {
        buf: &mut buf[..],
        at: 0,
    };
    w.bytes(&MAGIC);
    w.u16(VERSION);
    w.u16(kind);
    w.u64(seq);
    w.f64s(&[sent]);
    match message {
        Message::Hit(h) => {
            w.u32(h.id);
            w.u32(h.stroke);
            w.f64s(&[h.t_hit]);
            w.f64s(&h.rotation);
            w.f64s(&h.centre);
            w.f64s(&h.twist);
        }
        Message::Observation(o) => {
            w.u32(o.id);
            w.u32(0);
            w.f64s(&[o.camera_time]);
            w.f64s(&o.position);
        }
        Message::Status(s) => {
            w.u32(s.id);
            w.u16(s.status as u16);
            w.u16(0);
            w.f64s(&[s.earliest_t_hit, s.t_hit, s.planning_time]);
        }
        Message::Telemetry(t) => {
            w.f64s(&[t.time]);
            w.u64(t.cycle);
            w.u32(t.faults);
            w.u16(t.joints);
            w.u16(0);
            w.f64s(&t.q);
            w.f64s(&t.qd);
        }
    }
    debug_assert_eq!(w.at, len);
    len
}

/// Decodes one datagram, refusing anything that is not exactly a version-1 datagram of a known
/// kind with finite numbers.
pub fn decode(bytes: &[u8]) -> Result<Datagram, WireError> {
    if bytes.len() < HEADER_LEN {
        return Err(WireError::Truncated {
            len: bytes.len(),
            expected: HEADER_LEN,
        });
    }
    let mut r = Reader { buf: bytes, at: 0 };
    if r.take::<4>() != MAGIC {
        return Err(WireError::BadMagic);
    }
    let version = r.u16();
    if version != VERSION {
        return Err(WireError::UnsupportedVersion(version));
    }
    let kind = r.u16();
    let expected = HEADER_LEN + payload_len(kind).ok_or(WireError::UnknownKind(kind))?;
    if bytes.len() < expected {
        return Err(WireError::Truncated {
            len: bytes.len(),
            expected,
        });
    }
    if bytes.len() > expected {
        return Err(WireError::Oversized {
            len: bytes.len(),
            expected,
        });
    }
    let seq = r.u64();
    let sent = r.f64("sent")?;
    let message = match kind {
        1 => Message::Hit(HitMsg {
            id: r.u32(),
            stroke: r.u32(),
            t_hit: r.f64("t_hit")?,
            rotation: r.f64s("rotation")?,
            centre: r.f64s("centre")?,
            twist: r.f64s("twist")?,
        }),
        2 => {
            let id = r.u32();
            let _pad = r.u32();
            Message::Observation(ObservationMsg {
                id,
                camera_time: r.f64("camera_time")?,
                position: r.f64s("position")?,
            })
        }
        3 => {
            let id = r.u32();
            let status = PlanStatus::from_code(r.u16()).ok_or(WireError::BadValue("status"))?;
            let _pad = r.u16();
            Message::Status(StatusMsg {
                id,
                status,
                earliest_t_hit: r.f64_or_nan("earliest_t_hit")?,
                t_hit: r.f64_or_nan("t_hit")?,
                planning_time: r.f64("planning_time")?,
            })
        }
        _ => {
            let time = r.f64("time")?;
            let cycle = r.u64();
            let faults = r.u32();
            let joints = r.u16();
            if joints as usize > MAX_JOINTS {
                return Err(WireError::BadValue("joints"));
            }
            let _pad = r.u16();
            Message::Telemetry(TelemetryMsg {
                time,
                cycle,
                faults,
                joints,
                q: r.f64s("q")?,
                qd: r.f64s("qd")?,
            })
        }
    };
    Ok(Datagram { seq, sent, message })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn hit(x: f64) -> Message {
        Message::Hit(HitMsg {
            id: 7,
            stroke: 2,
            t_hit: 12.5,
            rotation: [1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0],
            centre: [x, -0.55, 0.05],
            twist: [0.9, -2.8, -0.6, 0.0, 0.1, 0.0],
        })
    }

    #[test]
    fn a_hit_from_a_pose_reads_back_as_that_pose() {
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let pose = nalgebra::IsometryMatrix3::from_parts(nalgebra::Translation3::new(0.35, -0.55, 0.05), r);
        let twist = [0.9, -2.8, -0.6, 0.0, 0.1, 0.0];
        let h = HitMsg::from_pose(7, 2, 12.5, &pose, twist);
        assert_eq!(
            (h.id, h.stroke, h.t_hit, h.twist, h.centre),
            (7, 2, 12.5, twist, [0.35, -0.55, 0.05])
        );
        assert_eq!(h.rotation[1], r.matrix()[(0, 1)], "row-major");
        let back = crate::online::planner::hit_pose(&h).unwrap();
        assert!((back.to_homogeneous() - pose.to_homogeneous()).abs().max() < 1e-15);
    }

    fn all() -> [Message; 4] {
        [
            hit(0.35),
            Message::Observation(ObservationMsg {
                id: 3,
                camera_time: 1.25,
                position: [-1.0, 0.2, 0.3],
            }),
            Message::Status(StatusMsg {
                id: 7,
                status: PlanStatus::TooEarly,
                earliest_t_hit: 12.61,
                t_hit: f64::NAN,
                planning_time: 8e-5,
            }),
            Message::Telemetry(TelemetryMsg {
                time: 3.0,
                cycle: 3000,
                faults: 0b10,
                joints: 6,
                q: [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.0, 0.0],
                qd: [0.0; MAX_JOINTS],
            }),
        ]
    }

    fn same(a: &Message, b: &Message) -> bool {
        // NaN marks "unknown" in a status: compare bit patterns, not values.
        format!("{a:?}") == format!("{b:?}")
    }

    #[test]
    fn every_kind_round_trips_with_its_fixed_length() {
        let lens = [184, 64, 56, 176];
        for (m, len) in all().iter().zip(lens) {
            let mut buf = [0u8; MAX_LEN];
            assert_eq!(encode(m, 41, 2.5, &mut buf), len);
            let d = decode(&buf[..len]).unwrap();
            assert_eq!((d.seq, d.sent), (41, 2.5));
            assert!(same(&d.message, m), "{m:?}");
        }
        assert_eq!(MAX_LEN, 184);
    }

    #[test]
    fn malformed_datagrams_are_refused_with_their_reason() {
        let mut buf = [0u8; MAX_LEN];
        let len = encode(&hit(0.35), 1, 0.0, &mut buf);
        assert!(matches!(
            decode(&buf[..10]),
            Err(WireError::Truncated { len: 10, expected: 24 })
        ));
        assert!(matches!(decode(&buf[..len - 1]), Err(WireError::Truncated { .. })));
        let mut long = buf.to_vec();
        long.push(0);
        assert!(matches!(decode(&long), Err(WireError::Oversized { .. })));
        let mut b = buf;
        b[0] = b'X';
        assert_eq!(decode(&b[..len]), Err(WireError::BadMagic));
        let mut b = buf;
        b[4] = 2;
        assert_eq!(decode(&b[..len]), Err(WireError::UnsupportedVersion(2)));
        let mut b = buf;
        b[6] = 9;
        assert_eq!(decode(&b[..len]), Err(WireError::UnknownKind(9)));
        let len = encode(&hit(f64::NAN), 1, 0.0, &mut buf);
        assert_eq!(decode(&buf[..len]), Err(WireError::NonFinite("centre")));
        let len = encode(&all()[2], 1, 0.0, &mut buf);
        buf[HEADER_LEN + 4] = 99;
        assert_eq!(decode(&buf[..len]), Err(WireError::BadValue("status")));
        let len = encode(&all()[3], 1, 0.0, &mut buf);
        buf[HEADER_LEN + 20] = 9;
        assert_eq!(decode(&buf[..len]), Err(WireError::BadValue("joints")));
        assert!(decode(&[]).is_err());
    }

    proptest! {
        /// Any byte string decodes to a datagram or a refusal, never a panic; and what decodes
        /// encodes back to the same bytes (up to the padding, which is written as zero).
        #[test]
        fn arbitrary_bytes_never_panic(
            fill in prop::collection::vec(any::<u8>(), MAX_LEN + 4),
            kind in 0u16..6,
            delta in -3i64..3,
        ) {
            let want = HEADER_LEN + payload_len(kind).unwrap_or(40);
            let len = (want as i64 + delta).max(0) as usize;
            let mut b = fill[..len].to_vec();
            if b.len() >= 8 {
                b[..4].copy_from_slice(&MAGIC);
                b[4..6].copy_from_slice(&VERSION.to_le_bytes());
                b[6..8].copy_from_slice(&kind.to_le_bytes());
            }
            match decode(&b) {
                Ok(d) => {
                    prop_assert_eq!(b.len(), want);
                    let mut buf = [0u8; MAX_LEN];
                    let n = encode(&d.message, d.seq, d.sent, &mut buf);
                    prop_assert_eq!(n, b.len());
                    prop_assert!(same(&decode(&buf[..n]).unwrap().message, &d.message));
                }
                Err(_) => prop_assert!(b.len() != want || payload_len(kind).is_none() || b.len() >= want),
            }
        }
    }
}
