//! `ttmanip.Robot`: a serial chain with forward kinematics and Jacobians, single or batched.
//!
//! Other binding modules add methods to `Robot` in their own `#[pymethods]` blocks
//! (PyO3's `multiple-pymethods`), reaching the model through [`PyRobot::chain`].

use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::PyString;
use ttkin::dh::DhColumns;
use ttkin::{Chain, DhConvention, JacobianFrame, JointType};

use crate::convert::{
    array_getters, f64_array, filled_without_gil, pose_to_numpy, shape_str, to_numpy, transform, value_getters, vector,
    zeros, Any, Array,
};
use crate::errors::{PyResultExt, TtmanipError};

/// A serial robot arm: joints from base to tool (m, rad, s). Immutable; share it freely.
#[pyclass(name = "Robot", module = "ttmanip", frozen)]
pub struct PyRobot {
    /// The kinematic (and later dynamic) model.
    pub chain: Arc<Chain>,
    /// The dynamic model, built on first use, and its scratch space.
    pub dynamics: ttkin::dynamics::DynamicsCache,
}

impl PyRobot {
    /// Wraps a chain.
    pub fn new(chain: Chain) -> Self {
        PyRobot {
            chain: Arc::new(chain),
            dynamics: Default::default(),
        }
    }

    /// Reads `q` as one configuration (n,) or a batch (N, n); returns the batch size (None for one).
    pub fn configs<'py>(&self, q: &Any<'py>, what: &str) -> PyResult<(crate::convert::F64Array<'py>, Option<usize>)> {
        crate::convert::configs(q, what, self.chain.dof())
    }
}

