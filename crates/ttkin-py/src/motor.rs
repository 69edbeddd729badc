//! `ttmanip.ServoSim`: one simulated servo axis (ttcan's cascade on ttcan's DC-motor plant).
//!
//! Parameters travel as nested dicts of SI values in the serde shape of `ttcan::AxisConfig`
//! (`ServoSim.defaults()`: the maxon RE 25 + GP 26 A 14:1 reference axis); a partial dict changes
//! only the entries it names. Every check happens in Rust when the simulator is built;
//! simulations release the GIL.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::{de::DeserializeOwned, Serialize};
use ttcan::sim::Trace;
use ttcan::{AxisConfig, Mode, MotorModel, Simulation};

use crate::convert::{table, vector_of_len};
use crate::errors::{PyResultExt, TtmanipError};

/// `base` with the entries of `changes` (a nested dict of `base`'s serde shape) put in:
/// `ttcan::axis_config::overlay` (a key or value the type does not take is a `TtmanipError`
/// naming its path, `model.motor.resistance`).
fn overlay<T: Serialize + DeserializeOwned>(base: &T, changes: Option<&Bound<'_, PyDict>>) -> PyResult<T> {
    let changes = match changes {
        Some(c) => pythonize::depythonize(c.as_any()).map_err(|e| TtmanipError::new_err(e.to_string()))?,
        None => ttcan::axis_config::Change::Table(Vec::new()),
    };
    ttcan::axis_config::overlay(base, changes).py()
}

fn to_dict<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    pythonize::pythonize(py, value).map_err(|e| TtmanipError::new_err(e.to_string()))
}

fn trace_dict<'py>(py: Python<'py>, t: Trace, fault: Option<ttcan::Fault>) -> PyResult<Bound<'py, PyDict>> {
    // A non-finite signal from finite parameters is refused, never returned (issue 29).
    crate::convert::check_finite_outputs(&[&t.time, &t.current, &t.duty, &t.speed, &t.position])?;
    let d = PyDict::new(py);
    d.set_item("time", PyArray1::from_vec(py, t.time))?;
    d.set_item("current", PyArray1::from_vec(py, t.current))?;
    d.set_item("current_reference", PyArray1::from_vec(py, t.current_reference))?;
    d.set_item("duty", PyArray1::from_vec(py, t.duty))?;
    d.set_item("speed", PyArray1::from_vec(py, t.speed))?;
    d.set_item("speed_reference", PyArray1::from_vec(py, t.speed_reference))?;
    d.set_item("position", PyArray1::from_vec(py, t.position))?;
    d.set_item("position_reference", PyArray1::from_vec(py, t.position_reference))?;
    d.set_item("following_error", PyArray1::from_vec(py, t.following_error))?;
    d.set_item("state", PyArray1::from_vec(py, t.state))?;
    d.set_item("fault", fault.map(|f| format!("{f:?}")))?;
    Ok(d)
}

/// A simulated servo axis: DC motor + gearbox + load plant under the current/speed/position cascade.
#[pyclass(name = "ServoSim", module = "ttmanip", frozen)]
pub struct PyServoSim {
    config: AxisConfig,
    plant: MotorModel,
}

impl PyServoSim {
    fn simulation(&self, seed: i128) -> PyResult<Simulation> {
        let seed: u64 = crate::args::unsigned(seed, "seed")?; // not PyO3's OverflowError (issue 14)
        let mut s = Simulation::new(&self.plant, &self.config).py()?;
        s.plant.seed_noise(seed);
        Ok(s)
    }

    /// Runs `f` on a fresh simulation without the GIL; the trace and the axis' fault as a dict.
    fn run<'py>(
        &self,
        py: Python<'py>,
        seed: i128,
        f: impl Send + FnOnce(&mut Simulation, ttkin::budget::Stop<'_>) -> ttcan::Result<Trace>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mut s = self.simulation(seed)?;
        // Ctrl-C stops a long run within about a thousand loop periods (issue 29).
        let (trace, fault) = crate::interrupt::detach_interruptible(py, |cancel| {
            let trace = f(&mut s, &|| crate::interrupt::cancelled(cancel));
            (trace, s.axis.fault())
        })?;
        trace_dict(py, trace.py()?, fault)
    }
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl PyServoSim {
    /// Builds the controller from `params` (entries of `defaults()`, SI units; missing entries keep
    /// the default) and the simulated actuator from the controller's `model` overridden by `plant`
    /// (entries of `defaults()["model"]`), so that the controller's model can differ from the plant.
    #[new]
    #[pyo3(signature = (params=None, plant=None))]
    fn new(params: Option<&Bound<'_, PyDict>>, plant: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let config = overlay(&AxisConfig::new(MotorModel::maxon_re25_gp26()), params)?;
        let plant = overlay(&config.model, plant)?;
        Simulation::new(&plant, &config).py()?; // checks the plant and the whole configuration
        Ok(PyServoSim { config, plant })
    }

    /// The reference axis' parameters (maxon RE 25 + GP 26 A 14:1, 24 V, 20/5/1 kHz), SI units.
    #[staticmethod]
    fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
        to_dict(py, &AxisConfig::new(MotorModel::maxon_re25_gp26()))
    }

