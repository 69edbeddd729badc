//! Real-time helpers for the controller threads: the monotonic clock, absolute-deadline sleeping
//! (`clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME)`, through `nix`), SCHED_FIFO (through
//! `thread-priority`) and locked memory (`mlockall`). Refusals are returned as warnings for the
//! caller to print: the controller still runs, with worse latency.

use nix::sys::mman::{mlockall, MlockAllFlags};
use nix::sys::time::TimeSpec;
use nix::time::{clock_gettime, clock_nanosleep, ClockId, ClockNanosleepFlags};
use std::time::Duration;

/// Monotonic time, ns.
pub fn now_ns() -> u64 {
    match clock_gettime(ClockId::CLOCK_MONOTONIC) {
        Ok(t) => t.tv_sec() as u64 * 1_000_000_000 + t.tv_nsec() as u64,
        Err(_) => 0,
    }
}

/// Sleeps until the monotonic time `deadline_ns` (returns at once if it has passed).
pub fn sleep_until(deadline_ns: u64) {
    let ts = TimeSpec::from_duration(Duration::from_nanos(deadline_ns));
    loop {
        match clock_nanosleep(ClockId::CLOCK_MONOTONIC, ClockNanosleepFlags::TIMER_ABSTIME, &ts) {
            Err(nix::errno::Errno::EINTR) => continue,
            _ => return,
        }
    }
}

/// Switches the calling thread to SCHED_FIFO at `priority` (1–99); `Err` with a warning text
/// when not permitted.
pub fn make_thread_realtime(priority: u8) -> Result<(), String> {
    use thread_priority::unix::{
        set_thread_priority_and_policy, thread_native_id, RealtimeThreadSchedulePolicy, ThreadSchedulePolicy,
    };
    use thread_priority::{ThreadPriority, ThreadPriorityValue};
    let value =
        ThreadPriorityValue::try_from(priority.clamp(1, 99)).map_err(|e| format!("priority {priority}: {e}"))?;
    set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| format!("SCHED_FIFO refused ({e:?}): running with normal scheduling"))
}

/// Locks all present and future pages of the process in memory; `Err` with a warning text when
/// not permitted.
pub fn lock_memory() -> Result<(), String> {
    mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE)
        .map_err(|e| format!("mlockall refused ({e}): pages may fault in the cycle"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absolute_sleep_does_not_return_early() {
        let t0 = now_ns();
        sleep_until(t0 + 2_000_000);
        assert!(now_ns() >= t0 + 2_000_000);
        sleep_until(t0); // in the past: returns at once
    }
}
