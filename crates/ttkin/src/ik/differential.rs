//! Differential IK (patent step S103): joint velocities q̇ from a tool twist V = [v; ω].
//!
//! For a square chain away from singularities q̇ = J⁻¹V. In general q̇ is the weighted
//! least-norm, least-squares solution q̇ = W^{−½}(J W^{−½})⁺V, computed from the SVD
//! J W^{−½} = Σ σ_i u_i v_iᵀ: for a redundant chain (n > 6) with full row rank this is seed 000's
//! q̇ = W⁻¹Jᵀ(JW⁻¹Jᵀ)⁻¹V (eq. 20, with W tied to the joint-limit criterion by
//! [`joint_limit_weights`], Chan & Dubey 1995); for n < 6 it is the least-squares q̇.
//!
//! Singularity: when the smallest singular value σ_min drops below ε (`epsilon`), the inverse is
//! damped (Nakamura & Hanafusa, Maciejewski): q̇ = Σ σ_i/(σ_i² + λ²)·v_i·u_iᵀV with
//! λ² = (1 − (σ_min/ε)²)·λ_max² (`lambda_max`), the damping of
//! [`crate::redundancy::Damping`] with the same names. Then ‖q̇‖ ≤ ‖V‖·max(1/ε, 1/(2λ)) stays bounded,
//! and the result says `singular = true`. For the gantry, det J = −L3·c4·s45: J is singular at
//! c4 = 0 (arm along the shoulder axis) and at s45 = 0 (racket axis along θ3's axis).

use nalgebra::{DMatrix, DVector};

use crate::chain::{Chain, JacobianFrame};
use crate::error::{check_finite, check_vector, Error, Result};

/// Settings of differential IK.
#[derive(Debug, Clone, PartialEq)]
pub struct DifferentialIk {
    /// ε: σ_min below which the inverse is damped (units of the Jacobian: m or rad per joint
    /// unit); was `threshold`.
    pub epsilon: f64,
    /// Damping λ_max reached at an exact singularity; was `max_damping`.
    pub lambda_max: f64,
    /// Frame of the twist's axes.
    pub frame: JacobianFrame,
}

impl Default for DifferentialIk {
    /// ε 1e-3, λ_max 1e-2, base-frame twist.
    fn default() -> Self {
        DifferentialIk {
            epsilon: 1e-3,
            lambda_max: 1e-2,
            frame: JacobianFrame::Base,
        }
    }
}

/// Joint velocities from a twist, with the conditioning that produced them.
#[derive(Debug, Clone, PartialEq)]
pub struct JointVelocity {
    /// Joint velocities (m/s or rad/s), chain order (was `qdot`).
    pub qd: Vec<f64>,
    /// True when σ_min < ε and the damped inverse was used.
    pub singular: bool,
    /// Smallest singular value of the (weighted) Jacobian.
    pub sigma_min: f64,
    /// Damping λ used (0 away from singularities).
    pub damping: f64,
    /// ‖J·q̇ − V‖: 0 up to rounding for an exact solve, > 0 when damped or when n < 6.
    pub residual: f64,
}

impl JointVelocity {
    /// Deprecated name of the field [`JointVelocity::qd`] (joint velocities, m/s or rad/s).
    #[deprecated(note = "one name per concept: use the field `qd`")]
    pub fn qdot(&self) -> &[f64] {
        &self.qd
    }
}

/// [`DifferentialIk::solve`] with default settings and no weights: q̇ for twist V = [v (m/s);
/// ω (rad/s)] of the tool point, base-frame axes.
pub fn joint_velocity(chain: &Chain, q: &[f64], twist: &[f64]) -> Result<JointVelocity> {
    DifferentialIk::default().solve(chain, q, twist, None)
}

