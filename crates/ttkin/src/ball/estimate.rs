//! Ball state from noisy observed positions: robust to outliers and to a bounce in the window.
//!
//! Method. Observations with a non-finite value are dropped (counted). A bounce inside the window
//! is found as an interior minimum of the (median-of-three filtered) height near the surface; the
//! fit then uses the observations after it when they last long enough to fit the spin
//! (`spin_min_duration`, ≥ 8 observations), otherwise those before it, predicted through the bounce.
//!
//! On one flight arc the state θ = (p0, v0, ω) at the arc's last observation time t0 is fitted by
//! Gauss–Newton with iteratively reweighted least squares. Start: p0 + v0·τ + a·τ²/2
//! (τ = t_i − t0) fitted per axis with a constant acceleration, first gravity alone, then with the
//! drag at that velocity and robust weights. Each iteration integrates the flight model back over
//! the window together with its sensitivities ∂p(t_i)/∂(v0, ω) ([`super::sensitivity`]: RK4 steps
//! of at most `step`, cubic Hermite positions between them), so the Jacobian rows are
//! [I, ∂p/∂v0, ∂p/∂ω], and solves the 9 × 9 normal equations by Cholesky. The spin component along
//! the velocity makes no Magnus force: it is observable only through the arc's curvature, so a
//! ridge (prior σ = 40 rad/s per component) keeps it bounded. Weights are Huber's (c = 3σ on the
//! 3-D residual, σ from the median residual: for Gaussian noise σ_axis = median|r| / 1.538, the
//! median of a χ₃) and residuals beyond 6σ get weight 0 (outliers). It stops when a step moves the
//! state by < 2 % of its standard deviation (δᵀNδ/σ² < 0.02²), after 3 to 5 iterations on the
//! bench's windows; the Jacobian is integrated on the first and then kept (chord method). Covariance: σ²·(JᵀWJ + ridge)⁻¹.

use super::flight::{BallState, Flight};
use super::sensitivity::{Knot, Sens, WindowPath};
use nalgebra::{SMatrix, SVector, Vector3};
use std::ops::AddAssign;

/// Options of [`estimate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EstimateOptions {
    /// Flight model used for the fit.
    pub flight: Flight,
    /// Fewest usable observations on the fitted arc (≥ 4; 5 by default).
    pub min_observations: usize,
    /// Fit the spin (perpendicular to v) when the arc lasts at least this long (s); 0.06 by default.
    pub spin_min_duration: f64,
    /// Gauss–Newton iterations at most (8 by default; at least 2 are made).
    pub iterations: usize,
    /// Longest integration step of the fit (s): 20 ms by default (RK4; the model error over a
    /// 0.2 s window is below 1e-7 m, and the fit within 1 % of its standard deviation of a 1 ms
    /// one, tested).
    pub step: f64,
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
            step: 0.02,
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

