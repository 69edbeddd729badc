//! `ttmanip.DriveSim`: all axes of a robot through their drive cascades on its rigid-body dynamics
//! (`ttcan::coupled::CoupledSim`). Conversion only: arrays in, arrays out, errors mapped.

use std::sync::atomic::{AtomicU64, Ordering};

use numpy::PyArray1;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use ttcan::coupled::journal::Journal;
use ttcan::{CoupledOptions, CoupledSim};

use crate::args;
use crate::convert::{f64_array, to_numpy, value_getters, vector};
use crate::errors::{PyResultExt, TtmanipError};
use crate::robot::PyRobot as Robot;

/// Every joint of a robot driven by its own current/speed/position cascade, on the robot's shared
/// rigid-body mechanics (gravity included), stepped one current-loop period at a time.
#[pyclass(module = "ttmanip._ttmanip")]
pub struct DriveSim {
    chain: std::sync::Arc<ttkin::Chain>,
    options: CoupledOptions,
    /// The cyclic setpoint period the drives interpolate, s (1 / `setpoint_hz`).
    setpoint_period: f64,
    sim: CoupledSim,
    /// What made `sim` from a fresh `from_chain` (issue 31): the last reset and every call
    /// since, replayed by unpickling (the simulation is deterministic, so the copy is exact).
    journal: Journal,
}

impl DriveSim {
    /// The simulator back from its pickle state (the robot's chain, the options, the setpoint
    /// period and the journal of calls, issue 31): rebuilt, then the journal replayed (without
    /// the GIL, interruptible: a journal of 10¹⁵ ticks is Ctrl-C-able work, not a hang).
    fn from_state(
        py: Python<'_>,
        (chain, options, setpoint_period, journal): (ttkin::Chain, CoupledOptions, f64, Journal),
    ) -> PyResult<Self> {
        // the constructor's check (a NaN period unpickled and ran)
        let setpoint_period = args::positive("setpoint_period", setpoint_period)?;
        let sim = crate::interrupt::detach_interruptible(py, |cancel| {
            journal.replay_until(&chain, options, setpoint_period, &|| {
                crate::interrupt::cancelled(cancel)
            })
        })?
        .py()?;
        Ok(DriveSim {
            chain: std::sync::Arc::new(chain),
            options,
            setpoint_period,
            sim,
            journal,
        })
    }
}

