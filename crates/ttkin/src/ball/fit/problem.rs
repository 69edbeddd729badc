//! One flight's least-squares problem: its observations, robust weights, nuisance state (p0, v0,
//! ω) with the spin prior, the weighted residuals and their forward-difference Jacobians, and
//! Levenberg–Marquardt on the nuisance alone.

use super::{FitModel, FitOptions, Recording};
use crate::ball::flight::BallState;
use nalgebra::{DMatrix, DVector, SMatrix, SVector, Vector3};

/// Length scale (m) of the spin prior's residual rows: one σ of spin weighs as 5 mm of position.
const S_REF: f64 = 0.005;
/// One flight's nuisance: p0 (m), v0 (m/s), ω (rad/s) at its first frame.
pub(super) type Vec9 = SVector<f64, 9>;
/// A 9 × 9 block in the nuisance (U_i = A_iᵀA_i).
pub(super) type Mat9 = SMatrix<f64, 9, 9>;
/// Nuisance × globals block (W_i = A_iᵀB_i).
pub(super) type Mat96 = SMatrix<f64, 9, 6>;
/// A 6 × 6 block in the globals (V = Σ B_iᵀB_i).
pub(super) type Mat6 = SMatrix<f64, 6, 6>;
/// The globals (k_d, k_m, e, μ, surface, period) as a vector.
pub(super) type Vec6 = SVector<f64, 6>;

/// The ball state at t = 0 of a nuisance vector.
pub(super) fn state_of(x: &Vec9) -> BallState {
    BallState {
        t: 0.0,
        p: Vector3::new(x[0], x[1], x[2]),
        v: Vector3::new(x[3], x[4], x[5]),
        w: Vector3::new(x[6], x[7], x[8]),
    }
}

/// One flight's problem: observations, weights, nuisance.
pub(super) struct Problem<'a> {
    /// Observed positions (m) of the segment's frames.
    pub(super) obs: &'a [[f64; 3]],
    /// Robust weight per frame.
    pub(super) weights: Vec<f64>,
    /// The nuisance (p0, v0, ω) at the first frame.
    pub(super) x: Vec9,
    /// Prior of the spin: mean (rad/s, recording frame), the rotation into the axes where its
    /// components are independent, and their standard deviations (rad/s).
    pub(super) spin_mean: Vector3<f64>,
    pub(super) prior_axes: nalgebra::Matrix3<f64>,
    pub(super) prior_std: Vector3<f64>,
}

impl Problem<'_> {
    /// Weighted residuals (3 per frame, then 3 spin-prior rows).
    pub(super) fn residuals(&self, fm: &FitModel, x: &Vec9, opts: &FitOptions) -> DVector<f64> {
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

    /// The weighted sum of squared residuals.
    pub(super) fn cost(&self, fm: &FitModel, x: &Vec9, opts: &FitOptions) -> f64 {
        self.residuals(fm, x, opts).norm_squared()
    }

    /// Residuals and the Jacobians in the nuisance (A) and, with `globals`, the globals (B).
    pub(super) fn linearise(
        &self,
        fm: &FitModel,
        opts: &FitOptions,
        globals: bool,
    ) -> (DVector<f64>, DMatrix<f64>, DMatrix<f64>) {
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
pub(super) fn huber(res: &[f64], c: f64) -> Vec<f64> {
    res.iter().map(|&r| if r <= c { 1.0 } else { c / r }).collect()
}

/// Starting nuisance of a flight: the first position, the tracker's velocity there (or a finite
/// difference), no spin.
pub(super) fn start(r: &Recording, period: f64) -> Vec9 {
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
pub(super) fn fit_nuisance(fm: &FitModel, pb: &mut Problem, opts: &FitOptions) -> usize {
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
/// The flight axes of a velocity `v`: along its horizontal part, horizontal across it (z × that),
/// and z; as the columns of a rotation.
pub(super) fn flight_axes(v: &Vector3<f64>) -> nalgebra::Matrix3<f64> {
    let h = Vector3::new(v.x, v.y, 0.0);
    let e1 = if h.norm() > 1e-9 { h.normalize() } else { Vector3::x() };
    let e2 = Vector3::z().cross(&e1);
    nalgebra::Matrix3::from_columns(&[e1, e2, Vector3::z()])
}
