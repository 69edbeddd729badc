//! The joint-space mass matrix M(q) by the composite rigid body algorithm (Featherstone 2008,
//! §6.2), armature on the diagonal.

use nalgebra::{DMatrix, Vector3};

use super::model::{Dynamics, DynamicsData};
use crate::error::{check_vector, Result};
use crate::joint::JointType;

impl Dynamics {
    /// Composite rigid body algorithm without checks; M (with armature) in `data.mass`.
    pub(super) fn crba_unchecked(&self, data: &mut DynamicsData, q: &[f64]) {
        let n = self.dof();
        self.place(data, q);
        data.composite.copy_from_slice(&self.bodies);
        let z = Vector3::z();
        for i in (0..n).rev() {
            let body = data.composite[i];
            // F = I_c·S_i, a force in F_i.
            let (mut m, mut f) = match self.kinds[i] {
                JointType::Revolute => body.apply(&z, &Vector3::zeros()),
                JointType::Prismatic => body.apply(&Vector3::zeros(), &z),
            };
            data.mass[(i, i)] = self.project(i, &m, &f) + self.armature[i];
            for j in (0..i).rev() {
                // Carry F from F_{j+1} into F_j and project on S_j.
                let r = &data.rot[j + 1];
                f = r * f;
                m = r * m + data.pos[j + 1].cross(&f);
                let mij = self.project(j, &m, &f);
                data.mass[(i, j)] = mij;
                data.mass[(j, i)] = mij;
            }
            if i > 0 {
                let parent = body.in_parent(&data.rot[i], &data.pos[i]);
                data.composite[i - 1].add(&parent);
            }
        }
    }

    /// Sᵀ·(moment; force) for joint `i`.
    #[inline(always)]
    pub(super) fn project(&self, i: usize, m: &Vector3<f64>, f: &Vector3<f64>) -> f64 {
        match self.kinds[i] {
            JointType::Revolute => m.z,
            JointType::Prismatic => f.z,
        }
    }

    /// Joint-space mass matrix M(q) (kg·m², kg, kg·m), symmetric positive definite, armature on
    /// the diagonal (composite rigid body algorithm, Pinocchio's `crba`).
    pub fn mass_matrix<'d>(&self, data: &'d mut DynamicsData, q: &[f64]) -> Result<&'d DMatrix<f64>> {
        self.check_data(data)?;
        check_vector("q", q, self.dof())?;
        self.crba_unchecked(data, q);
        Ok(&data.mass)
    }
}