#[ttkin_py_guard::guarded]
#[pymethods]
impl DriveSim {
    /// `setpoint_rate` is the deprecated name of `setpoint_hz`.
    #[new]
    #[pyo3(signature = (robot, *, gravity=true, setpoint_hz=ttcan::coupled::SETPOINT_HZ, noise=None, seed=CoupledOptions::default().seed as i128, ideal_current=false, setpoint_rate=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        robot: &Robot,
        gravity: bool,
        setpoint_hz: f64,
        noise: Option<f64>,
        seed: i128,
        ideal_current: bool,
        setpoint_rate: Option<f64>,
    ) -> PyResult<Self> {
        let setpoint_hz = args::renamed(
            py,
            setpoint_hz,
            setpoint_rate,
            "DriveSim(setpoint_rate=...)",
            "setpoint_hz=...",
        )?;
        let setpoint_period = 1.0 / args::positive("setpoint_hz", setpoint_hz)?;
        let noise = noise.map(|a| args::non_negative("noise", a)).transpose()?;
        let options = CoupledOptions {
            // On: the robot's own gravity (`Chain::gravity`, the core's default).
            gravity: (!gravity).then_some([0.0; 3]),
            ideal_current,
            seed: args::unsigned(seed, "seed")?,
            setpoint_period: Some(setpoint_period),
            ..CoupledOptions::default()
        };
        let options = noise.map_or(options, |a| options.with_current_noise(a));
        let q0 = vec![0.0; robot.chain.dof()];
        let sim = CoupledSim::from_chain(&robot.chain, &q0, options).py()?;
        Ok(DriveSim {
            chain: robot.chain.clone(),
            options,
            setpoint_period,
            sim,
            journal: Journal::default(),
        })
    }

    /// Rebuilds the drives around (q0, qd0 or rest): time 0, every axis holding q0.
    #[pyo3(signature = (q0, qd0=None))]
    fn reset(&mut self, q0: &Bound<'_, PyAny>, qd0: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
        let n = self.sim.dof();
        let q0 = vector(q0, "q0", n)?;
        let qd0 = qd0.map(|v| vector(v, "qd0", n)).transpose()?;
        let journal = Journal::from_reset(q0, qd0);
        self.sim = journal.start(&self.chain, self.options).py()?;
        self.journal = journal;
        Ok(())
    }

    /// Hands every axis a setpoint (joint space, SI) and a joint-side torque feed-forward.
    #[pyo3(signature = (q, qd=None, qdd=None, tau_ff=None))]
    fn set_setpoint(
        &mut self,
        q: &Bound<'_, PyAny>,
        qd: Option<&Bound<'_, PyAny>>,
        qdd: Option<&Bound<'_, PyAny>>,
        tau_ff: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let n = self.sim.dof();
        let q = vector(q, "q", n)?;
        let zeros = vec![0.0; n];
        let qd = qd
            .map(|v| vector(v, "qd", n))
            .transpose()?
            .unwrap_or_else(|| zeros.clone());
        let qdd = qdd
            .map(|v| vector(v, "qdd", n))
            .transpose()?
            .unwrap_or_else(|| zeros.clone());
        let tau = tau_ff.map(|v| vector(v, "tau_ff", n)).transpose()?;
        let result = self.sim.set_setpoint(&q, &qd, &qdd, tau.as_deref());
        self.journal.setpoint(q, qd, qdd, tau); // failed or not (see `Journal::replay`)
        result.py()
    }

    /// Advances `n` current-loop periods.
    #[pyo3(signature = (n=ttcan::coupled::TICKS_PER_CALL as i128))]
    fn tick(&mut self, py: Python<'_>, n: i128) -> PyResult<()> {
        let n: u64 = args::unsigned(n, "n")?;
        if n > ttcan::coupled::MAX_RUN_TICKS {
            return Err(TtmanipError::new_err(format!(
                "n: at most {} ticks per call, got {n}",
                ttcan::coupled::MAX_RUN_TICKS
            )));
        }
        let sim = &mut self.sim;
        // Ctrl-C stops within about a thousand ticks (issue 29); the ticks run are journaled.
        let mut ran = 0;
        let interrupted = crate::interrupt::detach_interruptible(py, |cancel| {
            ran = sim.tick_n_until(n, &|| crate::interrupt::cancelled(cancel));
        });
        self.journal.ticks(ran);
        interrupted
    }

    /// True joint positions, rad or m.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.sim.q())
    }

    /// True joint speeds, rad/s or m/s.
    #[getter]
    fn qd<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.sim.qd())
    }

    /// Winding currents, A.
    #[getter]
    fn current<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.sim.current())
    }

    /// Current references after limiting, A (`Servo`'s `current_reference`, the axis'
    /// `current_reference()`).
    #[getter]
    fn current_reference<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.sim.current_references())
    }

    /// Deprecated name of `current_reference` (issue 30 item 5: one name per concept).
    #[getter]
    fn current_ref<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        crate::errors::deprecated(py, "DriveSim.current_ref", "DriveSim.current_reference")?;
        self.current_reference(py) // a PyResult: `#[guarded]` wraps every method's result
    }

    /// Runs the reference (t (K,), q, qd, qdd and optional tau_ff (K, n)); returns the recorded arrays.
    #[pyo3(signature = (t, q, qd, qdd, tau_ff=None))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        t: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        qd: &Bound<'py, PyAny>,
        qdd: &Bound<'py, PyAny>,
        tau_ff: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let n = self.sim.dof();
        let t = f64_array(t, "t")?;
        let k = t.data().len();
        let arr = |a: &Bound<'py, PyAny>, what: &str| -> PyResult<Vec<f64>> {
            let a = f64_array(a, what)?;
            if a.shape() != [k, n] {
                return Err(crate::errors::ShapeError::new_err(format!(
                    "{what}: expected shape ({k}, {n}), got {}",
                    a.shape_str()
                )));
            }
            Ok(a.data().to_vec())
        };
        let (q, qd, qdd) = (arr(q, "q")?, arr(qd, "qd")?, arr(qdd, "qdd")?);
        let tau = tau_ff.map(|a| arr(a, "tau_ff")).transpose()?;
        let times = t.data().to_vec();
        let period = self.setpoint_period;
        let sim = &mut self.sim;
        // Ctrl-C stops the run within about a thousand ticks (issue 29); the number of stop polls
        // is journaled, so that a pickle replays the run to the same tick.
        let polls = AtomicU64::new(0);
        let stopped_at = AtomicU64::new(0);
        let tr = crate::interrupt::detach_interruptible(py, |cancel| {
            let stop = || {
                let k = polls.fetch_add(1, Ordering::Relaxed) + 1;
                let stop = crate::interrupt::cancelled(cancel);
                if stop {
                    stopped_at.store(k, Ordering::Relaxed);
                }
                stop
            };
            sim.run_until(&times, &q, &qd, &qdd, tau.as_deref(), period, &stop)
        });
        // failed or not, stopped (after its last poll) or not: see `Journal::replay`
        let stopped_after = if tr.is_err() {
            stopped_at.load(Ordering::Relaxed)
        } else {
            0
        };
        self.journal.run((times, q, qd, qdd, tau), stopped_after);
        let tr = tr?.py()?;
        let rows = tr.len();
        let d = PyDict::new(py);
        d.set_item("t", to_numpy(py, &[rows], &tr.t))?;
        d.set_item("q", to_numpy(py, &[rows, n], &tr.q))?;
        d.set_item("qd", to_numpy(py, &[rows, n], &tr.qd))?;
        d.set_item("q_ref", to_numpy(py, &[rows, n], &tr.q_ref))?;
        d.set_item("current", to_numpy(py, &[rows, n], &tr.current))?;
        d.set_item("current_ref", to_numpy(py, &[rows, n], &tr.current_ref))?;
        d.set_item("torque", to_numpy(py, &[rows, n], &tr.torque))?;
        d.set_item("faults", tr.faults)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!("DriveSim({} axes, {} Hz)", self.sim.dof(), self.sim.tick_hz())
    }

    /// Deprecated name of `tick_hz`.
    #[getter]
    fn tick_rate(&self, py: Python<'_>) -> PyResult<f64> {
        crate::errors::deprecated(py, "DriveSim.tick_rate", "DriveSim.tick_hz")?;
        Ok(self.sim.tick_hz())
    }
}

