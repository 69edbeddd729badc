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

// Numeric loops index several parallel arrays by the same input index: keep them as loops.
#![allow(clippy::needless_range_loop)]

use crate::error::{Error, Result};

/// Largest task dimension the solver handles.
pub const MAX_TASK_DIM: usize = 6;

/// Inverse-iteration sweeps per solve for σ_min (warm-started from the previous solve's vector).
const INVERSE_ITERATIONS: usize = 2;

/// Smallest singular value below which an undamped step is refused as singular.
pub const SINGULAR_SIGMA: f64 = 1e-9;

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

/// Singularity-robust damping: λ² = λ_max²(1 − (σ_min/ε)²) below σ_min = ε, 0 above.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Damping {
    /// Singular value (task units per input unit) below which damping starts.
    pub epsilon: f64,
    /// Damping factor λ at σ_min = 0 (task units).
    pub lambda_max: f64,
}

impl Default for Damping {
    /// ε = 1e-3, λ_max = 0.05: no damping anywhere a 1e-6 tracking error is achievable.
    fn default() -> Self {
        Damping {
            epsilon: 1e-3,
            lambda_max: 0.05,
        }
    }
}

impl Damping {
    /// No damping at all (pure weighted pseudo-inverse; fails at a singularity).
    pub fn none() -> Self {
        Damping {
            epsilon: 0.0,
            lambda_max: 0.0,
        }
    }

    /// Checks that both numbers are finite and ≥ 0.
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [
            ("damping epsilon", self.epsilon),
            ("damping lambda_max", self.lambda_max),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Error::invalid(what, format!("must be finite and ≥ 0, got {v}")));
            }
        }
        Ok(())
    }

    /// λ² for a smallest singular value `sigma_min`.
    pub fn lambda_squared(&self, sigma_min: f64) -> f64 {
        if sigma_min >= self.epsilon || self.epsilon == 0.0 {
            0.0
        } else {
            let r = sigma_min / self.epsilon;
            self.lambda_max * self.lambda_max * (1.0 - r * r)
        }
    }
}

/// What one solve did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Estimated smallest singular value of J W^{-1/2} over the free inputs.
    pub sigma_min: f64,
    /// Damping factor λ used (0 away from singularities).
    pub lambda: f64,
    /// Fraction of the task velocity achieved (1 unless the velocity boxes forced task scaling).
    pub scale: f64,
    /// Number of inputs held at a bound of their velocity box.
    pub saturated: usize,
}

/// Preallocated solver for an m × n task (model/data split: one per thread; a solve allocates
/// nothing). Inputs are the n columns of the task Jacobian.
#[derive(Debug, Clone)]
pub struct WlsSolver {
    m: usize,
    n: usize,
    damping: Damping,
    winv: Vec<f64>,
    free: Vec<bool>,
    fixed: Vec<f64>,
    a_part: Vec<f64>,
    b_part: Vec<f64>,
    best: Vec<f64>,
    chol: [f64; MAX_TASK_DIM * MAX_TASK_DIM],
    gram: [f64; MAX_TASK_DIM * MAX_TASK_DIM],
    eig: [f64; MAX_TASK_DIM],
    factor_fn: FactorFn,
    solve_fn: SolveFn,
    gram_fn: GramFn,
    cached: Option<(f64, f64)>,
    cached_chol: [f64; MAX_TASK_DIM * MAX_TASK_DIM],
}

impl WlsSolver {
    /// A solver for tasks of `m` rows (1..=6) and `n` ≥ 1 inputs.
    pub fn new(m: usize, n: usize, damping: Damping) -> Result<Self> {
        if m == 0 || m > MAX_TASK_DIM {
            return Err(Error::invalid("task dimension", format!("must be 1..=6, got {m}")));
        }
        if n == 0 {
            return Err(Error::invalid("inputs", "need at least one input"));
        }
        damping.validate()?;
        let mut eig = [0.0; MAX_TASK_DIM];
        eig[..m].fill(1.0 / (m as f64).sqrt());
        Ok(WlsSolver {
            m,
            n,
            damping,
            winv: vec![1.0; n],
            free: vec![true; n],
            fixed: vec![0.0; n],
            a_part: vec![0.0; n],
            b_part: vec![0.0; n],
            best: vec![0.0; n],
            chol: [0.0; MAX_TASK_DIM * MAX_TASK_DIM],
            gram: [0.0; MAX_TASK_DIM * MAX_TASK_DIM],
            eig,
            factor_fn: kernels(m).0,
            solve_fn: kernels(m).1,
            gram_fn: kernels(m).2,
            cached: None,
            cached_chol: [0.0; MAX_TASK_DIM * MAX_TASK_DIM],
        })
    }

