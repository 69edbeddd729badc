//! Dynamics methods of `ttmanip.Robot` (RNEA, mass matrix, gravity, forward dynamics, simulation,
//! torque profile) and the `ttmanip.TorqueProfile` result. Conversion only: the maths is
//! `ttkin::dynamics`.
//!
//! Each robot builds its `ttkin::Dynamics` model once, on the first dynamics call, and keeps one
//! scratch `DynamicsData` behind a mutex for single calls (a second thread that finds it busy
//! uses a fresh one). Batches run in parallel without the GIL.

use std::sync::Arc;

use nalgebra::Vector3;
use pyo3::prelude::*;
use ttkin::{Dynamics, DynamicsData, Wrench};

use crate::convert::{
    array_getters, filled_without_gil, finite_to_numpy, table, to_numpy, vector, Any, Array, F64Array,
};
use crate::errors::{PyResultExt, ShapeError};
use crate::robot::PyRobot;

impl PyRobot {
    /// The dynamic model (an error names the first link without inertia).
    pub(crate) fn dynamics(&self) -> PyResult<&Arc<Dynamics>> {
        self.dynamics.model(&self.chain).py()
    }

    /// Runs `f` with the model and a scratch space.
    fn with_data<T>(&self, f: impl FnOnce(&Dynamics, &mut DynamicsData) -> T) -> PyResult<T> {
        self.dynamics.with_data(&self.chain, f).py()
    }

    /// One configuration through `one` (shared scratch space), or a batch of `count` through
    /// `many` without the GIL: shape `item`, or (count, *item).
    fn one_or_many<'py, O, M>(
        &self,
        py: Python<'py>,
        batch: Option<usize>,
        item: &[usize],
        one: O,
        many: M,
    ) -> PyResult<Array<'py>>
    where
        O: for<'d> FnOnce(&Dynamics, &'d mut DynamicsData) -> ttkin::Result<&'d [f64]>,
        M: FnOnce(&Dynamics, &mut [f64]) -> ttkin::Result<()> + Send,
    {
        match batch {
            // The single-state path allocates nothing for the shape: it is `item`.
            None => self
                .with_data(|dy, d| one(dy, d).map(|v| finite_to_numpy(py, item, v)))?
                .py()?,
            Some(count) => {
                let dy = self.dynamics()?;
                filled_without_gil(py, &crate::convert::batch_shape(count, item), |o| many(dy, o))
            }
        }
    }

    /// Reads several per-configuration arrays that must all be (n,) or all (N, n) with the same N.
    pub(crate) fn states<'py, const K: usize>(
        &self,
        arrays: [(&Any<'py>, &str); K],
    ) -> PyResult<(Vec<F64Array<'py>>, Option<usize>)> {
        crate::convert::same_batch(&arrays, self.chain.dof())
    }
}

/// Gravity argument: None → the robot's own (`Chain::gravity`, base frame), else a 3-vector in
/// the base frame.
pub(crate) fn gravity_arg(g: Option<&Any<'_>>, chain: &ttkin::Chain) -> PyResult<[f64; 3]> {
    match g {
        None => Ok(chain.gravity()),
        Some(g) => {
            let v = vector(g, "gravity", 3)?;
            Ok([v[0], v[1], v[2]])
        }
    }
}

/// Wrench argument: None, or [fx, fy, fz, mx, my, mz] (N, N·m) on the tool, tool-frame axes.
pub(crate) fn wrench_arg(w: Option<&Any<'_>>) -> PyResult<Option<Wrench>> {
    w.map(|w| {
        let v = vector(w, "wrench", 6)?;
        Ok(Wrench {
            force: Vector3::new(v[0], v[1], v[2]),
            torque: Vector3::new(v[3], v[4], v[5]),
        })
    })
    .transpose()
}

