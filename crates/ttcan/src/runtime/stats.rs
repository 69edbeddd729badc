//! Cycle statistics without allocation in the cycle: a histogram of wake-up latency (how late the
//! thread woke after its absolute deadline) in 1 µs bins up to 50 ms, deadline misses (woken
//! later than one period, or cycle work finishing after the next deadline), and cycle work time.

/// Number of 1 µs latency bins (the last bin collects everything beyond).
pub const BINS: usize = 50_000;

/// Latency and deadline statistics of one channel thread.
#[derive(Debug, Clone)]
pub struct CycleStats {
    histogram: Box<[u32]>,
    count: u64,
    max_ns: u64,
    max_work_ns: u64,
    sum_work_ns: u64,
    /// Cycles whose work finished after the next deadline, or that woke more than a period late.
    pub deadline_misses: u64,
}

impl Default for CycleStats {
    fn default() -> Self {
        Self::new()
    }
}

/// A summary of [`CycleStats`], µs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LatencySummary {
    /// Cycles recorded.
    pub cycles: u64,
    /// Median wake-up latency, µs.
    pub p50_us: f64,
    /// 99th percentile wake-up latency, µs.
    pub p99_us: f64,
    /// Largest wake-up latency, µs.
    pub max_us: f64,
    /// Mean cycle work time, µs.
    pub mean_work_us: f64,
    /// Largest cycle work time, µs.
    pub max_work_us: f64,
    /// Deadline misses.
    pub deadline_misses: u64,
}

impl CycleStats {
    /// Empty statistics (allocates the histogram once, here).
    pub fn new() -> Self {
        CycleStats {
            histogram: vec![0u32; BINS].into_boxed_slice(),
            count: 0,
            max_ns: 0,
            max_work_ns: 0,
            sum_work_ns: 0,
            deadline_misses: 0,
        }
    }

    /// Records one cycle: wake-up latency, work time and the period, ns.
    pub fn record(&mut self, latency_ns: u64, work_ns: u64, period_ns: u64) {
        let bin = ((latency_ns / 1000) as usize).min(BINS - 1);
        self.histogram[bin] = self.histogram[bin].saturating_add(1);
        self.count += 1;
        self.max_ns = self.max_ns.max(latency_ns);
        self.max_work_ns = self.max_work_ns.max(work_ns);
        self.sum_work_ns += work_ns;
        if latency_ns + work_ns > period_ns {
            self.deadline_misses += 1;
        }
    }

    /// Merges `other` into `self` (for a whole-controller summary).
    pub fn merge(&mut self, other: &CycleStats) {
        for (a, b) in self.histogram.iter_mut().zip(other.histogram.iter()) {
            *a = a.saturating_add(*b);
        }
        self.count += other.count;
        self.max_ns = self.max_ns.max(other.max_ns);
        self.max_work_ns = self.max_work_ns.max(other.max_work_ns);
        self.sum_work_ns += other.sum_work_ns;
        self.deadline_misses += other.deadline_misses;
    }

    fn percentile_us(&self, p: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let rank = ((p * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0u64;
        for (k, &c) in self.histogram.iter().enumerate() {
            seen += c as u64;
            if seen >= rank {
                return k as f64 + 0.5;
            }
        }
        BINS as f64
    }

    /// p50, p99, max wake-up latency, work time and misses.
    pub fn summary(&self) -> LatencySummary {
        LatencySummary {
            cycles: self.count,
            p50_us: self.percentile_us(0.50),
            p99_us: self.percentile_us(0.99),
            max_us: self.max_ns as f64 / 1000.0,
            mean_work_us: if self.count > 0 {
                self.sum_work_ns as f64 / self.count as f64 / 1000.0
            } else {
                0.0
            },
            max_work_us: self.max_work_ns as f64 / 1000.0,
            deadline_misses: self.deadline_misses,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_a_known_distribution() {
        let mut s = CycleStats::new();
        for k in 0..100u64 {
            s.record(k * 1000, 10_000, 1_000_000);
        }
        s.record(2_000_000, 0, 1_000_000);
        let m = s.summary();
        assert_eq!(m.cycles, 101);
        assert!((m.p50_us - 50.5).abs() < 1.01, "{m:?}");
        assert!((m.p99_us - 99.5).abs() < 1.01, "{m:?}");
        assert_eq!(m.max_us, 2000.0);
        assert_eq!(m.deadline_misses, 1);
    }
}
