//! Seed 000's joint-limit criterion H (21), its gradient, and the Chan–Dubey weight built on it
//! (corrected form: see the module documentation of [`crate::redundancy`]).

use crate::error::{Error, Result};

/// Cap on |∂H/∂q| (and so on a weight) at or beyond a limit, where the criterion is infinite.
pub const MAX_LIMIT_GRADIENT: f64 = 1e12;

/// Seed 000's joint-limit criterion H (21) for one joint at `q` with limits [lower, upper]
/// (m or rad); 0 for a joint without finite limits, +∞ on or beyond a limit.
pub fn limit_criterion(q: f64, lower: f64, upper: f64) -> f64 {
    if !(lower.is_finite() && upper.is_finite()) || upper <= lower {
        return 0.0;
    }
    let d = (upper - q) * (q - lower);
    if d <= 0.0 {
        return f64::INFINITY;
    }
    (upper - lower).powi(2) / (4.0 * d)
}

/// ∂H/∂q of [`limit_criterion`] (1/m or 1/rad): positive above mid-range, negative below, 0 at
/// mid-range and for a joint without finite limits; ±[`MAX_LIMIT_GRADIENT`] on or beyond a limit.
pub fn limit_gradient(q: f64, lower: f64, upper: f64) -> f64 {
    if !(lower.is_finite() && upper.is_finite()) || upper <= lower {
        return 0.0;
    }
    let (a, b) = (upper - q, q - lower);
    let s = 2.0 * q - upper - lower;
    if a <= 0.0 || b <= 0.0 {
        return MAX_LIMIT_GRADIENT.copysign(s);
    }
    let g = (upper - lower).powi(2) * s / (4.0 * a * a * b * b);
    g.clamp(-MAX_LIMIT_GRADIENT, MAX_LIMIT_GRADIENT)
}

/// Chan–Dubey weight of one joint at `q` with limits [lower, upper] whose latest motion is `qdot`:
/// 1 + |∂H/∂q| when moving toward a limit (or at rest), 1 when moving away.
pub fn chan_dubey_weight(q: f64, lower: f64, upper: f64, qdot: f64) -> f64 {
    let g = limit_gradient(q, lower, upper);
    if g * qdot >= 0.0 {
        1.0 + g.abs()
    } else {
        1.0
    }
}

/// How the weighting matrix W is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Weighting {
    /// W = diag(base weights): plain (or constant-weighted) least norm.
    None,
    /// W = diag(base weight × Chan–Dubey weight).
    ChanDubey,
}

impl Weighting {
    /// Parses `"none"` or `"chan-dubey"`.
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "none" => Ok(Weighting::None),
            "chan-dubey" => Ok(Weighting::ChanDubey),
            other => Err(Error::invalid(
                "weights",
                format!("unknown weighting '{other}'; choose 'chan-dubey' or 'none'"),
            )),
        }
    }
}
