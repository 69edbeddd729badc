//! Calibration of the ball model on recorded flights: drag, Magnus, table restitution and
//! friction, with the table height and the camera's frame period, by Levenberg–Marquardt over
//! every flight at once; and the prediction error of a model on flights it was not fitted on.
//!
//! **Data.** A [`Recording`] is one flight: ball-centre positions (m) at equally spaced camera
//! frames in the recording's own frame (z up, gravity along −z; no time stamps), optionally the
//! tracker's velocities (m/s; used only to estimate the frame period and to start the fit).
//!
//! **Segment.** Each flight is used from its first frame through its first table bounce (the first
//! local height minimum within [`FitOptions::bounce_band`] of the median first minimum over all
//! flights) up to the frame before the ball comes down to within `bounce_band` of that height
//! again (a second bounce, or the ball leaving the table's end and falling past its surface): one
//! bounce per segment, on an unbounded plane z = surface. Flights without such a bounce are left
//! out and counted.
//!
//! **Model.** Flight as in [`super::flight`] (a = g − k_d·|v|·v + k_m·ω × v, RK4 at ≤ 2 ms steps,
//! spin constant in flight), the bounce where the centre reaches surface + r (located by
//! bisection) by [`super::contact::impulse`] (restitution e, Coulomb friction μ with the rolling
//! cap), or, for published models of that form, [`Bounce::Linear`]. Parameters: the globals
//! θ = (k_d, k_m, e, μ, surface, period) and per flight the nuisance x_i = (p0, v0, ω) at its
//! first frame. Residuals: the simulated minus the observed position at every frame of the
//! segment (m), and a weak prior on the spin, ω/σ_ω·s (σ_ω = [`FitOptions::spin_prior`], s = 5
//! mm): spin along the velocity makes no Magnus force and shows only through the bounce.
//!
//! **Solver.** Levenberg–Marquardt (Marquardt's diagonal scaling) on the block-arrow normal
//! matrix: per flight U_i = A_iᵀA_i (9 × 9), W_i = A_iᵀB_i, and V = Σ B_iᵀB_i for the globals;
//! the globals' step from the Schur complement S = V − Σ W_iᵀU_i⁻¹W_i, then each flight's step.
//! Jacobians by forward differences. Robust: three rounds, the first unweighted, then Huber
//! weights per frame (threshold 3 × the median residual distance) from the previous round's
//! residuals. The
//! globals' covariance is σ²·S⁻¹ (undamped, the nuisance marginalised), σ² = Σ w·r² / (N − P).
//!
//! **Prediction error** ([`prediction_error`]): a flight's state is fitted on its first `k`
//! frames (the model's constants fixed, the same spin prior), then the flight is predicted from
//! there through the bounce; the error is the distance between predicted and observed positions
//! at the later frames of the segment: RMS over those after the bounce, and over all of them.

use super::contact::impulse;
use super::flight::{BallState, Flight};
use super::model::BallModel;
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, SMatrix, SVector, Vector3};
use rayon::prelude::*;

/// One recorded flight: positions (m) at equally spaced frames and, optionally, the tracker's
/// velocities (m/s) at the same frames (empty when not recorded); recording frame, z up.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Name (e.g. the file), for reports.
    pub name: String,
    /// Ball-centre positions (m), one per frame.
    pub positions: Vec<[f64; 3]>,
    /// The tracker's velocity estimates (m/s), one per frame, or empty.
    pub velocities: Vec<[f64; 3]>,
}

/// How the ball leaves the table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bounce {
    /// The impulse model of [`super::contact::impulse`] with the model's table restitution and friction.
    Impulse,
    /// A linear map of the velocity, v' = (c_x·v_x, c_y·v_y, −c_z·v_z), spin unchanged (the form of
    /// the MPI table-tennis code's table contact, no spin).
    Linear([f64; 3]),
}

/// A ball model as the fit sees it: flight and bounce constants, the table surface height (m,
/// recording frame) and the frame period (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitModel {
    /// Flight constants (k_d, k_m) and, for [`Bounce::Impulse`], restitution and friction.
    pub model: BallModel,
    /// The bounce law.
    pub bounce: Bounce,
    /// Height (m) of the table surface in the recording frame.
    pub surface: f64,
    /// Camera frame period (s).
    pub period: f64,
}

/// Fit settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Largest RK4 step (s).
    pub step: f64,
    /// Prior standard deviation of each spin component (rad/s).
    pub spin_prior: f64,
    /// Height band (m) around the median first minimum that counts as a table bounce.
    pub bounce_band: f64,
    /// Levenberg–Marquardt iterations per round.
    pub iterations: usize,
    /// Which globals are fitted: k_d, k_m, e, μ, surface, period.
    pub free: [bool; 6],
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            step: 0.002,
            spin_prior: 300.0,
            bounce_band: 0.05,
            iterations: 30,
            free: [true; 6],
        }
    }
}

/// Names of the globals, in the order of [`Calibration::globals`].
pub const GLOBAL_NAMES: [&str; 6] = [
    "k_drag",
    "k_magnus",
    "table_restitution",
    "table_friction",
    "surface",
    "period",
];

/// One flight's fitted state and residual.
#[derive(Debug, Clone, PartialEq)]
pub struct FlightFit {
    /// Index of the recording.
    pub index: usize,
    /// State at the first frame (t = 0; position m, velocity m/s, spin rad/s).
    pub state: BallState,
    /// Frames used (the segment).
    pub frames: usize,
    /// Frame of the bounce (the observed minimum).
    pub bounce_frame: usize,
    /// RMS position residual (m) over the segment.
    pub rms: f64,
    /// The friction coefficient above which its first bounce ends rolling (the rolling cap's
    /// impulse over the normal impulse: |u|/κ / ((1+e)·|v_n|)); NaN without a bounce.
    pub friction_to_roll: f64,
}

