//! Ball state from noisy observed positions: robust to outliers and to a bounce in the window.
//!
//! Method. Observations with a non-finite value are dropped (counted). A bounce inside the window
//! is found as an interior minimum of the (median-of-three filtered) height near the surface; the
//! fit then uses the observations after it when they last long enough to fit the spin
//! (`spin_min_duration`, ≥ 8 observations), otherwise those before it, predicted through the bounce. On one flight arc the state at the arc's last observation time t0
//! is fitted by a fixed-point iteration on the flight model: with the current estimate integrated
//! to every observation time, x(t_i), the part not explained by p0 + v0·τ + ½·A·τ² (τ = t_i − t0,
//! A = k_m·ω × v0 the Magnus acceleration at t0) is subtracted from the observations and
//! (p0, v0, A) re-solved by weighted linear least squares, shared 3×3 normal equations for the
//! three axes. The spin follows from A: ω⊥ = v0 × A / (k_m·|v0|²), the part perpendicular to v0
//! (the component along v0 produces no force in flight and is not observable; it is 0). Weights
//! are Huber's (c = 3σ on the 3-D residual, σ from the median residual: for Gaussian noise σ_axis =
//! median|r| / 1.538, the median of a χ₃) and residuals beyond 6σ get weight 0 (outliers). The
//! contraction factor of the iteration is about k_d·|v|·T (≈ 0.15 for a 0.2 s window), so it
//! converges in a few iterations. Covariance: σ²·(BᵀWB)⁻¹ per axis, for (p0, v0) and A.

use super::flight::{BallState, Flight};
use nalgebra::{Matrix3, Vector3};

/// Options of [`estimate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateOptions {
    /// Flight model used for the fit.
    pub flight: Flight,
    /// Fewest usable observations on the fitted arc (≥ 4; 5 by default).
    pub min_observations: usize,
    /// Fit the spin (perpendicular to v) when the arc lasts at least this long (s); 0.06 by default.
    pub spin_min_duration: f64,
    /// Fixed-point iterations at most (8 by default).
    pub iterations: usize,
    /// Smallest noise scale assumed (m), so exact data do not divide by zero: 1e-4.
    pub sigma_floor: f64,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        EstimateOptions {
            flight: Flight::default(),
            min_observations: 5,
            spin_min_duration: 0.06,
            iterations: 8,
            sigma_floor: 1e-4,
        }
    }
}

/// Which part of the window the fit used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Segment {
    /// No bounce in the window: all observations.
    Whole,
    /// A bounce in the window; the observations after it.
    AfterBounce,
    /// A bounce in the window with too few observations after it: those before, predicted through it.
    BeforeBounce,
}

/// An estimated ball state with its uncertainty.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Ball state at the time of the last usable observation.
    pub state: BallState,
    /// Covariance (m², m²/s, m²/s²) of [p; v] at the fitted arc's last time, order px py pz vx vy vz.
    pub covariance: [[f64; 6]; 6],
    /// Standard deviation (rad/s) of each spin component perpendicular to v (0 when not fitted).
    pub spin_std: f64,
    /// Whether the spin was fitted (arc long enough) or left at zero.
    pub spin_fitted: bool,
    /// Robust residual scale σ (m, per axis).
    pub sigma: f64,
    /// Observations used in the fit (weight > 0).
    pub used: usize,
    /// Observations rejected as outliers.
    pub outliers: usize,
    /// Observations dropped for NaN or infinite values.
    pub nonfinite: usize,
    /// Time (s) of the bounce found in the window, if any.
    pub bounce_time: Option<f64>,
    /// Which part of the window was fitted.
    pub segment: Segment,
}

/// Why no estimate could be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EstimateError {
    /// `t` and `p` have different lengths.
    #[error("p: expected {expected} rows (one per time in t), got {got}")]
    Shape {
        /// Rows expected.
        expected: usize,
        /// Rows given.
        got: usize,
    },
    /// Too few finite observations.
    #[error("too few observations: {usable} usable (finite, on one arc) of {total}, need at least {need}")]
    TooFew {
        /// Usable observations.
        usable: usize,
        /// Observations given.
        total: usize,
        /// Observations needed.
        need: usize,
    },
    /// Times not strictly increasing.
    #[error("t: times must increase strictly, t[{index}] = {value} s does not")]
    Times {
        /// Index of the offending time.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// The fit did not produce a finite state (degenerate geometry).
    #[error("the fit is degenerate: {0}")]
    Degenerate(String),
}

impl From<EstimateError> for crate::Error {
    fn from(e: EstimateError) -> Self {
        match e {
            EstimateError::Shape { expected, got } => {
                crate::Error::shape("p", format!("({expected}, 3)"), format!("({got}, 3)"))
            }
            other => crate::Error::invalid("observations", other.to_string()),
        }
    }
}

