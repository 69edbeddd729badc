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
            /// Latency from the arrival of the datagram a stroke was decided on (the hit, or the
            /// last observation used) to the stroke's first cycle (its first changed setpoint).
            pub latency: LatencyHistogram,
            /// The same for the strokes of a brain that were ready after their first splice cycle
            /// (planned again from a newer observation, retimed or decided again).
            pub latency_late: LatencyHistogram,
        }

        /// A copy of the counters at one moment.
        #[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
        pub struct CountersSnapshot {
            $($(#[$doc])* pub $name: u64,)*
            /// Strokes whose decision latency was measured.
            pub decision_latency_count: u64,
            /// Decision latency (arrival → first changed setpoint), median, µs (0 without strokes).
            pub decision_latency_p50_us: u64,
            /// Decision latency, 90th percentile, µs.
            pub decision_latency_p90_us: u64,
            /// Decision latency, 99th percentile, µs.
            pub decision_latency_p99_us: u64,
            /// Strokes whose decision latency exceeded 2 ms.
            pub decision_latency_over_2ms: u64,
            /// Decision latency, largest, µs.
            pub decision_latency_max_us: u64,
            /// Strokes of a brain handed over after a missed splice cycle (`latency_late`).
            pub decision_latency_late_count: u64,
            /// Of those, the strokes whose decision latency exceeded 2 ms.
            pub decision_latency_late_over_2ms: u64,
        }

        impl Counters {
            /// Reads every counter.
            pub fn snapshot(&self) -> CountersSnapshot {
                CountersSnapshot {
                    $($name: self.$name.load(Ordering::Relaxed),)*
                    decision_latency_count: self.latency.count(),
                    decision_latency_p50_us: self.latency.percentile_us(0.50),
                    decision_latency_p90_us: self.latency.percentile_us(0.90),
                    decision_latency_p99_us: self.latency.percentile_us(0.99),
                    decision_latency_over_2ms: self.latency.count_above_us(2000),
                    decision_latency_max_us: self.latency.max_us(),
                    decision_latency_late_count: self.latency_late.count(),
                    decision_latency_late_over_2ms: self.latency_late.count_above_us(2000),
                }
            }
        }

        impl CountersSnapshot {
            /// Every counter as (name, value), in declaration order (for the statistics file).
            pub fn entries(&self) -> Vec<(&'static str, u64)> {
                vec![
                    $((stringify!($name), self.$name),)*
                    ("decision_latency_count", self.decision_latency_count),
                    ("decision_latency_p50_us", self.decision_latency_p50_us),
                    ("decision_latency_p90_us", self.decision_latency_p90_us),
                    ("decision_latency_p99_us", self.decision_latency_p99_us),
                    ("decision_latency_over_2ms", self.decision_latency_over_2ms),
                    ("decision_latency_max_us", self.decision_latency_max_us),
                    ("decision_latency_late_count", self.decision_latency_late_count),
                    ("decision_latency_late_over_2ms", self.decision_latency_late_over_2ms),
                ]
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
    /// Statuses sent: out of step (a second status of an accepted hit, before it).
    status_out_of_step,
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
    /// Brain decisions made again for a later splice (the stroke was ready after its splice
    /// cycle: the decision took longer than the splice lead).
    splices_redecided,
    /// Strokes of a brain whose hit was planned again like an upper computer's (still late after
    /// 3 decisions, or not starting from the scheduled state).
    splices_replanned,
    /// Online threads (receiver, planning, telemetry) whose SCHED_FIFO priority the system
    /// refused: they run on normal scheduling.
    realtime_refused,
    /// Re-plans of a pending hit that brought the channels back in step after a channel thread
    /// stalled while the joints moved (`Splicer::resync`).
    resyncs,
    /// Such re-plans that found no feasible leg, or came too close to the hit.
    resyncs_failed,
    /// Executed hits every channel commanded at the same deadline.
    hits_in_step,
    /// Executed hits the channels commanded at different deadlines (a stall too close to the hit
    /// to re-plan, or no feasible re-plan): the commanded racket was not the planned one.
    hits_out_of_step,
    /// Largest spread (cycles) of the deadlines at which the channels commanded one hit.
    hit_skew_max_cycles,
    /// Ball mode: observations the brain received.
    ball_observations,
    /// Ball mode: observations older than the latency budget on arrival (dropped).
    ball_stale,
    /// Ball mode: observations of a ball already decided, or not later than its previous one.
    ball_ignored,
    /// Ball mode: balls seen (distinct consecutive ids).
    balls,
    /// Ball mode: balls whose first estimate failed.
    ball_estimate_failed,
    /// Ball mode: balls without a hit (the plans found none).
    ball_no_hit,
    /// Ball mode: first hits decided.
    ball_planned,
    /// Ball mode: hits corrected after the bounce.
    ball_corrected,
    /// Ball mode: balls lost (camera silent) before a hit was planned.
    ball_lost,
    /// Ball mode: the brain's hits answered otherwise than accepted or replaced.
    ball_refused,
    /// Ball mode: late strokes whose hit was kept, its leg planned again from a later splice
    /// (counted within `splices_redecided`).
    ball_retimed,
    /// Ball mode: late strokes whose hit was planned again, without a search, from the
    /// observations that came after their decision (counted within `splices_redecided`).
    ball_refined,
    /// Ball mode: decisions' searches made a few observations ahead of them.
    ball_speculated,
    /// Ball mode: decisions that planned the hit found ahead again instead of searching.
    ball_speculation_used,
    /// Ball mode: decisions with a hit found ahead that could not use it and searched.
    ball_speculation_unused,
    /// Ball mode: decisions due while their search ahead still ran on the worker thread (they
    /// waited for it, within their lead).
    ball_speculation_waited,
    /// Ball mode: of those, the decisions whose search ahead had not ended in time (searched).
    ball_speculation_pending,
    /// Ball mode: decisions that planned again a next best hit of the search ahead (the best
    /// not feasible any more; counted within `ball_speculation_used`).
    ball_speculation_alternative,
    /// Ball mode: searches ahead made again one frame before their decision (the held hits
    /// planned again from the newest estimate first) on the worker thread.
    ball_speculation_refreshed,
    /// Brain strokes ready after their splice cycle because their observation waited for the
    /// planning thread (busy with something else) longer than half the lead.
    late_queued,
    /// Brain strokes ready after their splice cycle though planned again from the hit found
    /// ahead (no search): that re-plan ran past the lead.
    late_replan_slow,
    /// Brain strokes ready after their splice cycle whose hit found ahead was infeasible at the
    /// decision (searched).
    late_held_infeasible,
    /// Brain strokes ready after their splice cycle whose search ahead was still running at the
    /// decision (searched).
    late_search_pending,
    /// Brain strokes ready after their splice cycle without a hit found ahead (searched).
    late_searched,
    /// Brain strokes ready after their splice cycle, the brain's path not known.
    late_other,
    /// Brain strokes handed over at their first splice cycle whose latency exceeded 2 ms (their
    /// observation waited for the planning thread).
    over_2ms_in_time,
    /// Late brain strokes over 2 ms, by why they were late (the `late_*` causes).
    over_2ms_queued,
    /// See `over_2ms_queued`.
    over_2ms_replan_slow,
    /// See `over_2ms_queued`.
    over_2ms_held_infeasible,
    /// See `over_2ms_queued`.
    over_2ms_search_pending,
    /// See `over_2ms_queued`.
    over_2ms_searched,
    /// See `over_2ms_queued`.
    over_2ms_other,
}

/// Bins of the latency histogram, each [`LatencyHistogram::BIN_US`] wide (the last: beyond).
const LATENCY_BINS: usize = 5000;

/// A histogram of latencies (10 µs bins up to 50 ms, then one bin beyond) in relaxed atomics:
/// recorded by the planning thread, read for the statistics.
#[derive(Debug)]
pub struct LatencyHistogram {
    bins: Box<[AtomicU64]>,
    max_us: AtomicU64,
}

impl Default for LatencyHistogram {
    fn default() -> Self {
        LatencyHistogram {
            bins: (0..LATENCY_BINS).map(|_| AtomicU64::new(0)).collect(),
            max_us: AtomicU64::new(0),
        }
    }
}

impl LatencyHistogram {
    /// Width of a bin, µs.
    pub const BIN_US: u64 = 10;

    /// Records one latency of `s` seconds (negative counts as 0, NaN is ignored).
    pub fn record(&self, s: f64) {
        if s.is_nan() {
            return;
        }
        let us = (s.max(0.0) * 1e6).round().min(u64::MAX as f64 / 2.0) as u64;
        let bin = ((us / Self::BIN_US) as usize).min(LATENCY_BINS - 1);
        self.bins[bin].fetch_add(1, Ordering::Relaxed);
        self.max_us.fetch_max(us, Ordering::Relaxed);
    }

    /// Latencies recorded.
    pub fn count(&self) -> u64 {
        self.bins.iter().map(|b| b.load(Ordering::Relaxed)).sum()
    }

    /// Latencies recorded above `us` µs (a multiple of [`Self::BIN_US`]).
    pub fn count_above_us(&self, us: u64) -> u64 {
        let from = ((us / Self::BIN_US) as usize).min(LATENCY_BINS);
        self.bins[from..].iter().map(|b| b.load(Ordering::Relaxed)).sum()
    }

    /// Largest latency recorded, µs.
    pub fn max_us(&self) -> u64 {
        self.max_us.load(Ordering::Relaxed)
    }

    /// The `p` quantile (0..=1), µs: the upper edge of the bin holding it (at most the largest
    /// latency recorded); 0 when nothing was recorded.
    pub fn percentile_us(&self, p: f64) -> u64 {
        let n = self.count();
        if n == 0 {
            return 0;
        }
        let rank = ((p.clamp(0.0, 1.0) * n as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (k, b) in self.bins.iter().enumerate() {
            seen += b.load(Ordering::Relaxed);
            if seen >= rank {
                return ((k as u64 + 1) * Self::BIN_US).min(self.max_us());
            }
        }
        self.max_us()
    }
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
            PlanStatus::OutOfStep => &self.status_out_of_step,
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
            + self.status_out_of_step
    }
}