/// The result of [`calibrate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The fitted model (impulse bounce).
    pub fit: FitModel,
    /// The globals (k_d, k_m, e, μ, surface, period), as in [`GLOBAL_NAMES`].
    pub globals: [f64; 6],
    /// Their standard deviations (NaN where not fitted or not identified).
    pub std: [f64; 6],
    /// Their correlation matrix (row-major 6 × 6; NaN where not fitted).
    pub correlation: [[f64; 6]; 6],
    /// Residual standard deviation σ (m) of the final round.
    pub sigma: f64,
    /// RMS position residual (m) over every fitted frame.
    pub rms: f64,
    /// Per-flight results.
    pub flights: Vec<FlightFit>,
    /// Levenberg–Marquardt iterations, all rounds.
    pub iterations: usize,
    /// Frames in the fit.
    pub observations: usize,
    /// The fitted spins' mean and standard deviation in each flight's axes at its first frame
    /// ([`SpinPrior`]): the population prior for a new flight of the same source.
    pub spin: SpinPrior,
}

/// The frame period (s) from positions and tracker velocities: the median over frames of
/// Δp·v̄ / |v̄|² (v̄ the mean of the two frames' velocities), frames near a bounce excluded (the
/// vertical velocity changes sign there). Needs velocities.
pub fn estimate_period(recordings: &[Recording]) -> Result<f64> {
    let mut ratios = Vec::new();
    for r in recordings {
        if r.velocities.len() != r.positions.len() {
            continue;
        }
        for k in 1..r.positions.len() {
            let (v0, v1) = (Vector3::from(r.velocities[k - 1]), Vector3::from(r.velocities[k]));
            if v0.z * v1.z < 0.0 && v0.z < 0.0 {
                continue;
            }
            let vb = 0.5 * (v0 + v1);
            let dp = Vector3::from(r.positions[k]) - Vector3::from(r.positions[k - 1]);
            let q = dp.dot(&vb) / vb.norm_squared();
            if q.is_finite() {
                ratios.push(q);
            }
        }
    }
    if ratios.is_empty() {
        return Err(Error::invalid(
            "recordings",
            "no frames with velocities: give the frame period instead",
        ));
    }
    Ok(median(&mut ratios))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The first bounce-like height minimum of a flight (frame index) within `band` of `level` (any
/// when `level` is NaN): the lowest frame of its ±3 neighbours, with the height falling by more
/// than 2 cm over the 3 frames before and rising by more than 2 cm over the 3 after (a bounce at
/// ≥ 1 m/s; the noise around an apex does neither).
fn first_minimum(z: &[f64], level: f64, band: f64) -> Option<usize> {
    (3..z.len().saturating_sub(3)).find(|&k| {
        let lowest = (k - 3..=k + 3).all(|j| z[j] >= z[k]);
        lowest && z[k - 3] - z[k] > 0.02 && z[k + 3] - z[k] > 0.02 && (level.is_nan() || (z[k] - level).abs() <= band)
    })
}

/// The height (m) of the bounces' lowest frames: the median over flights of the first local
/// minimum of the height (the ball gun shoots upward, so the first minimum is the bounce).
pub fn bounce_level(recordings: &[Recording]) -> Result<f64> {
    let mut lows: Vec<f64> = recordings
        .iter()
        .filter_map(|r| {
            let z: Vec<f64> = r.positions.iter().map(|p| p[2]).collect();
            first_minimum(&z, f64::NAN, 0.0).map(|k| z[k])
        })
        .collect();
    if lows.is_empty() {
        return Err(Error::invalid(
            "recordings",
            "no flight has a height minimum (a bounce)",
        ));
    }
    Ok(median(&mut lows))
}

/// The segment of a flight (see the module doc): (frames used, bounce frame), or `None` without a
/// bounce near `level`.
pub fn segment(r: &Recording, level: f64, band: f64) -> Option<(usize, usize)> {
    let z: Vec<f64> = r.positions.iter().map(|p| p[2]).collect();
    if z.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let b = first_minimum(&z, level, band)?;
    let mut end = z.len();
    for k in b + 2..z.len() {
        if z[k] < z[k - 1] && z[k] < level + band {
            end = k;
            break;
        }
    }
    (end > b + 3 && b >= 4).then_some((end, b))
}

impl FitModel {
    /// Positions (m) at frames `0..frames` (t = k·period) of the flight from `s0` (at t = 0),
    /// through bounces on the plane z = surface (at the centre height surface + r).
    pub fn path(&self, s0: &BallState, frames: usize, step: f64) -> Vec<Vector3<f64>> {
        self.path_with(s0, frames, step, &mut |_| {})
    }

    /// [`FitModel::path`], calling `on_bounce` with the state just before each bounce.
    pub fn path_with(
        &self,
        s0: &BallState,
        frames: usize,
        step: f64,
        on_bounce: &mut dyn FnMut(&BallState),
    ) -> Vec<Vector3<f64>> {
        let flight = Flight {
            model: self.model,
            ..Flight::default()
        };
        let zc = self.surface + self.model.radius;
        let mut cur = *s0;
        let mut out = Vec::with_capacity(frames);
        for k in 0..frames {
            let t = k as f64 * self.period;
            let mut guard = 0;
            while cur.t < t - 1e-12 && guard < 100_000 {
                guard += 1;
                let h = step.min(t - cur.t);
                let next = flight.rk4(&cur, h);
                if cur.p.z <= zc && cur.v.z == 0.0 && next.p.z < zc {
                    // Rolling on the plane (after a rebound below MIN_REBOUND_SPEED): the plane
                    // holds the ball up, no bounce to look for.
                    cur = next;
                    cur.p.z = zc;
                    cur.v.z = 0.0;
                } else if cur.p.z >= zc && next.p.z < zc {
                    // Bisection on the RK4 step from `cur` for the contact time.
                    let (mut lo, mut hi) = (0.0, h);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if flight.rk4(&cur, mid).p.z >= zc {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let b = flight.rk4(&cur, lo);
                    on_bounce(&b);
                    cur = self.bounce(&b);
                    if cur.v.z <= MIN_REBOUND_SPEED {
                        // No rebound (e = 0), or one below 0.1 mm: the ball stays on the plane's
                        // level. Without the floor a ball bouncing ever lower (e < 1) bounced
                        // without end in finite time, each bounce a bisection: a frame period far
                        // from the data's ran the fit for hours (issue 29).
                        cur.v.z = 0.0;
                        cur = flight.rk4(&cur, (h - lo).max(0.0));
                        if cur.p.z <= zc {
                            cur.p.z = zc;
                            cur.v.z = cur.v.z.max(0.0);
                        }
                    }
                } else {
                    cur = next;
                }
            }
            out.push(cur.p);
        }
        out
    }

    fn bounce(&self, b: &BallState) -> BallState {
        match self.bounce {
            Bounce::Impulse => {
                let m = &self.model;
                let (dv, dw) = impulse(m, &b.v, &b.w, &Vector3::z(), m.table_restitution, m.table_friction);
                BallState {
                    v: b.v + dv,
                    w: b.w + dw,
                    ..*b
                }
            }
            Bounce::Linear(c) => BallState {
                v: Vector3::new(c[0] * b.v.x, c[1] * b.v.y, -c[2] * b.v.z),
                ..*b
            },
        }
    }

    fn globals(&self) -> [f64; 6] {
        [
            self.model.k_drag,
            self.model.k_magnus,
            self.model.table_restitution,
            self.model.table_friction,
            self.surface,
            self.period,
        ]
    }

    fn with_globals(&self, g: &[f64; 6]) -> FitModel {
        FitModel {
            model: BallModel {
                k_drag: g[0].max(0.0),
                k_magnus: g[1].max(0.0),
                table_restitution: g[2].clamp(0.0, 1.0),
                table_friction: g[3].max(0.0),
                ..self.model
            },
            surface: g[4],
            period: g[5].max(1e-6),
            ..*self
        }
    }
}

const S_REF: f64 = 0.005;
type Vec9 = SVector<f64, 9>;
type Mat9 = SMatrix<f64, 9, 9>;
type Mat96 = SMatrix<f64, 9, 6>;
type Mat6 = SMatrix<f64, 6, 6>;
type Vec6 = SVector<f64, 6>;

fn state_of(x: &Vec9) -> BallState {
    BallState {
        t: 0.0,
        p: Vector3::new(x[0], x[1], x[2]),
        v: Vector3::new(x[3], x[4], x[5]),
        w: Vector3::new(x[6], x[7], x[8]),
    }
}

/// One flight's problem: observations, weights, nuisance.
struct Problem<'a> {
    obs: &'a [[f64; 3]],
    weights: Vec<f64>,
    x: Vec9,
    /// Prior of the spin: mean (rad/s, recording frame), the rotation into the axes where its
    /// components are independent, and their standard deviations (rad/s).
    spin_mean: Vector3<f64>,
    prior_axes: nalgebra::Matrix3<f64>,
    prior_std: Vector3<f64>,
}

impl Problem<'_> {
    /// Weighted residuals (3 per frame, then 3 spin-prior rows).
    fn residuals(&self, fm: &FitModel, x: &Vec9, opts: &FitOptions) -> DVector<f64> {
        let path = fm.path(&state_of(x), self.obs.len(), opts.step);
        let n = self.obs.len();
        let mut r = DVector::zeros(3 * n + 3);
        for k in 0..n {
            let sw = self.weights[k].sqrt();
            for a in 0..3 {
                r[3 * k + a] = sw * (path[k][a] - self.obs[k][a]);
            }
        }
        let dw = self.prior_axes * (Vector3::new(x[6], x[7], x[8]) - self.spin_mean);
        for a in 0..3 {
            r[3 * n + a] = dw[a] / self.prior_std[a] * S_REF;
        }
        r
    }

    fn cost(&self, fm: &FitModel, x: &Vec9, opts: &FitOptions) -> f64 {
        self.residuals(fm, x, opts).norm_squared()
    }

    /// Residuals and the Jacobians in the nuisance (A) and, with `globals`, the globals (B).
    fn linearise(&self, fm: &FitModel, opts: &FitOptions, globals: bool) -> (DVector<f64>, DMatrix<f64>, DMatrix<f64>) {
        let r0 = self.residuals(fm, &self.x, opts);
        let m = r0.len();
        let mut a = DMatrix::zeros(m, 9);
        const HX: [f64; 9] = [1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-3, 1e-3, 1e-3];
        for j in 0..9 {
            let mut x = self.x;
            x[j] += HX[j];
            let r = self.residuals(fm, &x, opts);
            a.set_column(j, &((r - &r0) / HX[j]));
        }
        let mut b = DMatrix::zeros(m, 6);
        if globals {
            const HG: [f64; 6] = [1e-6, 1e-7, 1e-6, 1e-6, 1e-7, 1e-9];
            let g0 = fm.globals();
            for j in 0..6 {
                if !opts.free[j] {
                    continue;
                }
                let mut g = g0;
                // Step inward at the bounds (e ≤ 1, the others ≥ 0).
                let h = if j == 2 && g[2] + HG[2] > 1.0 { -HG[j] } else { HG[j] };
                g[j] += h;
                let r = self.residuals(&fm.with_globals(&g), &self.x, opts);
                b.set_column(j, &((r - &r0) / h));
            }
        }
        (r0, a, b)
    }
}

/// Robust weights from residual norms per frame: Huber at `c` (m).
fn huber(res: &[f64], c: f64) -> Vec<f64> {
    res.iter().map(|&r| if r <= c { 1.0 } else { c / r }).collect()
}

/// Starting nuisance of a flight: the first position, the tracker's velocity there (or a finite
/// difference), no spin.
fn start(r: &Recording, period: f64) -> Vec9 {
    let p = r.positions[0];
    let v = if r.velocities.len() == r.positions.len() {
        r.velocities[0]
    } else {
        let q = r.positions[2];
        [
            (q[0] - p[0]) / (2.0 * period),
            (q[1] - p[1]) / (2.0 * period),
            (q[2] - p[2]) / (2.0 * period) + 9.81 * period,
        ]
    };
    Vec9::from_column_slice(&[p[0], p[1], p[2], v[0], v[1], v[2], 0.0, 0.0, 0.0])
}

/// Levenberg–Marquardt on the nuisance of one flight, the model fixed; returns the nuisance and
/// iterations.
fn fit_nuisance(fm: &FitModel, pb: &mut Problem, opts: &FitOptions) -> usize {
    let mut lambda = 1e-3;
    let mut cost = pb.cost(fm, &pb.x, opts);
    let mut it = 0;
    while it < opts.iterations {
        it += 1;
        let (r, a, _) = pb.linearise(fm, opts, false);
        let jt = a.transpose();
        let u = &jt * &a;
        let g = &jt * &r;
        let mut improved = false;
        for _ in 0..10 {
            let mut ud = u.clone();
            for j in 0..9 {
                ud[(j, j)] += lambda * u[(j, j)].max(1e-12);
            }
            let Some(ch) = ud.cholesky() else {
                lambda *= 10.0;
                continue;
            };
            let dx = -ch.solve(&g);
            let x = pb.x + Vec9::from_iterator(dx.iter().copied());
            let c = pb.cost(fm, &x, opts);
            if c < cost {
                let rel = (cost - c) / cost.max(1e-300);
                pb.x = x;
                cost = c;
                lambda = (lambda * 0.3).max(1e-9);
                improved = rel > 1e-10;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    it
}

/// Fits the globals (those `opts.free` says; the others as in `initial`) and every flight's
/// nuisance to `recordings` (see the module doc). `initial.bounce` must be [`Bounce::Impulse`].
pub fn calibrate(recordings: &[Recording], initial: &FitModel, opts: &FitOptions) -> Result<Calibration> {
    if initial.bounce != Bounce::Impulse {
        return Err(Error::invalid(
            "initial",
            "the calibration fits the impulse bounce; give Bounce::Impulse",
        ));
    }
    initial.model.validate()?;
    if !(initial.period > 0.0 && initial.period.is_finite() && initial.surface.is_finite()) {
        return Err(Error::invalid("initial", "period must be > 0 and surface finite"));
    }
    let level = bounce_level(recordings)?;
    let segs: Vec<(usize, (usize, usize))> = recordings
        .iter()
        .enumerate()
        .filter_map(|(i, r)| segment(r, level, opts.bounce_band).map(|s| (i, s)))
        .collect();
    if segs.is_empty() {
        return Err(Error::invalid(
            "recordings",
            "no flight has a usable segment with a bounce",
        ));
    }
    let mut fm = *initial;
    let mut problems: Vec<Problem> = segs
        .iter()
        .map(|&(i, (end, _))| {
            let r = &recordings[i];
            Problem {
                obs: &r.positions[..end],
                weights: vec![1.0; end],
                x: start(r, fm.period),
                spin_mean: Vector3::zeros(),
                prior_axes: nalgebra::Matrix3::identity(),
                prior_std: Vector3::repeat(opts.spin_prior),
            }
        })
        .collect();
    problems.par_iter_mut().for_each(|pb| {
        fit_nuisance(&fm, pb, opts);
    });
    let free: Vec<usize> = (0..6).filter(|&j| opts.free[j]).collect();
    let nf = free.len();
    let mut iterations = 0;
    let mut sigma = f64::NAN;
    let mut s_final = DMatrix::<f64>::zeros(nf, nf);
    for round in 0..3 {
        if round > 0 {
            // Huber weights from the current residuals.
            let norms: Vec<Vec<f64>> = problems
                .par_iter()
                .map(|pb| {
                    let path = fm.path(&state_of(&pb.x), pb.obs.len(), opts.step);
                    path.iter()
                        .zip(pb.obs)
                        .map(|(p, o)| (p - Vector3::from(*o)).norm())
                        .collect()
                })
                .collect();
            let mut all: Vec<f64> = norms.iter().flatten().copied().collect();
            let c = 3.0 * median(&mut all);
            for (pb, n) in problems.iter_mut().zip(&norms) {
                pb.weights = huber(n, c);
            }
        }
        let mut lambda = 1e-3;
        let total =
            |fm: &FitModel, probs: &[Problem]| -> f64 { probs.par_iter().map(|pb| pb.cost(fm, &pb.x, opts)).sum() };
        let mut cost = total(&fm, &problems);
        for _ in 0..opts.iterations {
            iterations += 1;
            // Per flight: r, A, B → U, W, g_x; the globals' V and g.
            let blocks: Vec<(Mat9, Mat96, Vec9, Mat6, Vec6)> = problems
                .par_iter()
                .map(|pb| {
                    let (r, a, b) = pb.linearise(&fm, opts, true);
                    let at = a.transpose();
                    let bt = b.transpose();
                    let u = Mat9::from_iterator((&at * &a).iter().copied());
                    let w = Mat96::from_iterator((&at * &b).iter().copied());
                    let gx = Vec9::from_iterator((&at * &r).iter().copied());
                    let v = Mat6::from_iterator((&bt * &b).iter().copied());
                    let gg = Vec6::from_iterator((&bt * &r).iter().copied());
                    (u, w, gx, v, gg)
                })
                .collect();
            let schur = |lam: f64| -> Option<(DMatrix<f64>, DVector<f64>, Vec<Mat9>)> {
                let mut v = Mat6::zeros();
                let mut gg = Vec6::zeros();
                for bl in &blocks {
                    v += bl.3;
                    gg += bl.4;
                }
                let mut s = DMatrix::zeros(nf, nf);
                let mut rhs = DVector::zeros(nf);
                for (a, &ja) in free.iter().enumerate() {
                    rhs[a] = gg[ja];
                    for (b, &jb) in free.iter().enumerate() {
                        s[(a, b)] = v[(ja, jb)];
                    }
                    s[(a, a)] += lam * v[(ja, ja)].max(1e-30);
                }
                let mut inv = Vec::with_capacity(blocks.len());
                for (u, w, gx, _, _) in &blocks {
                    let mut ud = *u;
                    for j in 0..9 {
                        ud[(j, j)] += lam * u[(j, j)].max(1e-12);
                    }
                    let ui = ud.try_inverse()?;
                    let wt_ui = w.transpose() * ui;
                    let m = wt_ui * w;
                    let q = wt_ui * gx;
                    for (a, &ja) in free.iter().enumerate() {
                        rhs[a] -= q[ja];
                        for (b, &jb) in free.iter().enumerate() {
                            s[(a, b)] -= m[(ja, jb)];
                        }
                    }
                    inv.push(ui);
                }
                Some((s, rhs, inv))
            };
            let mut improved = false;
            for _ in 0..12 {
                let Some((s, rhs, inv)) = schur(lambda) else {
                    lambda *= 10.0;
                    continue;
                };
                let Some(ch) = s.clone().cholesky() else {
                    lambda *= 10.0;
                    continue;
                };
                let dg = -ch.solve(&rhs);
                let mut g = fm.globals();
                let mut dgf = Vec6::zeros();
                for (a, &ja) in free.iter().enumerate() {
                    g[ja] += dg[a];
                    dgf[ja] = dg[a];
                }
                let trial = fm.with_globals(&g);
                let xs: Vec<Vec9> = blocks
                    .iter()
                    .zip(&inv)
                    .zip(&problems)
                    .map(|(((_, w, gx, _, _), ui), pb)| pb.x - ui * (gx + w * dgf))
                    .collect();
                let c: f64 = problems
                    .par_iter()
                    .zip(&xs)
                    .map(|(pb, x)| pb.cost(&trial, x, opts))
                    .sum();
                if c < cost {
                    let rel = (cost - c) / cost.max(1e-300);
                    fm = trial;
                    for (pb, x) in problems.iter_mut().zip(xs) {
                        pb.x = x;
                    }
                    cost = c;
                    lambda = (lambda * 0.3).max(1e-9);
                    improved = rel > 1e-9;
                    break;
                }
                lambda *= 10.0;
            }
            if !improved {
                break;
            }
        }
        // The undamped Schur complement at the solution, for the covariance.
        if let Some(s) = schur_at(&fm, &problems, opts, &free) {
            s_final = s;
        }
        let n_res: usize = problems.iter().map(|pb| 3 * pb.obs.len()).sum();
        let n_par = 9 * problems.len() + nf;
        sigma = (cost / (n_res.saturating_sub(n_par)).max(1) as f64).sqrt();
    }
    // Parameters whose column vanishes (μ when every bounce rolls) are not identified: the
    // covariance of the others, theirs NaN.
    let scale = (0..nf).map(|a| s_final[(a, a)]).fold(0.0, f64::max);
    let ident: Vec<usize> = (0..nf).filter(|&a| s_final[(a, a)] > 1e-12 * scale).collect();
    let sub = DMatrix::from_fn(ident.len(), ident.len(), |a, b| s_final[(ident[a], ident[b])]);
    let mut std = [f64::NAN; 6];
    let mut correlation = [[f64::NAN; 6]; 6];
    if let Some(ch) = sub.cholesky() {
        let cov = ch.inverse() * (sigma * sigma);
        for (a, &ia) in ident.iter().enumerate() {
            std[free[ia]] = cov[(a, a)].sqrt();
        }
        for (a, &ia) in ident.iter().enumerate() {
            for (b, &ib) in ident.iter().enumerate() {
                correlation[free[ia]][free[ib]] = cov[(a, b)] / (std[free[ia]] * std[free[ib]]);
            }
        }
    }
    let flights: Vec<FlightFit> = problems
        .par_iter()
        .zip(&segs)
        .map(|(pb, &(i, (end, b)))| {
            let mut roll = f64::NAN;
            let m = fm.model;
            let path = fm.path_with(&state_of(&pb.x), end, opts.step, &mut |b| {
                if roll.is_nan() {
                    let kappa = 1.0 + m.mass * m.radius * m.radius / m.inertia();
                    let slip = Vector3::new(b.v.x, b.v.y, 0.0) + b.w.cross(&(-m.radius * Vector3::z()));
                    roll = slip.norm() / kappa / ((1.0 + m.table_restitution) * b.v.z.abs());
                }
            });
            let ss: f64 = path
                .iter()
                .zip(pb.obs)
                .map(|(p, o)| (p - Vector3::from(*o)).norm_squared())
                .sum();
            FlightFit {
                index: i,
                state: state_of(&pb.x),
                frames: end,
                bounce_frame: b,
                rms: (ss / end as f64).sqrt(),
                friction_to_roll: roll,
            }
        })
        .collect();
    let observations: usize = flights.iter().map(|f| f.frames).sum();
    let rms = (flights.iter().map(|f| f.rms * f.rms * f.frames as f64).sum::<f64>() / observations as f64).sqrt();
    let local: Vec<Vector3<f64>> = flights
        .iter()
        .map(|f| flight_axes(&f.state.v).transpose() * f.state.w)
        .collect();
    let nfl = local.len() as f64;
    let mean = local.iter().sum::<Vector3<f64>>() / nfl;
    let var = local
        .iter()
        .map(|w| (w - mean).component_mul(&(w - mean)))
        .sum::<Vector3<f64>>()
        / (nfl - 1.0).max(1.0);
    Ok(Calibration {
        spin: SpinPrior {
            mean: mean.into(),
            std: var.map(|v| v.sqrt().max(1.0)).into(),
        },
        fit: fm,
        globals: fm.globals(),
        std,
        correlation,
        sigma,
        rms,
        flights,
        iterations,
        observations,
    })
}

/// The undamped Schur complement of the globals at the current solution.
fn schur_at(fm: &FitModel, problems: &[Problem], opts: &FitOptions, free: &[usize]) -> Option<DMatrix<f64>> {
    let nf = free.len();
    let parts: Vec<Option<DMatrix<f64>>> = problems
        .par_iter()
        .map(|pb| {
            let (_, a, b) = pb.linearise(fm, opts, true);
            let at = a.transpose();
            let u = &at * &a;
            let w = &at * &b;
            let v = b.transpose() * &b;
            let ui = u.try_inverse()?;
            Some(v - w.transpose() * ui * w)
        })
        .collect();
    let mut s = DMatrix::zeros(nf, nf);
    for p in parts {
        let p = p?;
        for (a, &ja) in free.iter().enumerate() {
            for (b, &jb) in free.iter().enumerate() {
                s[(a, b)] += p[(ja, jb)];
            }
        }
    }
    Some(s)
}

/// The flight axes of a velocity `v`: along its horizontal part, horizontal across it (z × that),
/// and z; as the columns of a rotation.
fn flight_axes(v: &Vector3<f64>) -> nalgebra::Matrix3<f64> {
    let h = Vector3::new(v.x, v.y, 0.0);
    let e1 = if h.norm() > 1e-9 { h.normalize() } else { Vector3::x() };
    let e2 = Vector3::z().cross(&e1);
    nalgebra::Matrix3::from_columns(&[e1, e2, Vector3::z()])
}

/// The spin prior of a flight's state fitted from its first frames, in the flight axes of its
/// first velocity (along the horizontal velocity, horizontal across it, vertical): mean and
/// standard deviation per axis (rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpinPrior {
    /// Mean (rad/s, flight axes).
    pub mean: [f64; 3],
    /// Standard deviation (rad/s, flight axes).
    pub std: [f64; 3],
}

/// Prediction error of one flight under a fixed model.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictionError {
    /// Frames the state was fitted on.
    pub window: usize,
    /// Frames predicted (the rest of the segment).
    pub predicted: usize,
    /// RMS distance (m) between predicted and observed positions over the predicted frames
    /// after the bounce frame.
    pub rms_after_bounce: f64,
    /// RMS distance (m) over every predicted frame.
    pub rms: f64,
    /// Largest distance (m) over the predicted frames.
    pub max: f64,
    /// The predicted positions (m) at every frame of the segment (the window's included).
    pub path: Vec<[f64; 3]>,
}

/// The prediction error of `fm` on `recording` (see the module doc): its state fitted on the
/// first `window` frames, then predicted over the rest of its segment (found with `level`, the
/// bounces' height of [`bounce_level`]). `None` without a segment, or when the window does not
/// end at least two frames before the bounce.
pub fn prediction_error(
    recording: &Recording,
    fm: &FitModel,
    window: usize,
    level: f64,
    prior: &SpinPrior,
    opts: &FitOptions,
) -> Option<PredictionError> {
    let (end, b) = segment(recording, level, opts.bounce_band)?;
    if window < MIN_WINDOW || window + 2 > b {
        return None;
    }
    let x = start(recording, fm.period);
    let axes = flight_axes(&Vector3::new(x[3], x[4], x[5]));
    let mut pb = Problem {
        obs: &recording.positions[..window],
        weights: vec![1.0; window],
        x,
        spin_mean: axes * Vector3::from(prior.mean),
        prior_axes: axes.transpose(),
        prior_std: Vector3::from(prior.std),
    };
    pb.x.fixed_rows_mut::<3>(6).copy_from(&pb.spin_mean);
    fit_nuisance(fm, &mut pb, opts);
    let path = fm.path(&state_of(&pb.x), end, opts.step);
    let d: Vec<f64> = (window..end)
        .map(|k| (path[k] - Vector3::from(recording.positions[k])).norm())
        .collect();
    let rms = |s: &[f64]| (s.iter().map(|x| x * x).sum::<f64>() / s.len().max(1) as f64).sqrt();
    Some(PredictionError {
        window,
        predicted: d.len(),
        rms_after_bounce: rms(&d[(b + 1 - window)..]),
        rms: rms(&d),
        max: d.iter().copied().fold(0.0, f64::max),
        path: path.iter().map(|p| (*p).into()).collect(),
    })
}

/// The held-out split: recordings sorted by name, every fourth (positions 3, 7, 11, … of the
/// sorted order) held out. Returns one flag per recording (true: held out).
pub fn held_out(names: &[&str]) -> Vec<bool> {
    let mut order: Vec<usize> = (0..names.len()).collect();
    order.sort_by(|&a, &b| names[a].cmp(names[b]));
    let mut out = vec![false; names.len()];
    for (rank, &i) in order.iter().enumerate() {
        out[i] = rank % 4 == 3;
    }
    out
}

/// Published constants compared with the calibration on the same held-out flights, on the
/// recording's `surface` (m) and `period` (s): (name, model, source).
///
/// - `mpi_linear`: the MPI table-tennis code's ball model (drag k_d = 0.1414 /m, no spin, table
///   contact v' = (0.68·v_x, 0.72·v_y, −0.88·v_z); Mülling, Kober, Peters and Koç's robot
///   table-tennis code, github.com/RobotLearning `ball_params`/`loadTennisTableValues.m`, in the
///   same lab's frame as these recordings: y along the table). Its comment notes that 0.92 fits
///   observed data better than 0.88: `mpi_linear_092` uses c_z = 0.92.
/// - `muelling`, `tt3d`, `mpi`: the presets of [`BallModel`] (flight constants as published),
///   with this crate's impulse bounce at its pre-calibration constants (e = 0.93, μ = 0.25,
///   Nakashima et al. 2010).
/// - `aero_default`: the pre-calibration default (sphere aerodynamics, k_d = 0.1377, k_m = 0.00551).
pub fn published(surface: f64, period: f64) -> Vec<(&'static str, FitModel)> {
    let with = |model: BallModel, bounce: Bounce| FitModel {
        model,
        bounce,
        surface,
        period,
    };
    let pre = BallModel::from_air(1.184, 0.50, 1.0);
    let bounce = |m: BallModel| BallModel {
        table_restitution: 0.93,
        table_friction: 0.25,
        ..m
    };
    let flight = |k_drag: f64, k_magnus: f64| {
        bounce(BallModel {
            k_drag,
            k_magnus,
            ..pre
        })
    };
    vec![
        (
            "mpi_linear",
            with(flight(0.1414, 0.0), Bounce::Linear([0.68, 0.72, 0.88])),
        ),
        (
            "mpi_linear_092",
            with(flight(0.1414, 0.0), Bounce::Linear([0.68, 0.72, 0.92])),
        ),
        ("muelling", with(flight(0.1414, 0.001), Bounce::Impulse)),
        ("tt3d", with(flight(0.141, 0.0018), Bounce::Impulse)),
        ("mpi", with(flight(0.129, 0.00807), Bounce::Impulse)),
        ("aero_default", with(bounce(pre), Bounce::Impulse)),
    ]
}

/// One model's prediction errors on the held-out flights.
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// Model name ("calibrated" or one of [`published`]).
    pub name: String,
    /// The model.
    pub model: FitModel,
    /// Per held-out flight (recording index, error); flights without a usable window left out.
    pub errors: Vec<(usize, PredictionError)>,
    /// Median over flights of the RMS error after the bounce (m).
    pub median_after_bounce: f64,
    /// Mean over flights of the RMS error after the bounce (m).
    pub mean_after_bounce: f64,
    /// Median over flights of the RMS error over every predicted frame (m).
    pub median_rms: f64,
}

/// The calibration experiment: frame period and bounce height from the data, the split
/// ([`held_out`]), the fit on the training flights and every model's prediction error on the
/// held-out flights from a `window`-frame start.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// Frame period (s) estimated from positions and velocities (the fit's starting value).
    pub period_estimate: f64,
    /// Height (m) of the bounces' lowest frames (median first minimum).
    pub bounce_level: f64,
    /// Held-out flag per recording.
    pub held_out: Vec<bool>,
    /// Recordings without a usable segment (indices).
    pub unusable: Vec<usize>,
    /// The fit on the training flights.
    pub calibration: Calibration,
    /// Calibrated first, then [`published`], on the same held-out flights.
    pub comparisons: Vec<Comparison>,
    /// Frames of the prediction window.
    pub window: usize,
}