/// Fits the ball state to observed centre positions `p` (m, world) at times `t` (s).
pub fn estimate(t: &[f64], p: &[[f64; 3]], opts: &EstimateOptions) -> Result<Estimate, EstimateError> {
    if t.len() != p.len() {
        return Err(EstimateError::Shape {
            expected: t.len(),
            got: p.len(),
        });
    }
    let need = opts.min_observations.max(4);
    let mut idx: Vec<usize> = Vec::with_capacity(t.len());
    for i in 0..t.len() {
        if t[i].is_finite() && p[i].iter().all(|x| x.is_finite()) {
            if let Some(&j) = idx.last() {
                if !(t[i] > t[j]) {
                    return Err(EstimateError::Times { index: i, value: t[i] });
                }
            }
            idx.push(i);
        }
    }
    let nonfinite = t.len() - idx.len();
    if idx.len() < need {
        return Err(EstimateError::TooFew {
            usable: idx.len(),
            total: t.len(),
            need,
        });
    }
    let bounce = find_bounce(&idx, p, opts);
    // After a bounce, the arc after it is used once it is long enough to fit the spin (or the arc
    // before it is too short); otherwise the longer arc before it, predicted through the bounce.
    let long_after = |k: usize| {
        idx.len() - k > need.max(8) && t[*idx.last().expect("non-empty")] - t[idx[k + 1]] >= opts.spin_min_duration
    };
    let (arc, segment) = match bounce {
        None => (&idx[..], Segment::Whole),
        Some(k) if idx.len() - k > need && (long_after(k) || k < need) => (&idx[k + 1..], Segment::AfterBounce),
        Some(k) if k >= need => (&idx[..k], Segment::BeforeBounce),
        Some(k) => {
            return Err(EstimateError::TooFew {
                usable: k.max(idx.len() - k - 1),
                total: t.len(),
                need,
            });
        }
    };
    let mut fit = fit_arc(t, p, arc, opts)?;
    fit.nonfinite = nonfinite;
    fit.segment = segment;
    fit.bounce_time = bounce.map(|k| t[idx[k]]);
    if segment == Segment::BeforeBounce {
        let t_last = t[*idx.last().expect("non-empty")];
        let (s, _) = opts.flight.run(&fit.state, t_last, None);
        fit.state = s;
    }
    Ok(fit)
}

/// Index (into `idx`) of an interior height minimum near the table surface, if any.
fn find_bounce(idx: &[usize], p: &[[f64; 3]], opts: &EstimateOptions) -> Option<usize> {
    let n = idx.len();
    if n < 5 {
        return None;
    }
    let z = |k: usize| {
        let a = p[idx[k.saturating_sub(1)]][2];
        let b = p[idx[k]][2];
        let c = p[idx[(k + 1).min(n - 1)]][2];
        a.max(b.min(c)).min(b.max(c)) // median of three
    };
    let (k, zmin) = (1..n - 1)
        .map(|k| (k, z(k)))
        .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    let r = opts.flight.model.radius;
    let rise = 0.01;
    if k >= 1 && k + 1 < n && zmin < r + 0.05 && z(0).max(p[idx[0]][2]) > zmin + rise && z(n - 1) > zmin + rise {
        Some(k)
    } else {
        None
    }
}