    /// The controller's parameters (all entries), SI units.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_dict(py, &self.config)
    }

    /// The simulated actuator's parameters (motor, gearbox, load, drive), SI units.
    #[getter]
    fn plant_params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_dict(py, &self.plant)
    }

    /// Gains, crossovers (Hz), phase margins (deg) and bandwidths (Hz) of the three loops.
    #[getter]
    fn tuning<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_dict(py, Simulation::new(&self.plant, &self.config).py()?.axis.tuning())
    }

    /// Loop rates (current, speed, position), Hz.
    #[getter]
    fn rates(&self) -> (f64, f64, f64) {
        let r = self.config.rates;
        (r.current_hz(), r.speed_hz(), r.position_hz())
    }

    /// Step response: `kind` is 'current' (A), 'velocity' (rad/s) or 'position' (rad, a step with
    /// zero velocity and acceleration); `external_torque` (N·m at the output) acts throughout.
    /// Returns a dict of numpy arrays sampled every current-loop period, plus 'fault'.
    #[pyo3(signature = (kind, amplitude, duration, external_torque=Simulation::NO_LOAD, seed=Simulation::NOISE_SEED as i128))]
    fn step<'py>(
        &self,
        py: Python<'py>,
        kind: &str,
        amplitude: f64,
        duration: f64,
        external_torque: f64,
        seed: i128,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mode: Mode = kind.parse().map_err(|e| TtmanipError::new_err(format!("kind: {e}")))?;
        self.run(py, seed, |s, stop| {
            s.step_response_until(mode, amplitude, duration, external_torque, stop)
        })
    }

    /// Follows a position trajectory given at the position-loop rate (1-D arrays q rad, qd rad/s,
    /// qdd rad/s² of equal length n ≥ 1, sample k for the k-th position period) from rest at q[0],
    /// then holds the last sample for `settle` seconds. Returns a dict of numpy arrays plus 'fault'.
    #[pyo3(signature = (q, qd, qdd, settle=Simulation::NO_SETTLE, external_torque=Simulation::NO_LOAD, seed=Simulation::NOISE_SEED as i128))]
    #[allow(clippy::too_many_arguments)]
    fn follow<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qd: &Bound<'py, PyAny>,
        qdd: &Bound<'py, PyAny>,
        settle: f64,
        external_torque: f64,
        seed: i128,
    ) -> PyResult<Bound<'py, PyDict>> {
        let q = vector_of_len(q, "q", 1)?;
        let (qd, qdd) = (table(qd, "qd", q.len(), 1)?, table(qdd, "qdd", q.len(), 1)?);
        self.run(py, seed, |s, stop| {
            s.follow_until(&q, &qd, &qdd, settle, external_torque, stop)
        })
    }

    fn __repr__(&self) -> String {
        let m = &self.config.model;
        let r = self.config.rates;
        format!(
            "ServoSim(R={} Ω, L={} H, Kt={} N·m/A, N={}, load {} kg·m², {:.0}/{:.0}/{:.0} Hz)",
            m.motor.resistance,
            m.motor.inductance,
            m.motor.torque_constant,
            m.gearbox.ratio,
            m.load.inertia,
            r.current_hz(),
            r.speed_hz(),
            r.position_hz()
        )
    }
}

crate::pickle::pickled!(serde PyServoSim, _unpickle_servo_sim, "ServoSim", |s| (&s.config, &s.plant), |_, (config, plant): _| Ok(PyServoSim { config, plant }));

/// Adds `ServoSim` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_servo_sim, m)?)?;
    m.add_class::<PyServoSim>()?;
    Ok(())
}