/// Default prediction window (frames) of the calibration experiment: the observations a
/// prediction starts from.
pub const WINDOW: usize = 20;

/// Slowest rebound (m/s) a bounce of [`FitModel::path`] keeps: √(2 g · 0.1 mm); a slower one
/// leaves the ball on the plane, rolling.
pub const MIN_REBOUND_SPEED: f64 = 0.044;

/// The shortest prediction window, frames: the observations a predicted state is fitted on.
pub const MIN_WINDOW: usize = 5;

/// The camera frame periods [`experiment`] takes, s (10 µs to 0.1 s: 100 kHz to 10 Hz), given
/// or estimated: the flights are integrated over their frames, and a period of 1e300 s ran for
/// hours (issue 29).
pub const FRAME_PERIOD_RANGE: (f64, f64) = (1e-5, 0.1);

/// Runs the calibration experiment (see [`Experiment`]); `period` overrides the estimate when given.
pub fn experiment(
    recordings: &[Recording],
    window: usize,
    period: Option<f64>,
    opts: &FitOptions,
) -> Result<Experiment> {
    if recordings.is_empty() {
        return Err(Error::invalid("recordings", "no flights given"));
    }
    if window < MIN_WINDOW {
        // no flight could be compared: the experiment would report no prediction error at all
        return Err(Error::invalid(
            "window",
            format!("at least {MIN_WINDOW} frames (the observations a prediction starts from), got {window}"),
        ));
    }
    for r in recordings {
        if !r.velocities.is_empty() && r.velocities.len() != r.positions.len() {
            return Err(Error::invalid(
                "recordings",
                format!(
                    "{}: {} velocities for {} positions",
                    r.name,
                    r.velocities.len(),
                    r.positions.len()
                ),
            ));
        }
    }
    let (lo, hi) = FRAME_PERIOD_RANGE;
    let period_estimate = match period {
        Some(p) if (lo..=hi).contains(&p) => p,
        Some(p) => {
            return Err(Error::invalid(
                "period",
                format!("a camera frame period in [{lo:e}, {hi}] s, got {p}"),
            ))
        }
        None => match estimate_period(recordings)? {
            p if (lo..=hi).contains(&p) => p,
            p => {
                return Err(Error::invalid(
                    "period",
                    format!(
                        "the frame period estimated from the flights' velocities, {p} s, is not a camera's \
                         (in [{lo:e}, {hi}] s): give the period"
                    ),
                ))
            }
        },
    };
    let level = bounce_level(recordings)?;
    let names: Vec<&str> = recordings.iter().map(|r| r.name.as_str()).collect();
    let held = held_out(&names);
    let unusable: Vec<usize> = (0..recordings.len())
        .filter(|&i| segment(&recordings[i], level, opts.bounce_band).is_none())
        .collect();
    let train: Vec<Recording> = recordings
        .iter()
        .zip(&held)
        .filter(|(_, &h)| !h)
        .map(|(r, _)| r.clone())
        .collect();
    let start_model = FitModel {
        model: BallModel {
            k_drag: 0.14,
            k_magnus: 0.002,
            table_restitution: 0.9,
            table_friction: 0.25,
            ..BallModel::default()
        },
        bounce: Bounce::Impulse,
        surface: level - BallModel::default().radius,
        period: period_estimate,
    };
    let calibration = calibrate(&train, &start_model, opts)?;
    let fit = calibration.fit;
    let prior = calibration.spin;
    let mut models = vec![("calibrated", fit)];
    models.extend(published(fit.surface, fit.period));
    let test: Vec<usize> = (0..recordings.len()).filter(|&i| held[i]).collect();
    let comparisons = models
        .into_iter()
        .map(|(name, model)| {
            let errors: Vec<(usize, PredictionError)> = test
                .par_iter()
                .filter_map(|&i| prediction_error(&recordings[i], &model, window, level, &prior, opts).map(|e| (i, e)))
                .collect();
            let mut after: Vec<f64> = errors.iter().map(|(_, e)| e.rms_after_bounce).collect();
            let mut all: Vec<f64> = errors.iter().map(|(_, e)| e.rms).collect();
            let mean_after_bounce = after.iter().sum::<f64>() / after.len().max(1) as f64;
            Comparison {
                name: name.to_string(),
                model,
                median_after_bounce: if after.is_empty() { f64::NAN } else { median(&mut after) },
                mean_after_bounce,
                median_rms: if all.is_empty() { f64::NAN } else { median(&mut all) },
                errors,
            }
        })
        .collect();
    Ok(Experiment {
        period_estimate,
        bounce_level: level,
        held_out: held,
        unusable,
        calibration,
        comparisons,
        window,
    })
}

