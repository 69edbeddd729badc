//! Closed-loop inverse kinematics (Siciliano's CLIK) of a task trajectory at a fixed control rate:
//! at each sample t_k, with e_k the task residual against x_d(t_k) and f the feed-forward of the
//! target velocity in residual coordinates ([`Task::feedforward`]),
//! u_k = W⁻¹J_eᵀ(J_eW⁻¹J_eᵀ + λ²I)⁻¹(f + K·e_k) + null-space motion, then q_{k+1} = q_k ⊕ u_k·dt.
//!
//! The feed-forward is taken at mid-interval ((f_k + f_{k+1})/2), so the target's acceleration
//! enters the step to second order; the default gain is K = 1/dt (one-step correction of the
//! discrete loop, stable for 0 < K·dt < 2). Every input stays inside a box made of its speed limit
//! and of its position limits reached within one step, so no sample ever lies beyond a limit; the
//! solver ([`WlsSolver`]) saturates inputs in the null space and scales the task only as a last
//! resort. The result carries a [`ClikStatus`] instead of garbage when the task cannot be followed.

// Numeric loops index several parallel arrays by the same input index: keep them as loops.
#![allow(clippy::needless_range_loop)]

use nalgebra::{IsometryMatrix3, Matrix6xX};

use crate::error::{Error, Result};
use crate::redundancy::{chan_dubey_weight, limit_gradient, manipulability, Damping, StepReport, Weighting, WlsSolver};
use crate::task::Task;

pub mod trajectory;

use crate::wholebody::{WholeBody, WholeBodyData};
pub use trajectory::TaskTrajectory;

/// Options of [`track`].
#[derive(Debug, Clone, PartialEq)]
pub struct ClikOptions {
    /// Feedback gain K (1/s); `None` for 1/dt.
    pub gain: Option<f64>,
    /// Weighting of the least-norm solution.
    pub weighting: Weighting,
    /// Singularity-robust damping.
    pub damping: Damping,
    /// Constant per-input cost factors (nu values, > 0), multiplied into W; e.g. a large value on
    /// the base inputs makes the heavy base move little. `None` for all 1.
    pub input_weights: Option<Vec<f64>>,
    /// Gain (1/s) of the null-space motion −k·∂H/∂q away from the joint limits (0 = off).
    pub limit_gain: f64,
    /// Gain of the null-space motion +k·∂w/∂q up the manipulability w = √det(J_e J_eᵀ) of the task
    /// (0 = off; the gradient takes 2 extra Jacobians per arm joint by central differences).
    pub manipulability_gain: f64,
    /// Keep every input inside its speed limit and every joint inside its position limits.
    pub respect_limits: bool,
    /// Tracking error (norm of the residual, task units) at which the motion is declared failed.
    pub max_error: f64,
    /// Add one Gauss–Newton corrector per sample: predict the pose at the next sample, and
    /// correct the inputs by the weighted least-norm solution for the predicted residual / dt
    /// (same weights and boxes). Removes the O(dt²) error of the forward-Euler step.
    pub corrector: bool,
}

impl Default for ClikOptions {
    /// K = 1/dt, Chan–Dubey weights, default damping, no base cost, no null-space motion, limits
    /// respected, failure above an error of 0.05, with the corrector.
    fn default() -> Self {
        ClikOptions {
            gain: None,
            weighting: Weighting::ChanDubey,
            damping: Damping::default(),
            input_weights: None,
            limit_gain: 0.0,
            manipulability_gain: 0.0,
            respect_limits: true,
            max_error: 0.05,
            corrector: true,
        }
    }
}

/// How a tracked motion ended.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ClikStatus {
    /// Every sample tracked with the full task velocity.
    Completed,
    /// Completed, but at some samples the limits allowed only part of the task velocity.
    Saturated {
        /// Time of the first scaled sample (s).
        first_time: f64,
        /// Number of scaled samples.
        samples: usize,
        /// Smallest task scale used.
        min_scale: f64,
    },
    /// Stopped: the arrays end at `time`.
    Failed {
        /// Time of the last recorded sample (s).
        time: f64,
        /// Why.
        reason: String,
    },
}

impl ClikStatus {
    /// `"completed"`, `"saturated"` or `"failed"`.
    pub fn name(&self) -> &'static str {
        match self {
            ClikStatus::Completed => "completed",
            ClikStatus::Saturated { .. } => "saturated",
            ClikStatus::Failed { .. } => "failed",
        }
    }
}

impl std::fmt::Display for ClikStatus {
    /// A sentence on how the motion ended.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ClikStatus::Completed => f.write_str("completed: full task velocity at every sample"),
            ClikStatus::Saturated {
                first_time,
                samples,
                min_scale,
            } => write!(
                f,
                "saturated: limits scaled the task velocity at {samples} samples from t = {first_time:.3} s \
                 (smallest scale {min_scale:.3})"
            ),
            ClikStatus::Failed { time, reason } => write!(f, "failed at t = {time:.3} s: {reason}"),
        }
    }
}

