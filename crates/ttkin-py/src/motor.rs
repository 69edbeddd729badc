//! `ttmanip.ServoSim`: one simulated servo axis (ttcan's cascade on ttcan's DC-motor plant).
//!
//! Parameters travel as a flat dict of SI values whose keys are listed by `ServoSim.defaults()`
//! (the maxon RE 25 + GP 26 A 14:1 reference axis); the Python layer (`ttmanip.motor`) builds it from
//! dataclasses. Every check happens in Rust when the simulator is built; simulations release the GIL.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use ttcan::sim::Trace;
use ttcan::{AxisConfig, Mode, MotorModel, Rates, Setpoint, Simulation};

use crate::convert::f64_array;
use crate::errors::{ModelError, NonFiniteError, ShapeError, TtmanipError};

/// Converts a `ttcan` error to the matching Python exception.
fn to_py(e: ttcan::Error) -> PyErr {
    let msg = e.to_string();
    match e {
        ttcan::Error::NonFinite { .. } => NonFiniteError::new_err(msg),
        ttcan::Error::InvalidParameter { .. } => ModelError::new_err(msg),
        _ => TtmanipError::new_err(msg),
    }
}

const MODEL_KEYS: [&str; 16] = [
    "resistance",
    "inductance",
    "torque_constant",
    "back_emf_constant",
    "rotor_inertia",
    "viscous_friction",
    "coulomb_friction",
    "gear_ratio",
    "gear_efficiency",
    "gear_inertia",
    "load_inertia",
    "load_viscous_friction",
    "bus_voltage",
    "max_duty",
    "encoder_counts_per_rev",
    "current_noise",
];

const LOOP_KEYS: [&str; 20] = [
    "current_hz",
    "speed_hz",
    "position_hz",
    "current_bandwidth_hz",
    "speed_symmetric_optimum",
    "speed_output_filter_hz",
    "position_ratio",
    "observer_bandwidth_hz",
    "speed_reference_filter_hz",
    "continuous_current",
    "peak_current",
    "overcurrent_trip",
    "max_speed",
    "following_error_limit",
    "quick_stop_deceleration",
    "emf_filter_hz",
    "velocity_feedforward",
    "acceleration_feedforward",
    "emf_feedforward",
    "anti_windup",
];

fn model_dict<'py>(py: Python<'py>, m: &MotorModel) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("resistance", m.motor.resistance)?;
    d.set_item("inductance", m.motor.inductance)?;
    d.set_item("torque_constant", m.motor.torque_constant)?;
    d.set_item("back_emf_constant", m.motor.back_emf_constant)?;
    d.set_item("rotor_inertia", m.motor.rotor_inertia)?;
    d.set_item("viscous_friction", m.motor.viscous_friction)?;
    d.set_item("coulomb_friction", m.motor.coulomb_friction)?;
    d.set_item("gear_ratio", m.gearbox.ratio)?;
    d.set_item("gear_efficiency", m.gearbox.efficiency)?;
    d.set_item("gear_inertia", m.gearbox.inertia)?;
    d.set_item("load_inertia", m.load.inertia)?;
    d.set_item("load_viscous_friction", m.load.viscous_friction)?;
    d.set_item("bus_voltage", m.bus_voltage)?;
    d.set_item("max_duty", m.max_duty)?;
    d.set_item("encoder_counts_per_rev", m.encoder_counts_per_rev)?;
    d.set_item("current_noise", m.current_noise)?;
    Ok(d)
}

fn config_dict<'py>(py: Python<'py>, c: &AxisConfig) -> PyResult<Bound<'py, PyDict>> {
    let d = model_dict(py, &c.model)?;
    d.set_item("current_hz", c.rates.current_hz())?;
    d.set_item("speed_hz", c.rates.speed_hz())?;
    d.set_item("position_hz", c.rates.position_hz())?;
    d.set_item("current_bandwidth_hz", c.tuning.current_bandwidth_hz)?;
    d.set_item("speed_symmetric_optimum", c.tuning.speed_symmetric_optimum)?;
    d.set_item("speed_output_filter_hz", c.tuning.speed_output_filter_hz)?;
    d.set_item("position_ratio", c.tuning.position_ratio)?;
    d.set_item("observer_bandwidth_hz", c.tuning.observer_bandwidth_hz)?;
    d.set_item("speed_reference_filter_hz", c.speed_reference_filter_hz)?;
    d.set_item("continuous_current", c.continuous_current)?;
    d.set_item("peak_current", c.peak_current)?;
    d.set_item("overcurrent_trip", c.overcurrent_trip)?;
    d.set_item("max_speed", c.max_speed)?;
    d.set_item("following_error_limit", c.following_error_limit)?;
    d.set_item("quick_stop_deceleration", c.quick_stop_deceleration)?;
    d.set_item("emf_filter_hz", c.emf_filter_hz)?;
    d.set_item("velocity_feedforward", c.velocity_feedforward)?;
    d.set_item("acceleration_feedforward", c.acceleration_feedforward)?;
    d.set_item("emf_feedforward", c.emf_feedforward)?;
    d.set_item("anti_windup", c.anti_windup)?;
    Ok(d)
}