/// Joint types from a string such as "PRRRRR" or a list of "revolute"/"prismatic".
fn joint_types(types: &Any<'_>) -> PyResult<Vec<JointType>> {
    if let Ok(s) = types.cast::<PyString>() {
        return JointType::from_letters(&s.to_cow()?).py();
    }
    let items: Vec<String> = types.extract().map_err(|_| {
        TtmanipError::new_err("types: expected a string such as 'PRRRRR' or a list of 'revolute'/'prismatic'")
    })?;
    JointType::from_names(&items).py()
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyRobot {
    /// Robot from DH parameters: one value per joint in each of `a` (m), `alpha` (rad), `d` (m) and
    /// `theta` (rad); `theta` (revolute) or `d` (prismatic) is the joint offset at q = 0.
    /// `types` is a string like "PRRRRR" or a list of "revolute"/"prismatic" (default: all revolute);
    /// `convention` is "standard" (distal) or "modified" (Craig: a, alpha are a_{i-1}, alpha_{i-1});
    /// `limits` an (n, 2) array of lower/upper position limits; `base`, `tool` 4×4 rigid transforms.
    #[staticmethod]
    #[pyo3(signature = (a, alpha, d, theta, types=None, convention="standard", limits=None, base=None, tool=None, name="robot", names=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_dh(
        a: &Any<'_>,
        alpha: &Any<'_>,
        d: &Any<'_>,
        theta: &Any<'_>,
        types: Option<&Any<'_>>,
        convention: &str,
        limits: Option<&Any<'_>>,
        base: Option<&Any<'_>>,
        tool: Option<&Any<'_>>,
        name: &str,
        names: Option<Vec<String>>,
    ) -> PyResult<Self> {
        let n = f64_array(a, "a")?.shape().first().copied().unwrap_or(0);
        let column = |obj: &Any<'_>, what: &str| vector(obj, what, n);
        let (a, alpha, d, theta) = (
            column(a, "a")?,
            column(alpha, "alpha")?,
            column(d, "d")?,
            column(theta, "theta")?,
        );
        let types = types.map(joint_types).transpose()?;
        let limits = limits.map(|l| crate::convert::table(l, "limits", n, 2)).transpose()?;
        let chain = DhColumns {
            a: &a,
            alpha: &alpha,
            d: &d,
            theta: &theta,
            types: types.as_deref(),
            limits: limits.as_deref(),
            base: base.map(|b| transform(b, "base")).transpose()?,
            tool: tool.map(|t| transform(t, "tool")).transpose()?,
        }
        .chain(name, convention.parse::<DhConvention>().py()?, names)
        .py()?;
        Ok(PyRobot::new(chain))
    }

    /// Robot from a ttmanip robot file (TOML).
    #[staticmethod]
    fn from_file(path: std::path::PathBuf) -> PyResult<Self> {
        if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf")) {
            return Err(crate::errors::RobotFileError::new_err(format!(
                "{}: a URDF needs the two ends of the chain: use Robot.from_urdf(path, base_link, tip_link)",
                path.display()
            )));
        }
        Ok(PyRobot::new(ttkin::description::load(&path).py()?))
    }

    /// Robot from robot-file text (TOML).
    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Self> {
        Ok(PyRobot::new(ttkin::description::from_toml_str(text, "<string>").py()?))
    }

    /// Robot from the serial chain between `base_link` and `tip_link` of a URDF file.
    #[staticmethod]
    fn from_urdf(path: std::path::PathBuf, base_link: &str, tip_link: &str) -> PyResult<Self> {
        Ok(PyRobot::new(ttkin::urdf::load(&path, base_link, tip_link).py()?))
    }

    /// Robot from URDF text (see `from_urdf`).
    #[staticmethod]
    fn from_urdf_string(text: &str, base_link: &str, tip_link: &str) -> PyResult<Self> {
        Ok(PyRobot::new(
            ttkin::urdf::from_urdf_str(text, base_link, tip_link).py()?,
        ))
    }

    /// A built-in robot: one of `Robot.builtin_names()` ("mobile8", "gantry6", "arm4", "ur5").
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        Ok(PyRobot::new(ttkin::robots::by_name(name).py()?))
    }

    /// Names of the built-in robots, in the order of `ttkin::robots::NAMES`.
    #[staticmethod]
    fn builtin_names() -> Vec<&'static str> {
        ttkin::robots::NAMES.to_vec()
    }

    /// URDF text of this robot (links base_link, link0 … linkN, tool; link i is DH frame i).
    fn to_urdf(&self) -> String {
        ttkin::urdf::to_urdf_string(&self.chain)
    }

    /// Robot-file text (TOML, SI units) of this robot.
    fn to_toml(&self) -> String {
        ttkin::description::to_toml(&self.chain)
    }

    /// The same robot with another tool transform (last link frame → tool frame, 4×4).
    fn with_tool(&self, tool: &Any<'_>) -> PyResult<Self> {
        Ok(PyRobot::new(self.chain.with_tool(transform(tool, "tool")?).py()?))
    }

    /// The same robot with another base transform (base frame → frame 0, 4×4).
    fn with_base(&self, base: &Any<'_>) -> PyResult<Self> {
        Ok(PyRobot::new(self.chain.with_base(transform(base, "base")?).py()?))
    }

    /// The same robot carrying its racket at `mount` (racket frame in the tool frame, 4×4, m).
    fn with_racket(&self, mount: &Any<'_>) -> PyResult<Self> {
        Ok(PyRobot::new(self.chain.with_racket(transform(mount, "mount")?).py()?))
    }

    /// The same robot with the ready (rest) configuration `q` (n,) in m or rad, within the limits.
    fn with_ready(&self, q: &Any<'_>) -> PyResult<Self> {
        let q = vector(q, "q", self.chain.dof())?;
        Ok(PyRobot::new(self.chain.with_ready(&q).py()?))
    }

    /// Deprecated name of `dof`.
    #[getter]
    fn n(&self, py: Python<'_>) -> PyResult<usize> {
        crate::errors::deprecated(py, "Robot.n", "Robot.dof")?;
        Ok(self.chain.dof())
    }

    /// (n, 2) lower and upper position limits (m or rad; ±inf where unbounded).
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> Array<'py> {
        to_numpy(py, &[self.chain.dof(), 2], &self.chain.position_limit_table())
    }

    /// (n,) ready (rest) configuration (m or rad): where strokes start and return to; the
    /// robot's own (robot file `ready`) or the middle of each joint range.
    #[getter]
    fn ready<'py>(&self, py: Python<'py>) -> Array<'py> {
        to_numpy(py, &[self.chain.dof()], &self.chain.ready())
    }

    /// (3,) gravity in the base frame (m/s²): the default of every dynamics call on this robot
    /// (robot file `gravity`; (0, 0, −9.81) unless the file says otherwise, (−9.81, 0, 0) for
    /// mobile8, whose base frame has x up).
    #[getter]
    fn gravity_vector<'py>(&self, py: Python<'py>) -> Array<'py> {
        to_numpy(py, &[3], &self.chain.gravity())
    }

    /// Base frame → frame 0 (4×4).
    #[getter]
    fn base<'py>(&self, py: Python<'py>) -> Array<'py> {
        pose_to_numpy(py, self.chain.base())
    }

    /// Last link frame → tool frame (4×4).
    #[getter]
    fn tool<'py>(&self, py: Python<'py>) -> Array<'py> {
        pose_to_numpy(py, self.chain.tool())
    }

    /// Tool pose in the base frame: (4, 4) for q of shape (n,), (N, 4, 4) for (N, n).
    /// q in m (prismatic) and rad (revolute); limits are not enforced.
    fn fk<'py>(&self, py: Python<'py>, q: &Any<'py>) -> PyResult<Array<'py>> {
        let (a, batch) = self.configs(q, "q")?;
        match batch {
            None => Ok(pose_to_numpy(py, &self.chain.fk(a.data()).py()?)),
            Some(count) => {
                let (qs, chain) = (a.data(), &*self.chain);
                filled_without_gil(py, &[count, 4, 4], |o| chain.fk_batch(qs, o))
            }
        }
    }

    /// Effective effort limits (N or N·m) at joint speeds `qd` (m/s or rad/s): (n,) for qd of
    /// shape (n,), (N, n) for (N, n); the drive's bus voltage lowers them with speed.
    fn effort_limits_at<'py>(&self, py: Python<'py>, qd: &Any<'py>) -> PyResult<Array<'py>> {
        let (a, batch) = self.configs(qd, "qd")?;
        let n = self.chain.dof();
        let limits = ttkin::effort::EffortLimits::of(&self.chain).at_rows(a.data());
        Ok(match batch {
            None => to_numpy(py, &[n], &limits),
            Some(count) => to_numpy(py, &[count, n], &limits),
        })
    }

    /// Every link frame in the base frame (tool transform not applied): (n, 4, 4) or (N, n, 4, 4).
    fn fk_all<'py>(&self, py: Python<'py>, q: &Any<'py>) -> PyResult<Array<'py>> {
        let (a, batch) = self.configs(q, "q")?;
        let n = self.chain.dof();
        let (count, shape) = match batch {
            None => (1, vec![n, 4, 4]),
            Some(c) => (c, vec![c, n, 4, 4]),
        };
        let (qs, chain) = (a.data(), &*self.chain);
        if count > 64 {
            return filled_without_gil(py, &shape, |o| chain.fk_all_batch(qs, o));
        }
        let out = zeros(py, &shape);
        crate::convert::fill_fresh(&out, |o| chain.fk_all_batch(qs, o).py())?;
        Ok(out)
    }

    /// Geometric Jacobian [v; ω] (v of the tool point), rows in the axes of `frame` ("base" or
    /// "tool"): (6, n) for q of shape (n,), (N, 6, n) for (N, n). Units m/s and rad/s per joint unit.
    #[pyo3(signature = (q, frame="base"))]
    fn jacobian<'py>(&self, py: Python<'py>, q: &Any<'py>, frame: &str) -> PyResult<Array<'py>> {
        let frame: JacobianFrame = frame.parse::<JacobianFrame>().py()?;
        let (a, batch) = self.configs(q, "q")?;
        let n = self.chain.dof();
        match batch {
            None => {
                let j = self.chain.jacobian(a.data(), frame).py()?;
                Ok(to_numpy(py, &[6, n], j.transpose().as_slice()))
            }
            Some(count) => {
                let (qs, chain) = (a.data(), &*self.chain);
                filled_without_gil(py, &[count, 6, n], |o| chain.jacobian_batch(qs, frame, o))
            }
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Robot('{}', dof={}, joints='{}')",
            self.chain.name(),
            self.chain.dof(),
            self.chain.joint_letters()
        )
    }
}