impl DifferentialIk {
    /// Joint velocities for `twist` = [v; ω] (m/s, rad/s, axes of `self.frame`, v of the tool
    /// point) at configuration `q`; `weights` (one > 0 per joint, default 1) weight the joint-rate
    /// norm Σ w_i q̇_i² that a redundant chain minimises.
    pub fn solve(&self, chain: &Chain, q: &[f64], twist: &[f64], weights: Option<&[f64]>) -> Result<JointVelocity> {
        chain.check_q("q", q)?;
        check_vector("twist", twist, 6)?;
        // inf is meaningless for both: damping everywhere, or without bound (q̇ = 0)
        check_finite("epsilon", &[self.epsilon])?;
        check_finite("lambda_max", &[self.lambda_max])?;
        if !(self.epsilon > 0.0) || !(self.lambda_max >= 0.0) {
            return Err(Error::invalid(
                "differential IK",
                format!(
                    "epsilon must be > 0 and lambda_max ≥ 0, got {} and {}",
                    self.epsilon, self.lambda_max
                ),
            ));
        }
        let n = chain.dof();
        let scale: Vec<f64> = match weights {
            None => vec![1.0; n],
            Some(w) => {
                check_vector("weights", w, n)?;
                if let Some(bad) = w.iter().find(|v| !(**v > 0.0)) {
                    return Err(Error::invalid(
                        "weights",
                        format!("every weight must be > 0, got {bad}"),
                    ));
                }
                w.iter().map(|v| 1.0 / v.sqrt()).collect()
            }
        };
        let j = chain.jacobian(q, self.frame)?;
        let mut jw = DMatrix::from_iterator(6, n, j.iter().copied());
        for (c, s) in scale.iter().enumerate() {
            jw.column_mut(c).scale_mut(*s);
        }
        let v = DVector::from_column_slice(twist);
        let svd = jw.svd(true, true);
        let (Some(u), Some(vt)) = (&svd.u, &svd.v_t) else {
            return Err(Error::Singular("SVD of the Jacobian failed".into()));
        };
        let sigma = &svd.singular_values;
        let rank_dim = sigma.len();
        // min(6, n) singular values: for n < 6 the twist directions no joint can produce do not
        // count as a singularity (they show up in `residual` instead).
        let sigma_min = sigma.iter().copied().fold(f64::INFINITY, f64::min);
        let singular = sigma_min < self.epsilon;
        let damping = if singular {
            ((1.0 - (sigma_min / self.epsilon).powi(2)).max(0.0)).sqrt() * self.lambda_max
        } else {
            0.0
        };
        let utv = u.transpose() * &v;
        let mut qdot = DVector::zeros(n);
        for i in 0..rank_dim {
            let s = sigma[i];
            let denom = s * s + damping * damping;
            if denom > 0.0 {
                qdot += vt.row(i).transpose() * (s / denom * utv[i]);
            }
        }
        for (qi, s) in qdot.iter_mut().zip(&scale) {
            *qi *= s;
        }
        let residual = (&j * &qdot - v).norm();
        Ok(JointVelocity {
            qd: qdot.iter().copied().collect(),
            singular,
            sigma_min,
            damping,
            residual,
        })
    }
}

/// Seed 000's joint-limit criterion H(q) = Σ (q_max − q_min)² / [4(q_max − q)(q − q_min)] (eq. 21,
/// corrected to per-joint limits) and Chan & Dubey's weights: w_i = 1 + |∂H/∂q_i| while |∂H/∂q_i|
/// grows (the joint moves toward a limit; without `previous_gradient` it is taken as growing),
/// w_i = 1 while it shrinks. Joints with an infinite limit get w_i = 1. Returns (weights, ∂H/∂q);
/// pass the gradient back as `previous_gradient` on the next call. `q` must be strictly inside
/// the limits.
pub fn joint_limit_weights(
    chain: &Chain,
    q: &[f64],
    previous_gradient: Option<&[f64]>,
) -> Result<(Vec<f64>, Vec<f64>)> {
    chain.check_q("q", q)?;
    if let Some(p) = previous_gradient {
        check_vector("previous_gradient", p, chain.dof())?;
    }
    let mut w = Vec::with_capacity(q.len());
    let mut grad = Vec::with_capacity(q.len());
    for (i, (l, &qi)) in chain.limits().iter().zip(q).enumerate() {
        if !(l.lower.is_finite() && l.upper.is_finite()) || l.upper <= l.lower {
            w.push(1.0);
            grad.push(0.0);
            continue;
        }
        if !(qi > l.lower && qi < l.upper) {
            return Err(Error::invalid(
                "q",
                format!(
                    "joint {i} = {qi} must be strictly inside its limits ({}, {}) for the joint-limit criterion",
                    l.lower, l.upper
                ),
            ));
        }
        let range = l.upper - l.lower;
        let g =
            range * range * (2.0 * qi - l.upper - l.lower) / (4.0 * (l.upper - qi).powi(2) * (qi - l.lower).powi(2));
        let growing = previous_gradient.is_none_or(|p| g.abs() >= p[i].abs());
        w.push(if growing { 1.0 + g.abs() } else { 1.0 });
        grad.push(g);
    }
    Ok((w, grad))
}
