//! Reference cases of the drive layer, shared by the tests, the demo's `summary.json` and its
//! figure, so that the numbers quoted anywhere come from one computation.
//!
//! The θ5 case (issue 10): gantry6's demo hitting stroke (the pipeline's default hit request:
//! racket at (0.35, −0.55, 0.05) m, face normal (0.3, −1, −0.2), 3 m/s along the normal at
//! t = 0.3 s, from and back to the ready pose (0, 0, 0, 0.6, 0.6, 0)), joint θ5 (index 4) driven
//! alone by a maxon RE 25 + GP 26 A 14:1 with a 4096-count encoder, its load 0.0148 kg·m² as the
//! issue defines it (the mean link-only mass-matrix entry M₄₄ along the stroke plus
//! [`ISSUE_THETA5_ARMATURE`], so the case does not move when gantry6's drives change), no gravity
//! (as in the demo).

use nalgebra::Vector3;
use ttkin::hit::{Hit, RacketMount};
use ttkin::ik::{Analytic, LimitFilter};
use ttkin::traj::limits::KinematicLimits;
use ttkin::traj::{stroke::stroke, JointState, JointTrajectory};
use ttkin::{Chain, Dynamics, DynamicsData};

use crate::axis::{AxisConfig, Mode};
use crate::error::{Error, Result};
use crate::motor::{Load, MotorModel};
use crate::sim::{Simulation, Trace};

/// The gantry6 demo stroke: the planned joint trajectory (m, rad) and its hit time (s).
#[derive(Debug, Clone)]
pub struct DemoStroke {
    /// Hit leg then return leg, starting at 0 s.
    pub trajectory: JointTrajectory,
    /// Planned hit time, s.
    pub t_hit: f64,
}

fn ttkin_error(e: ttkin::Error) -> Error {
    Error::Model(e.to_string())
}

/// Plans the demo stroke of gantry6 (the default hit request of `ttmanip.pipeline`): the hit as a
/// [`ttkin::hit::Hit`] (the one racket frame, [`ttkin::hit::racket_frame`]), the IK target through
/// the chain's racket mount, q̇ = J⁻¹V, then the quintic stroke at 0.30 s.
pub fn gantry6_demo_stroke(chain: &Chain) -> Result<DemoStroke> {
    let normal = Vector3::new(0.3, -1.0, -0.2).normalize();
    let v = normal * 3.0;
    let hit = Hit::from_normal([0.35, -0.55, 0.05], normal.into(), v.into(), 0.30, None, None).map_err(ttkin_error)?;
    let ready = chain.ready();
    let ik = Analytic::for_chain(chain).ok_or_else(|| Error::Model("gantry6 has no analytic IK".into()))?;
    let racket = RacketMount::for_chain(chain);
    let target = racket.tool_pose(&hit.pose);
    let q_hit = ik.nearest(&target, &ready, LimitFilter::Enforce).map_err(ttkin_error)?;
    let twist = racket.tool_twist(&target, &hit.twist);
    let qd_hit = ttkin::ik::differential::DifferentialIk::default()
        .solve(chain, &q_hit, &twist, None)
        .map_err(ttkin_error)?
        .qd;
    let limits = KinematicLimits::from_chain(chain, None).map_err(ttkin_error)?;
    let (lower, upper): (Vec<f64>, Vec<f64>) = chain
        .joints()
        .iter()
        .map(|j| (j.limits().lower, j.limits().upper))
        .unzip();
    let limits = limits.with_position(&lower, &upper).map_err(ttkin_error)?;
    let hit = JointState {
        q: q_hit.clone(),
        qd: qd_hit.to_vec(),
        qdd: vec![0.0; q_hit.len()],
    };
    let s = stroke(&JointState::rest(&ready), &hit, 0.30, &ready, None, &limits).map_err(ttkin_error)?;
    Ok(DemoStroke {
        trajectory: s.trajectory,
        t_hit: s.t_hit,
    })
}

/// Mean of the mass-matrix diagonal entry of `joint` (the drive armature G²·J included or not), sampled at
/// 50 instants along `trajectory` (kg·m² or kg).
pub fn mean_joint_inertia(
    chain: &Chain,
    trajectory: &JointTrajectory,
    joint: usize,
    with_armature: bool,
) -> Result<f64> {
    let dynamics = Dynamics::new(chain).map_err(ttkin_error)?;
    let mut data = DynamicsData::new(&dynamics);
    let n = dynamics.dof();
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let samples = 50;
    let mut sum = 0.0;
    for k in 0..samples {
        let t = trajectory.duration() * k as f64 / samples as f64;
        trajectory.sample(t, &mut q, &mut qd, &mut qdd).map_err(ttkin_error)?;
        let m = dynamics.mass_matrix(&mut data, &q).map_err(ttkin_error)?;
        sum += m[(joint, joint)] - if with_armature { 0.0 } else { dynamics.armature()[joint] };
    }
    Ok(sum / samples as f64)
}

/// The armature of the θ5 drive gantry6 had when issue 10 was filed (30:1, 2·10⁻⁶ kg·m² rotor):
/// part of the case's load as the issue defines it (0.0148 kg·m²), whatever gantry6's drive is now.
pub const ISSUE_THETA5_ARMATURE: f64 = 30.0 * 30.0 * 2.0e-6;

