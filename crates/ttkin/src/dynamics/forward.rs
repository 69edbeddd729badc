//! Forward dynamics q̈ = M(q)⁻¹(τ − h(q, q̇)) by a Cholesky solve of the mass matrix
//! ([`crate::linalg::cholesky`]), the semi-implicit Euler step and the simulation of a torque
//! sequence.

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DVector, Vector3};

use super::model::{check_wrench, vec3, Dynamics, DynamicsData};
use super::Wrench;
use crate::error::check_rows as batch_count;
use crate::error::{check_finite, Error, Result};

impl Dynamics {
    /// Forward dynamics without checks: q̈ = M⁻¹(τ − τ_f − h) in `data.qdd`, the friction τ_f
    /// only when `friction` is true.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn forward_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        gravity: &Vector3<f64>,
        wrench: Option<&Wrench>,
        friction: bool,
    ) -> Result<()> {
        self.bias_unchecked(data, q, qd, gravity, wrench);
        for i in 0..self.dof() {
            let tf = if friction {
                self.drives[i].map_or(0.0, |d| d.friction(qd[i]))
            } else {
                0.0
            };
            data.qdd[i] = tau[i] - tf - data.tau[i];
        }
        self.crba_unchecked(data, q);
        data.solve_mass_matrix()
    }

    /// Forward dynamics: joint accelerations q̈ = M(q)⁻¹(τ − h(q, q̇) + Jᵀw) (rad/s², m/s²) under
    /// joint torques `tau` (N·m, N), `gravity` (m/s², base frame) and an optional tool `wrench`;
    /// no friction (subtract [`Dynamics::friction`] from `tau` to include it). Cholesky solve of
    /// the mass matrix; the inverse of [`Dynamics::rnea`].
    pub fn forward_dynamics<'d>(
        &self,
        data: &'d mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
    ) -> Result<&'d DVector<f64>> {
        let g = self.check_call(data, q, qd, ("tau", tau), gravity)?;
        check_wrench(wrench)?;
        self.forward_unchecked(data, q, qd, tau, &g, wrench, false)?;
        Ok(&data.qdd)
    }

    /// One semi-implicit (symplectic) Euler step of length `dt` s under joint torques `tau`:
    /// q̇ ← q̇ + dt·q̈(q, q̇, τ − friction), then q ← q + dt·q̇ (the new speed). Friction is applied
    /// when `friction` is true (Coulomb friction as b·q̇ + f_c·sign(q̇): expect chatter near rest).
    /// The energy error of a frictionless, torque-free motion stays O(dt) without drift.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &self,
        data: &mut DynamicsData,
        q: &mut [f64],
        qd: &mut [f64],
        tau: &[f64],
        dt: f64,
        gravity: &[f64; 3],
        friction: bool,
    ) -> Result<()> {
        let g = self.check_call(data, q, qd, ("tau", tau), gravity)?;
        check_dt(dt)?;
        self.step_unchecked(data, q, qd, tau, dt, &g, friction)
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn step_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &mut [f64],
        qd: &mut [f64],
        tau: &[f64],
        dt: f64,
        gravity: &Vector3<f64>,
        friction: bool,
    ) -> Result<()> {
        let n = self.dof();
        self.forward_unchecked(data, q, qd, tau, gravity, None, friction)?;
        for i in 0..n {
            qd[i] += dt * data.qdd[i];
            q[i] += dt * qd[i];
        }
        Ok(())
    }

    /// Simulates N semi-implicit Euler steps of `dt` s from (`q0`, `qd0`) under the torques `taus`
    /// (N × n row-major, N·m or N, held over each step). Returns (q, q̇) at the N + 1 instants
    /// 0, dt, …, N·dt, each (N + 1) × n row-major.
    pub fn simulate(
        &self,
        q0: &[f64],
        qd0: &[f64],
        taus: &[f64],
        dt: f64,
        gravity: &[f64; 3],
        friction: bool,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let n = self.dof();
        let mut data = DynamicsData::new(self);
        self.check_state(&data, q0, qd0)?;
        let steps = batch_count("tau", taus, n)?;
        let g = vec3("gravity", gravity)?;
        check_dt(dt)?;
        let (mut q, mut qd) = (q0.to_vec(), qd0.to_vec());
        let mut qs = Vec::with_capacity((steps + 1) * n);
        let mut qds = Vec::with_capacity((steps + 1) * n);
        qs.extend_from_slice(&q);
        qds.extend_from_slice(&qd);
        for tau in taus.chunks_exact(n) {
            self.step_unchecked(&mut data, &mut q, &mut qd, tau, dt, &g, friction)?;
            if let Err(e) = check_finite("simulated state", &q).and_then(|_| check_finite("simulated state", &qd)) {
                return Err(Error::invalid(
                    "dt",
                    format!("the simulation diverged ({e}); use a smaller step"),
                ));
            }
            qs.extend_from_slice(&q);
            qds.extend_from_slice(&qd);
        }
        Ok((qs, qds))
    }
}

/// Checks an integration step: finite and > 0 s.
fn check_dt(dt: f64) -> Result<()> {
    if !(dt > 0.0 && dt.is_finite()) {
        return Err(Error::invalid(
            "dt",
            format!("time step must be finite and > 0 s, got {dt}"),
        ));
    }
    Ok(())
}