impl Recording {
    /// Recordings from parallel columns: `names` (F,), `positions` (F lists of frames, m) and
    /// optionally `velocities` (F lists, m/s; each recording's velocities empty when None).
    pub fn from_columns(
        names: Vec<String>,
        positions: Vec<Vec<[f64; 3]>>,
        velocities: Option<Vec<Vec<[f64; 3]>>>,
    ) -> Result<Vec<Recording>> {
        let f = names.len();
        if positions.len() != f || velocities.as_ref().is_some_and(|v| v.len() != f) {
            return Err(Error::invalid(
                "ball_fit",
                format!(
                    "{f} names, {} position arrays and {} velocity arrays: give one of each per flight",
                    positions.len(),
                    velocities.as_ref().map_or(f, Vec::len)
                ),
            ));
        }
        let velocities = velocities.unwrap_or_else(|| vec![Vec::new(); f]);
        Ok(names
            .into_iter()
            .zip(positions)
            .zip(velocities)
            .map(|((name, positions), velocities)| Recording {
                name,
                positions,
                velocities,
            })
            .collect())
    }
}

// The report form of the experiment (serde): plain records, the calibration's globals and their
// standard deviations keyed by `GLOBAL_NAMES`, ball states as 10-value rows (`BallState::to_array`),
// paths as rows of 3 (m); what `ttmanip.ball_fit` returns and writes.

