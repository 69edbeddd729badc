//! Trajectories through via points: cubic segments with continuous velocity, the C² cubic spline
//! with clamped ends, and quintic segments with continuous acceleration.
//!
//! Via points are given as a row-major `m × dof` array `points` (rad or m) reached at `m ≥ 2`
//! strictly increasing `times` (s). The trajectory's own time starts at 0 at `times[0]`.
//!
//! Heuristic via velocities (Craig, *Introduction to Robotics*, §7.3; seed 000 (13)–(16) and seed
//! 001 (17)–(25) leave the choice open): zero at both ends; at an interior point the mean of the
//! slopes of the two adjacent segments when they have the same sign, else zero (the joint turns
//! there). Heuristic via accelerations for quintic segments: zero at both ends, the central
//! difference of the via velocities inside.

use super::{poly, JointTrajectory};
use crate::error::{check_finite, check_vector, Error, Result};

/// Which polynomial segments join the via points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViaKind {
    /// Cubic segments, velocity continuous (via velocities given or heuristic).
    Cubic,
    /// C² cubic spline with clamped end velocities (zero unless given).
    Spline,
    /// Quintic segments, velocity and acceleration continuous (given or heuristic).
    Quintic,
}

impl ViaKind {
    /// Parses "cubic", "spline" or "quintic".
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "cubic" => Ok(ViaKind::Cubic),
            "spline" => Ok(ViaKind::Spline),
            "quintic" => Ok(ViaKind::Quintic),
            _ => Err(Error::invalid(
                "kind",
                format!("expected cubic, spline or quintic, got '{name}'"),
            )),
        }
    }
}

/// Checks points and times; returns (m, dof) and the segment durations (s).
fn check_points(points: &[f64], times: &[f64], dof: usize) -> Result<(usize, Vec<f64>)> {
    let m = times.len();
    if m < 2 {
        return Err(Error::shape("times", "at least 2 via times", format!("{m} times")));
    }
    if dof == 0 {
        return Err(Error::shape("dof", "at least one joint", "0"));
    }
    check_finite("times", times)?;
    check_vector("points", points, m * dof)?;
    let h: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
    if let Some(k) = h.iter().position(|&hk| !(hk > 0.0)) {
        return Err(Error::invalid(
            "times",
            format!(
                "via times must be strictly increasing, got times[{k}] = {} then times[{}] = {}",
                times[k],
                k + 1,
                times[k + 1]
            ),
        ));
    }
    Ok((m, h))
}

fn knots(times: &[f64]) -> Vec<f64> {
    let mut k: Vec<f64> = times.iter().map(|&t| t - times[0]).collect();
    k[0] = 0.0;
    k
}

/// Craig's heuristic via velocities (row-major m × dof), zero at both ends.
pub fn heuristic_velocities(points: &[f64], times: &[f64], dof: usize) -> Result<Vec<f64>> {
    let (m, h) = check_points(points, times, dof)?;
    let mut v = vec![0.0; m * dof];
    for k in 1..m - 1 {
        for j in 0..dof {
            let before = (points[k * dof + j] - points[(k - 1) * dof + j]) / h[k - 1];
            let after = (points[(k + 1) * dof + j] - points[k * dof + j]) / h[k];
            if before * after > 0.0 {
                v[k * dof + j] = 0.5 * (before + after);
            }
        }
    }
    Ok(v)
}

/// The `m` via velocities (row-major m × dof): `given`, checked, or [`heuristic_velocities`].
fn via_velocities(points: &[f64], times: &[f64], dof: usize, m: usize, given: Option<&[f64]>) -> Result<Vec<f64>> {
    match given {
        Some(v) => {
            check_vector("velocities", v, m * dof)?;
            Ok(v.to_vec())
        }
        None => heuristic_velocities(points, times, dof),
    }
}

/// Cubic segments through the via points, velocity continuous. `velocities` (row-major m × dof,
/// rad/s or m/s) are the via velocities, or [`heuristic_velocities`] when `None`.
pub fn cubic(points: &[f64], times: &[f64], dof: usize, velocities: Option<&[f64]>) -> Result<JointTrajectory> {
    let (m, h) = check_points(points, times, dof)?;
    let v = via_velocities(points, times, dof, m, velocities)?;
    let mut coeffs = Vec::with_capacity((m - 1) * dof);
    for (k, &hk) in h.iter().enumerate() {
        for j in 0..dof {
            let (a, b) = (k * dof + j, (k + 1) * dof + j);
            coeffs.push(poly::cubic(points[a], points[b], v[a], v[b], hk));
        }
    }
    Ok(JointTrajectory::from_parts(dof, knots(times), coeffs))
}

