//! Table-tennis ball: flight, contacts, estimation from observations, prediction, racket impact,
//! hit planning and a simulated rally.
//!
//! **World frame** (every position, velocity and spin in this module unless said otherwise):
//! origin at the centre of the table's playing surface, x along the table's long axis toward the
//! opponent (the robot stands behind the end line x = −1.37 m), z up (surface at z = 0, floor at
//! z = −0.76 m), y = z × x (to the robot's left). Metres, m/s, rad/s, seconds.
//! [`hitplan::Placement`] says how the robot's base frame sits in it.
//!
//! One concept per file: [`model`] (ball and table constants), [`flight`] (integration with events),
//! [`contact`] (table, edge, net contacts and the bounce impulse), [`estimate`](mod@estimate) (state from
//! observations; its path sensitivities in [`sensitivity`]; [`update`] with later observations through the bounce), [`predict`] (positions, crossings), [`impact`] (racket impact and its inverse),
//! [`hitplan`] (where and when to hit, handing the hit to the one robot-side planner
//! [`crate::hit::HitPlanner`]), [`reach`] (the robot's reachable region,
//! independent of the planner), [`rally`] (the closed loop in simulation).

pub mod contact;
pub mod decide;
pub mod estimate;
pub mod fit;
pub mod flight;
pub mod hitplan;
pub mod impact;
pub mod model;
pub mod predict;
pub mod rally;
pub mod reach;
pub mod sensitivity;
pub mod update;

pub use estimate::{estimate, Estimate, EstimateOptions};
pub use flight::{BallState, Event, EventKind, Flight};
pub use model::{BallModel, Table};