value_getters!(DriveSim, |s| {
    /// Simulated time since the last reset, s.
    t: f64 => s.sim.time();
    /// Fault of each axis ("" when none).
    faults: Vec<String> => s.sim.fault_names();
    /// Current-loop (tick) rate, Hz.
    tick_hz: f64 => s.sim.tick_hz();
});

/// (10–90 % rise time in s, overshoot as a fraction) of `y` sampled at `t` towards `target`.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn step_metrics(t: &Bound<'_, PyAny>, y: &Bound<'_, PyAny>, target: f64) -> PyResult<(f64, f64)> {
    let t = f64_array(t, "t")?;
    let y = crate::convert::table(y, "y", t.data().len(), 1)?;
    ttcan::sim::step_metrics(t.data(), &y, target).py()
}

crate::pickle::pickled!(serde DriveSim, _unpickle_drive_sim, "DriveSim", |s| (&*s.chain, &s.options, s.setpoint_period, &s.journal), |py, state: _| DriveSim::from_state(py, state));

/// Adds `DriveSim`, `drive_theta5_case`, `actuators` and `step_metrics` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_unpickle_drive_sim, m)?)?;
    m.add_class::<DriveSim>()?;
    m.add_function(wrap_pyfunction!(actuators, m)?)?;
    m.add_function(wrap_pyfunction!(step_metrics, m)?)?;
    m.add_function(wrap_pyfunction!(drive_theta5_case, m)?)
}

/// Issue 10's θ5 case (`ttcan::cases::theta5_case`): its RMS numbers and traces. `setpoint_rate`
/// is the deprecated name of `setpoint_hz` (and of the result's key, kept beside it one release).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (setpoint_hz=ttcan::coupled::SETPOINT_HZ, *, setpoint_rate=None))]
fn drive_theta5_case<'py>(
    py: Python<'py>,
    setpoint_hz: f64,
    setpoint_rate: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let setpoint_hz = args::renamed(
        py,
        setpoint_hz,
        setpoint_rate,
        "drive_theta5_case(setpoint_rate=...)",
        "setpoint_hz=...",
    )?;
    let setpoint_hz = args::positive("setpoint_hz", setpoint_hz)?;
    let c = py.detach(|| ttcan::cases::theta5_case(setpoint_hz)).py()?;
    let d = PyDict::new(py);
    d.set_item("load_inertia", c.load_inertia)?;
    d.set_item("setpoint_hz", c.setpoint_hz)?;
    d.set_item("setpoint_rate", c.setpoint_hz)?; // the old key, one release (a dict cannot warn)
    d.set_item("current_ripple_rms", c.current_ripple_rms)?;
    d.set_item("current_error_rms", c.current_error_rms)?;
    d.set_item("max_following_error", c.max_following_error)?;
    let k = c.trace.len();
    d.set_item("t", to_numpy(py, &[k], &c.trace.time))?;
    d.set_item("current", to_numpy(py, &[k], &c.trace.current))?;
    d.set_item("current_ref", to_numpy(py, &[k], &c.trace.current_reference))?;
    d.set_item("current_needed", to_numpy(py, &[k], &c.current_needed))?;
    d.set_item("position", to_numpy(py, &[k], &c.trace.position))?;
    d.set_item("position_ref", to_numpy(py, &[k], &c.reference))?;
    Ok(d)
}

/// Each joint's actuator as `ttcan::actuator` builds it from the robot file's drive section (at
/// q = 0): `joint`, `drive` (the section's values as given, SI units, motor side; None without
/// one) and the axis' `continuous_current`, `peak_current` (A), `max_speed` (rad/s or m/s at the
/// joint), `bus_voltage` (V), `encoder_counts`, `gear_ratio`.
#[ttkin_py_guard::guarded]
#[pyfunction]
fn actuators<'py>(py: Python<'py>, robot: &Robot) -> PyResult<Bound<'py, PyAny>> {
    crate::convert::serde_to_python(py, &ttcan::coupled::actuator_summaries(&robot.chain).py()?)
}
