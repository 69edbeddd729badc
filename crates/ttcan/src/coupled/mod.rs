//! All axes of a robot together: N [`Axis`] cascades, each on its own motor winding, driving the
//! robot's shared rigid-body mechanics from `ttkin`.
//!
//! Per current-loop period T (one tick):
//!
//! ```text
//! drive k:   i_k⁺ = a_k i_k + (1 − a_k)(u_k − K_e,k G_k q̇_k)/R_k,  a_k = e^{−R_k T/L_k}   (u_k = d_k V_bus)
//! joints:    q̈ = M(q)⁻¹ (τ − h(q, q̇) − τ_f(q̇)),   τ_k = G_k K_t,k ī_k
//! integrate: q̇ ← q̇ + T q̈,  q ← q + T q̇           (semi-implicit Euler)
//! ```
//!
//! The winding is integrated exactly for the duty held over the period and the back-EMF of the
//! speed at its start (L/R = 0.1 ms is of the order of T, an explicit step would be wrong); ī is
//! the period's mean current of that exact solution. M(q) (with the drives' armature G²J_rotor on
//! its diagonal, counted there and only there: the axis controllers are given the link inertia
//! M_kk − G_k²J_k as their load and the rotor inertia as their motor's) and h(q, q̇) (Coriolis,
//! centrifugal, gravity) come from [`ttkin::Dynamics`] and are refreshed every `refresh_ticks`
//! periods (default: every speed-loop period, 5 kHz): the robot's configuration moves by at most
//! q̇_max·4T ≈ 2 mrad between refreshes at 10 rad/s, which changes M and h by parts in 10³ of
//! what the drives' torques change in one period; the Cholesky factor of M is kept between
//! refreshes, so a tick costs one triangular solve.
//!
//! Friction is the drives' joint-side b q̇ + f_c sign(q̇), the Coulomb part saturated linearly
//! below the speed f_c T / M_kk it removes in one period (it stops a joint rather than reversing
//! it: no chatter at rest).
//!
//! Bridge off (axis disabled or faulted) is an open winding: the free-wheeling diodes apply
//! −V_bus·sign(i) until the current reaches zero, then no current flows while |K_e ω_m| < V_bus
//! (the joint coasts; a gravity-loaded joint falls).
//!
//! Energy: every tick adds the electrical input Σ u ī T, the copper loss Σ R ī² T (mean-square of
//! the exact exponential solution) and the friction work Σ τ_f q̇ T; with the kinetic and
//! potential energies of [`ttkin::Dynamics`] and the magnetic ½ L i², input = copper + friction +
//! Δ(kinetic + potential + magnetic) closes to the integration error.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};
use ttkin::{Chain, Dynamics, DynamicsData, JointType, Limits};

use crate::axis::{Axis, AxisConfig, Mode};

mod drives;
pub mod execute;
pub mod journal;
mod trace;
mod winding;
use crate::error::{Error, Result};
use crate::motor::Measurement;
use crate::noise::Gaussian;
use crate::schedule::Scheduler;
pub use drives::{actuator_summaries, axis_configs_from_chain, ActuatorSummary};
pub use trace::CoupledTrace;
use winding::{open_winding_step, winding_step, Winding};

/// Default rate (Hz) of the setpoints handed to the simulated drives (Python `DriveSim`, the θ5
/// case, the rally's drive execution).
pub const SETPOINT_HZ: f64 = 1000.0;

/// Deprecated name of [`SETPOINT_HZ`] (a rate in Hz is `*_hz`, see the glossary).
#[deprecated(since = "0.1.0", note = "use SETPOINT_HZ (a rate in Hz is named *_hz)")]
pub const SETPOINT_RATE: f64 = SETPOINT_HZ;

