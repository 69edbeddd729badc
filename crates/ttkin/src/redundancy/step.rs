//! One weighted least-norm step of a whole-body model: task Jacobian at the current pose,
//! Chan–Dubey weights, solve ([`WlsStep`]).

// Index loops over several per-joint arrays read like the equations.
#![allow(clippy::needless_range_loop)]

use super::limits::{chan_dubey_weight, Weighting};
use super::solver::{Damping, StepReport, WlsSolver};
use super::SINGULAR_SIGMA;
use crate::error::{Error, Result};

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
        task.check_inputs(n)?;
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
        if self.weighting == Weighting::ChanDubey {
            // H of Chan & Dubey (1995) is defined inside the limits only; outside, its gradient
            // changes sign and the weights steer the step anywhere (issue 14: a silent residual).
            for (k, &(lo, hi)) in self.limits.iter().enumerate() {
                if let Some(c) = self.model.input_coordinate(k) {
                    if !(lo..=hi).contains(&q[c]) {
                        return Err(Error::invalid(
                            "q",
                            format!(
                                "q[{c}] = {} is outside its joint limits [{lo}, {hi}]: the Chan–Dubey \
                                 joint-limit weights are undefined there; start inside the limits or use \
                                 weights='none'",
                                q[c]
                            ),
                        ));
                    }
                }
            }
        }
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