array_getters!(PyRobot, |r| {
    /// (n,) speed limits (m/s or rad/s; inf where none).
    velocity_limits => r.chain.limit_column(|l| l.velocity), [r.chain.dof()];
    /// (n,) acceleration limits (m/s² or rad/s²; inf where none).
    acceleration_limits => r.chain.limit_column(|l| l.acceleration), [r.chain.dof()];
    /// (n,) effort limits (N or N·m; inf where none).
    effort_limits => r.chain.limit_column(|l| l.effort), [r.chain.dof()];
    /// (n,) what each joint's drive delivers at peak current, G·k_t·I_peak·η (N or N·m; inf where
    /// the drive data lacks it).
    drive_effort_limits => ttkin::effort::EffortLimits::of(&r.chain).drive_peaks(), [r.chain.dof()];
    /// (n,) effective effort limits at standstill: the smaller of `effort_limits` and
    /// `drive_effort_limits` (N or N·m; inf where neither); the limit the planners use.
    effective_effort_limits => ttkin::effort::EffortLimits::of(&r.chain).at_rest(), [r.chain.dof()];
    /// (n,) the largest speed each joint's drive delivers, min(ω_motor,max, 0.9·(U·d_max −
    /// R·I_cont)/k_t)/G (m/s or rad/s; inf where the drive data lacks it).
    drive_velocity_limits => ttkin::speed::drive_velocity_limits(&r.chain), [r.chain.dof()];
    /// (n,) effective speed limits: the smaller of `velocity_limits` and `drive_velocity_limits`
    /// (m/s or rad/s; inf where neither); the limit the planners use.
    effective_velocity_limits => ttkin::speed::effective_velocity_limits(&r.chain), [r.chain.dof()];
});

