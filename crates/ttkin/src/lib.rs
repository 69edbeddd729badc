//! `ttkin`: the maths of the ttmanip motion stack for table-tennis robots.
//!
//! Robot descriptions (DH in either convention, robot files, URDF) become a [`Chain`]; on it live
//! forward kinematics ([`Chain::fk`], [`Chain::fk_all`]) and the geometric Jacobian
//! ([`Chain::jacobian`]). Everything is `f64`, in SI units (m, rad, s), frames named in each doc
//! comment. No devices, no Python, no global state.
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// `!(x > 0.0)` is how this crate rejects NaN together with the out-of-range values: keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod budget;
pub mod chain;
pub mod clik;
pub mod description;
pub mod dh;
pub mod diffdrive;
pub mod dynamics;
pub mod effort;
pub mod error;
pub mod hit;
pub mod ik;
pub mod inertial;
pub mod joint;
pub mod linalg;
pub mod redundancy;
pub mod robots;
pub mod speed;
pub mod tables;
pub mod task;
pub mod traj;
pub mod transform;
pub mod trig;
pub mod urdf;
pub mod wholebody;
// issue 13: ball flight, estimation, prediction, hit planning, rally
pub mod ball;

pub use chain::{Chain, JacobianFrame};
pub use dynamics::{Dynamics, DynamicsData, Wrench};
pub use error::{Error, Result};
pub use inertial::Inertial;
pub use joint::{Dh, DhConvention, Drive, Geometry, Joint, JointType, Limits};
