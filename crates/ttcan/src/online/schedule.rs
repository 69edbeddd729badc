//! The commanded state the cycle threads will follow: the strokes handed over per channel, on
//! that channel's stroke clock ([`Schedule`]), and where a new stroke starts ([`Splice`]: one
//! deadline for every channel, each channel's start cycle that deadline less its skips).

use ttkin::traj::{JointState, JointTrajectory};

/// The strokes handed over, as the cycle threads follow them: the commanded state at any cycle.
#[derive(Debug, Clone)]
pub struct Schedule {
    hold: Vec<f64>,
    period: f64,
    segments: Vec<(u64, JointTrajectory)>,
}

impl Schedule {
    /// Holding `hold` (the enable positions) before any stroke; cycle period `period` s.
    pub fn new(hold: Vec<f64>, period: f64) -> Self {
        Schedule {
            hold,
            period,
            segments: Vec::new(),
        }
    }

    /// The state commanded at deadline `k`.
    pub fn state_at(&self, k: u64) -> JointState {
        match self.segments.iter().rev().find(|(s, _)| *s <= k) {
            Some((s, traj)) => {
                let t = ((k - s) as f64 * self.period).min(traj.duration());
                traj.state(t).unwrap_or_else(|_| JointState::rest(&self.hold))
            }
            None => JointState::rest(&self.hold),
        }
    }

    /// Adds a stroke starting at `start`: it supersedes every stroke starting at or after it
    /// (as [`super::handoff::StrokeFollower`] does).
    pub fn push(&mut self, start: u64, traj: JointTrajectory) {
        self.segments.retain(|(s, _)| *s < start);
        self.segments.push((start, traj));
        // only the last few are ever looked at
        if self.segments.len() > 16 {
            self.segments.drain(..self.segments.len() - 16);
        }
    }

    /// The cycle from which the schedule holds still: the end of the last stroke.
    pub fn end_cycle(&self) -> u64 {
        self.segments
            .last()
            .map_or(0, |(s, t)| s + (t.duration() / self.period).ceil() as u64)
    }
}

/// Where a stroke starts: one deadline for all channels, each channel's start cycle on its own
/// stroke clock that deadline less the deadlines it had skipped (`skips`, read together).
#[derive(Debug, Clone, PartialEq)]
pub struct Splice {
    pub(super) deadline: u64,
    pub(super) skips: Vec<u64>,
}

impl Splice {
    /// Channel `c`'s executed cycle of the splice.
    pub fn start(&self, c: usize) -> u64 {
        self.deadline.saturating_sub(self.skips.get(c).copied().unwrap_or(0))
    }
}