value_getters!(PyRobot, |r| {
    /// Number of joints (degrees of freedom).
    dof: usize => r.chain.dof();
    /// Robot name.
    name: String => r.chain.name().to_string();
    /// Joint names, base to tool.
    joint_names: Vec<String> => r.chain.joint_names();
    /// Which limit governs each joint's effective effort limit at standstill: "robot file",
    /// "drive peak current", "drive voltage" or "none".
    effort_limit_sources: Vec<&'static str> => ttkin::effort::EffortLimits::of(&r.chain).sources_at_rest();
    /// Which limit governs each joint's effective speed limit: "robot file", "drive" or "none".
    velocity_limit_sources: Vec<&'static str> => ttkin::speed::velocity_limit_sources(&r.chain);
    /// Joint types, "revolute" or "prismatic".
    joint_types: Vec<&'static str> => r.chain.joint_type_names();
});

crate::pickle::pickled!(serde PyRobot, _unpickle_robot, "Robot", |r| *r.chain, |_, chain: Chain| Ok(PyRobot::new(chain)));

/// Adds `Robot` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_robot, m)?)?;
    m.add_class::<PyRobot>()?;
    // standard gravity in a z-up base frame, m/s² (ttkin::dynamics::EARTH_GRAVITY)
    m.add("EARTH_GRAVITY", ttkin::dynamics::EARTH_GRAVITY)?;
    let _ = shape_str;
    Ok(())
}