    /// Task rows m.
    pub fn task_dim(&self) -> usize {
        self.m
    }

    /// Inputs n.
    pub fn inputs(&self) -> usize {
        self.n
    }

    /// The damping in use.
    pub fn damping(&self) -> Damping {
        self.damping
    }

    /// Solves for `qdot` (n inputs) given the m × n Jacobian `jac` (column-major slice, m·n values),
    /// the weights `w` (n values > 0), the task velocity `xdot` (m), an optional secondary motion
    /// `z` (n) to project into the null space, and a velocity box `lower ≤ q̇ ≤ upper` (n each, may
    /// be ±∞; must contain 0). Inputs hitting their box are saturated and the rest re-solved; if no
    /// saturation set achieves the task the largest feasible fraction of it is returned
    /// (`StepReport::scale` < 1). Slices must have the stated lengths (unchecked, debug-asserted).
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &mut self,
        jac: &[f64],
        w: &[f64],
        xdot: &[f64],
        z: Option<&[f64]>,
        lower: &[f64],
        upper: &[f64],
        qdot: &mut [f64],
    ) -> StepReport {
        debug_assert!(w.len() == self.n);
        for (wi, &x) in self.winv.iter_mut().zip(w) {
            *wi = 1.0 / x;
        }
        self.cached = None;
        self.solve_inner(jac, xdot, z, lower, upper, qdot)
    }

    /// [`WlsSolver::solve`] with the Jacobian and weights of the previous `solve` (only the task
    /// velocity, secondary motion and box change): reuses the factorisation when possible.
    pub fn resolve(
        &mut self,
        jac: &[f64],
        xdot: &[f64],
        z: Option<&[f64]>,
        lower: &[f64],
        upper: &[f64],
        qdot: &mut [f64],
    ) -> StepReport {
        self.solve_inner(jac, xdot, z, lower, upper, qdot)
    }

    fn solve_inner(
        &mut self,
        jac: &[f64],
        xdot: &[f64],
        z: Option<&[f64]>,
        lower: &[f64],
        upper: &[f64],
        qdot: &mut [f64],
    ) -> StepReport {
        let (m, n) = (self.m, self.n);
        debug_assert!(jac.len() == m * n && xdot.len() == m && qdot.len() == n);
        debug_assert!(lower.len() == n && upper.len() == n);
        let mut z = z;
        'with_z: loop {
            self.free.fill(true);
            self.fixed.fill(0.0);
            let mut best_scale = -1.0;
            let mut best_report = StepReport {
                sigma_min: 0.0,
                lambda: 0.0,
                scale: 0.0,
                saturated: 0,
            };
            for saturated in 0..=n {
                let (sigma, lambda2) = match (saturated, self.cached) {
                    (0, Some(c)) => {
                        self.chol = self.cached_chol;
                        c
                    }
                    (0, None) => {
                        let c = self.factor(jac);
                        self.cached = Some(c);
                        self.cached_chol = self.chol;
                        c
                    }
                    _ => self.factor(jac),
                };
                self.parts(jac, xdot, z);
                // Largest s ∈ [0, 1] with lower ≤ a + s·b ≤ upper on the free inputs.
                let mut s_max = 1.0f64;
                let mut worst = usize::MAX;
                let mut feasible = true;
                for i in 0..n {
                    if !self.free[i] {
                        continue;
                    }
                    let (a, b) = (self.a_part[i], self.b_part[i]);
                    if a > upper[i] || a < lower[i] {
                        feasible = false;
                        if worst == usize::MAX {
                            worst = i;
                        }
                        continue;
                    }
                    let s = if b > 0.0 {
                        (upper[i] - a) / b
                    } else if b < 0.0 {
                        (lower[i] - a) / b
                    } else {
                        f64::INFINITY
                    };
                    if s < s_max {
                        s_max = s.max(0.0);
                        worst = i;
                    }
                }
                let report = StepReport {
                    sigma_min: sigma,
                    lambda: lambda2.sqrt(),
                    scale: s_max,
                    saturated,
                };
                if feasible && worst == usize::MAX {
                    self.compose(qdot, 1.0);
                    return StepReport { scale: 1.0, ..report };
                }
                if feasible && s_max > best_scale {
                    best_scale = s_max;
                    best_report = report;
                    for i in 0..n {
                        self.best[i] = if self.free[i] {
                            self.a_part[i] + s_max * self.b_part[i]
                        } else {
                            self.fixed[i]
                        };
                    }
                }
                if !feasible && z.is_some() {
                    // The secondary motion alone leaves the box: drop it and start over.
                    z = None;
                    continue 'with_z;
                }
                // Saturate the input that limits the task most at the bound it would cross.
                let i = worst;
                let v = self.a_part[i] + self.b_part[i];
                self.fixed[i] = v.clamp(lower[i], upper[i]);
                self.free[i] = false;
                if self.free.iter().filter(|&&f| f).count() == 0 {
                    break;
                }
            }
            if best_scale < 0.0 {
                // Nothing feasible (a box that excludes the task everywhere): stand still.
                qdot.iter_mut().for_each(|v| *v = 0.0);
                return StepReport {
                    scale: 0.0,
                    saturated: n,
                    ..best_report
                };
            }
            qdot.copy_from_slice(&self.best);
            return best_report;
        }
    }

    /// Writes the free part a + s·b and the fixed part into `qdot`.
    fn compose(&self, qdot: &mut [f64], s: f64) {
        for i in 0..self.n {
            qdot[i] = if self.free[i] {
                self.a_part[i] + s * self.b_part[i]
            } else {
                self.fixed[i]
            };
        }
    }

    /// Builds G = J_F W⁻¹ J_Fᵀ, estimates σ_min, factors G + λ²I into `chol`. Returns (σ_min, λ²).
    fn factor(&mut self, jac: &[f64]) -> (f64, f64) {
        let m = self.m;
        (self.gram_fn)(jac, &self.winv, &self.free, &mut self.gram);
        let g = &self.gram;
        // σ_min² = λ_min(G): inverse iteration warm-started from the previous eigenvector.
        let mut sigma = 0.0;
        self.chol[..m * m].copy_from_slice(&g[..m * m]);
        let factored = (self.factor_fn)(&mut self.chol);
        if factored {
            let mut lam = f64::INFINITY;
            for _ in 0..INVERSE_ITERATIONS {
                (self.solve_fn)(&self.chol, &mut self.eig);
                let norm = self.eig[..m].iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(norm.is_finite() && norm > 0.0) {
                    self.eig[..m].fill(1.0 / (m as f64).sqrt());
                    lam = 0.0;
                    break;
                }
                self.eig[..m].iter_mut().for_each(|v| *v /= norm);
                lam = 1.0 / norm;
            }
            sigma = lam.max(0.0).sqrt();
        }
        let lambda2 = self.damping.lambda_squared(sigma);
        if factored && lambda2 == 0.0 {
            // Away from singularities the factor of G is the one to solve with.
            return (sigma, 0.0);
        }
        self.chol[..m * m].copy_from_slice(&g[..m * m]);
        for r in 0..m {
            self.chol[r * m + r] += lambda2;
        }
        if !(self.factor_fn)(&mut self.chol) {
            // Exactly singular and undamped: regularise minimally so the result stays finite.
            let tiny = 1e-12 * (1.0 + (0..m).map(|r| g[r * m + r]).fold(0.0, f64::max));
            self.chol[..m * m].copy_from_slice(&g[..m * m]);
            for r in 0..m {
                self.chol[r * m + r] += lambda2 + tiny;
            }
            (self.factor_fn)(&mut self.chol);
            return (sigma, lambda2 + tiny);
        }
        (sigma, lambda2)
    }

    /// With the factor in place: a = z + W⁻¹J_Fᵀ G⁻¹(−J_S q̇_S − J_F z_F) on free inputs (z = 0 if
    /// none) and b = W⁻¹J_Fᵀ G⁻¹ ẋ.
    fn parts(&mut self, jac: &[f64], xdot: &[f64], z: Option<&[f64]>) {
        let (m, n) = (self.m, self.n);
        let mut ra = [0.0; MAX_TASK_DIM];
        let mut rb = [0.0; MAX_TASK_DIM];
        rb[..m].copy_from_slice(xdot);
        for k in 0..n {
            let col = &jac[k * m..(k + 1) * m];
            let v = if self.free[k] {
                z.map_or(0.0, |z| z[k])
            } else {
                self.fixed[k]
            };
            if v != 0.0 {
                for r in 0..m {
                    ra[r] -= col[r] * v;
                }
            }
        }
        (self.solve_fn)(&self.chol, &mut ra);
        (self.solve_fn)(&self.chol, &mut rb);
        for k in 0..n {
            if !self.free[k] {
                self.a_part[k] = self.fixed[k];
                self.b_part[k] = 0.0;
                continue;
            }
            let col = &jac[k * m..(k + 1) * m];
            let (mut da, mut db) = (0.0, 0.0);
            for r in 0..m {
                da += col[r] * ra[r];
                db += col[r] * rb[r];
            }
            self.a_part[k] = z.map_or(0.0, |z| z[k]) + self.winv[k] * da;
            self.b_part[k] = self.winv[k] * db;
        }
    }
}