/// Values keyed by [`GLOBAL_NAMES`] (serde: a map).
struct Globals<'a>(&'a [f64; 6]);

impl serde::Serialize for Globals<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_map(GLOBAL_NAMES.iter().zip(self.0.iter()))
    }
}

/// Rows of fixed width as a sequence of sequences (serde).
fn rows<const N: usize>(rows: &[[f64; N]]) -> Vec<&[f64]> {
    rows.iter().map(|r| &r[..]).collect()
}

impl serde::Serialize for Experiment {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(7))?;
        m.serialize_entry("period_estimate", &self.period_estimate)?;
        m.serialize_entry("bounce_level", &self.bounce_level)?;
        m.serialize_entry("held_out", &self.held_out)?;
        m.serialize_entry("unusable", &self.unusable)?;
        m.serialize_entry("window", &self.window)?;
        m.serialize_entry("calibration", &self.calibration)?;
        m.serialize_entry("comparisons", &self.comparisons)?;
        m.end()
    }
}

impl serde::Serialize for Calibration {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(10))?;
        m.serialize_entry("globals", &Globals(&self.globals))?;
        m.serialize_entry("std", &Globals(&self.std))?;
        m.serialize_entry("correlation", &rows(&self.correlation))?;
        m.serialize_entry("sigma", &self.sigma)?;
        m.serialize_entry("rms", &self.rms)?;
        m.serialize_entry("iterations", &self.iterations)?;
        m.serialize_entry("observations", &self.observations)?;
        m.serialize_entry("spin_mean", &self.spin.mean[..])?;
        m.serialize_entry("spin_std", &self.spin.std[..])?;
        m.serialize_entry("flights", &self.flights)?;
        m.end()
    }
}