fn float(d: &Bound<'_, PyDict>, key: &str, target: &mut f64) -> PyResult<()> {
    if let Some(v) = d.get_item(key)? {
        *target = v
            .extract::<f64>()
            .map_err(|_| TtmanipError::new_err(format!("{key}: expected a number")))?;
    }
    Ok(())
}

fn flag(d: &Bound<'_, PyDict>, key: &str, target: &mut bool) -> PyResult<()> {
    if let Some(v) = d.get_item(key)? {
        *target = v
            .extract::<bool>()
            .map_err(|_| TtmanipError::new_err(format!("{key}: expected True or False")))?;
    }
    Ok(())
}

fn check_keys(d: &Bound<'_, PyDict>, allowed: &[&[&str]], what: &str) -> PyResult<()> {
    for k in d.keys() {
        let k: String = k.extract()?;
        if !allowed.iter().any(|set| set.contains(&k.as_str())) {
            return Err(TtmanipError::new_err(format!(
                "{what}: unknown parameter '{k}' (see ServoSim.defaults() for the known ones)"
            )));
        }
    }
    Ok(())
}

fn apply_model(d: &Bound<'_, PyDict>, m: &mut MotorModel) -> PyResult<()> {
    float(d, "resistance", &mut m.motor.resistance)?;
    float(d, "inductance", &mut m.motor.inductance)?;
    float(d, "torque_constant", &mut m.motor.torque_constant)?;
    float(d, "back_emf_constant", &mut m.motor.back_emf_constant)?;
    float(d, "rotor_inertia", &mut m.motor.rotor_inertia)?;
    float(d, "viscous_friction", &mut m.motor.viscous_friction)?;
    float(d, "coulomb_friction", &mut m.motor.coulomb_friction)?;
    float(d, "gear_ratio", &mut m.gearbox.ratio)?;
    float(d, "gear_efficiency", &mut m.gearbox.efficiency)?;
    float(d, "gear_inertia", &mut m.gearbox.inertia)?;
    float(d, "load_inertia", &mut m.load.inertia)?;
    float(d, "load_viscous_friction", &mut m.load.viscous_friction)?;
    float(d, "bus_voltage", &mut m.bus_voltage)?;
    float(d, "max_duty", &mut m.max_duty)?;
    float(d, "current_noise", &mut m.current_noise)?;
    if let Some(v) = d.get_item("encoder_counts_per_rev")? {
        m.encoder_counts_per_rev = v.extract::<u32>().map_err(|_| {
            ModelError::new_err("encoder_counts_per_rev: expected a positive integer (counts per motor revolution)")
        })?;
    }
    Ok(())
}

fn apply_config(d: &Bound<'_, PyDict>, c: &mut AxisConfig) -> PyResult<()> {
    apply_model(d, &mut c.model)?;
    let (mut fc, mut fs, mut fp) = (c.rates.current_hz(), c.rates.speed_hz(), c.rates.position_hz());
    float(d, "current_hz", &mut fc)?;
    float(d, "speed_hz", &mut fs)?;
    float(d, "position_hz", &mut fp)?;
    c.rates = Rates::new(fc, fs, fp).map_err(to_py)?;
    float(d, "current_bandwidth_hz", &mut c.tuning.current_bandwidth_hz)?;
    float(d, "speed_symmetric_optimum", &mut c.tuning.speed_symmetric_optimum)?;
    float(d, "speed_output_filter_hz", &mut c.tuning.speed_output_filter_hz)?;
    float(d, "position_ratio", &mut c.tuning.position_ratio)?;
    float(d, "observer_bandwidth_hz", &mut c.tuning.observer_bandwidth_hz)?;
    if let Some(v) = d.get_item("speed_reference_filter_hz")? {
        c.speed_reference_filter_hz = v
            .extract::<Option<f64>>()
            .map_err(|_| TtmanipError::new_err("speed_reference_filter_hz: expected a number or None"))?;
    }
    float(d, "continuous_current", &mut c.continuous_current)?;
    float(d, "peak_current", &mut c.peak_current)?;
    float(d, "overcurrent_trip", &mut c.overcurrent_trip)?;
    float(d, "max_speed", &mut c.max_speed)?;
    float(d, "following_error_limit", &mut c.following_error_limit)?;
    float(d, "quick_stop_deceleration", &mut c.quick_stop_deceleration)?;
    float(d, "emf_filter_hz", &mut c.emf_filter_hz)?;
    flag(d, "velocity_feedforward", &mut c.velocity_feedforward)?;
    flag(d, "acceleration_feedforward", &mut c.acceleration_feedforward)?;
    flag(d, "emf_feedforward", &mut c.emf_feedforward)?;
    flag(d, "anti_windup", &mut c.anti_windup)?;
    Ok(())
}

