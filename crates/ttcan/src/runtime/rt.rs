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

/// What the system did to a thread (or the process) so far: page faults and involuntary context
/// switches (`getrusage`), for the statistics of a run (read outside the cycle loop).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Usage {
    /// Minor page faults (a page mapped on first touch; none once memory is locked and touched).
    pub minor_faults: u64,
    /// Major page faults (a page read from disk).
    pub major_faults: u64,
    /// Involuntary context switches (preempted by a thread of higher or equal priority, or by
    /// the kernel's real-time throttling).
    pub preempted: u64,
}

impl Usage {
    /// The calling thread's usage so far (zeros when the system refuses).
    pub fn thread() -> Self {
        Self::of(nix::sys::resource::UsageWho::RUSAGE_THREAD)
    }

    /// The whole process's usage so far (zeros when the system refuses).
    pub fn process() -> Self {
        Self::of(nix::sys::resource::UsageWho::RUSAGE_SELF)
    }

    fn of(who: nix::sys::resource::UsageWho) -> Self {
        match nix::sys::resource::getrusage(who) {
            Ok(u) => Usage {
                minor_faults: u.minor_page_faults() as u64,
                major_faults: u.major_page_faults() as u64,
                preempted: u.involuntary_context_switches() as u64,
            },
            Err(_) => Usage::default(),
        }
    }

    /// What happened between `earlier` and this reading.
    pub fn since(&self, earlier: &Usage) -> Usage {
        Usage {
            minor_faults: self.minor_faults.saturating_sub(earlier.minor_faults),
            major_faults: self.major_faults.saturating_sub(earlier.major_faults),
            preempted: self.preempted.saturating_sub(earlier.preempted),
        }
    }
}

/// Time (ms) the hypervisor ran something else while this virtual machine's CPUs wanted to run,
/// summed over its CPUs since boot (`steal` of `/proc/stat`, in clock ticks of 10 ms); `None`
/// where the system does not say. A stall of the host shows as steal, not as anything the
/// controller can change.
pub fn steal_ms() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    let cpu = stat.lines().next()?.strip_prefix("cpu ")?;
    let steal: u64 = cpu.split_whitespace().nth(7)?.parse().ok()?;
    Some(steal as f64 * 10.0)
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

    #[test]
    fn usage_counts_the_faults_of_fresh_pages() {
        let before = Usage::thread();
        // 4 MB touched for the first time: at least some pages fault (unless memory is locked,
        // when mlockall touched them at allocation: this test does not lock)
        let v = vec![1u8; 4 << 20];
        let after = Usage::thread().since(&before);
        assert!(v.iter().map(|&x| x as u64).sum::<u64>() == 4 << 20);
        assert!(after.minor_faults > 0, "{after:?}");
        assert!(Usage::process().minor_faults >= after.minor_faults);
        if let Some(s) = steal_ms() {
            assert!(s >= 0.0 && s.is_finite());
        }
    }
}