/// A `#[pymethods]` block of the inverse-dynamics methods: one signature (q, qd, qdd of shape (n,)
/// or (N, n), optional gravity and wrench) and one body, [`PyRobot::inverse`], that differ only in
/// whether joint friction is added.
macro_rules! inverse_dynamics_methods {
    ($( $(#[$doc:meta])* $name:ident => friction: $friction:expr; )*) => {
        #[ttkin_py_guard::guarded]
        #[pymethods]
        impl PyRobot {
            $(
                $(#[$doc])*
                #[pyo3(signature = (q, qd, qdd, gravity=None, wrench=None))]
                fn $name<'py>(
                    &self,
                    py: Python<'py>,
                    q: &Any<'py>,
                    qd: &Any<'py>,
                    qdd: &Any<'py>,
                    gravity: Option<&Any<'py>>,
                    wrench: Option<&Any<'py>>,
                ) -> PyResult<Array<'py>> {
                    self.inverse(py, q, qd, qdd, gravity, wrench, $friction)
                }
            )*
        }
    };
}

array_getters!(PyRobot, |r| {
    /// (n,) rotor inertia reflected to each joint, G²·J (kg·m² or kg); Pinocchio's model.armature.
    armature => r.chain.armatures(), [r.chain.dof()];
    /// (n,) link masses (kg; NaN where a link has no inertial).
    masses => r.chain.masses(), [r.chain.dof()];
});

inverse_dynamics_methods! {
    /// Inverse dynamics (recursive Newton–Euler): joint torques (N·m) / forces (N) for q, qd, qdd
    /// of shape (n,) or (N, n); rigid bodies plus rotor armature, no friction (Pinocchio's rnea).
    /// `gravity` is a base-frame vector (default the robot's, `Robot.gravity_vector`: (0, 0, −9.81) m/s²
    /// unless its file says otherwise); `wrench` [fx, fy, fz, mx, my,
    /// mz] (N, N·m) is applied to the tool by the environment, tool-frame axes, moment about the
    /// tool point.
    rnea => friction: false;
    /// `rnea` plus joint friction b·q̇ + f_c·sign(q̇): the torques the drives must deliver.
    inverse_dynamics => friction: true;
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyRobot {
    /// Joint-space mass matrix M(q), armature included: (n, n) or (N, n, n).
    fn mass_matrix<'py>(&self, py: Python<'py>, q: &Any<'py>) -> PyResult<Array<'py>> {
        let (a, batch) = self.configs(q, "q")?;
        let n = self.chain.dof();
        let q = a.data();
        self.one_or_many(
            py,
            batch,
            &[n, n],
            |dy, d| dy.mass_matrix(d, q).map(|m| m.as_slice()),
            |dy, o| dy.mass_matrix_batch(q, o),
        )
    }

    /// Gravity torques g(q) (N·m or N) that hold the robot still: (n,) or (N, n).
    #[pyo3(signature = (q, gravity=None))]
    fn gravity<'py>(&self, py: Python<'py>, q: &Any<'py>, gravity: Option<&Any<'py>>) -> PyResult<Array<'py>> {
        let g = gravity_arg(gravity, &self.chain)?;
        let (a, batch) = self.configs(q, "q")?;
        let n = self.chain.dof();
        let q = a.data();
        self.one_or_many(
            py,
            batch,
            &[n],
            |dy, d| dy.gravity(d, q, &g).map(|t| t.as_slice()),
            |dy, o| dy.gravity_batch(q, &g, o),
        )
    }

    /// Coriolis and centrifugal torques C(q, q̇)·q̇ (N·m or N), gravity excluded: (n,) or (N, n).
    fn coriolis<'py>(&self, py: Python<'py>, q: &Any<'py>, qd: &Any<'py>) -> PyResult<Array<'py>> {
        let (arrays, batch) = self.states([(q, "q"), (qd, "qd")])?;
        let (q, qd, n) = (arrays[0].data(), arrays[1].data(), self.chain.dof());
        self.one_or_many(
            py,
            batch,
            &[n],
            |dy, d| dy.coriolis(d, q, qd).map(|t| t.as_slice()),
            |dy, o| dy.coriolis_batch(q, qd, o),
        )
    }

    /// Nonlinear effects h(q, q̇) = C(q, q̇)·q̇ + g(q) (N·m or N): (n,) or (N, n).
    #[pyo3(signature = (q, qd, gravity=None))]
    fn nonlinear_effects<'py>(
        &self,
        py: Python<'py>,
        q: &Any<'py>,
        qd: &Any<'py>,
        gravity: Option<&Any<'py>>,
    ) -> PyResult<Array<'py>> {
        let g = gravity_arg(gravity, &self.chain)?;
        let (arrays, batch) = self.states([(q, "q"), (qd, "qd")])?;
        let (q, qd, n) = (arrays[0].data(), arrays[1].data(), self.chain.dof());
        self.one_or_many(
            py,
            batch,
            &[n],
            |dy, d| dy.nonlinear_effects(d, q, qd, &g).map(|t| t.as_slice()),
            |dy, o| dy.nonlinear_effects_batch(q, qd, &g, o),
        )
    }

    /// Forward dynamics q̈ = M⁻¹(τ − h + Jᵀw) (rad/s², m/s²) for q, qd, tau of shape (n,) or
    /// (N, n); no friction (the inverse of `rnea`). `gravity` and `wrench` as in `rnea`.
    #[pyo3(signature = (q, qd, tau, gravity=None, wrench=None))]
    fn forward_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Any<'py>,
        qd: &Any<'py>,
        tau: &Any<'py>,
        gravity: Option<&Any<'py>>,
        wrench: Option<&Any<'py>>,
    ) -> PyResult<Array<'py>> {
        let g = gravity_arg(gravity, &self.chain)?;
        let w = wrench_arg(wrench)?;
        let (arrays, batch) = self.states([(q, "q"), (qd, "qd"), (tau, "tau")])?;
        let n = self.chain.dof();
        let (q, qd, tau) = (arrays[0].data(), arrays[1].data(), arrays[2].data());
        self.one_or_many(
            py,
            batch,
            &[n],
            |dy, d| dy.forward_dynamics(d, q, qd, tau, &g, w.as_ref()).map(|a| a.as_slice()),
            |dy, o| dy.forward_dynamics_batch(q, qd, tau, &g, w.as_ref(), o),
        )
    }

    /// Joint friction b·q̇ + f_c·sign(q̇) (N·m or N) at speeds qd: (n,) or (N, n).
    fn friction<'py>(&self, py: Python<'py>, qd: &Any<'py>) -> PyResult<Array<'py>> {
        let (a, batch) = self.configs(qd, "qd")?;
        let dy = self.dynamics()?;
        let item = [self.chain.dof()];
        let shape = batch.map_or(item.to_vec(), |count| crate::convert::batch_shape(count, &item));
        let qd = a.data();
        filled_without_gil(py, &shape, |o| dy.friction_batch(qd, o))
    }

    /// Kinetic energy ½ q̇ᵀ M q̇ (J) at one state (n,).
    fn kinetic_energy(&self, q: &Any<'_>, qd: &Any<'_>) -> PyResult<f64> {
        let n = self.chain.dof();
        let (q, qd) = (vector(q, "q", n)?, vector(qd, "qd", n)?);
        crate::convert::finite_scalar(self.with_data(|dy, d| dy.kinetic_energy(d, &q, &qd))?.py()?)
    }

    /// Potential energy −Σ m_i g·c_i (J) at one configuration (n,).
    #[pyo3(signature = (q, gravity=None))]
    fn potential_energy(&self, q: &Any<'_>, gravity: Option<&Any<'_>>) -> PyResult<f64> {
        let g = gravity_arg(gravity, &self.chain)?;
        let q = vector(q, "q", self.chain.dof())?;
        crate::convert::finite_scalar(self.dynamics()?.potential_energy(&q, &g).py()?)
    }

    /// Simulates with the semi-implicit Euler integrator: from q0, qd0 (n,) under torques tau
    /// (N, n) held over steps of dt s; returns (q, qd), each (N + 1, n). `friction` subtracts the
    /// joint friction from tau.
    #[pyo3(signature = (q0, qd0, tau, dt, gravity=None, friction=true))]
    #[allow(clippy::too_many_arguments)]
    fn simulate<'py>(
        &self,
        py: Python<'py>,
        q0: &Any<'py>,
        qd0: &Any<'py>,
        tau: &Any<'py>,
        dt: f64,
        gravity: Option<&Any<'py>>,
        friction: bool,
    ) -> PyResult<(Array<'py>, Array<'py>)> {
        let n = self.chain.dof();
        let g = gravity_arg(gravity, &self.chain)?;
        let (q0, qd0) = (vector(q0, "q0", n)?, vector(qd0, "qd0", n)?);
        let (t, batch) = self.configs(tau, "tau")?;
        if batch.is_none() {
            return Err(ShapeError::new_err(format!(
                "tau: expected shape (N, {n}), one row per step, got {}",
                t.shape_str()
            )));
        }
        let dy = self.dynamics()?;
        let taus = t.data();
        let (qs, qds) = py.detach(|| dy.simulate(&q0, &qd0, taus, dt, &g, friction)).py()?;
        let rows = qs.len() / n;
        Ok((to_numpy(py, &[rows, n], &qs), to_numpy(py, &[rows, n], &qds)))
    }

    /// Drive of each joint as a dict (gear_ratio, rotor_inertia, viscous, coulomb,
    /// torque_constant), or None.
    #[getter]
    fn drives<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::serde_to_python(py, &self.chain.drive_rows())
    }

    /// The same robot with new link inertias: `mass` (n,) kg, `com` (n, 3) m and `inertia`
    /// (n, 3, 3) kg·m² about the centre of mass, all in each link's frame (DH frame i / URDF link i).
    fn with_inertials(&self, mass: &Any<'_>, com: &Any<'_>, inertia: &Any<'_>) -> PyResult<PyRobot> {
        let n = self.chain.dof();
        let (m, c, i) = (
            table(mass, "mass", n, 1)?,
            table(com, "com", n, 3)?,
            table(inertia, "inertia", n, 9)?,
        );
        let inertials = ttkin::tables::inertials_from_columns(&m, &c, &i).py()?;
        Ok(PyRobot::new(self.chain.with_inertials(&inertials).py()?))
    }

    /// The same robot with new drives, one value per joint (n,): gear ratio G (> 0), rotor inertia
    /// (kg·m², motor side), viscous (N·m·s/rad or N·s/m) and Coulomb (N·m or N) friction (joint
    /// side), torque constant (N·m/A; NaN for unknown).
    #[pyo3(signature = (gear_ratio, rotor_inertia=None, viscous=None, coulomb=None, torque_constant=None))]
    fn with_drives(
        &self,
        gear_ratio: &Any<'_>,
        rotor_inertia: Option<&Any<'_>>,
        viscous: Option<&Any<'_>>,
        coulomb: Option<&Any<'_>>,
        torque_constant: Option<&Any<'_>>,
    ) -> PyResult<PyRobot> {
        let n = self.chain.dof();
        let column = |obj: Option<&Any<'_>>, what: &str| -> PyResult<Option<Vec<f64>>> {
            obj.map(|o| vector(o, what, n)).transpose()
        };
        let g = vector(gear_ratio, "gear_ratio", n)?;
        let (j, b, c) = (
            column(rotor_inertia, "rotor_inertia")?,
            column(viscous, "viscous")?,
            column(coulomb, "coulomb")?,
        );
        // NaN: unknown; otherwise finite and > 0, errors named torque_constant[i] (issue 14)
        let kt = torque_constant
            .map(|o| crate::args::positive_or_nan_vector(o, "torque_constant", n))
            .transpose()?;
        let drives = ttkin::tables::DriveColumns {
            gear_ratio: &g,
            rotor_inertia: j.as_deref(),
            viscous: b.as_deref(),
            coulomb: c.as_deref(),
            torque_constant: kt.as_deref(),
        }
        .drives()
        .py()?;
        Ok(PyRobot::new(self.chain.with_drives(&drives).py()?))
    }
}