fn trace_dict<'py>(py: Python<'py>, t: Trace, fault: Option<ttcan::Fault>) -> PyResult<Bound<'py, PyDict>> {
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

fn mode_from_str(kind: &str) -> PyResult<Mode> {
    match kind {
        "current" => Ok(Mode::Current),
        "velocity" | "speed" => Ok(Mode::Velocity),
        "position" => Ok(Mode::Position),
        other => Err(TtmanipError::new_err(format!(
            "kind: expected 'current', 'velocity' or 'position', got '{other}'"
        ))),
    }
}

fn finite(what: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(NonFiniteError::new_err(format!("{what} = {v}: must be finite")))
    }
}

/// A simulated servo axis: DC motor + gearbox + load plant under the current/speed/position cascade.
#[pyclass(name = "ServoSim", module = "ttmanip", frozen)]
pub struct PyServoSim {
    config: AxisConfig,
    plant: MotorModel,
}

impl PyServoSim {
    fn simulation(&self, seed: u64) -> PyResult<Simulation> {
        let mut s = Simulation::new(&self.plant, &self.config).map_err(to_py)?;
        s.plant.seed_noise(seed);
        Ok(s)
    }
}

#[pymethods]
impl PyServoSim {
    /// Builds the controller from `params` (keys of `defaults()`, SI units; missing keys keep the
    /// default) and the simulated actuator from the same values overridden by `plant` (motor,
    /// gearbox, load and drive keys only), so that the controller's model can differ from the plant.
    #[new]
    #[pyo3(signature = (params=None, plant=None))]
    fn new(params: Option<&Bound<'_, PyDict>>, plant: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut config = AxisConfig::new(MotorModel::maxon_re25_gp26());
        if let Some(p) = params {
            check_keys(p, &[&MODEL_KEYS, &LOOP_KEYS], "params")?;
            apply_config(p, &mut config)?;
        }
        let mut plant_model = config.model;
        if let Some(p) = plant {
            check_keys(p, &[&MODEL_KEYS], "plant")?;
            apply_model(p, &mut plant_model)?;
        }
        // Validate both now: building a simulation checks the plant and the whole configuration.
        Simulation::new(&plant_model, &config).map_err(to_py)?;
        Ok(PyServoSim {
            config,
            plant: plant_model,
        })
    }