/// The longest whole-trajectory run [`CoupledSim::run`] accepts, in current-loop ticks (50 s at
/// 20 kHz): its trace keeps every tick (about 100 bytes per tick and axis).
pub const MAX_RUN_TICKS: u64 = 1_000_000;
/// How far beyond a joint's position limits a setpoint may lie, rad or m (the rounding of a
/// stroke sampled at its limit); further is refused (see [`CoupledSim::set_setpoint`]).
pub const SETPOINT_POSITION_MARGIN: f64 = 1e-6;

/// How far over a joint's velocity limit a setpoint's speed may lie, as a share of the limit.
pub const SETPOINT_VELOCITY_MARGIN: f64 = 1e-6;

/// Ticks one step of a caller that names no count advances (the Python `DriveSim.tick()`).
pub const TICKS_PER_CALL: u64 = 1;

/// Options of a [`CoupledSim`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoupledOptions {
    /// Gravity in the base frame, m/s² (`Some([0.0; 3])` to switch it off; `None`: the robot's own,
    /// [`ttkin::Chain::gravity`]).
    pub gravity: Option<[f64; 3]>,
    /// Ideal current loops: the winding current equals the current reference every period.
    pub ideal_current: bool,
    /// Periods between refreshes of M(q), its factor and h(q, q̇) (≥ 1).
    pub refresh_ticks: u32,
    /// Seed of the current-sense noise.
    pub seed: u64,
    /// Cyclic setpoint period given to the axes [`CoupledSim::from_chain`] builds, s (`None`:
    /// setpoints used as they come).
    pub setpoint_period: Option<f64>,
    /// Scale of the current-sense noise of those axes (1: each drive's own, which is
    /// [`DEFAULT_CURRENT_NOISE`](crate::motor::DEFAULT_CURRENT_NOISE) for a drive section; 0: none).
    pub noise_scale: f64,
}

impl CoupledOptions {
    /// The gravity (m/s², base frame) these options give on `chain`: their own, else the chain's.
    pub fn gravity_on(&self, chain: &Chain) -> [f64; 3] {
        self.gravity.unwrap_or_else(|| chain.gravity())
    }
}

impl Default for CoupledOptions {
    fn default() -> Self {
        CoupledOptions {
            gravity: None,
            ideal_current: false,
            refresh_ticks: 4,
            seed: 0,
            setpoint_period: Some(1e-3),
            noise_scale: 1.0,
        }
    }
}

/// Energy flows accumulated since the last [`CoupledSim::reset`], J.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct EnergyBalance {
    /// Electrical energy delivered by the bridges, Σ∫u i dt.
    pub electrical_input: f64,
    /// Heat in the windings, Σ∫R i² dt.
    pub copper_loss: f64,
    /// Work done against joint friction, Σ∫τ_f q̇ dt.
    pub friction_loss: f64,
}

/// N axes on one rigid-body robot, stepped one current-loop period at a time.
#[derive(Debug, Clone)]
pub struct CoupledSim {
    dynamics: Dynamics,
    data: DynamicsData,
    axes: Vec<Axis>,
    /// The joints' limits (the robot file's), which every setpoint must keep.
    limits: Vec<Limits>,
    windings: Vec<Winding>,
    coulomb: Vec<f64>,
    viscous: Vec<f64>,
    scheduler: Scheduler,
    options: CoupledOptions,
    /// Gravity used (m/s², base frame): the options' or the chain's.
    gravity: [f64; 3],
    period: f64,
    time: f64,
    ticks: u64,
    q: Vec<f64>,
    qd: Vec<f64>,
    current: Vec<f64>,
    torque: Vec<f64>,
    h: DVector<f64>,
    diag: Vec<f64>,
    chol: Option<Cholesky<f64, Dyn>>,
    rhs: DVector<f64>,
    energy: EnergyBalance,
    rng: Gaussian,
}

pub(crate) fn model_error(e: ttkin::Error) -> Error {
    Error::Model(e.to_string())
}

