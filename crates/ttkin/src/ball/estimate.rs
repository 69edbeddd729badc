//! Ball state from noisy observed positions: robust to outliers and to a bounce in the window.
//!
//! Method. Observations with a non-finite value are dropped (counted). A bounce inside the window
//! is found as an interior minimum of the (median-of-three filtered) height near the surface; the
//! fit then uses the observations after it when they last long enough to fit the spin
//! (`spin_min_duration`, ≥ 8 observations), otherwise those before it, predicted through the bounce.
//!
//! On one flight arc the state at the arc's last observation time t0 is fitted by a fixed-point
//! iteration on the flight model: with the current estimate integrated to every observation time,
//! x(t_i), the part not explained by the linear model p0 + v0·τ + k_m·ω × V2(τ) (τ = t_i − t0,
//! V2 the double integral of the velocity, v0·τ²/2 + a·τ³/6) is subtracted from the observations and
//! (p0, v0, ω) re-solved by weighted linear least squares (9 × 9 normal equations). The spin
//! component along the velocity makes no Magnus force: it is observable only through the arc's
//! curvature, so a ridge (prior σ = 200 rad/s per component) keeps it bounded. Weights are Huber's
//! (c = 3σ on the 3-D residual, σ from the median residual: for Gaussian noise σ_axis = median|r| /
//! 1.538, the median of a χ₃) and residuals beyond 6σ get weight 0 (outliers). The contraction
//! factor of the iteration is about k_d·|v|·T (≈ 0.15 for a 0.2 s window), so it converges in a
//! few iterations (it stops when an iteration moves the state by < 10 µm). Covariance: σ²·(BᵀWB + ridge)⁻¹.

use super::flight::{BallState, Flight};
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

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

/// Prior standard deviation (rad/s) of each spin component: a ridge that keeps the component
/// along the velocity (no Magnus force, unobservable on a straight arc) near zero.
const SPIN_PRIOR: f64 = 40.0;

/// Double integral of the velocity from t0 over τ (τ ≤ 0), to second order: v0·τ²/2 + a·τ³/6.
fn v2(v0: &Vector3<f64>, a: &Vector3<f64>, tau: f64) -> Vector3<f64> {
    v0 * (0.5 * tau * tau) + a * (tau * tau * tau / 6.0)
}

