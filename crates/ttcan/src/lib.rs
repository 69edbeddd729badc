//! `ttcan`: motor control for the ttmanip motion stack.
//!
//! The cascade of seed 000 §2.1 (current, speed and position loops, its Figs 2–4) as allocation-free
//! `f64` loops ([`loops`]), one motor's worth of them with sensing and a fault state machine
//! ([`axis`]), a multi-rate stepper for many axes ([`stepper`]), gain tuning from motor parameters
//! ([`tuning`]), and plant models with exact discretisation to simulate it all ([`motor`], [`sim`]).
//! CiA 402 over CAN: the sans-I/O protocol ([`canopen`]), buses ([`bus`]: in-memory, SocketCAN),
//! the controller runtime ([`runtime`]) and the virtual drive on top of [`sim`] ([`vdrive`]).
//!
//! Units: SI; positions and speeds are at the output (joint) side of the gearbox unless a name says
//! `motor`.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod actuator;
pub mod axis;
pub mod axis_config;
pub mod bus;
pub mod canopen;
pub mod cases;
pub mod coupled;
pub mod error;
pub mod loops;
pub mod motor;
pub mod noise;
pub mod observer;
pub mod online;
pub mod runtime;
pub mod schedule;
pub mod setpoint;
pub mod sim;
pub mod sizing;
pub mod stepper;
pub mod thermal;
pub mod tuning;
pub mod vdrive;

pub use axis::{Axis, AxisConfig, AxisState, Fault, HoldingBrake, Mode, Reaction};
pub use coupled::{CoupledOptions, CoupledSim, CoupledTrace, EnergyBalance};
pub use error::{Error, Result};
pub use motor::{DcMotor, Gearbox, Load, Measurement, MotorModel, Plant};
pub use schedule::{Due, Rates, Scheduler};
pub use sim::{Setpoint, Simulation, Trace};
pub use stepper::Stepper;
pub use tuning::{CascadeTuning, LoopReport, TuningTargets};
