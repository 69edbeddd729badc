//! Rigid-body dynamics of a serial chain: inverse dynamics (recursive Newton–Euler), gravity and
//! Coriolis torques, the joint-space mass matrix (composite rigid body algorithm), forward dynamics
//! (Cholesky solve of the mass matrix), a semi-implicit Euler integrator and the torque profile of
//! a planned motion with its effort-limit check and motor-side torques and currents.
//!
//! Model/data separation as in Pinocchio: [`Dynamics`] is what the robot is (built once from a
//! [`Chain`](crate::chain::Chain), validated, immutable), [`DynamicsData`] is the scratch space of the algorithms
//! (allocated once; the single-configuration calls allocate nothing).
//!
//! Frames. Every joint is `pre · M(q) · post` (see [`crate::joint`]). The algorithms work in the
//! joint frames F_i = (frame before joint i) · pre_i · M(q_i), whose z axis is the joint axis, so the
//! motion subspace is the constant S = (ẑ, 0) for a revolute and S = (0, ẑ) for a prismatic joint,
//! whichever DH convention or URDF origin described it. Link inertias, given in the link frame
//! (F_i · post_i), are moved into F_i once, when the model is built. Spatial vectors are
//! (angular; linear) pairs, velocities at the frame origin, forces as (moment about the origin;
//! force), Featherstone's notation (Rigid Body Dynamics Algorithms, 2008, ch. 5–6).
//!
//! Equation of motion, with the armature A = diag(G_i²·J_rotor,i) of the drives included in M:
//! τ = M(q)·q̈ + C(q, q̇)·q̇ + g(q) − Jᵀ(q)·w_ext (+ friction, see [`Dynamics::inverse_dynamics`]).
//! Gravity is a vector in the base frame (m/s², e.g. (0, 0, −9.81)).
//!
//! One algorithm per file, as Pinocchio's `src/algorithm/`: [`model`] (the model, its scratch
//! space and the joint placement all algorithms share), [`rnea`] (inverse dynamics and its special
//! cases), [`crba`] (mass matrix), [`forward`] (forward dynamics and the integrator), [`energy`],
//! [`profile`] (torque profile of a planned motion), [`batch`] (parallel batches over samples) and
//! [`cache`] (a lazily built model with a shared scratch space for callers that hold a chain).

pub mod batch;
pub mod cache;
pub mod crba;
pub mod energy;
pub mod forward;
pub mod interval;
pub mod model;
pub mod peak;
pub mod profile;
pub mod rnea;

use nalgebra::Vector3;

pub use cache::DynamicsCache;
pub use model::{Dynamics, DynamicsData};
pub use peak::{EffortPeak, PeakStop};
pub use profile::{EffortViolation, TorqueProfile};

/// Standard gravity in a z-up base frame, m/s².
pub const EARTH_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// A wrench the environment applies to the tool (a ball on the racket, a payload's weight):
/// force in N and moment about the tool point in N·m, both in tool-frame axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force on the tool, N, tool-frame axes.
    pub force: Vector3<f64>,
    /// Moment on the tool about the tool point, N·m, tool-frame axes.
    pub torque: Vector3<f64>,
}
