//! The seam between what decides hits and the runtime that plans and executes them. In hit mode
//! the hits come from the upper computer's datagrams; in ball mode a [`Brain`] turns camera
//! observations into the same hits. Both run on the planning thread, never on a cycle thread.

use super::wire::{HitMsg, ObservationMsg, StatusMsg};
use ttkin::traj::JointState;

/// What the robot is asked to do, on the controller's clock.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Plan and execute this hit (robot base frame, controller clock); a newer hit with the same
    /// `stroke` replaces an older one while the replacement is still feasible.
    Hit(HitMsg),
    /// Go back to the ready pose and hold it.
    Ready,
}

/// A ball-mode decision maker: camera observations in, commands out.
pub trait Brain: Send {
    /// One camera observation received at controller time `now` (s), with the state the
    /// controller commands at that time (`commanded`, joint space); returns what to do, if
    /// anything changes.
    fn observe(&mut self, obs: &ObservationMsg, now: f64, commanded: &JointState) -> Option<Command>;
    /// [`Brain::observe`] with the datagram header's send time `sent` (s, on the sender's clock),
    /// for a brain that relates the camera's clock to the controller's by it; the runtime calls
    /// this one. By default the send time is not used.
    fn observe_sent(&mut self, obs: &ObservationMsg, sent: f64, now: f64, commanded: &JointState) -> Option<Command> {
        let _ = sent;
        self.observe(obs, now, commanded)
    }
    /// Called on the planning thread at least every 10 ms (controller time `now`, s), for
    /// timeouts (a ball gone, silence); returns what to do, if anything changes.
    fn tick(&mut self, now: f64, commanded: &JointState) -> Option<Command>;
    /// How a hit this brain asked for came out (its status as sent to the upper computer).
    fn outcome(&mut self, status: &StatusMsg);
}