/// Cholesky factorisation of an M × M row-major matrix in place (lower triangle).
type FactorFn = fn(&mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]) -> bool;
/// Solve with a Cholesky factor in place.
type SolveFn = fn(&[f64; MAX_TASK_DIM * MAX_TASK_DIM], &mut [f64; MAX_TASK_DIM]);
/// Gram matrix of the free columns.
type GramFn = fn(&[f64], &[f64], &[bool], &mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]);

/// The factor/solve pair for task dimension `m` (1..=6), monomorphised so the loops unroll.
fn kernels(m: usize) -> (FactorFn, SolveFn, GramFn) {
    match m {
        1 => (cholesky::<1>, cholesky_solve::<1>, gram::<1>),
        2 => (cholesky::<2>, cholesky_solve::<2>, gram::<2>),
        3 => (cholesky::<3>, cholesky_solve::<3>, gram::<3>),
        4 => (cholesky::<4>, cholesky_solve::<4>, gram::<4>),
        5 => (cholesky::<5>, cholesky_solve::<5>, gram::<5>),
        _ => (cholesky::<6>, cholesky_solve::<6>, gram::<6>),
    }
}

/// In-place Cholesky G = L Lᵀ of the lower triangle of an M × M row-major matrix (stride M),
/// storing 1/L_jj on the diagonal (the solves then multiply instead of divide); false when G is not
/// positive definite (to working precision).
fn cholesky<const M: usize>(a: &mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]) -> bool {
    for j in 0..M {
        let mut d = a[j * M + j];
        for k in 0..j {
            d -= a[j * M + k] * a[j * M + k];
        }
        if !(d > 1e-300) {
            return false;
        }
        let inv = 1.0 / d.sqrt();
        a[j * M + j] = inv;
        for i in j + 1..M {
            let mut s = a[i * M + j];
            for k in 0..j {
                s -= a[i * M + k] * a[j * M + k];
            }
            a[i * M + j] = s * inv;
        }
    }
    true
}