impl CoupledSim {
    /// One axis per joint of `chain` (which needs inertias and drives), axis `k` built from
    /// `configs[k]`, all on the loop rates of `configs[0]`, at rest at q = 0.
    pub fn new(chain: &Chain, configs: &[AxisConfig], options: CoupledOptions) -> Result<Self> {
        let dynamics = Dynamics::new(chain).map_err(model_error)?;
        let n = dynamics.dof();
        if configs.len() != n {
            return Err(Error::Stepper(format!(
                "{} axis configurations for {n} joints",
                configs.len()
            )));
        }
        if options.refresh_ticks == 0 {
            return Err(Error::InvalidParameter {
                what: "refresh ticks".into(),
                value: 0.0,
                reason: "must be >= 1".into(),
            });
        }
        let gravity = options.gravity_on(chain);
        crate::error::finite("gravity", gravity.iter().map(|g| g.abs()).sum())?;
        let rates = configs[0].rates;
        let mut axes = Vec::with_capacity(n);
        let mut windings = Vec::with_capacity(n);
        let (mut coulomb, mut viscous) = (vec![0.0; n], vec![0.0; n]);
        let period = rates.periods()[0];
        for (k, (c, j)) in configs.iter().zip(chain.joints()).enumerate() {
            if c.rates != rates {
                return Err(Error::Stepper(format!("axis {k} has loop rates different from axis 0")));
            }
            let drive = j
                .drive()
                .ok_or_else(|| Error::Model(format!("joint '{}' has no drive", j.name())))?;
            axes.push(Axis::new(c)?);
            let m = &c.model.motor;
            if (c.model.gearbox.ratio - drive.gear_ratio).abs() > 1e-9 * drive.gear_ratio {
                return Err(Error::InvalidParameter {
                    what: format!("axis {k} gear ratio"),
                    value: c.model.gearbox.ratio,
                    reason: format!("must equal the robot file's drive gear ratio {}", drive.gear_ratio),
                });
            }
            windings.push(Winding {
                resistance: m.resistance,
                inductance: m.inductance,
                torque_constant: m.torque_constant,
                back_emf_constant: m.back_emf_constant,
                gear: drive.gear_ratio,
                bus_voltage: c.model.bus_voltage,
                counts_per_rev: c.model.encoder_counts_per_rev as f64,
                current_noise: c.model.current_noise,
                decay: (-m.resistance * period / m.inductance).exp(),
            });
            coulomb[k] = drive.coulomb;
            viscous[k] = drive.viscous;
        }
        let data = DynamicsData::new(&dynamics);
        let mut sim = CoupledSim {
            dynamics,
            data,
            axes,
            limits: chain.limits(),
            windings,
            coulomb,
            viscous,
            scheduler: Scheduler::new(&rates),
            options,
            gravity,
            period,
            time: 0.0,
            ticks: 0,
            q: vec![0.0; n],
            qd: vec![0.0; n],
            current: vec![0.0; n],
            torque: vec![0.0; n],
            h: DVector::zeros(n),
            diag: vec![1.0; n],
            chol: None,
            rhs: DVector::zeros(n),
            energy: EnergyBalance::default(),
            rng: Gaussian::new(options.seed ^ 0x5eed_c0de),
        };
        sim.reset(&vec![0.0; n], None)?;
        Ok(sim)
    }

    /// One axis per joint built from the robot's drive sections by [`axis_configs_from_chain`] at `q0`, then
    /// [`CoupledSim::reset`] to (`q0`, 0).
    pub fn from_chain(chain: &Chain, q0: &[f64], options: CoupledOptions) -> Result<Self> {
        let configs = axis_configs_from_chain(chain, q0, &options)?;
        let mut sim = CoupledSim::new(chain, &configs, options)?;
        sim.reset(q0, None)?;
        Ok(sim)
    }

