//! Redundancy resolution for a task of m ≤ 6 rows and n ≥ m inputs: weighted least norm with the
//! joint-limit weights of Chan & Dubey (1995), singularity-robust damping that is zero away from
//! singularities, null-space projection of a secondary motion, and input velocity boxes respected
//! without leaving the task (saturation in the null space, then task scaling as the last resort).
//!
//! The solve is q̇ = z + W⁻¹Jᵀ(JW⁻¹Jᵀ + λ²I)⁻¹(ẋ − J z) over the inputs that are not saturated
//! (seed 000, (18)–(20), which need J of full row rank; the damping λ² handles the rank loss).
//! λ² = λ_max²(1 − (σ_min/ε)²) when the smallest singular value σ_min of J W^{-1/2} is below ε, else
//! 0 (Maciejewski & Klein; Chiaverini). With λ = 0 and full rank, J q̇ = ẋ exactly and the null-space
//! part z − W⁻¹Jᵀ(JW⁻¹Jᵀ)⁻¹Jz does not move the task.
//!
//! The joint-limit criterion is seed 000's (21) with per-joint limits (corrected form, see
//! ../shared/seeds/README.md): H = Σ (q_max − q_min)² / [4(q_max − q)(q − q_min)],
//! ∂H/∂q_i = (q_max − q_min)²(2q − q_max − q_min) / [4(q_max − q)²(q − q_min)²];
//! w_i = 1 + |∂H/∂q_i| while |∂H/∂q_i| grows, 1 while it shrinks. |∂H/∂q_i| grows exactly when
//! the joint moves away from mid-range, so "grows" is tested as ∂H/∂q_i · q̇_i ≥ 0 with the
//! joint's latest motion q̇_i (a joint at rest counts as approaching, the safe side).
//!
//! Rooms: [`limits`] (the joint-limit criterion and the Chan–Dubey weights), [`solver`] (the
//! damped weighted least-norm solve with velocity boxes, [`WlsSolver`]), [`kernels`] (fixed-size
//! Gram and Cholesky kernels, manipulability) and [`step`] (one step of a whole-body model,
//! [`WlsStep`]). The Cholesky itself is the crate's one, [`crate::linalg::cholesky`].

pub mod kernels;
pub mod limits;
pub mod solver;
pub mod step;

pub use kernels::manipulability;
pub use limits::{chan_dubey_weight, limit_criterion, limit_gradient, Weighting, MAX_LIMIT_GRADIENT};
pub use solver::{Damping, StepReport, WlsSolver};
pub use step::WlsStep;

/// Largest task dimension the solver handles.
pub const MAX_TASK_DIM: usize = 6;

/// Smallest singular value below which an undamped step is refused as singular.
pub const SINGULAR_SIGMA: f64 = 1e-9;
