//! Numeric IK for any chain: bounded Levenberg–Marquardt with random restarts.
//!
//! Each attempt minimises E(q) = ½‖e(q)‖², e the residual of a [`Task`] (target − current, base
//! axes; m and rad), over the box of joint limits. A step solves (JᵀJ + λI)·δq = Jᵀe, where J is
//! the task Jacobian (ė = −J·q̇). Joint limits are handled inside the iteration, as in a projected
//! trust-region method: a joint sitting on a bound whose gradient pushes it outward is frozen for
//! that step (its row and column are removed), the others are solved for, and the trial point is
//! projected onto the box. The trial is accepted only if E decreases; λ follows Nielsen's gain-ratio
//! rule (λ·max(⅓, 1 − (2ρ − 1)³) after a good step, λ·ν with ν doubling after a rejected one), so
//! the method moves between Gauss–Newton (fast final convergence) and gradient descent (far away).
//! Projection never wraps or flips a joint: a revolute joint only moves continuously inside its
//! limits.
//!
//! An attempt stops on convergence (position and orientation errors both within tolerance), on
//! stagnation (E not halved in [`STALL_WINDOW`] steps, or λ exploding: a local minimum or a joint
//! limit wall) or after `max_iterations`. The solver then restarts from a uniformly random
//! configuration within the limits, drawn from a generator seeded by `seed`, until it converges,
//! runs out of restarts or out of its time budget. With a fixed seed and a budget that does not
//! bind (set `time_budget: None`), the result is a deterministic function of the inputs.
//!
//! The racket task is solved with a 6-row residual [c* − c; n* − n] (centre, and the chord between
//! the face normals) rather than [`Task::error`]'s 2-D tangent form: ½‖n* − n‖² = 1 − cos∠(n, n*)
//! grows monotonically with the angle, while the tangent form Bᵀ(n × n*) also vanishes at the
//! flipped normal n = −n*, a false minimum a descent method can fall into.
//!
//! Hot loops allocate nothing: all buffers live in an [`IkScratch`] (Pinocchio's model/data split).
//!
//! One solver, its settings, scratch and restart loop, read top to bottom; the residual it
//! minimises and its Jacobian are [`super::residual`], the front end that chooses it is
//! [`super::batch`].

// Index loops over joints read like the maths here (several arrays per index): keep them.
#![allow(clippy::needless_range_loop)]

use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector, IsometryMatrix3, Matrix6xX};
use rayon::prelude::*;

use crate::chain::{Chain, JacobianFrame};
use crate::error::{check_finite, check_vector, Error, Result};
use crate::joint::JointType;
use crate::task::Task;

pub use super::residual::{measure, residual_dim};
use super::residual::{residual_errors, residual_into, residual_jacobian_into};

/// Steps after which an attempt must have halved its cost E, or it is abandoned as stalled.
pub const STALL_WINDOW: usize = 6;

/// Settings of the numeric IK solver.
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolver {
    /// What part of the tool pose to reach.
    pub task: Task,
    /// Success threshold on the position error (m): tool point, or racket centre.
    pub position_tolerance: f64,
    /// Success threshold on the orientation error (rad): rotation angle, or angle between racket
    /// normals. Ignored by [`Task::Position`].
    pub orientation_tolerance: f64,
    /// Most LM steps (accepted or rejected) per attempt.
    pub max_iterations: usize,
    /// Most random restarts after the first attempt from `q0`.
    pub max_restarts: usize,
    /// Wall-clock budget of one solve (`None`: unlimited, fully deterministic).
    pub time_budget: Option<Duration>,
    /// Seed of the restart generator.
    pub seed: u64,
}

impl Default for IkSolver {
    /// Full pose, 1e-6 m and 1e-6 rad, 60 steps per attempt, up to 500 restarts within 1 ms, seed 0.
    fn default() -> Self {
        IkSolver {
            task: Task::Pose,
            position_tolerance: 1e-6,
            orientation_tolerance: 1e-6,
            max_iterations: 60,
            max_restarts: 500,
            time_budget: Some(Duration::from_millis(1)),
            seed: 0,
        }
    }
}