/// Arrays of a tracked motion, row-major, one row per sample (N rows).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClikResult {
    /// Sample times (s), N.
    pub time: Vec<f64>,
    /// Configurations, N × nq.
    pub q: Vec<f64>,
    /// Inputs commanded at each sample (m/s, rad/s), N × nu (was `qdot`; the serde form reads
    /// both names).
    #[serde(alias = "qdot")]
    pub qd: Vec<f64>,
    /// Task coordinates reached, N × dim.
    pub x: Vec<f64>,
    /// Norm of the task residual (task units: m and rad mixed), N.
    pub error: Vec<f64>,
    /// Position part of the residual (m), N.
    pub position_error: Vec<f64>,
    /// Orientation part of the residual (rad; 0 for the position task), N.
    pub orientation_error: Vec<f64>,
    /// Distance of each arm joint to its nearer position limit (m or rad), N × arm dof.
    pub margin: Vec<f64>,
    /// Task scale used at each sample (1 = full task velocity), N.
    pub scale: Vec<f64>,
    /// Smallest singular value estimate at each sample, N.
    pub sigma_min: Vec<f64>,
    /// How it ended.
    pub status: ClikStatus,
    /// Columns of `q`.
    pub nq: usize,
    /// Columns of `qdot`.
    pub nu: usize,
    /// Columns of `x`.
    pub dim: usize,
    /// Columns of `margin`.
    pub n_margin: usize,
}

impl ClikResult {
    /// Deprecated name of the field [`ClikResult::qd`] (inputs, N × nu, m/s and rad/s).
    #[deprecated(note = "one name per concept: use the field `qd`")]
    pub fn qdot(&self) -> &[f64] {
        &self.qd
    }

    /// Number of samples N.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True when no sample was recorded.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
}

/// One CLIK controller: model, task, options and every scratch buffer (a step allocates nothing).
#[derive(Debug, Clone)]
pub struct Clik<'a> {
    model: &'a WholeBody,
    task: Task,
    options: ClikOptions,
    solver: WlsSolver,
    data: WholeBodyData,
    jac6: Matrix6xX<f64>,
    jtask: Vec<f64>,
    limits: Vec<(f64, f64)>,
    speed: Vec<f64>,
    base_w: Vec<f64>,
    w: Vec<f64>,
    z: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    e: [f64; 6],
    cmd: [f64; 6],
    q_pred: Vec<f64>,
    du: Vec<f64>,
    ff: [f64; 6],
    jac6_fd: Matrix6xX<f64>,
    jtask_fd: Vec<f64>,
}

impl<'a> Clik<'a> {
    /// A controller of `task` on `model` with `options` (validated here).
    pub fn new(model: &'a WholeBody, task: Task, options: ClikOptions) -> Result<Self> {
        let nu = model.nu();
        let base_w = match &options.input_weights {
            None => vec![1.0; nu],
            Some(v) => {
                crate::error::check_vector("input_weights", v, nu)?;
                if let Some(x) = v.iter().find(|x| !(**x > 0.0)) {
                    return Err(Error::invalid(
                        "input_weights",
                        format!("every weight must be > 0, got {x}"),
                    ));
                }
                v.clone()
            }
        };
        if let Some(k) = options.gain {
            crate::error::check_positive("gain", k, "1/s")?;
        }
        if !(options.limit_gain >= 0.0 && options.limit_gain.is_finite()) {
            return Err(Error::invalid("limit_gain", "must be finite and ≥ 0"));
        }
        if !(options.manipulability_gain >= 0.0 && options.manipulability_gain.is_finite()) {
            return Err(Error::invalid("manipulability_gain", "must be finite and ≥ 0"));
        }
        if !(options.max_error > 0.0) {
            return Err(Error::invalid("max_error", "must be > 0"));
        }
        let m = task.dim();
        task.check_inputs(nu)?;
        Ok(Clik {
            model,
            task,
            solver: WlsSolver::new(m, nu, options.damping)?,
            options,
            data: model.data(),
            jac6: Matrix6xX::zeros(nu),
            jtask: vec![0.0; m * nu],
            limits: model.input_position_limits(),
            speed: model.input_speed_limits(),
            base_w,
            w: vec![1.0; nu],
            z: vec![0.0; nu],
            lo: vec![0.0; nu],
            hi: vec![0.0; nu],
            e: [0.0; 6],
            cmd: [0.0; 6],
            q_pred: vec![0.0; model.nq()],
            du: vec![0.0; nu],
            ff: [0.0; 6],
            jac6_fd: Matrix6xX::zeros(nu),
            jtask_fd: vec![0.0; m * nu],
        })
    }

