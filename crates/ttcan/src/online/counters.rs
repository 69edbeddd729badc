//! The online mode's counters: every datagram refused by class, every status sent by kind, the
//! splices, silences and telemetry. Shared by the receiver, planning and telemetry threads as
//! relaxed atomics (counting only, no ordering implied); [`Counters::snapshot`] reads them for
//! the statistics.

use std::sync::atomic::{AtomicU64, Ordering};

use super::wire::{PlanStatus, WireError};

macro_rules! counters {
    ($($(#[$doc:meta])* $name:ident),* $(,)?) => {
        /// The live counters (atomics).
        #[derive(Debug, Default)]
        pub struct Counters {
            $($(#[$doc])* pub $name: AtomicU64,)*
        }

        /// A copy of the counters at one moment.
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
        pub struct CountersSnapshot {
            $($(#[$doc])* pub $name: u64,)*
        }

        impl Counters {
            /// Reads every counter.
            pub fn snapshot(&self) -> CountersSnapshot {
                CountersSnapshot { $($name: self.$name.load(Ordering::Relaxed),)* }
            }
        }

        impl CountersSnapshot {
            /// Every counter as (name, value), in declaration order (for the statistics file).
            pub fn entries(&self) -> Vec<(&'static str, u64)> {
                vec![$((stringify!($name), self.$name),)*]
            }
        }
    };
}

counters! {
    /// Datagrams received (any content).
    received,
    /// Datagrams that passed every check and were handed on.
    accepted,
    /// Refused: not a ttmanip datagram (magic), an unknown kind or a value out of range.
    malformed,
    /// Refused: shorter than the header or than its kind.
    truncated,
    /// Refused: longer than its kind.
    oversized,
    /// Refused: a version this controller does not speak.
    unknown_version,
    /// Refused: a NaN or infinite number.
    non_finite,
    /// Refused: the sender's sequence number was seen last (a duplicate).
    duplicate,
    /// Refused: the sender's sequence number is older than its last one (reordered).
    out_of_order,
    /// Refused: sent longer ago than the latency budget (hits: send time on the controller clock).
    stale,
    /// Refused: a kind this mode does not take (status or telemetry, observations in hit mode).
    unexpected,
    /// Refused: the planning thread's queue was full (answered `rejected`).
    overload,
    /// Hits handed to the planner.
    hits,
    /// Observations handed to the planner.
    observations,
    /// Statuses sent: accepted.
    status_accepted,
    /// Statuses sent: too early.
    status_too_early,
    /// Statuses sent: unreachable.
    status_unreachable,
    /// Statuses sent: infeasible.
    status_infeasible,
    /// Statuses sent: replaced.
    status_replaced,
    /// Statuses sent: rejected.
    status_rejected,
    /// Strokes handed over to the cycle threads and taken on time.
    splices,
    /// Strokes refused by a cycle thread because they came after their splice cycle.
    splices_late,
    /// Plans made (hits and returns to ready).
    plans,
    /// Longest planning time, µs (arrival to handover).
    plan_time_max_us,
    /// Silences longer than the configured timeout (each brought the robot back to ready).
    silence_timeouts,
    /// Telemetry datagrams sent.
    telemetry_sent,
    /// Datagrams that could not be sent (socket errors).
    send_errors,
}

impl Counters {
    /// Counts one refusal of the wire decoder under its class.
    pub fn refused(&self, e: &WireError) {
        let c = match e {
            WireError::Truncated { .. } => &self.truncated,
            WireError::Oversized { .. } => &self.oversized,
            WireError::UnsupportedVersion(_) => &self.unknown_version,
            WireError::NonFinite(_) => &self.non_finite,
            WireError::BadMagic | WireError::UnknownKind(_) | WireError::BadValue(_) => &self.malformed,
        };
        c.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts one status sent.
    pub fn status(&self, s: PlanStatus) {
        let c = match s {
            PlanStatus::Accepted => &self.status_accepted,
            PlanStatus::TooEarly => &self.status_too_early,
            PlanStatus::Unreachable => &self.status_unreachable,
            PlanStatus::Infeasible => &self.status_infeasible,
            PlanStatus::Replaced => &self.status_replaced,
            PlanStatus::Rejected => &self.status_rejected,
        };
        c.fetch_add(1, Ordering::Relaxed);
    }

    /// Adds one to `c`.
    pub fn bump(c: &AtomicU64) {
        c.fetch_add(1, Ordering::Relaxed);
    }
}

impl CountersSnapshot {
    /// Datagrams refused, every class.
    pub fn refused(&self) -> u64 {
        self.malformed
            + self.truncated
            + self.oversized
            + self.unknown_version
            + self.non_finite
            + self.duplicate
            + self.out_of_order
            + self.stale
            + self.unexpected
            + self.overload
    }

    /// Statuses sent, every kind.
    pub fn statuses(&self) -> u64 {
        self.status_accepted
            + self.status_too_early
            + self.status_unreachable
            + self.status_infeasible
            + self.status_replaced
            + self.status_rejected
    }
}