/// Solves L Lᵀ x = b in place with the factor from [`cholesky`].
fn cholesky_solve<const M: usize>(l: &[f64; MAX_TASK_DIM * MAX_TASK_DIM], b: &mut [f64; MAX_TASK_DIM]) {
    for i in 0..M {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * M + k] * b[k];
        }
        b[i] = s * l[i * M + i];
    }
    for i in (0..M).rev() {
        let mut s = b[i];
        for k in i + 1..M {
            s -= l[k * M + i] * b[k];
        }
        b[i] = s * l[i * M + i];
    }
}

/// Gram matrix G = J_F W⁻¹ J_Fᵀ (lower triangle, stride M) over the free inputs.
fn gram<const M: usize>(jac: &[f64], winv: &[f64], free: &[bool], g: &mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]) {
    g[..M * M].fill(0.0);
    for ((col, &wk), &f) in jac.chunks_exact(M).zip(winv).zip(free) {
        if !f {
            continue;
        }
        let mut c = [0.0; M];
        c.copy_from_slice(col);
        for r in 0..M {
            let jr = c[r] * wk;
            for k in 0..=r {
                g[r * M + k] += jr * c[k];
            }
        }
    }
}

/// One weighted least-norm step of a whole-body model with preallocated scratch: task Jacobian at
/// the current pose, weights, solve. `xdot` is in the task's residual coordinates at the current
/// pose (position: m/s; pose: m/s then rad/s, world axes; racket: centre velocity m/s, then the
/// rotation rate of the face normal (rad/s) along the two tangent directions of
/// [`crate::task::tangent_basis`] of the current normal).
#[derive(Debug, Clone)]
pub struct WlsStep<'a> {
    model: &'a crate::wholebody::WholeBody,
    task: crate::task::Task,
    weighting: Weighting,
    solver: WlsSolver,
    data: crate::wholebody::WholeBodyData,
    jac6: nalgebra::Matrix6xX<f64>,
    jtask: Vec<f64>,
    limits: Vec<(f64, f64)>,
    w: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    qdot: Vec<f64>,
}