    /// One control step at configuration `q` toward the target pose `target` with feed-forward
    /// `ff` (residual coordinates) over `dt` s; `prev` holds the previous inputs (for the
    /// Chan–Dubey direction test) and receives the new ones. Returns the tool pose, the report.
    fn step(
        &mut self,
        q: &[f64],
        target_x: &[f64],
        next_x: Option<&[f64]>,
        gain: f64,
        dt: f64,
        prev: &mut [f64],
    ) -> (IsometryMatrix3<f64>, StepReport) {
        let m = self.task.dim();
        let t = self.model.jacobian_into(q, &mut self.data, &mut self.jac6);
        let target = self.task.target_pose(target_x, &t);
        self.task.error_into(&t, &target, &mut self.e[..m]);
        self.task.jacobian_into(&self.jac6, &t, &target, &mut self.jtask);
        for i in 0..m {
            self.cmd[i] = self.ff[i] + gain * self.e[i];
        }
        let nu = self.model.nu();
        for k in 0..nu {
            let (lo, hi) = self.limits[k];
            let pos = self.model.input_coordinate(k).map_or(0.0, |c| q[c]);
            let cd = match self.options.weighting {
                Weighting::None => 1.0,
                Weighting::ChanDubey => chan_dubey_weight(pos, lo, hi, prev[k]),
            };
            self.w[k] = self.base_w[k] * cd;
            self.z[k] = -self.options.limit_gain * limit_gradient(pos, lo, hi);
            if self.options.respect_limits {
                let shrink = 1.0 - 1e-9;
                self.lo[k] = (-self.speed[k]).max((lo - pos) * shrink / dt).min(0.0);
                self.hi[k] = self.speed[k].min((hi - pos) * shrink / dt).max(0.0);
            } else {
                self.lo[k] = f64::NEG_INFINITY;
                self.hi[k] = f64::INFINITY;
            }
        }
        if self.options.manipulability_gain > 0.0 {
            self.add_manipulability_gradient(q);
        }
        let z = if self.options.limit_gain > 0.0 || self.options.manipulability_gain > 0.0 {
            Some(&self.z[..])
        } else {
            None
        };
        let mut report = self
            .solver
            .solve(&self.jtask, &self.w, &self.cmd[..m], z, &self.lo, &self.hi, prev);
        if let (true, Some(next_x)) = (self.options.corrector, next_x) {
            // Gauss–Newton corrector toward the next sample, inside the remaining box.
            self.q_pred.copy_from_slice(q);
            self.model.integrate(&mut self.q_pred, prev, dt);
            let tp = self.model.tool_pose_unchecked(&self.q_pred);
            let next = self.task.target_pose(next_x, &tp);
            // in the tangent basis of the Jacobian's target (the cached factorisation is reused)
            self.task.error_in_basis_into(&tp, &next, &target, &mut self.cmd[..m]);
            for i in 0..m {
                self.cmd[i] /= dt;
            }
            for k in 0..nu {
                self.lo[k] -= prev[k];
                self.hi[k] -= prev[k];
            }
            let rep2 = self
                .solver
                .resolve(&self.jtask, &self.cmd[..m], None, &self.lo, &self.hi, &mut self.du);
            for k in 0..nu {
                prev[k] += self.du[k];
            }
            report.scale = report.scale.min(rep2.scale);
            report.saturated = report.saturated.max(rep2.saturated);
        }
        (t, report)
    }

    /// Adds k·∂w/∂q (central differences, h = 1e-6) to the null-space motion `z` for every input
    /// that drives a configuration coordinate; base inputs get none (w does not change with the
    /// base pose).
    fn add_manipulability_gradient(&mut self, q: &[f64]) {
        let h = 1e-6;
        let m = self.task.dim();
        self.q_pred.copy_from_slice(q);
        for k in 0..self.model.nu() {
            let Some(c) = self.model.input_coordinate(k) else {
                continue;
            };
            let mut w = [0.0; 2];
            for (side, sign) in [(0, 1.0), (1, -1.0)] {
                self.q_pred[c] = q[c] + sign * h;
                let t = self
                    .model
                    .jacobian_into(&self.q_pred, &mut self.data, &mut self.jac6_fd);
                self.task.jacobian_into(&self.jac6_fd, &t, &t, &mut self.jtask_fd);
                w[side] = manipulability(&self.jtask_fd, m);
            }
            self.q_pred[c] = q[c];
            self.z[k] += self.options.manipulability_gain * (w[0] - w[1]) / (2.0 * h);
        }
    }

