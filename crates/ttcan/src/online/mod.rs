//! The controller's contact with the world at run time (issue 26): what an upper computer or a
//! camera process sends to a running `ttctl`, and what it answers. The datagram format
//! ([`wire`]), the seam between deciding hits and executing them ([`brain`]) and the ball mode's
//! brain ([`ball`]) with its search-ahead worker thread ([`speculator`]); the run time of the online modes: the receiver thread ([`receiver`]) with its
//! [`counters`], the planning thread ([`planner`]: its schedule of the
//! commanded state [`schedule`], its state and splice [`splicer`], hit planning [`hits`], keeping
//! the channels in step [`resync`]), the wait-free handoff to the cycle threads
//! ([`handoff`]) and the session that starts them with the telemetry thread ([`session`]).

pub mod ball;
pub mod brain;
pub mod counters;
pub mod handoff;
pub mod hits;
pub mod planner;
pub mod receiver;
pub mod resync;
pub mod schedule;
pub mod session;
pub mod speculator;
pub mod splicer;
pub mod wire;