    /// The reference axis' parameters (maxon RE 25 + GP 26 A 14:1, 24 V, 20/5/1 kHz), SI units.
    #[staticmethod]
    fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
        config_dict(py, &AxisConfig::new(MotorModel::maxon_re25_gp26()))
    }

    /// The controller's parameters (all keys), SI units.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        config_dict(py, &self.config)
    }

    /// The simulated actuator's parameters (motor, gearbox, load, drive keys), SI units.
    #[getter]
    fn plant_params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        model_dict(py, &self.plant)
    }

    /// Gains, crossovers (Hz), phase margins (deg) and bandwidths (Hz) of the three loops.
    #[getter]
    fn tuning<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = Simulation::new(&self.plant, &self.config).map_err(to_py)?;
        let t = *s.axis.tuning();
        let d = PyDict::new(py);
        for (name, r) in [("current", t.current), ("speed", t.speed), ("position", t.position)] {
            let l = PyDict::new(py);
            l.set_item("kp", r.kp)?;
            l.set_item("ki", r.ki)?;
            l.set_item("crossover_hz", r.crossover_hz)?;
            l.set_item("phase_margin_deg", r.phase_margin_deg)?;
            l.set_item("bandwidth_hz", r.bandwidth_hz)?;
            d.set_item(name, l)?;
        }
        d.set_item("t_sigma", t.t_sigma)?;
        d.set_item("speed_reference_filter_hz", t.speed_reference_filter_hz)?;
        Ok(d)
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
    #[pyo3(signature = (kind, amplitude, duration, external_torque=0.0, seed=7))]
    fn step<'py>(
        &self,
        py: Python<'py>,
        kind: &str,
        amplitude: f64,
        duration: f64,
        external_torque: f64,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mode = mode_from_str(kind)?;
        let amplitude = finite("amplitude", amplitude)?;
        let external_torque = finite("external_torque", external_torque)?;
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(TtmanipError::new_err(format!(
                "duration = {duration} s: must be finite and >= 0"
            )));
        }
        let mut s = self.simulation(seed)?;
        s.plant.set_external_torque(external_torque);
        s.enable(mode);
        let setpoint = match mode {
            Mode::Current => Setpoint::Current(amplitude),
            Mode::Velocity => Setpoint::Velocity(amplitude),
            Mode::Position => Setpoint::Position(amplitude, 0.0, 0.0),
        };
        let (trace, fault) = py.detach(|| {
            let t = s.run(duration, |_| setpoint);
            (t, s.axis.fault())
        });
        trace_dict(py, trace.map_err(to_py)?, fault)
    }

    /// Tracks a position trajectory given at the position-loop rate (1-D arrays q rad, qd rad/s,
    /// qdd rad/s² of equal length, sample k for the k-th position period), then holds the last
    /// sample for `settle` seconds. Returns a dict of numpy arrays plus 'fault'.
    #[pyo3(signature = (q, qd, qdd, settle=0.0, external_torque=0.0, seed=7))]
    #[allow(clippy::too_many_arguments)]
    fn trajectory<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qd: &Bound<'py, PyAny>,
        qdd: &Bound<'py, PyAny>,
        settle: f64,
        external_torque: f64,
        seed: u64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let read = |a: &Bound<'py, PyAny>, what: &str| -> PyResult<Vec<f64>> {
            let arr = f64_array(a, what)?;
            match arr.shape() {
                [n] if *n > 0 => Ok(arr.data().to_vec()),
                _ => Err(ShapeError::new_err(format!(
                    "{what}: expected shape (n,) with n ≥ 1, got {}",
                    arr.shape_str()
                ))),
            }
        };
        let (q, qd, qdd) = (read(q, "q")?, read(qd, "qd")?, read(qdd, "qdd")?);
        if qd.len() != q.len() || qdd.len() != q.len() {
            return Err(ShapeError::new_err(format!(
                "q, qd, qdd: expected equal lengths, got {}, {}, {}",
                q.len(),
                qd.len(),
                qdd.len()
            )));
        }
        for (what, v) in [("q", &q), ("qd", &qd), ("qdd", &qdd)] {
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(NonFiniteError::new_err(format!(
                    "{what}[{k}] = {}: must be finite",
                    v[k]
                )));
            }
        }
        let external_torque = finite("external_torque", external_torque)?;
        if !(settle.is_finite() && settle >= 0.0) {
            return Err(TtmanipError::new_err(format!(
                "settle = {settle} s: must be finite and >= 0"
            )));
        }
        let mut s = self.simulation(seed)?;
        s.plant.set_external_torque(external_torque);
        s.plant.set_output_state(q[0], 0.0);
        s.enable(Mode::Position);
        let last = Setpoint::Position(q[q.len() - 1], qd[qd.len() - 1], qdd[qdd.len() - 1]);
        let (trace, fault) = py.detach(|| {
            let mut run = || -> ttcan::Result<Trace> {
                let mut t = s.run_position(&q, &qd, &qdd)?;
                let tail = s.run(settle, |_| last)?;
                append(&mut t, tail);
                Ok(t)
            };
            let t = run();
            (t, s.axis.fault())
        });
        trace_dict(py, trace.map_err(to_py)?, fault)
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

fn append(t: &mut Trace, tail: Trace) {
    t.time.extend(tail.time);
    t.current.extend(tail.current);
    t.current_reference.extend(tail.current_reference);
    t.duty.extend(tail.duty);
    t.speed.extend(tail.speed);
    t.speed_reference.extend(tail.speed_reference);
    t.position.extend(tail.position);
    t.position_reference.extend(tail.position_reference);
    t.following_error.extend(tail.following_error);
    t.state.extend(tail.state);
}

/// Adds `ServoSim` to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyServoSim>()?;
    Ok(())
}