/// Outcome of a numeric solve: a status, not an error, for a merely unreachable target.
#[derive(Debug, Clone, PartialEq)]
pub struct IkResult {
    /// Best configuration found (m, rad), within the joint limits.
    pub q: Vec<f64>,
    /// True when both errors are within the solver's tolerances.
    pub success: bool,
    /// Position error of `q` (m).
    pub position_error: f64,
    /// Orientation error of `q` (rad); 0 for the position task.
    pub orientation_error: f64,
    /// LM steps taken over all attempts.
    pub iterations: usize,
    /// Random restarts used.
    pub restarts: usize,
}

/// Preallocated buffers of the numeric solver for one chain and one task dimension.
#[derive(Debug, Clone)]
pub struct IkScratch {
    n: usize,
    m: usize,
    jac: Matrix6xX<f64>,
    jac_trial: Matrix6xX<f64>,
    je: DMatrix<f64>,
    a: DMatrix<f64>,
    lhs: DMatrix<f64>,
    g: DVector<f64>,
    dq: DVector<f64>,
    e: DVector<f64>,
    e_trial: DVector<f64>,
    q: Vec<f64>,
    q_trial: Vec<f64>,
    best_q: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    frozen: Vec<bool>,
}

impl IkScratch {
    /// Buffers for `chain` and a task of `task_dim` rows.
    pub fn new(chain: &Chain, task_dim: usize) -> Self {
        let n = chain.dof();
        let (lower, upper) = chain.limits().iter().map(|l| (l.lower, l.upper)).unzip();
        IkScratch {
            n,
            m: task_dim,
            jac: Matrix6xX::zeros(n),
            jac_trial: Matrix6xX::zeros(n),
            je: DMatrix::zeros(task_dim, n),
            a: DMatrix::zeros(n, n),
            lhs: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            dq: DVector::zeros(n),
            e: DVector::zeros(task_dim),
            e_trial: DVector::zeros(task_dim),
            q: vec![0.0; n],
            q_trial: vec![0.0; n],
            best_q: vec![0.0; n],
            lower,
            upper,
            frozen: vec![false; n],
        }
    }

    fn fits(&self, chain: &Chain, m: usize) -> bool {
        self.n == chain.dof()
            && self.m == m
            && chain
                .joints()
                .iter()
                .zip(self.lower.iter().zip(&self.upper))
                .all(|(j, (lo, hi))| j.limits().lower == *lo && j.limits().upper == *hi)
    }
}

/// Why an attempt ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Attempt {
    Converged,
    Stalled,
    OutOfTime,
}

