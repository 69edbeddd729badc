//! The seam between what decides hits and the runtime that plans and executes them. In hit mode
//! the hits come from the upper computer's datagrams; in ball mode a [`Brain`] turns camera
//! observations into strokes it builds itself. Both run on the planning thread, never on a cycle
//! thread.

use super::counters::Counters;
use super::wire::{HitMsg, ObservationMsg, StatusMsg};
use std::time::Instant;
use ttkin::traj::{JointState, JointTrajectory};

/// A stroke a brain built completely: the hit it executes and the joint trajectory from the
/// splice instant it was planned from ([`SpliceAt`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedStroke {
    /// The hit (robot base frame, controller clock), as the status and a re-plan see it.
    pub hit: HitMsg,
    /// Deadline the stroke starts at (its time 0; each channel at its own executed cycle), the
    /// [`SpliceAt::cycle`] it was planned for.
    pub cycle: u64,
    /// Controller time of that cycle, s.
    pub start: f64,
    /// Joint trajectory from the state commanded at `start` (time 0) through the hit and back
    /// to rest (m or rad, s from `start`).
    pub traj: JointTrajectory,
}

/// What the robot is asked to do, on the controller's clock.
#[derive(Debug, Clone, PartialEq)]
pub enum Command {
    /// Plan and execute this hit (robot base frame, controller clock); a newer hit with the same
    /// `stroke` replaces an older one while the replacement is still feasible.
    Hit(HitMsg),
    /// Execute this stroke, already planned from the splice instant it names; a newer stroke
    /// with the same `hit.stroke` replaces an older one. When the splice instant has passed by
    /// the time the runtime gets it, the runtime plans `hit` again from a later instant.
    Stroke(Box<PlannedStroke>),
    /// Go back to the ready pose and hold it.
    Ready,
}

/// The earliest instant a stroke decided now can start at, as the runtime offers it to a brain
/// with each observation: the deadline, its controller time (s) and the joint state the
/// controller commands then (m or rad; velocities, accelerations). A stroke planned from it is
/// continuous with what runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SpliceAt {
    /// Deadline index (each channel starts at it less the deadlines it skipped).
    pub cycle: u64,
    /// Controller time of that cycle, s.
    pub t: f64,
    /// The state commanded at that cycle.
    pub state: JointState,
    /// The instant (monotonic clock) by which a stroke for this splice must be built to be
    /// handed over in time: a brain's planning budget (`ttkin::ball::hitplan::PlanBudget`);
    /// `None`: no budget.
    pub deadline: Option<Instant>,
}

impl SpliceAt {
    /// A splice at controller time `t` (s) from `state`, cycle 0, no deadline (for a brain
    /// driven off-line).
    pub fn at(t: f64, state: JointState) -> Self {
        SpliceAt {
            cycle: 0,
            t,
            state,
            deadline: None,
        }
    }
}

/// A camera observation as the planning thread received it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observed {
    /// The observation.
    pub obs: ObservationMsg,
    /// The header's send time on the camera's clock, s.
    pub sent: f64,
    /// Controller clock at its arrival, s.
    pub arrival: f64,
}

/// A brain's late stroke waiting for a newer observation ([`Brain::awaits`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Awaiting {
    /// The ball (observation id) whose next observation is awaited.
    pub ball: u32,
    /// Longest wait (s) for it, from now; then the brain retries without it ([`Brain::retry`]).
    pub wait: f64,
}

/// How a brain's last decision found its hit (why its stroke may come after its splice cycle).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecisionPath {
    /// Planned again from the hit found ahead (no search): late only when that re-plan ran past
    /// the lead.
    Held,
    /// A hit found ahead was not feasible from the decision's estimate and state: searched.
    HeldInfeasible,
    /// The search ahead was still running when the decision was due (past its wait): searched.
    SearchPending,
    /// No hit found ahead (none found, or no search ahead): searched.
    Searched,
}

/// A ball-mode decision maker: camera observations in, commands out.
pub trait Brain: Send {
    /// One camera observation received at controller time `now` (s), with the header's send time
    /// `sent` (s, on the sender's clock; NaN when unknown) and the earliest splice instant
    /// (`splice`: a stroke decided now starts there, from its state); returns what to do, if
    /// anything changes.
    fn observe(&mut self, obs: &ObservationMsg, sent: f64, now: f64, splice: &SpliceAt) -> Option<Command>;
    /// The last observation's decision made again for a later splice instant (its stroke came
    /// too late for the one it was planned for), from `splice`: the same hit with its leg planned
    /// again from there when that is feasible, else the decision made again from the brain's
    /// state before that observation. `None` when there is nothing to retry.
    fn retry(&mut self, splice: &SpliceAt) -> Option<Command> {
        let _ = splice;
        None
    }
    /// Whether the brain's last stroke, ready after its splice cycle, is better planned again
    /// from an observation newer than the one it was decided on ([`Brain::refine`]) than retried
    /// at once: which ball's observation to wait for, and how long at most. `None` (the
    /// default): retry at once.
    fn awaits(&self) -> Option<Awaiting> {
        None
    }
    /// The last stroke's hit, ready after its splice cycle, planned again for `splice` with the
    /// observations received since (`newer`, in arrival order; they are also observed as usual
    /// afterwards, [`Brain::observe`]): the stroke and the index in `newer` of the newest
    /// observation it used (its decision latency counts from that one's arrival). `None`: no
    /// such stroke (the caller retries, [`Brain::retry`]).
    fn refine(&mut self, newer: &[Observed], splice: &SpliceAt) -> Option<(Command, usize)> {
        let _ = (newer, splice);
        None
    }
    /// Called on the planning thread at least every 10 ms (controller time `now`, s), for
    /// timeouts (a ball gone, silence); returns what to do, if anything changes.
    fn tick(&mut self, now: f64, commanded: &JointState) -> Option<Command>;
    /// How a hit this brain asked for came out (its status as sent to the upper computer).
    fn outcome(&mut self, status: &StatusMsg);
    /// How the last decision that made a stroke found its hit (`None`: not known, the default).
    fn decision_path(&self) -> Option<DecisionPath> {
        None
    }
    /// Copies the brain's own counters into the statistics (nothing by default).
    fn publish(&self, counters: &Counters) {
        let _ = counters;
    }
}