    /// Puts the robot at (`q0`, `qd0` or rest) with zero currents, every axis enabled in position
    /// mode holding `q0`, time 0, energy counters 0.
    pub fn reset(&mut self, q0: &[f64], qd0: Option<&[f64]>) -> Result<()> {
        let n = self.dof();
        check_vector("q0", q0, n)?;
        if let Some(v) = qd0 {
            check_vector("qd0", v, n)?;
        }
        self.q.copy_from_slice(q0);
        match qd0 {
            Some(v) => self.qd.copy_from_slice(v),
            None => self.qd.iter_mut().for_each(|v| *v = 0.0),
        }
        self.current.iter_mut().for_each(|i| *i = 0.0);
        self.torque.iter_mut().for_each(|t| *t = 0.0);
        self.time = 0.0;
        self.ticks = 0;
        self.energy = EnergyBalance::default();
        self.rng = Gaussian::new(self.options.seed ^ 0x5eed_c0de);
        let rates = *self.axes[0].rates();
        self.scheduler = Scheduler::new(&rates);
        for k in 0..n {
            let config = *self.axes[k].config();
            self.axes[k] = Axis::new(&config)?;
        }
        self.refresh()?;
        // One tick with the bridges off lets every axis read its encoder, then hold where it is.
        self.tick();
        for a in &mut self.axes {
            a.enable(Mode::Position);
        }
        Ok(())
    }

    fn refresh(&mut self) -> Result<()> {
        let n = self.dof();
        let h = self
            .dynamics
            .nonlinear_effects(&mut self.data, &self.q, &self.qd, &self.gravity)
            .map_err(model_error)?;
        self.h.copy_from(h);
        let m = self
            .dynamics
            .mass_matrix(&mut self.data, &self.q)
            .map_err(model_error)?;
        for k in 0..n {
            self.diag[k] = m[(k, k)];
        }
        let m: DMatrix<f64> = m.clone();
        self.chol = Some(Cholesky::new(m).ok_or_else(|| Error::Model("mass matrix is not positive definite".into()))?);
        Ok(())
    }

    /// Number of axes (joints).
    pub fn dof(&self) -> usize {
        self.q.len()
    }

    /// One current-loop period: measure, run every axis, step the windings and the mechanics.
    pub fn tick(&mut self) {
        let n = self.dof();
        let t = self.period;
        if self.ticks.is_multiple_of(self.options.refresh_ticks as u64) && self.ticks > 0 {
            // A configuration the model rejects (non-finite after a divergence) keeps the old factor.
            let _ = self.refresh();
        }
        let due = self.scheduler.next_tick();
        for k in 0..n {
            let w = self.windings[k];
            let noise = if w.current_noise > 0.0 {
                w.current_noise * self.rng.normal()
            } else {
                0.0
            };
            let motor_angle = self.q[k] * w.gear;
            let counts = (motor_angle * w.counts_per_rev / (2.0 * std::f64::consts::PI)).floor();
            let m = Measurement {
                current: self.current[k] + noise,
                encoder_counts: counts as i64,
                bus_voltage: Some(w.bus_voltage),
            };
            let duty = self.axes[k].tick(m, due);
            let bridge_on = self.axes[k].bridge_on();
            let omega_m = w.gear * self.qd[k];
            let emf = w.back_emf_constant * omega_m;
            let i0 = self.current[k];
            let (u, i1, mean, mean_sq) = if self.options.ideal_current && bridge_on {
                let i = self.axes[k].current_reference();
                (w.resistance * i + emf, i, i, i * i)
            } else if bridge_on {
                let u = duty.clamp(-1.0, 1.0) * w.bus_voltage;
                let (i1, mean, mean_sq) = winding_step(&w, i0, u - emf, t);
                (u, i1, mean, mean_sq)
            } else {
                open_winding_step(&w, i0, emf, t)
            };
            self.current[k] = i1;
            self.torque[k] = w.gear * w.torque_constant * mean;
            self.energy.electrical_input += u * mean * t;
            self.energy.copper_loss += w.resistance * mean_sq * t;
        }
        // Mechanics: q̈ = M⁻¹(τ − h − τ_f).
        for k in 0..n {
            let v = self.qd[k];
            let v_stick = self.coulomb[k] * t / self.diag[k].max(1e-12);
            let coulomb = if v_stick > 0.0 {
                self.coulomb[k] * (v / v_stick).clamp(-1.0, 1.0)
            } else {
                0.0
            };
            let friction = self.viscous[k] * v + coulomb;
            self.energy.friction_loss += friction * v * t;
            self.rhs[k] = self.torque[k] - self.h[k] - friction;
        }
        if let Some(c) = &self.chol {
            c.solve_mut(&mut self.rhs);
        }
        for k in 0..n {
            self.qd[k] += t * self.rhs[k];
            self.q[k] += t * self.qd[k];
        }
        self.time += t;
        self.ticks += 1;
    }

