//! The damped weighted least-norm solve of an m × n task with velocity boxes: [`WlsSolver`]
//! (preallocated, allocation-free), its damping law [`Damping`] and what a solve did
//! ([`StepReport`]).

// Numeric loops index several parallel arrays by the same input index: keep them as loops.
#![allow(clippy::needless_range_loop)]

use super::kernels::{kernels, FactorFn, GramFn, SolveFn};
use super::MAX_TASK_DIM;
use crate::error::{Error, Result};

/// Inverse-iteration sweeps per solve for σ_min (warm-started from the previous solve's vector).
const INVERSE_ITERATIONS: usize = 2;

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

    /// Damping that starts below σ_min = `epsilon` and rises to `lambda_max`, both checked
    /// ([`Damping::validate`]).
    pub fn new(epsilon: f64, lambda_max: f64) -> Result<Self> {
        let d = Damping { epsilon, lambda_max };
        d.validate()?;
        Ok(d)
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
        self.resolve(jac, xdot, z, lower, upper, qdot)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `Damping::new` keeps good numbers and refuses negative or non-finite ones by name.
    #[test]
    fn damping_new_checks_both_numbers() {
        let d = Damping::new(0.02, 0.05).unwrap();
        assert_eq!((d.epsilon, d.lambda_max), (0.02, 0.05));
        assert!(Damping::new(-1.0, 0.05).unwrap_err().to_string().contains("epsilon"));
        assert!(Damping::new(0.02, f64::NAN)
            .unwrap_err()
            .to_string()
            .contains("lambda_max"));
    }
}
