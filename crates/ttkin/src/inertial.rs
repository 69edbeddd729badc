//! Rigid-body inertial parameters of a link, expressed in the link's own frame.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Mass (kg), centre of mass (m, link frame) and rotational inertia about the centre of mass
/// (kg·m², axes of the link frame) of one link.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Inertial {
    /// Mass in kg (> 0).
    pub mass: f64,
    /// Centre of mass in the link frame, m.
    pub com: Vector3<f64>,
    /// Inertia tensor about the centre of mass, link-frame axes, kg·m² (symmetric positive definite).
    pub inertia: Matrix3<f64>,
}

impl Inertial {
    /// Builds from mass, centre of mass and the six independent tensor entries (ixx, iyy, izz, ixy, ixz, iyz).
    pub fn new(mass: f64, com: [f64; 3], i: [f64; 6]) -> Self {
        let [ixx, iyy, izz, ixy, ixz, iyz] = i;
        Inertial {
            mass,
            com: Vector3::from(com),
            inertia: Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz),
        }
    }

    /// The six independent entries (ixx, iyy, izz, ixy, ixz, iyz), kg·m².
    pub fn components(&self) -> [f64; 6] {
        let i = &self.inertia;
        [i[(0, 0)], i[(1, 1)], i[(2, 2)], i[(0, 1)], i[(0, 2)], i[(1, 2)]]
    }

    /// Checks that the parameters describe a physical body: finite, positive mass, symmetric tensor
    /// with positive principal moments that satisfy the triangle inequality.
    pub fn validate(&self, link: &str) -> Result<()> {
        let what = format!("inertial of link '{link}'");
        let mut all = vec![self.mass];
        all.extend(self.com.iter());
        all.extend(self.inertia.iter());
        crate::error::check_finite(&what, &all)?;
        if self.mass <= 0.0 {
            return Err(Error::Model(format!("{what}: mass must be > 0 kg, got {}", self.mass)));
        }
        let asym = (self.inertia - self.inertia.transpose()).abs().max();
        if asym > 1e-12 * (1.0 + self.inertia.abs().max()) {
            return Err(Error::Model(format!("{what}: inertia tensor is not symmetric")));
        }
        let eig = self.inertia.symmetric_eigenvalues();
        let (a, b, c) = (eig[0], eig[1], eig[2]);
        let scale = a.abs().max(b.abs()).max(c.abs()).max(f64::MIN_POSITIVE);
        if a <= 0.0 || b <= 0.0 || c <= 0.0 {
            return Err(Error::Model(format!(
                "{what}: inertia tensor must be positive definite, principal moments are {a:.4e}, {b:.4e}, {c:.4e} kg·m²"
            )));
        }
        let tol = 1e-12 * scale;
        if a + b < c - tol || a + c < b - tol || b + c < a - tol {
            return Err(Error::Model(format!(
                "{what}: principal moments {a:.4e}, {b:.4e}, {c:.4e} kg·m² break the triangle inequality (each must be ≤ the sum of the other two)"
            )));
        }
        Ok(())
    }
}

impl Inertial {
    /// The same body described in another frame: `t` maps the current frame into the new one
    /// (new-frame pose of the current frame).
    pub fn transformed(&self, t: &nalgebra::IsometryMatrix3<f64>) -> Inertial {
        let r = t.rotation.matrix();
        Inertial {
            mass: self.mass,
            com: (t * nalgebra::Point3::from(self.com)).coords,
            inertia: r * self.inertia * r.transpose(),
        }
    }

    /// One body from two rigidly joined bodies in the same frame (parallel-axis theorem).
    pub fn combine(&self, other: &Inertial) -> Inertial {
        let mass = self.mass + other.mass;
        let com = (self.com * self.mass + other.com * other.mass) / mass;
        let shift = |b: &Inertial| {
            let d = b.com - com;
            b.mass * (Matrix3::identity() * d.dot(&d) - d * d.transpose())
        };
        Inertial {
            mass,
            com,
            inertia: self.inertia + shift(self) + other.inertia + shift(other),
        }
    }
}
