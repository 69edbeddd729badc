//! `Robot.torques` and its result `ttmanip.TorqueProfile`: joint, motor-side and current profiles
//! of a planned motion with the effort check (patent step S105). Conversion only: the maths is
//! `ttkin::dynamics::profile`.

use pyo3::prelude::*;
use ttkin::dynamics::TorqueProfile;

use crate::convert::{array_getters, Any};
use crate::dynamics::{gravity_arg, wrench_arg};
use crate::errors::PyResultExt;
use crate::robot::PyRobot;

/// The result of `Robot.torques`: joint, motor-side and current profiles and the effort check.
#[pyclass(name = "TorqueProfile", module = "ttmanip", frozen)]
pub struct PyTorqueProfile {
    profile: TorqueProfile,
}

impl PyTorqueProfile {
    /// Number of samples N of the profile.
    fn len(&self) -> usize {
        self.profile.joint.len() / self.profile.dof
    }
}

array_getters!(PyTorqueProfile, |t| {
    /// (N, n) joint torques (N·m) / forces (N): rigid body + armature + friction.
    joint => t.profile.joint, [t.len(), t.profile.dof];
    /// (N, n) motor torques τ/G (N·m).
    motor => t.profile.motor, [t.len(), t.profile.dof];
    /// (N, n) motor currents τ_motor/k_t (A); NaN for joints without a torque constant.
    current => t.profile.current, [t.len(), t.profile.dof];
    /// (n,) largest |joint torque| over the profile (N·m or N).
    peak => t.profile.peak, [t.profile.dof];
});

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyTorqueProfile {
    /// True when no sample exceeds any joint's effort limit.
    #[getter]
    fn within_limits(&self) -> bool {
        self.profile.within_limits()
    }

    /// Every (sample, joint, torque, limit) whose |torque| exceeds the effort limit.
    #[getter]
    fn violations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyList>> {
        crate::convert::list(py, &self.profile.violations, |v| (v.sample, v.joint, v.torque, v.limit))
    }

    fn __repr__(&self) -> String {
        let p = &self.profile;
        format!(
            "TorqueProfile({} samples × {} joints, within_limits={}, {} violations)",
            self.len(),
            p.dof,
            if p.within_limits() { "True" } else { "False" },
            p.violations.len()
        )
    }
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyRobot {
    /// Torque profile of a planned motion (patent step S105): `torques(q, qd, qdd)` with (N, n)
    /// arrays, `torques((q, qd, qdd))` or `torques(traj)` for an object with attributes q, qd, qdd
    /// (or position, velocity, acceleration), each (N, n).
    /// Joint torques include friction; motor side through the gear ratio and torque constant.
    #[pyo3(signature = (trajectory, qd=None, qdd=None, gravity=None, wrench=None))]
    fn torques<'py>(
        &self,
        py: Python<'py>,
        trajectory: &Any<'py>,
        qd: Option<&Any<'py>>,
        qdd: Option<&Any<'py>>,
        gravity: Option<&Any<'py>>,
        wrench: Option<&Any<'py>>,
    ) -> PyResult<PyTorqueProfile> {
        let g = gravity_arg(gravity, &self.chain)?;
        let w = wrench_arg(wrench)?;
        let [q, qd, qdd] = crate::args::trajectory_arrays(trajectory, qd, qdd)?;
        let (arrays, _) = self.states([(&q, "q"), (&qd, "qd"), (&qdd, "qdd")])?;
        let dy = self.dynamics()?;
        let (q, qd, qdd) = (arrays[0].data(), arrays[1].data(), arrays[2].data());
        let profile = py.detach(|| dy.torque_profile(q, qd, qdd, &g, w.as_ref())).py()?;
        Ok(PyTorqueProfile { profile })
    }
}

crate::pickle::pickled!(serde PyTorqueProfile, _unpickle_torque_profile, "TorqueProfile", |p| p.profile, |_, profile: _| Ok(PyTorqueProfile { profile }));

/// Adds `TorqueProfile` to the module (`Robot.torques` lives on `Robot`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_torque_profile, m)?)?;
    m.add_class::<PyTorqueProfile>()
}