impl IkSolver {
    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [
            ("position_tolerance", self.position_tolerance),
            ("orientation_tolerance", self.orientation_tolerance),
        ] {
            if !(v > 0.0) || !v.is_finite() {
                return Err(Error::invalid(what, format!("must be a finite value > 0, got {v}")));
            }
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be ≥ 1"));
        }
        if let Task::Racket { offset } = self.task {
            check_finite("racket offset", &[offset])?;
        }
        Ok(())
    }

    /// Solves for a tool pose `target` (base frame, m) from `q0` (m, rad; projected into the limits
    /// first), allocating its own buffers. See [`IkSolver::solve_with`].
    pub fn solve(&self, chain: &Chain, target: &IsometryMatrix3<f64>, q0: &[f64]) -> Result<IkResult> {
        let mut scratch = IkScratch::new(chain, residual_dim(&self.task));
        self.solve_with(chain, target, q0, &mut scratch)
    }

    /// Solves with caller-owned buffers (resized if they belong to another chain or task).
    /// Errors only for bad input (wrong length, NaN, bad settings); an unreachable target gives
    /// `success = false` with the best configuration found.
    pub fn solve_with(
        &self,
        chain: &Chain,
        target: &IsometryMatrix3<f64>,
        q0: &[f64],
        s: &mut IkScratch,
    ) -> Result<IkResult> {
        self.validate()?;
        check_vector("q0", q0, chain.dof())?;
        check_finite("target pose", target.rotation.matrix().as_slice())?;
        check_finite("target pose", target.translation.vector.as_slice())?;
        if !s.fits(chain, residual_dim(&self.task)) {
            *s = IkScratch::new(chain, residual_dim(&self.task));
        }
        Ok(self.solve_unchecked(chain, target, q0, s, self.seed))
    }

    /// Solves N targets in parallel: `targets[i]` from `q0s[i]` (or every target from `q0s[0]`
    /// when one start is given), target i with seed `seed + i`. Same errors as [`IkSolver::solve`].
    pub fn solve_batch(
        &self,
        chain: &Chain,
        targets: &[IsometryMatrix3<f64>],
        q0s: &[Vec<f64>],
    ) -> Result<Vec<IkResult>> {
        self.validate()?;
        check_batch(chain, targets, q0s)?;
        Ok(targets
            .par_iter()
            .enumerate()
            .map_init(
                || IkScratch::new(chain, residual_dim(&self.task)),
                |s, (i, t)| {
                    let q0 = if q0s.len() == 1 { &q0s[0] } else { &q0s[i] };
                    self.solve_unchecked(chain, t, q0, s, self.seed.wrapping_add(i as u64))
                },
            )
            .collect())
    }

    fn solve_unchecked(
        &self,
        chain: &Chain,
        target: &IsometryMatrix3<f64>,
        q0: &[f64],
        s: &mut IkScratch,
        seed: u64,
    ) -> IkResult {
        let deadline = self.time_budget.map(|b| Instant::now() + b);
        let mut rng = fastrand::Rng::with_seed(seed);
        for i in 0..s.n {
            s.q[i] = q0[i].clamp(s.lower[i], s.upper[i]);
        }
        s.best_q.copy_from_slice(&s.q);
        let mut best = f64::INFINITY;
        let mut iterations = 0;
        let mut restarts = 0;
        loop {
            let outcome = self.attempt(chain, target, s, &mut best, &mut iterations, deadline);
            if outcome != Attempt::Stalled || restarts >= self.max_restarts {
                break;
            }
            restarts += 1;
            for i in 0..s.n {
                s.q[i] = random_in(&mut rng, s.lower[i], s.upper[i], chain.joints()[i].kind());
            }
        }
        let t = chain.fk_unchecked(&s.best_q);
        let (position_error, orientation_error) = measure(&self.task, &t, target);
        IkResult {
            q: s.best_q.clone(),
            success: self.within(position_error, orientation_error),
            position_error,
            orientation_error,
            iterations,
            restarts,
        }
    }

    fn within(&self, pos: f64, ori: f64) -> bool {
        pos <= self.position_tolerance && (matches!(self.task, Task::Position) || ori <= self.orientation_tolerance)
    }

    /// One bounded-LM descent from `s.q`; keeps the best point in `s.best_q` (cost `best`).
    fn attempt(
        &self,
        chain: &Chain,
        target: &IsometryMatrix3<f64>,
        s: &mut IkScratch,
        best: &mut f64,
        iterations: &mut usize,
        deadline: Option<Instant>,
    ) -> Attempt {
        let task = &self.task;
        let n = s.n;
        let mut t = chain.jacobian_into(&s.q, JacobianFrame::Base, &mut s.jac);
        residual_into(task, &t, target, s.e.as_mut_slice());
        let mut cost = 0.5 * s.e.norm_squared();
        let mut lambda = -1.0;
        let mut nu = 2.0;
        let mut window_cost = cost;
        let mut since_window = 0;
        for _ in 0..self.max_iterations {
            if cost < *best {
                *best = cost;
                s.best_q.copy_from_slice(&s.q);
            }
            let (pos, ori) = residual_errors(task, s.e.as_slice());
            if self.within(pos, ori) {
                return Attempt::Converged;
            }
            if since_window % 4 == 0 && deadline.is_some_and(|d| Instant::now() >= d) {
                return Attempt::OutOfTime;
            }
            if since_window == STALL_WINDOW {
                if cost > 0.5 * window_cost {
                    return Attempt::Stalled;
                }
                window_cost = cost;
                since_window = 0;
            }
            since_window += 1;
            *iterations += 1;
            // Normal equations A = JᵀJ, g = Jᵀe.
            residual_jacobian_into(task, &s.jac, &t, target, &mut s.je);
            s.a.gemm_tr(1.0, &s.je, &s.je, 0.0);
            s.je.tr_mul_to(&s.e, &mut s.g);
            if lambda < 0.0 {
                lambda = 1e-3 * (0..n).map(|i| s.a[(i, i)]).fold(1e-12, f64::max);
            }
            // Joints on a bound that the gradient pushes outward are frozen for this step.
            for i in 0..n {
                s.frozen[i] = (s.q[i] <= s.lower[i] && s.g[i] < 0.0) || (s.q[i] >= s.upper[i] && s.g[i] > 0.0);
            }
            s.lhs.copy_from(&s.a);
            for i in 0..n {
                s.dq[i] = s.g[i];
                if s.frozen[i] {
                    for k in 0..n {
                        s.lhs[(i, k)] = 0.0;
                        s.lhs[(k, i)] = 0.0;
                    }
                    s.lhs[(i, i)] = 1.0;
                    s.dq[i] = 0.0;
                } else {
                    s.lhs[(i, i)] += lambda;
                }
            }
            // The crate's one Cholesky (`linalg::cholesky`); the symmetric column-major `lhs` is its
            // own row-major transpose.
            if crate::linalg::cholesky::factor_in_place(s.lhs.as_mut_slice(), n).is_err() {
                lambda *= nu;
                nu *= 2.0;
                continue;
            }
            crate::linalg::cholesky::solve_in_place(s.lhs.as_slice(), n, s.dq.as_mut_slice());
            for i in 0..n {
                s.q_trial[i] = (s.q[i] + s.dq[i]).clamp(s.lower[i], s.upper[i]);
                s.dq[i] = s.q_trial[i] - s.q[i];
            }
            let t_trial = chain.jacobian_into(&s.q_trial, JacobianFrame::Base, &mut s.jac_trial);
            residual_into(task, &t_trial, target, s.e_trial.as_mut_slice());
            let cost_trial = 0.5 * s.e_trial.norm_squared();
            // Predicted decrease of the linear model for the projected step: gᵀδ − ½ δᵀAδ.
            let mut predicted = 0.0;
            for i in 0..n {
                let mut ad = 0.0;
                for k in 0..n {
                    ad += s.a[(i, k)] * s.dq[k];
                }
                predicted += s.dq[i] * (s.g[i] - 0.5 * ad);
            }
            if cost_trial < cost {
                let rho = if predicted > 0.0 {
                    (cost - cost_trial) / predicted
                } else {
                    0.5
                };
                lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                nu = 2.0;
                std::mem::swap(&mut s.q, &mut s.q_trial);
                std::mem::swap(&mut s.jac, &mut s.jac_trial);
                std::mem::swap(&mut s.e, &mut s.e_trial);
                cost = cost_trial;
                t = t_trial;
            } else {
                lambda *= nu;
                nu *= 2.0;
                if lambda > 1e10 {
                    return Attempt::Stalled;
                }
            }
        }
        if cost < *best {
            *best = cost;
            s.best_q.copy_from_slice(&s.q);
        }
        let (pos, ori) = residual_errors(task, s.e.as_slice());
        if self.within(pos, ori) {
            Attempt::Converged
        } else if deadline.is_some_and(|d| Instant::now() >= d) {
            Attempt::OutOfTime
        } else {
            Attempt::Stalled
        }
    }
}