/// The C² cubic spline through the via points with clamped end velocities `v_start`, `v_end`
/// (dof long each, zero when `None`).
///
/// The interior via velocities solve, for each joint, the tridiagonal system that equates the
/// accelerations of adjacent segments: h_k·v_{k−1} + 2(h_{k−1} + h_k)·v_k + h_{k−1}·v_{k+1}
/// = 3[h_k·Δ_{k−1}/h_{k−1} + h_{k−1}·Δ_k/h_k], with Δ_k = q_{k+1} − q_k and h_k the segment
/// durations (strictly diagonally dominant, so the Thomas algorithm is stable).
pub fn spline(
    points: &[f64],
    times: &[f64],
    dof: usize,
    v_start: Option<&[f64]>,
    v_end: Option<&[f64]>,
) -> Result<JointTrajectory> {
    let (m, h) = check_points(points, times, dof)?;
    for (what, v) in [("v_start", v_start), ("v_end", v_end)] {
        if let Some(v) = v {
            check_vector(what, v, dof)?;
        }
    }
    let mut v = vec![0.0; m * dof];
    if let Some(vs) = v_start {
        v[..dof].copy_from_slice(vs);
    }
    if let Some(ve) = v_end {
        v[(m - 1) * dof..].copy_from_slice(ve);
    }
    let inner = m - 2;
    let (mut c_prime, mut d_prime) = (vec![0.0; inner], vec![0.0; inner]);
    for j in 0..dof {
        let q = |k: usize| points[k * dof + j];
        // Forward sweep over the interior unknowns v_1 … v_{m−2}.
        for i in 0..inner {
            let k = i + 1;
            let (hp, hn) = (h[k - 1], h[k]);
            let (lower, diag, upper) = (hn, 2.0 * (hp + hn), hp);
            let mut rhs = 3.0 * (hn * (q(k) - q(k - 1)) / hp + hp * (q(k + 1) - q(k)) / hn);
            if k == 1 {
                rhs -= lower * v[j];
            }
            if k == m - 2 {
                rhs -= upper * v[(m - 1) * dof + j];
            }
            let (cp, dp) = if i == 0 {
                (0.0, 0.0)
            } else {
                (c_prime[i - 1], d_prime[i - 1])
            };
            let denom = diag - lower * cp;
            c_prime[i] = upper / denom;
            d_prime[i] = (rhs - lower * dp) / denom;
        }
        // Back substitution.
        for i in (0..inner).rev() {
            let next = if i + 1 < inner { v[(i + 2) * dof + j] } else { 0.0 };
            v[(i + 1) * dof + j] = d_prime[i] - if i + 1 < inner { c_prime[i] * next } else { 0.0 };
        }
    }
    cubic(points, times, dof, Some(&v))
}

/// Quintic segments through the via points, velocity and acceleration continuous. Via velocities
/// and accelerations (row-major m × dof) are given, or heuristic when `None` (see the module doc).
pub fn quintic(
    points: &[f64],
    times: &[f64],
    dof: usize,
    velocities: Option<&[f64]>,
    accelerations: Option<&[f64]>,
) -> Result<JointTrajectory> {
    let (m, h) = check_points(points, times, dof)?;
    let v = via_velocities(points, times, dof, m, velocities)?;
    let a = match accelerations {
        Some(a) => {
            check_vector("accelerations", a, m * dof)?;
            a.to_vec()
        }
        None => {
            let mut a = vec![0.0; m * dof];
            for k in 1..m - 1 {
                for j in 0..dof {
                    a[k * dof + j] = (v[(k + 1) * dof + j] - v[(k - 1) * dof + j]) / (times[k + 1] - times[k - 1]);
                }
            }
            a
        }
    };
    let mut coeffs = Vec::with_capacity((m - 1) * dof);
    for (k, &hk) in h.iter().enumerate() {
        for j in 0..dof {
            let (s, e) = (k * dof + j, (k + 1) * dof + j);
            coeffs.push(poly::quintic(points[s], v[s], a[s], points[e], v[e], a[e], hk));
        }
    }
    Ok(JointTrajectory::from_parts(dof, knots(times), coeffs))
}

/// Via-point trajectory of the given kind with heuristic (cubic, quintic) or clamped-at-rest
/// (spline) velocities.
pub fn through(points: &[f64], times: &[f64], dof: usize, kind: ViaKind) -> Result<JointTrajectory> {
    match kind {
        ViaKind::Cubic => cubic(points, times, dof, None),
        ViaKind::Spline => spline(points, times, dof, None, None),
        ViaKind::Quintic => quintic(points, times, dof, None, None),
    }
}