impl Segment {
    /// The segment's name: "whole", "after_bounce" or "before_bounce".
    pub fn name(&self) -> &'static str {
        match self {
            Segment::Whole => "whole",
            Segment::AfterBounce => "after_bounce",
            Segment::BeforeBounce => "before_bounce",
        }
    }
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
    /// Covariance of [p; v; ω] (m, m/s, rad/s; 9 × 9) at the same time as `covariance`, the
    /// spin's prior included; its spin rows and columns are zero when the spin is not fitted.
    pub full_covariance: [[f64; 9]; 9],
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
    /// An option lies outside its range.
    #[error("{what}: {message}")]
    Option {
        /// The option's name.
        what: &'static str,
        /// What is wrong with it.
        message: String,
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
            EstimateError::Option { what, message } => crate::Error::invalid(what, message),
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
    if !(opts.step > 0.0 && opts.step <= 0.05) {
        return Err(EstimateError::Option {
            what: "step",
            message: format!("must lie in (0, 0.05] s, got {}", opts.step),
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
    if let (Some(&a), Some(&b)) = (idx.first(), idx.last()) {
        // The fit integrates the window in steps of at most `step`, a node and its sensitivities
        // each: bounded before allocating, and the clock must carry the step at both ends.
        let node =
            std::mem::size_of::<super::sensitivity::Node>() + 2 * std::mem::size_of::<super::sensitivity::Sens>();
        let limit = |e: crate::Error| EstimateError::Option {
            what: "t",
            message: match e {
                crate::Error::InvalidArgument { reason, .. } => reason,
                other => other.to_string(),
            },
        };
        crate::budget::check_bytes("t", (t[b] - t[a]) / opts.step + 2.0, node).map_err(limit)?;
        for i in [a, b] {
            crate::budget::check_clock("t", t[i], opts.step).map_err(limit)?;
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
pub(super) const SPIN_PRIOR: f64 = 40.0;

/// Median of `res` / 1.538 (σ per axis of a 3-D Gaussian residual), at least `floor`; reorders `res`.
pub(super) fn robust_sigma(res: &mut [f64], floor: f64) -> f64 {
    let n = res.len();
    let (_, median, _) = res.select_nth_unstable_by(n / 2, |a, b| a.total_cmp(b));
    (*median / 1.538).max(floor)
}

/// Huber weight of a residual `r` (m) at scale `sigma`: 1 within 3σ, 3σ/r to 6σ, 0 beyond.
pub(super) fn huber(r: f64, sigma: f64) -> f64 {
    if r > 6.0 * sigma {
        0.0
    } else if r > 3.0 * sigma {
        3.0 * sigma / r
    } else {
        1.0
    }
}

/// Start of the fit: p0 + v0·τ + a·τ²/2 with a free constant acceleration a, by least squares
/// per axis (one 3 × 3 system shared by the axes), twice: unit weights, then Huber weights from the
/// first residuals. With `spin`, ω ⊥ v follows from the part of a that gravity and drag at the
/// window's middle velocity v_m do not explain: k_m·ω × v_m = a − g + k_d·|v_m|·v_m, so
/// ω = v_m × (a − g + k_d·|v_m|·v_m) / (k_m·|v_m|²). Returns (p0, v0, ω), or None when the times
/// do not determine a parabola.
fn initial_guess(
    rows: &mut [Row],
    m: &super::model::BallModel,
    spin: bool,
    floor: f64,
    scratch: &mut [f64],
) -> Option<(Vector3<f64>, Vector3<f64>, Vector3<f64>)> {
    let mut x = SMatrix::<f64, 3, 3>::zeros(); // columns p0, v0, a
    for round in 0..2 {
        let mut ata = SMatrix::<f64, 3, 3>::zeros();
        let mut aty = SMatrix::<f64, 3, 3>::zeros(); // rows p0, v0, a; columns the axes
        for row in rows.iter() {
            let (wk, tk) = (row.w, row.tau);
            let basis = Vector3::new(1.0, tk, 0.5 * tk * tk);
            ata += basis * basis.transpose() * wk;
            aty += basis * row.y.transpose() * wk;
        }
        x = ata.cholesky()?.solve(&aty).transpose();
        if round == 0 {
            for (row, res) in rows.iter_mut().zip(scratch.iter_mut()) {
                let tk = row.tau;
                row.res = (row.y - x * Vector3::new(1.0, tk, 0.5 * tk * tk)).norm();
                *res = row.res;
            }
            let sigma = robust_sigma(scratch, floor);
            for row in rows.iter_mut() {
                row.w = huber(row.res, sigma);
            }
        }
    }
    let (p0, v0, a) = (
        x.column(0).into_owned(),
        x.column(1).into_owned(),
        x.column(2).into_owned(),
    );
    let mut w = Vector3::zeros();
    if spin {
        let vm = v0 - a * (0.5 * rows[0].tau.abs());
        let speed2 = vm.norm_squared();
        if speed2 > 0.0 {
            let lift = a - Vector3::new(0.0, 0.0, -m.gravity) + vm * (m.k_drag * speed2.sqrt());
            w = vm.cross(&lift) / (m.k_magnus * speed2);
        }
    }
    let finite = p0.iter().chain(v0.iter()).chain(w.iter()).all(|c| c.is_finite());
    finite.then_some((p0, v0, w))
}

/// Iterations that integrate the sensitivities (the later ones keep the last Jacobian).
const JACOBIAN_ITERATIONS: usize = 1;

/// Convergence: a step shorter than this many standard deviations of the estimate.
const CONVERGED: f64 = 0.02;

/// Adds w·J_kᵀJ_k for J_k = [I, S_k] (S_k = ∂p/∂(v0, ω), 3 × 6) to the upper triangle of `n`.
fn add_row(n: &mut SMatrix<f64, 9, 9>, s: &Sens, wk: f64) {
    for i in 0..3 {
        n[(i, i)] += wk;
        for a in 0..6 {
            n[(i, 3 + a)] += wk * s[(i, a)];
        }
    }
    for a in 0..6 {
        let ws = [s[(0, a)] * wk, s[(1, a)] * wk, s[(2, a)] * wk];
        for b in a..6 {
            n[(3 + a, 3 + b)] += ws[0] * s[(0, b)] + ws[1] * s[(1, b)] + ws[2] * s[(2, b)];
        }
    }
}

/// Σ w_k·J_kᵀr_k over the rows.
fn gradient(rows: &[Row]) -> SVector<f64, 9> {
    let mut g = SVector::<f64, 9>::zeros();
    for row in rows.iter().filter(|row| row.w > 0.0) {
        let wr = row.r * row.w;
        g.fixed_rows_mut::<3>(0).add_assign(&wr);
        g.fixed_rows_mut::<6>(3).add_assign(&(row.s.tr_mul(&wr)));
    }
    g
}

/// The symmetric matrix whose upper triangle is that of `upper`.
fn symmetric(upper: &SMatrix<f64, 9, 9>) -> SMatrix<f64, 9, 9> {
    let mut n = *upper;
    for i in 0..9 {
        for j in i + 1..9 {
            n[(j, i)] = n[(i, j)];
        }
    }
    n
}

/// One observation of the fitted arc and its terms in the fit.
#[derive(Clone, Copy)]
struct Row {
    /// Observed position (m, world).
    y: Vector3<f64>,
    /// Time offset from the arc's last observation (s, ≤ 0).
    tau: f64,
    /// Its interval and interpolation weights on the window's path.
    knot: Knot,
    /// Residual y − p(τ) (m).
    r: Vector3<f64>,
    /// Its length (m).
    res: f64,
    /// Huber weight.
    w: f64,
    /// ∂p(τ)/∂(v0, ω) (kept between iterations: chord method).
    s: Sens,
}

fn fit_arc(t: &[f64], p: &[[f64; 3]], arc: &[usize], opts: &EstimateOptions) -> Result<Estimate, EstimateError> {
    let m = &opts.flight.model;
    let n = arc.len();
    let t0 = t[arc[n - 1]];
    let mut rows: Vec<Row> = arc
        .iter()
        .map(|&i| Row {
            y: Vector3::from(p[i]),
            tau: t[i] - t0,
            knot: Knot { j: 0, c: [0.0; 4] },
            r: Vector3::zeros(),
            res: 0.0,
            w: 1.0,
            s: Sens::zeros(),
        })
        .collect();
    let span = -rows[0].tau;
    let with_spin = m.k_magnus > 0.0 && span >= opts.spin_min_duration && n >= 8;
    let mut scratch = vec![0.0; n];
    let (mut p0, mut v0, mut w) = initial_guess(&mut rows, m, with_spin, opts.sigma_floor, &mut scratch)
        .ok_or_else(|| EstimateError::Degenerate("observation times do not span the fit".into()))?;
    let mut sigma = opts.sigma_floor;
    let mut path = WindowPath::integrate(m, &p0, &v0, &w, span, opts.step, with_spin, true);
    for row in rows.iter_mut() {
        row.knot = path.knot(row.tau);
    }
    // Upper triangle of Σ w_k·J_kᵀJ_k, updated by the weights' changes.
    let mut data = SMatrix::<f64, 9, 9>::zeros();
    let mut chol = None;
    for iter in 0..opts.iterations.max(2) {
        // Residuals at the current estimate; the Jacobian J_k = [I, ∂p/∂v0, ∂p/∂ω] on the first
        // JACOBIAN_ITERATIONS iterations, then kept (a chord method: it barely moves any more).
        let fresh = iter < JACOBIAN_ITERATIONS;
        if iter > 0 {
            path.integrate_into(m, &p0, &v0, &w, span, opts.step, with_spin, fresh);
        }
        for (row, x) in rows.iter_mut().zip(scratch.iter_mut()) {
            row.r = row.y - path.position_at(&row.knot);
            row.res = row.r.norm();
            *x = row.res;
            if fresh {
                row.s = path.sensitivity_at(&row.knot);
            }
        }
        sigma = robust_sigma(&mut scratch, opts.sigma_floor);
        if fresh {
            data = SMatrix::zeros();
        }
        for row in rows.iter_mut() {
            let wk = huber(row.res, sigma);
            if fresh {
                row.w = wk;
                if wk > 0.0 {
                    add_row(&mut data, &row.s, wk);
                }
            } else if wk != row.w {
                add_row(&mut data, &row.s, wk - row.w);
                row.w = wk;
            }
        }
        // N·δ = g with N = Σ w_k·J_kᵀJ_k + ridge and g = Σ w_k·J_kᵀr_k − ridge·ω.
        let mut rhs = gradient(&rows);
        let mut normal = symmetric(&data);
        let ridge = if with_spin { (sigma / SPIN_PRIOR).powi(2) } else { 1.0 };
        for c in 0..3 {
            normal[(6 + c, 6 + c)] += ridge;
            rhs[6 + c] -= ridge * w[c];
        }
        let c = normal
            .cholesky()
            .ok_or_else(|| EstimateError::Degenerate("observation times do not span the fit".into()))?;
        let d = c.solve(&rhs);
        chol = Some(c);
        p0 += Vector3::new(d[0], d[1], d[2]);
        v0 += Vector3::new(d[3], d[4], d[5]);
        if with_spin {
            w += Vector3::new(d[6], d[7], d[8]);
        }
        // The step in units of the estimate's standard deviation: δᵀNδ/σ² = δᵀg/σ².
        let moved = d.dot(&rhs).max(0.0).sqrt() / sigma;
        if iter >= 1 && moved < CONVERGED {
            break;
        }
    }
    let cov = chol.expect("at least one iteration").inverse();
    let used = rows.iter().filter(|row| row.w > 0.0).count();
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
    let mut full_covariance = [[0.0; 9]; 9];
    let fitted = if with_spin { 9 } else { 6 };
    for (r, row) in full_covariance.iter_mut().enumerate().take(fitted) {
        for (c, x) in row.iter_mut().enumerate().take(fitted) {
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
        full_covariance,
        spin_fitted: with_spin,
        sigma,
        used,
        outliers: n - used,
        nonfinite: 0,
        bounce_time: None,
        segment: Segment::Whole,
    })
}