/// Checks a batch: one start for all targets or one per target, each of the chain's length and
/// finite, and finite target poses.
pub(crate) fn check_batch(chain: &Chain, targets: &[IsometryMatrix3<f64>], q0s: &[Vec<f64>]) -> Result<()> {
    if q0s.len() != 1 && q0s.len() != targets.len() {
        return Err(Error::shape(
            "q0",
            format!("1 or {} start configurations", targets.len()),
            q0s.len(),
        ));
    }
    for q0 in q0s {
        check_vector("q0", q0, chain.dof())?;
    }
    for t in targets {
        check_finite("target pose", t.rotation.matrix().as_slice())?;
        check_finite("target pose", t.translation.vector.as_slice())?;
    }
    Ok(())
}

/// A uniform sample in [lower, upper]; unbounded revolute joints sample (−π, π], unbounded
/// prismatic ones (−1, 1) m around the finite bound or 0.
fn random_in(rng: &mut fastrand::Rng, lower: f64, upper: f64, kind: JointType) -> f64 {
    let u = rng.f64();
    match (lower.is_finite(), upper.is_finite()) {
        (true, true) => lower + (upper - lower) * u,
        _ => {
            let half = if kind == JointType::Revolute {
                std::f64::consts::PI
            } else {
                1.0
            };
            let centre = if lower.is_finite() {
                lower + half
            } else if upper.is_finite() {
                upper - half
            } else {
                0.0
            };
            centre + half * (2.0 * u - 1.0)
        }
    }
}