impl serde::Serialize for FlightFit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(6))?;
        m.serialize_entry("index", &self.index)?;
        m.serialize_entry("state", &self.state.to_array()[..])?;
        m.serialize_entry("frames", &self.frames)?;
        m.serialize_entry("bounce_frame", &self.bounce_frame)?;
        m.serialize_entry("rms", &self.rms)?;
        m.serialize_entry("friction_to_roll", &self.friction_to_roll)?;
        m.end()
    }
}

impl serde::Serialize for Comparison {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("name", &self.name)?;
        m.serialize_entry("k_drag", &self.model.model.k_drag)?;
        m.serialize_entry("k_magnus", &self.model.model.k_magnus)?;
        match self.model.bounce {
            Bounce::Impulse => {
                m.serialize_entry("bounce", "impulse")?;
                m.serialize_entry("table_restitution", &self.model.model.table_restitution)?;
                m.serialize_entry("table_friction", &self.model.model.table_friction)?;
            }
            Bounce::Linear(k) => {
                m.serialize_entry("bounce", "linear")?;
                m.serialize_entry("linear", &k[..])?;
            }
        }
        m.serialize_entry("median_after_bounce", &self.median_after_bounce)?;
        m.serialize_entry("mean_after_bounce", &self.mean_after_bounce)?;
        m.serialize_entry("median_rms", &self.median_rms)?;
        let errors: Vec<IndexedError<'_>> = self.errors.iter().map(|(i, e)| IndexedError(*i, e)).collect();
        m.serialize_entry("errors", &errors)?;
        m.end()
    }
}

/// A held-out flight's prediction error with the flight's index (serde: one record).
struct IndexedError<'a>(usize, &'a PredictionError);

impl serde::Serialize for IndexedError<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let e = self.1;
        let mut m = s.serialize_map(Some(7))?;
        m.serialize_entry("index", &self.0)?;
        m.serialize_entry("window", &e.window)?;
        m.serialize_entry("predicted", &e.predicted)?;
        m.serialize_entry("rms_after_bounce", &e.rms_after_bounce)?;
        m.serialize_entry("rms", &e.rms)?;
        m.serialize_entry("max", &e.max)?;
        m.serialize_entry("path", &rows(&e.path))?;
        m.end()
    }
}