fn fit_arc(t: &[f64], p: &[[f64; 3]], arc: &[usize], opts: &EstimateOptions) -> Result<Estimate, EstimateError> {
    let flight = &opts.flight;
    let m = &flight.model;
    let km = m.k_magnus;
    let n = arc.len();
    let t0 = t[arc[n - 1]];
    let tau: Vec<f64> = arc.iter().map(|&i| t[i] - t0).collect();
    let obs: Vec<Vector3<f64>> = arc.iter().map(|&i| Vector3::from(p[i])).collect();
    let with_spin = km > 0.0 && -tau[0] >= opts.spin_min_duration && n >= 8;
    let mut weights = vec![1.0; n];
    // x(t_i) − (p0 + v0·τ + k_m·ω × V2(τ)) of the current estimate; gravity only to start.
    let mut model_path: Vec<Vector3<f64>> = tau
        .iter()
        .map(|&tk| Vector3::new(0.0, 0.0, -0.5 * m.gravity * tk * tk))
        .collect();
    let (mut p0, mut v0, mut w) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
    let mut sigma = opts.sigma_floor;
    let mut cov = SMatrix::<f64, 9, 9>::zeros();
    for iter in 0..opts.iterations.max(2) {
        // Weighted linear least squares in (p0, v0, ω): rows [I, τ·I, −k_m·[V2(τ)]×].
        let acc = Vector3::new(0.0, 0.0, -m.gravity) - m.k_drag * v0.norm() * v0;
        // BᵀWB and BᵀWy from sums, B_k = [I, τ·I, C_k] with C_k = −k_m·[V2(τ_k)]×.
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        let (mut sc, mut stc, mut sctc) = (Matrix3::zeros(), Matrix3::zeros(), Matrix3::zeros());
        let (mut y0, mut y1, mut yc) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros());
        for k in 0..n {
            let (wk, tk) = (weights[k], tau[k]);
            let y = obs[k] - model_path[k];
            s0 += wk;
            s1 += wk * tk;
            s2 += wk * tk * tk;
            y0 += wk * y;
            y1 += (wk * tk) * y;
            if with_spin {
                let c = -km * v2(&v0, &acc, tk).cross_matrix();
                sc += wk * c;
                stc += (wk * tk) * c;
                sctc += wk * c.transpose() * c;
                yc += wk * c.transpose() * y;
            }
        }
        let eye = Matrix3::identity();
        let mut ata = SMatrix::<f64, 9, 9>::zeros();
        ata.fixed_view_mut::<3, 3>(0, 0).copy_from(&(eye * s0));
        ata.fixed_view_mut::<3, 3>(0, 3).copy_from(&(eye * s1));
        ata.fixed_view_mut::<3, 3>(3, 0).copy_from(&(eye * s1));
        ata.fixed_view_mut::<3, 3>(3, 3).copy_from(&(eye * s2));
        ata.fixed_view_mut::<3, 3>(0, 6).copy_from(&sc);
        ata.fixed_view_mut::<3, 3>(6, 0).copy_from(&sc.transpose());
        ata.fixed_view_mut::<3, 3>(3, 6).copy_from(&stc);
        ata.fixed_view_mut::<3, 3>(6, 3).copy_from(&stc.transpose());
        ata.fixed_view_mut::<3, 3>(6, 6).copy_from(&sctc);
        let mut atb = SVector::<f64, 9>::zeros();
        atb.fixed_rows_mut::<3>(0).copy_from(&y0);
        atb.fixed_rows_mut::<3>(3).copy_from(&y1);
        atb.fixed_rows_mut::<3>(6).copy_from(&yc);
        let ridge = if with_spin { (sigma / SPIN_PRIOR).powi(2) } else { 1.0 };
        for r in 6..9 {
            ata[(r, r)] += ridge;
        }
        let inv = ata
            .try_inverse()
            .ok_or_else(|| EstimateError::Degenerate("observation times do not span the fit".into()))?;
        let x = inv * atb;
        let (np0, nv0) = (Vector3::new(x[0], x[1], x[2]), Vector3::new(x[3], x[4], x[5]));
        let nw = if with_spin {
            Vector3::new(x[6], x[7], x[8])
        } else {
            Vector3::zeros()
        };
        let change = (np0 - p0).norm() + 0.05 * (nv0 - v0).norm() + 1e-4 * (nw - w).norm();
        (p0, v0, w) = (np0, nv0, nw);
        cov = inv;
        // Residuals against the flight model and robust weights.
        let state = BallState { t: t0, p: p0, v: v0, w };
        let path = integrate_back(flight, &state, &tau);
        let acc = Vector3::new(0.0, 0.0, -m.gravity) - m.k_drag * v0.norm() * v0;
        let res: Vec<f64> = (0..n).map(|k| (obs[k] - path[k]).norm()).collect();
        for k in 0..n {
            model_path[k] = path[k] - (p0 + v0 * tau[k] + km * w.cross(&v2(&v0, &acc, tau[k])));
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
        if iter >= 2 && change < 1e-5 {
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
    let state = BallState { t: t0, p: p0, v: v0, w };
    if state.validate("state").is_err() {
        return Err(EstimateError::Degenerate("non-finite state".into()));
    }
    let s2 = sigma * sigma;
    let mut covariance = [[0.0; 6]; 6];
    for (r, row) in covariance.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = s2 * cov[(r, c)];
        }
    }
    let spin_std = if with_spin {
        sigma * ((cov[(6, 6)] + cov[(7, 7)] + cov[(8, 8)]) / 3.0).sqrt()
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