impl<'a> WlsStep<'a> {
    /// A step solver of `task` on `model`.
    pub fn new(
        model: &'a crate::wholebody::WholeBody,
        task: crate::task::Task,
        weighting: Weighting,
        damping: Damping,
    ) -> Result<Self> {
        let (m, n) = (task.dim(), model.nu());
        if n < m {
            return Err(Error::invalid(
                "task",
                format!("the task has {m} rows but the robot only {n} inputs"),
            ));
        }
        Ok(WlsStep {
            model,
            task,
            weighting,
            solver: WlsSolver::new(m, n, damping)?,
            data: model.data(),
            jac6: nalgebra::Matrix6xX::zeros(n),
            jtask: vec![0.0; m * n],
            limits: model.input_position_limits(),
            w: vec![1.0; n],
            lo: vec![f64::NEG_INFINITY; n],
            hi: vec![f64::INFINITY; n],
            qdot: vec![0.0; n],
        })
    }

    /// Inputs q̇ (nu) for task velocity `xdot` at `q`; `previous` is the latest input motion for
    /// the Chan–Dubey direction test (all zeros: every joint treated as approaching its limit).
    /// Unchecked lengths: q nq, xdot dim, previous nu (see [`WlsStep::try_solve`]).
    pub fn solve(&mut self, q: &[f64], xdot: &[f64], previous: &[f64]) -> (&[f64], StepReport) {
        let t = self.model.jacobian_into(q, &mut self.data, &mut self.jac6);
        self.task.jacobian_into(&self.jac6, &t, &t, &mut self.jtask);
        for k in 0..self.w.len() {
            let (lo, hi) = self.limits[k];
            self.w[k] = match self.weighting {
                Weighting::None => 1.0,
                Weighting::ChanDubey => {
                    let pos = self.model.input_coordinate(k).map_or(0.0, |c| q[c]);
                    chan_dubey_weight(pos, lo, hi, previous[k])
                }
            };
        }
        let report = self
            .solver
            .solve(&self.jtask, &self.w, xdot, None, &self.lo, &self.hi, &mut self.qdot);
        (&self.qdot, report)
    }

    /// Checked [`WlsStep::solve`]: shapes, finiteness, and a finite result.
    pub fn try_solve(&mut self, q: &[f64], xdot: &[f64], previous: &[f64]) -> Result<(Vec<f64>, StepReport)> {
        self.model.check_q("q", q)?;
        crate::error::check_vector("xdot", xdot, self.task.dim())?;
        crate::error::check_vector("qdot_prev", previous, self.model.nu())?;
        let undamped = self.solver.damping().lambda_max == 0.0;
        let (qd, rep) = self.solve(q, xdot, previous);
        if qd.iter().any(|v| !v.is_finite()) || (undamped && rep.sigma_min < SINGULAR_SIGMA) {
            return Err(Error::Singular(format!(
                "the weighted task Jacobian is singular here (σ_min ≈ {:.1e}); pass a damping > 0 for a \
                 bounded least-squares step",
                rep.sigma_min
            )));
        }
        Ok((qd.to_vec(), rep))
    }
}

/// Manipulability √det(J Jᵀ) of an m × n task Jacobian (column-major slice), 0 when rank-deficient.
pub fn manipulability(jac: &[f64], m: usize) -> f64 {
    if m == 0 || m > MAX_TASK_DIM || !jac.len().is_multiple_of(m) {
        return 0.0;
    }
    let n = jac.len() / m;
    let (factor, _, gram) = kernels(m);
    let ones = [1.0; 64];
    let free = [true; 64];
    if n > ones.len() {
        return 0.0;
    }
    let mut g = [0.0; MAX_TASK_DIM * MAX_TASK_DIM];
    gram(jac, &ones[..n], &free[..n], &mut g);
    if !factor(&mut g) {
        return 0.0;
    }
    (0..m).map(|j| 1.0 / g[j * m + j]).product()
}