    /// Runs `n` ticks.
    pub fn tick_n(&mut self, n: u64) {
        self.tick_n_until(n, &|| false);
    }

    /// Runs `n` ticks, or fewer when `stop()` turns true (a caller's cancellation, polled every
    /// [`ttkin::budget::STOP_POLL_STEPS`] ticks); returns the ticks run.
    pub fn tick_n_until(&mut self, n: u64, stop: ttkin::budget::Stop<'_>) -> u64 {
        for k in 0..n {
            if (k + 1).is_multiple_of(ttkin::budget::STOP_POLL_STEPS) && stop() {
                return k;
            }
            self.tick();
        }
        n
    }

    /// Hands every axis a position setpoint (joint space: rad or m, per s, per s²) and a
    /// joint-side torque feed-forward (N·m or N; `None`: zero). A finite position outside the
    /// joint's limits or a speed over its velocity limit (beyond [`SETPOINT_POSITION_MARGIN`],
    /// [`SETPOINT_VELOCITY_MARGIN`]) is refused with [`Error::InvalidParameter`] before any axis
    /// takes it (a setpoint of 1e300 drove the axis into its following-error fault); a non-finite
    /// value faults the axis (`InvalidReference`), as a drive does.
    pub fn set_setpoint(&mut self, q: &[f64], qd: &[f64], qdd: &[f64], tau_ff: Option<&[f64]>) -> Result<()> {
        let n = self.dof();
        check_len("q", q, n)?;
        check_len("qd", qd, n)?;
        check_len("qdd", qdd, n)?;
        if let Some(t) = tau_ff {
            check_len("tau_ff", t, n)?;
        }
        self.check_within_limits(None, q, qd)?;
        for k in 0..n {
            self.axes[k].set_position(q[k], qd[k], qdd[k]);
            if let Some(t) = tau_ff {
                self.axes[k].set_torque_feedforward(t[k]);
            }
        }
        Ok(())
    }