fn fit_arc(t: &[f64], p: &[[f64; 3]], arc: &[usize], opts: &EstimateOptions) -> Result<Estimate, EstimateError> {
    let flight = &opts.flight;
    let km = flight.model.k_magnus;
    let n = arc.len();
    let t0 = t[arc[n - 1]];
    let tau: Vec<f64> = arc.iter().map(|&i| t[i] - t0).collect();
    let obs: Vec<Vector3<f64>> = arc.iter().map(|&i| Vector3::from(p[i])).collect();
    let with_spin = km > 0.0 && -tau[0] >= opts.spin_min_duration && n >= 8;
    let dim = if with_spin { 3 } else { 2 };
    let basis = |tk: f64| [1.0, tk, 0.5 * tk * tk];
    let mut weights = vec![1.0; n];
    let mut model_path = vec![Vector3::zeros(); n]; // x(t_i) − (p0 + v0 τ + ½Aτ²) of the current estimate
    for (k, &tk) in tau.iter().enumerate() {
        model_path[k] = Vector3::new(0.0, 0.0, -0.5 * flight.model.gravity * tk * tk);
    }
    let (mut p0, mut v0, mut acc) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
    let mut sigma = opts.sigma_floor;
    let mut cov = Matrix3::zeros();
    for iter in 0..opts.iterations.max(2) {
        // Weighted linear least squares on the basis, the same normal matrix for the 3 axes.
        let mut ata = Matrix3::zeros();
        let mut atb = [Vector3::zeros(); 3]; // per basis function, the 3 axes
        for k in 0..n {
            let b = basis(tau[k]);
            let y = obs[k] - model_path[k];
            for r in 0..dim {
                for c in 0..dim {
                    ata[(r, c)] += weights[k] * b[r] * b[c];
                }
                atb[r] += weights[k] * b[r] * y;
            }
        }
        if dim == 2 {
            ata[(2, 2)] = 1.0;
        }
        let inv = ata
            .try_inverse()
            .ok_or_else(|| EstimateError::Degenerate("observation times do not span the fit".into()))?;
        let coef = |r: usize| (0..dim).fold(Vector3::zeros(), |s, c| s + inv[(r, c)] * atb[c]);
        let (np0, nv0) = (coef(0), coef(1));
        let nacc = if with_spin { coef(2) } else { Vector3::zeros() };
        let change = (np0 - p0).norm() + 0.05 * (nv0 - v0).norm();
        (p0, v0, acc) = (np0, nv0, nacc);
        cov = inv;
        // Residuals and robust weights.
        let spin = spin_from(&v0, &acc, km);
        let state = BallState {
            t: t0,
            p: p0,
            v: v0,
            w: spin,
        };
        let path = integrate_back(flight, &state, &tau);
        let am = km * spin.cross(&v0);
        let mut res: Vec<f64> = (0..n).map(|k| (obs[k] - path[k]).norm()).collect();
        for k in 0..n {
            model_path[k] = path[k] - (p0 + v0 * tau[k] + 0.5 * am * tau[k] * tau[k]);
        }
        let mut sorted = res.clone();
        sorted.sort_by(|a, b| a.total_cmp(b));
        sigma = (sorted[n / 2] / 1.538).max(opts.sigma_floor);
        for k in 0..n {
            let r = res[k];
            weights[k] = if r > 6.0 * sigma {
                0.0
            } else if r > 3.0 * sigma {
                3.0 * sigma / r
            } else {
                1.0
            };
        }
        res.clear();
        if iter >= 2 && change < 1e-9 {
            break;
        }
    }
    let used = weights.iter().filter(|&&w| w > 0.0).count();
    if used < opts.min_observations.max(4) {
        return Err(EstimateError::TooFew {
            usable: used,
            total: t.len(),
            need: opts.min_observations.max(4),
        });
    }
    let spin = spin_from(&v0, &acc, km);
    let state = BallState {
        t: t0,
        p: p0,
        v: v0,
        w: spin,
    };
    if state.validate("state").is_err() {
        return Err(EstimateError::Degenerate("non-finite state".into()));
    }
    let s2 = sigma * sigma;
    let mut covariance = [[0.0; 6]; 6];
    for ax in 0..3 {
        covariance[ax][ax] = s2 * cov[(0, 0)];
        covariance[ax][ax + 3] = s2 * cov[(0, 1)];
        covariance[ax + 3][ax] = s2 * cov[(1, 0)];
        covariance[ax + 3][ax + 3] = s2 * cov[(1, 1)];
    }
    let spin_std = if with_spin {
        sigma * cov[(2, 2)].sqrt() / (km * v0.norm().max(1e-3))
    } else {
        0.0
    };
    Ok(Estimate {
        state,
        covariance,
        spin_std,
        spin_fitted: with_spin,
        sigma,
        used,
        outliers: n - used,
        nonfinite: 0,
        bounce_time: None,
        segment: Segment::Whole,
    })
}

/// Spin perpendicular to `v` (rad/s) that makes the Magnus acceleration `acc` (m/s²).
fn spin_from(v: &Vector3<f64>, acc: &Vector3<f64>, km: f64) -> Vector3<f64> {
    let v2 = v.norm_squared();
    if km > 0.0 && v2 > 1e-6 {
        v.cross(acc) / (km * v2)
    } else {
        Vector3::zeros()
    }
}

/// Positions at times t0 + τ_k (τ ≤ 0, increasing) by integrating `state` backward, no events.
fn integrate_back(flight: &Flight, state: &BallState, tau: &[f64]) -> Vec<Vector3<f64>> {
    let mut out = vec![Vector3::zeros(); tau.len()];
    let mut cur = *state;
    let t0 = state.t;
    for k in (0..tau.len()).rev() {
        let target = t0 + tau[k];
        while cur.t > target + 1e-15 {
            let h = flight.step.min(cur.t - target);
            cur = flight.rk4(&cur, -h);
        }
        out[k] = cur.p;
    }
    out
}