    /// Tracks `trajectory` from `q0`; see the module doc. Errors only for bad input (shapes,
    /// NaN, a start outside the limits); an infeasible motion comes back as a status.
    pub fn run(&mut self, q0: &[f64], trajectory: &TaskTrajectory) -> Result<ClikResult> {
        if trajectory.task() != self.task {
            return Err(Error::invalid(
                "task_trajectory",
                "its task differs from the controller's task",
            ));
        }
        if self.options.respect_limits {
            self.model.check_within_limits(q0)?;
        } else {
            self.model.check_q("q0", q0)?;
        }
        let (nq, nu, m) = (self.model.nq(), self.model.nu(), self.task.dim());
        let na = self.model.arm().dof();
        let nb = self.model.base_coordinates();
        let arm_limits = self.model.arm().limits();
        let count = trajectory.len();
        let dt = 1.0 / trajectory.rate_hz();
        let gain = self.options.gain.unwrap_or(1.0 / dt);
        let mut r = ClikResult {
            time: Vec::with_capacity(count),
            q: Vec::with_capacity(count * nq),
            qd: Vec::with_capacity(count * nu),
            x: Vec::with_capacity(count * m),
            error: Vec::with_capacity(count),
            position_error: Vec::with_capacity(count),
            orientation_error: Vec::with_capacity(count),
            margin: Vec::with_capacity(count * na),
            scale: Vec::with_capacity(count),
            sigma_min: Vec::with_capacity(count),
            status: ClikStatus::Completed,
            nq,
            nu,
            dim: m,
            n_margin: na,
        };
        let mut q = q0.to_vec();
        let mut u = vec![0.0; nu];
        let mut ff_next = [0.0; 6];
        let mut ff_next_here = [0.0; 6];
        let mut coords = [0.0; 6];
        let (mut first, mut scaled, mut min_scale) = (f64::NAN, 0usize, 1.0f64);
        self.task.feedforward(trajectory.x(0), trajectory.xdot(0), &mut ff_next);
        for k in 0..count {
            let time = k as f64 * dt;
            let ff_k = ff_next;
            if k + 1 < count {
                self.task
                    .feedforward(trajectory.x(k + 1), trajectory.xdot(k + 1), &mut ff_next);
                // the average in one tangent basis: that of sample k, which the step's residual uses
                self.task.feedforward_in_basis(
                    trajectory.x(k + 1),
                    trajectory.xdot(k + 1),
                    trajectory.x(k),
                    &mut ff_next_here,
                );
                for i in 0..m {
                    self.ff[i] = 0.5 * (ff_k[i] + ff_next_here[i]);
                }
            } else {
                self.ff[..m].copy_from_slice(&ff_k[..m]);
            }
            let next = if k + 1 < count { Some(trajectory.x(k + 1)) } else { None };
            let (t, rep) = self.step(&q, trajectory.x(k), next, gain, dt, &mut u);
            let pe = self.e[..3].iter().map(|v| v * v).sum::<f64>().sqrt();
            let oe = self.e[3..m].iter().map(|v| v * v).sum::<f64>().sqrt();
            let err = (pe * pe + oe * oe).sqrt();
            self.task.coordinates(&t, &mut coords);
            r.time.push(time);
            r.q.extend_from_slice(&q);
            r.qd.extend_from_slice(&u);
            r.x.extend_from_slice(&coords[..m]);
            r.error.push(err);
            r.position_error.push(pe);
            r.orientation_error.push(oe);
            r.margin
                .extend(arm_limits.iter().zip(&q[nb..]).map(|(l, &qi)| l.margin(qi)));
            r.scale.push(rep.scale);
            r.sigma_min.push(rep.sigma_min);
            if !(err <= self.options.max_error) || u.iter().any(|v| !v.is_finite()) {
                r.status = ClikStatus::Failed {
                    time,
                    reason: format!(
                        "tracking error {err:.3e} exceeds {:.3e} (target out of reach, or limits/singularity)",
                        self.options.max_error
                    ),
                };
                return Ok(r);
            }
            if rep.scale < 1.0 {
                if scaled == 0 {
                    first = time;
                }
                scaled += 1;
                min_scale = min_scale.min(rep.scale);
            }
            if k + 1 < count {
                self.model.integrate(&mut q, &u, dt);
            }
        }
        if scaled > 0 {
            r.status = ClikStatus::Saturated {
                first_time: first,
                samples: scaled,
                min_scale,
            };
        }
        Ok(r)
    }
}

/// Tracks `trajectory` with `model` from `q0`: builds a [`Clik`] and runs it.
pub fn track(model: &WholeBody, q0: &[f64], trajectory: &TaskTrajectory, options: ClikOptions) -> Result<ClikResult> {
    Clik::new(model, trajectory.task(), options)?.run(q0, trajectory)
}