/// What the θ5 case measures.
#[derive(Debug, Clone)]
pub struct Theta5Case {
    /// Load inertia about θ5 used (mean link-only M₄₄ along the stroke plus
    /// [`ISSUE_THETA5_ARMATURE`], as the issue defines it), kg·m².
    pub load_inertia: f64,
    /// Rate at which the position setpoints reach the drive, Hz.
    pub setpoint_hz: f64,
    /// RMS(i − i_ref) over the run, A.
    pub current_ripple_rms: f64,
    /// RMS(i − i_needed) over the run, A: i_needed = the current the reference motion needs
    /// (inertia × acceleration plus friction of the model, through k_t and the gear).
    pub current_error_rms: f64,
    /// Largest |q_ref(t) − q(t)| of the true joint against the reference trajectory at the
    /// setpoint instants, rad.
    pub max_following_error: f64,
    /// The recorded run (one sample per current-loop period).
    pub trace: Trace,
    /// The current the motion needs at each sample, A.
    pub current_needed: Vec<f64>,
    /// The reference trajectory at each sample (in the axis' coordinates), rad.
    pub reference: Vec<f64>,
}

/// Runs the θ5 case with setpoints arriving at `setpoint_hz` (a divisor of the speed-loop rate;
/// the position-loop rate gives the demo's case) with the default axis configuration of the
/// RE 25 + GP 26 A 14:1 actuator carrying the θ5 load.
pub fn theta5_case(setpoint_hz: f64) -> Result<Theta5Case> {
    theta5_case_with(setpoint_hz, |_| {})
}

/// [`theta5_case`] with the axis configuration changed by `tune` first.
pub fn theta5_case_with(setpoint_hz: f64, tune: impl FnOnce(&mut AxisConfig)) -> Result<Theta5Case> {
    let chain = ttkin::robots::gantry6();
    let s = gantry6_demo_stroke(&chain)?;
    let load_inertia = mean_joint_inertia(&chain, &s.trajectory, 4, false)? + ISSUE_THETA5_ARMATURE;
    let mut model = MotorModel::maxon_re25_gp26();
    model.load = Load {
        inertia: load_inertia,
        viscous_friction: 0.0,
    };
    let mut config = AxisConfig::new(model);
    config.setpoint_period = Some(1.0 / setpoint_hz);
    tune(&mut config);
    theta5_run(&s, 4, &model, &config, setpoint_hz, 0.05)
}

/// Drives joint `joint` of `stroke` (relative to its start) with one axis, setpoints at
/// `setpoint_hz`, then holds the end for `settle` s.
pub fn theta5_run(
    stroke: &DemoStroke,
    joint: usize,
    model: &MotorModel,
    config: &AxisConfig,
    setpoint_hz: f64,
    settle: f64,
) -> Result<Theta5Case> {
    let mut sim = Simulation::new(model, config)?;
    sim.enable(Mode::Position);
    // Start on a position-loop tick, so that each setpoint is used the tick it arrives.
    while !sim.next_due().position {
        sim.step();
    }
    let traj = &stroke.trajectory;
    let n = traj.dof();
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    traj.sample(0.0, &mut q, &mut qd, &mut qdd).map_err(ttkin_error)?;
    // Relative to where the axis believes it starts (mid-count), so that the first setpoint is no step.
    let q0 = q[joint] - sim.axis.position();
    let dt = config.rates.periods()[0];
    let ticks_per_setpoint = (1.0 / (setpoint_hz * dt)).round().max(1.0) as u64;
    let total = ((traj.duration() + settle) / dt).round() as u64;
    let mut reference = |t: f64| -> (f64, f64, f64) {
        let tt = t.clamp(0.0, traj.duration());
        let _ = traj.sample(tt, &mut q, &mut qd, &mut qdd);
        (q[joint] - q0, qd[joint], qdd[joint])
    };
    let mut trace = Trace::default();
    let mut needed = Vec::with_capacity(total as usize);
    let mut reference_at = Vec::with_capacity(total as usize);
    let mut max_fe = 0.0f64;
    let k_acc = model.acceleration_per_amp();
    let lead = if config.setpoint_period.is_some() {
        1.0 / setpoint_hz
    } else {
        0.0
    };
    for k in 0..total {
        let t = k as f64 * dt;
        if k % ticks_per_setpoint == 0 {
            // A host sends each setpoint one interpolation period ahead (the drive interpolates
            // from the previous setpoint to it over that period).
            let (a, b, c) = reference(t + lead);
            sim.axis.set_position(a, b, c);
        }
        let (qr, qdr, qddr) = reference(t);
        reference_at.push(qr);
        let m = &model.motor;
        let n_g = model.gearbox.ratio;
        let w_m = qdr * n_g;
        let friction = m.viscous_friction * w_m
            + if w_m.abs() > 1e-9 {
                m.coulomb_friction * w_m.signum()
            } else {
                0.0
            };
        needed.push(qddr / k_acc + friction / m.torque_constant);
        sim.record_into(&mut trace);
        if k % ticks_per_setpoint == 0 {
            max_fe = max_fe.max((qr - sim.plant.output_position()).abs());
        }
        sim.step();
    }
    let rms = |a: &[f64], b: &[f64]| {
        (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len().max(1) as f64).sqrt()
    };
    Ok(Theta5Case {
        load_inertia: model.load.inertia,
        setpoint_hz,
        current_ripple_rms: rms(&trace.current, &trace.current_reference),
        current_error_rms: rms(&trace.current, &needed),
        max_following_error: max_fe,
        trace,
        current_needed: needed,
        reference: reference_at,
    })
}