    /// Checks a setpoint (q, qd: one value per joint) against the joints' position and velocity
    /// limits with their margins; `row` names the sample of a run (`q[12, 3]`), `None` a single
    /// setpoint (`q[3]`). Non-finite values pass (they fault the axis that takes them).
    pub(crate) fn check_within_limits(&self, row: Option<usize>, q: &[f64], qd: &[f64]) -> Result<()> {
        let joints = self.dynamics.chain().joints();
        for (k, lim) in self.limits.iter().enumerate() {
            let (unit, speed) = match joints[k].kind() {
                JointType::Revolute => ("rad", "rad/s"),
                JointType::Prismatic => ("m", "m/s"),
            };
            let what = |name: &str| match row {
                Some(i) => format!("{name}[{i}, {k}]"),
                None => format!("{name}[{k}]"),
            };
            let (lo, hi) = (
                lim.lower - SETPOINT_POSITION_MARGIN,
                lim.upper + SETPOINT_POSITION_MARGIN,
            );
            if q[k].is_finite() && !(lo..=hi).contains(&q[k]) {
                return Err(Error::InvalidParameter {
                    what: what("q"),
                    value: q[k],
                    reason: format!(
                        "outside joint '{}' position limits [{}, {}] {unit}: the drives take setpoints within \
                         the robot's limits only",
                        joints[k].name(),
                        lim.lower,
                        lim.upper
                    ),
                });
            }
            if let Some(v) = lim.velocity.filter(|v| v.is_finite() && *v > 0.0) {
                if qd[k].is_finite() && qd[k].abs() > v * (1.0 + SETPOINT_VELOCITY_MARGIN) {
                    return Err(Error::InvalidParameter {
                        what: what("qd"),
                        value: qd[k],
                        reason: format!(
                            "over joint '{}' velocity limit {v} {speed}: the drives take setpoints within \
                             the robot's limits only",
                            joints[k].name()
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    /// Simulated time since the last reset, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Current-loop (tick) rate, Hz.
    pub fn tick_hz(&self) -> f64 {
        1.0 / self.period
    }

    /// Deprecated name of [`CoupledSim::tick_hz`].
    #[deprecated(since = "0.1.0", note = "use tick_hz (a rate in Hz is named *_hz)")]
    pub fn tick_rate(&self) -> f64 {
        self.tick_hz()
    }

    /// True joint positions, rad or m.
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// True joint speeds, rad/s or m/s.
    pub fn qd(&self) -> &[f64] {
        &self.qd
    }

    /// True winding currents, A.
    pub fn current(&self) -> &[f64] {
        &self.current
    }

    /// Joint-side motor torques of the last period (G k_t ī), N·m or N.
    pub fn torque(&self) -> &[f64] {
        &self.torque
    }

    /// The axes (their references, states, faults).
    pub fn axes(&self) -> &[Axis] {
        &self.axes
    }

    /// Each axis' current reference after limiting, A (its `current_reference()`).
    pub fn current_references(&self) -> Vec<f64> {
        self.axes.iter().map(Axis::current_reference).collect()
    }

    /// The axes (to enable, disable, clear faults).
    pub fn axes_mut(&mut self) -> &mut [Axis] {
        &mut self.axes
    }

    /// The robot's dynamic model.
    pub fn dynamics(&self) -> &Dynamics {
        &self.dynamics
    }

    /// Energy flows since the last reset.
    pub fn energy(&self) -> EnergyBalance {
        self.energy
    }

    /// Stored energy now, J: kinetic + potential of the robot + magnetic ½ L i² of the windings.
    pub fn stored_energy(&mut self) -> Result<f64> {
        let kinetic = self
            .dynamics
            .kinetic_energy(&mut self.data, &self.q, &self.qd)
            .map_err(model_error)?;
        let potential = self
            .dynamics
            .potential_energy(&self.q, &self.gravity)
            .map_err(model_error)?;
        let magnetic: f64 = self
            .windings
            .iter()
            .zip(&self.current)
            .map(|(w, i)| 0.5 * w.inductance * i * i)
            .sum();
        Ok(kinetic + potential + magnetic)
    }

    /// Joint kinds, chain order.
    pub fn joint_types(&self) -> Vec<JointType> {
        self.dynamics.chain().joints().iter().map(|j| j.kind()).collect()
    }

    /// Fault of each axis as text ("" when none).
    pub fn fault_names(&self) -> Vec<String> {
        self.axes
            .iter()
            .map(|a| a.fault().map_or(String::new(), |f| format!("{f:?}")))
            .collect()
    }
}

pub(super) fn check_vector(what: &str, v: &[f64], n: usize) -> Result<()> {
    check_len(what, v, n)?;
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite {
            what: format!("{what}[{i}]"),
            value: v[i],
        });
    }
    Ok(())
}

pub(super) fn check_len(what: &str, v: &[f64], n: usize) -> Result<()> {
    if v.len() != n {
        return Err(Error::InvalidParameter {
            what: format!("{what} length"),
            value: v.len() as f64,
            reason: format!("expected {n} values"),
        });
    }
    Ok(())
}