impl PyRobot {
    /// Shared body of rnea and inverse_dynamics (`friction`: add the joint friction).
    #[allow(clippy::too_many_arguments)]
    fn inverse<'py>(
        &self,
        py: Python<'py>,
        q: &Any<'py>,
        qd: &Any<'py>,
        qdd: &Any<'py>,
        gravity: Option<&Any<'py>>,
        wrench: Option<&Any<'py>>,
        friction: bool,
    ) -> PyResult<Array<'py>> {
        let g = gravity_arg(gravity, &self.chain)?;
        let w = wrench_arg(wrench)?;
        let (arrays, batch) = self.states([(q, "q"), (qd, "qd"), (qdd, "qdd")])?;
        let n = self.chain.dof();
        let (q, qd, qdd) = (arrays[0].data(), arrays[1].data(), arrays[2].data());
        let w = w.as_ref();
        self.one_or_many(
            py,
            batch,
            &[n],
            |dy, d| {
                let t = if friction {
                    dy.inverse_dynamics(d, q, qd, qdd, &g, w)
                } else {
                    dy.rnea(d, q, qd, qdd, &g, w)
                };
                t.map(|t| t.as_slice())
            },
            |dy, o| {
                if friction {
                    dy.inverse_dynamics_batch(q, qd, qdd, &g, w, o)
                } else {
                    dy.rnea_batch(q, qd, qdd, &g, w, o)
                }
            },
        )
    }
}
