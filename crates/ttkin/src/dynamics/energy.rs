//! Kinetic and potential energy of the chain (for energy-conservation checks of the integrator).

// Index loops over several per-joint arrays read like the equations.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector3;

use super::model::{vec3, Dynamics, DynamicsData};
use crate::error::Result;

impl Dynamics {
    /// Kinetic energy ½·q̇ᵀ·M(q)·q̇ (J), armature included.
    pub fn kinetic_energy(&self, data: &mut DynamicsData, q: &[f64], qd: &[f64]) -> Result<f64> {
        self.check_state(data, q, qd)?;
        self.bias_unchecked(data, q, qd, &Vector3::zeros(), None);
        let mut e = 0.0;
        for i in 0..self.dof() {
            let (m, f) = self.bodies[i].apply(&data.w[i], &data.v[i]);
            e += 0.5 * (data.w[i].dot(&m) + data.v[i].dot(&f)) + 0.5 * self.armature[i] * qd[i] * qd[i];
        }
        Ok(e)
    }

    /// Potential energy −Σ m_i·g·c_i (J) of the links in the field `gravity` (m/s², base frame),
    /// zero with every centre of mass at the base origin.
    pub fn potential_energy(&self, q: &[f64], gravity: &[f64; 3]) -> Result<f64> {
        let g = vec3("gravity", gravity)?;
        let frames = self.chain.fk_all(q)?;
        Ok(frames
            .iter()
            .zip(&self.links)
            .map(|(t, l)| -l.mass * g.dot(&(t * nalgebra::Point3::from(l.com)).coords))
            .sum())
    }
}
