//! Rigid-body dynamics of a serial chain: inverse dynamics (recursive Newton–Euler), gravity and
//! Coriolis torques, the joint-space mass matrix (composite rigid body algorithm), forward dynamics
//! (Cholesky solve of the mass matrix), a semi-implicit Euler integrator and the torque profile of
//! a planned motion with its effort-limit check and motor-side torques and currents.
//!
//! Model/data separation as in Pinocchio: [`Dynamics`] is what the robot is (built once from a
//! [`Chain`], validated, immutable), [`DynamicsData`] is the scratch space of the algorithms
//! (allocated once; the single-configuration calls allocate nothing).
//!
//! Frames. Every joint is `pre · M(q) · post` (see [`crate::joint`]). The algorithms work in the
//! joint frames F_i = (frame before joint i) · pre_i · M(q_i), whose z axis is the joint axis, so the
//! motion subspace is the constant S = (ẑ, 0) for a revolute and S = (0, ẑ) for a prismatic joint,
//! whichever DH convention or URDF origin described it. Link inertias, given in the link frame
//! (F_i · post_i), are moved into F_i once, when the model is built. Spatial vectors are
//! (angular; linear) pairs, velocities at the frame origin, forces as (moment about the origin;
//! force), Featherstone's notation (Rigid Body Dynamics Algorithms, 2008, ch. 5–6).
//!
//! Equation of motion, with the armature A = diag(G_i²·J_rotor,i) of the drives included in M:
//! τ = M(q)·q̈ + C(q, q̇)·q̇ + g(q) − Jᵀ(q)·w_ext (+ friction, see [`Dynamics::inverse_dynamics`]).
//! Gravity is a vector in the base frame (m/s², e.g. (0, 0, −9.81)).

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector, IsometryMatrix3, Matrix3, Vector3};
use rayon::prelude::*;

use crate::chain::Chain;
use crate::error::{check_finite, check_vector, Error, Result};
use crate::inertial::Inertial;
use crate::joint::{Drive, JointType};

/// Standard gravity in a z-up base frame, m/s².
pub const EARTH_GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// Configurations per rayon task in batch calls.
const BATCH_CHUNK: usize = 64;

/// A wrench the environment applies to the tool (a ball on the racket, a payload's weight):
/// force in N and moment about the tool point in N·m, both in tool-frame axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force on the tool, N, tool-frame axes.
    pub force: Vector3<f64>,
    /// Moment on the tool about the tool point, N·m, tool-frame axes.
    pub torque: Vector3<f64>,
}

/// Spatial inertia of a body about the origin of its joint frame: mass m (kg), first moment
/// h = m·c (kg·m) and rotational inertia about the origin I_o (kg·m²).
#[derive(Debug, Clone, Copy, PartialEq)]
struct BodyInertia {
    mass: f64,
    h: Vector3<f64>,
    i_o: Matrix3<f64>,
}

/// m·(|x|²·1 − x·xᵀ): the parallel-axis term of a point mass m at x.
#[inline(always)]
fn shift(m: f64, x: &Vector3<f64>) -> Matrix3<f64> {
    m * (Matrix3::identity() * x.dot(x) - x * x.transpose())
}

impl BodyInertia {
    const ZERO: BodyInertia = BodyInertia {
        mass: 0.0,
        h: Vector3::new(0.0, 0.0, 0.0),
        i_o: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// The inertia of `i` (given in the link frame) about the origin of the frame in which the link
    /// frame has pose `link`.
    fn from_inertial(i: &Inertial, link: &IsometryMatrix3<f64>) -> Self {
        let moved = i.transformed(link);
        BodyInertia {
            mass: moved.mass,
            h: moved.com * moved.mass,
            i_o: moved.inertia + shift(moved.mass, &moved.com),
        }
    }

    /// Momentum (moment about the origin; force) of the body moving with spatial velocity (ω; v).
    #[inline(always)]
    fn apply(&self, w: &Vector3<f64>, v: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        (self.i_o * w + self.h.cross(v), v * self.mass - self.h.cross(w))
    }

    /// The same body seen from the parent frame, in which this frame has rotation `r`, origin `p`.
    /// I_o' = R·I_o·Rᵀ + 2(y·p)·1 − (y·pᵀ + p·yᵀ) + m(|p|²·1 − p·pᵀ), y = R·h.
    #[inline(always)]
    fn in_parent(&self, r: &Matrix3<f64>, p: &Vector3<f64>) -> Self {
        let y = r * self.h;
        let yp = y * p.transpose();
        BodyInertia {
            mass: self.mass,
            h: y + p * self.mass,
            i_o: r * self.i_o * r.transpose() + Matrix3::identity() * (2.0 * y.dot(p)) - yp - yp.transpose()
                + shift(self.mass, p),
        }
    }

    #[inline(always)]
    fn add(&mut self, other: &BodyInertia) {
        self.mass += other.mass;
        self.h += other.h;
        self.i_o += other.i_o;
    }
}

/// The dynamic model of a chain: joint frames, link inertias in joint frames, drives. Built once
/// with [`Dynamics::new`]; immutable.
#[derive(Debug, Clone, PartialEq)]
pub struct Dynamics {
    chain: Chain,
    kinds: Vec<JointType>,
    /// fixed[0] = base·pre_0, fixed[i] = post_{i−1}·pre_i, fixed[n] = post_{n−1}·tool.
    fixed: Vec<IsometryMatrix3<f64>>,
    bodies: Vec<BodyInertia>,
    /// Link inertias in link frames (for the potential energy).
    links: Vec<Inertial>,
    armature: Vec<f64>,
    drives: Vec<Option<Drive>>,
}

/// Scratch space of the dynamics algorithms for one [`Dynamics`] model (no allocation per call).
#[derive(Debug, Clone)]
pub struct DynamicsData {
    rot: Vec<Matrix3<f64>>,
    pos: Vec<Vector3<f64>>,
    w: Vec<Vector3<f64>>,
    v: Vec<Vector3<f64>>,
    moment: Vec<Vector3<f64>>,
    force: Vec<Vector3<f64>>,
    composite: Vec<BodyInertia>,
    tau: DVector<f64>,
    mass: DMatrix<f64>,
    chol: DMatrix<f64>,
    qdd: DVector<f64>,
    zeros: DVector<f64>,
}

impl DynamicsData {
    /// Scratch space for `model`.
    pub fn new(model: &Dynamics) -> Self {
        let n = model.dof();
        let z3 = vec![Vector3::zeros(); n];
        DynamicsData {
            rot: vec![Matrix3::identity(); n],
            pos: z3.clone(),
            w: z3.clone(),
            v: z3.clone(),
            moment: z3.clone(),
            force: z3,
            composite: vec![BodyInertia::ZERO; n],
            tau: DVector::zeros(n),
            mass: DMatrix::zeros(n, n),
            chol: DMatrix::zeros(n, n),
            qdd: DVector::zeros(n),
            zeros: DVector::zeros(n),
        }
    }

    /// Number of joints this scratch space was made for.
    pub fn dof(&self) -> usize {
        self.tau.len()
    }
}

/// Torques along a planned motion: joint side (rigid body + armature + friction), motor side and
/// current, with the effort-limit check of the patent's step S105.
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueProfile {
    /// Number of joints n.
    pub dof: usize,
    /// Joint torques (N·m) or forces (N), N × n row-major.
    pub joint: Vec<f64>,
    /// Motor torques τ/G, N·m, N × n row-major (equal to `joint` for a joint without drive).
    pub motor: Vec<f64>,
    /// Motor currents τ_motor/k_t, A, N × n row-major; NaN for a joint without torque constant.
    pub current: Vec<f64>,
    /// Largest |joint torque| per joint over the profile (N·m or N).
    pub peak: Vec<f64>,
    /// Every (sample, joint) whose |joint torque| exceeds the joint's effort limit.
    pub violations: Vec<EffortViolation>,
}

impl TorqueProfile {
    /// True when no sample exceeds any effort limit.
    pub fn within_limits(&self) -> bool {
        self.violations.is_empty()
    }
}

/// One sample at which a joint needs more than its effort limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffortViolation {
    /// Index of the sample in the trajectory.
    pub sample: usize,
    /// Index of the joint.
    pub joint: usize,
    /// Required joint torque (N·m) or force (N).
    pub torque: f64,
    /// The joint's effort limit (N·m or N).
    pub limit: f64,
}

/// Checks a 3-vector argument and turns it into a `Vector3`.
fn vec3(what: &str, v: &[f64; 3]) -> Result<Vector3<f64>> {
    check_finite(what, v)?;
    Ok(Vector3::from(*v))
}

impl Dynamics {
    /// The dynamic model of `chain`. Every link needs an inertial (an error names the first link
    /// without one); inertias were already checked for physical consistency when attached.
    pub fn new(chain: &Chain) -> Result<Self> {
        let joints = chain.joints();
        let n = joints.len();
        let mut links = Vec::with_capacity(n);
        for (i, j) in joints.iter().enumerate() {
            match j.inertial() {
                Some(inertial) => {
                    inertial.validate(j.name())?;
                    links.push(*inertial);
                }
                None => {
                    return Err(Error::Model(format!(
                    "chain '{}': the link moved by joint '{}' (joint {} of {n}, 'link{}' in exported URDF) has no inertial; \
                         dynamics needs the mass, centre of mass and inertia of every link",
                    chain.name(),
                    j.name(),
                    i + 1,
                    i + 1
                )))
                }
            }
        }
        let mut fixed = Vec::with_capacity(n + 1);
        fixed.push(chain.base() * joints[0].pre());
        for i in 1..n {
            fixed.push(joints[i - 1].post() * joints[i].pre());
        }
        fixed.push(joints[n - 1].post() * chain.tool());
        let bodies = joints
            .iter()
            .zip(&links)
            .map(|(j, l)| BodyInertia::from_inertial(l, j.post()))
            .collect();
        Ok(Dynamics {
            chain: chain.clone(),
            kinds: joints.iter().map(|j| j.kind()).collect(),
            fixed,
            bodies,
            links,
            armature: joints.iter().map(|j| j.drive().map_or(0.0, Drive::armature)).collect(),
            drives: joints.iter().map(|j| j.drive().copied()).collect(),
        })
    }

    /// Number of joints n.
    pub fn dof(&self) -> usize {
        self.kinds.len()
    }

    /// The chain this model was built from.
    pub fn chain(&self) -> &Chain {
        &self.chain
    }

    /// Rotor inertia reflected to each joint, G²·J (kg·m² or kg); Pinocchio's `model.armature`.
    pub fn armature(&self) -> &[f64] {
        &self.armature
    }

    /// Total mass of the links, kg.
    pub fn total_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass).sum()
    }

    fn check_data(&self, data: &DynamicsData) -> Result<()> {
        if data.dof() != self.dof() {
            return Err(Error::shape(
                "dynamics data",
                format!("scratch space for {} joints", self.dof()),
                format!("{} joints", data.dof()),
            ));
        }
        Ok(())
    }

    /// Joint frame poses F_i in F_{i−1} (F_{−1} = base frame) at `q`, into `data.rot`/`data.pos`.
    #[inline(always)]
    fn place(&self, data: &mut DynamicsData, q: &[f64]) {
        for i in 0..self.dof() {
            let f = &self.fixed[i];
            let rf = f.rotation.matrix();
            match self.kinds[i] {
                JointType::Revolute => {
                    let (s, c) = crate::trig::sin_cos(q[i]);
                    let (c0, c1) = (rf.column(0), rf.column(1));
                    let r = &mut data.rot[i];
                    r.set_column(0, &(c0 * c + c1 * s));
                    r.set_column(1, &(c1 * c - c0 * s));
                    r.set_column(2, &rf.column(2));
                    data.pos[i] = f.translation.vector;
                }
                JointType::Prismatic => {
                    data.rot[i] = *rf;
                    data.pos[i] = f.translation.vector + rf.column(2) * q[i];
                }
            }
        }
    }

    /// Recursive Newton–Euler without argument checks; result in `data.tau`.
    fn rnea_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &Vector3<f64>,
        wrench: Option<&Wrench>,
    ) {
        let n = self.dof();
        self.place(data, q);
        // The base is fixed; gravity enters as an upward acceleration of the base, a_0 = −g.
        let (mut w, mut v, mut dw, mut dv) = (Vector3::zeros(), Vector3::zeros(), Vector3::zeros(), -gravity);
        for i in 0..n {
            let rt = data.rot[i].transpose();
            let p = &data.pos[i];
            let dv_parent = dv + dw.cross(p);
            let v_parent = v + w.cross(p);
            w = rt * w;
            v = rt * v_parent;
            dw = rt * dw;
            dv = rt * dv_parent;
            let z = Vector3::z();
            match self.kinds[i] {
                JointType::Revolute => {
                    w.z += qd[i];
                    // a_i += S·q̈ + v_i ×ₘ S·q̇, S = (ẑ; 0).
                    dw += w.cross(&z) * qd[i];
                    dw.z += qdd[i];
                    dv += v.cross(&z) * qd[i];
                }
                JointType::Prismatic => {
                    v.z += qd[i];
                    // a_i += S·q̈ + v_i ×ₘ S·q̇, S = (0; ẑ).
                    dv += w.cross(&z) * qd[i];
                    dv.z += qdd[i];
                }
            }
            // f_i = I·a + v ×* (I·v).
            let body = &self.bodies[i];
            let (ia_n, ia_f) = body.apply(&dw, &dv);
            let (iv_n, iv_f) = body.apply(&w, &v);
            data.moment[i] = ia_n + w.cross(&iv_n) + v.cross(&iv_f);
            data.force[i] = ia_f + w.cross(&iv_f);
            data.w[i] = w;
            data.v[i] = v;
        }
        if let Some(ext) = wrench {
            // The environment pushes on the tool: the joints need that much less.
            let t = &self.fixed[n];
            let f = t.rotation * ext.force;
            let m = t.rotation * ext.torque + t.translation.vector.cross(&f);
            data.force[n - 1] -= f;
            data.moment[n - 1] -= m;
        }
        for i in (0..n).rev() {
            data.tau[i] = match self.kinds[i] {
                JointType::Revolute => data.moment[i].z,
                JointType::Prismatic => data.force[i].z,
            } + self.armature[i] * qdd[i];
            if i > 0 {
                let r = &data.rot[i];
                let f = r * data.force[i];
                let m = r * data.moment[i] + data.pos[i].cross(&f);
                data.force[i - 1] += f;
                data.moment[i - 1] += m;
            }
        }
    }

    fn check_state(&self, data: &DynamicsData, q: &[f64], qd: &[f64]) -> Result<()> {
        self.check_data(data)?;
        check_vector("q", q, self.dof())?;
        check_vector("qd", qd, self.dof())
    }

    /// Inverse dynamics (recursive Newton–Euler): joint torques (N·m) / forces (N) that produce
    /// `qdd` at (`q`, `qd`) under `gravity` (m/s², base frame) with an optional `wrench` on the
    /// tool; rigid bodies plus armature, no friction (Pinocchio's `rnea`).
    pub fn rnea<'d>(
        &self,
        data: &'d mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
    ) -> Result<&'d DVector<f64>> {
        self.check_state(data, q, qd)?;
        check_vector("qdd", qdd, self.dof())?;
        let g = vec3("gravity", gravity)?;
        if let Some(w) = wrench {
            check_finite(
                "wrench",
                &[w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z],
            )?;
        }
        self.rnea_unchecked(data, q, qd, qdd, &g, wrench);
        Ok(&data.tau)
    }

    /// Joint friction b·q̇ + f_c·sign(q̇) (N·m or N) of every joint at speeds `qd`; zero for joints
    /// without a drive.
    pub fn friction(&self, qd: &[f64]) -> Result<DVector<f64>> {
        check_vector("qd", qd, self.dof())?;
        Ok(DVector::from_iterator(
            self.dof(),
            self.drives
                .iter()
                .zip(qd)
                .map(|(d, &v)| d.map_or(0.0, |d| d.friction(v))),
        ))
    }

    /// Torques the drives must deliver at the joints: [`Dynamics::rnea`] plus joint friction.
    pub fn inverse_dynamics<'d>(
        &self,
        data: &'d mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
    ) -> Result<&'d DVector<f64>> {
        self.rnea(data, q, qd, qdd, gravity, wrench)?;
        self.add_friction(&mut data.tau, qd);
        Ok(&data.tau)
    }

    fn add_friction(&self, tau: &mut DVector<f64>, qd: &[f64]) {
        for ((t, d), &v) in tau.iter_mut().zip(&self.drives).zip(qd) {
            if let Some(d) = d {
                *t += d.friction(v);
            }
        }
    }

    /// Gravity torques g(q) (N·m or N): what holds the robot still at `q` under `gravity`.
    pub fn gravity<'d>(&self, data: &'d mut DynamicsData, q: &[f64], gravity: &[f64; 3]) -> Result<&'d DVector<f64>> {
        self.check_data(data)?;
        check_vector("q", q, self.dof())?;
        let g = vec3("gravity", gravity)?;
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, zeros.as_slice(), zeros.as_slice(), &g, None);
        data.zeros = zeros;
        Ok(&data.tau)
    }

    /// Coriolis and centrifugal torques C(q, q̇)·q̇ (N·m or N), gravity excluded.
    pub fn coriolis<'d>(&self, data: &'d mut DynamicsData, q: &[f64], qd: &[f64]) -> Result<&'d DVector<f64>> {
        self.check_state(data, q, qd)?;
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, qd, zeros.as_slice(), &Vector3::zeros(), None);
        data.zeros = zeros;
        Ok(&data.tau)
    }

    /// Nonlinear effects h(q, q̇) = C(q, q̇)·q̇ + g(q) (N·m or N), Pinocchio's `nonLinearEffects`.
    pub fn nonlinear_effects<'d>(
        &self,
        data: &'d mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        gravity: &[f64; 3],
    ) -> Result<&'d DVector<f64>> {
        self.check_state(data, q, qd)?;
        let g = vec3("gravity", gravity)?;
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, qd, zeros.as_slice(), &g, None);
        data.zeros = zeros;
        Ok(&data.tau)
    }

    /// Composite rigid body algorithm without checks; M (with armature) in `data.mass`.
    fn crba_unchecked(&self, data: &mut DynamicsData, q: &[f64]) {
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
    fn project(&self, i: usize, m: &Vector3<f64>, f: &Vector3<f64>) -> f64 {
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

    /// Forward dynamics without checks: q̈ = M⁻¹(τ − h) in `data.qdd`.
    fn forward_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        gravity: &Vector3<f64>,
        wrench: Option<&Wrench>,
    ) -> Result<()> {
        let n = self.dof();
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, qd, zeros.as_slice(), gravity, wrench);
        data.zeros = zeros;
        for i in 0..n {
            data.qdd[i] = tau[i] - data.tau[i];
        }
        self.crba_unchecked(data, q);
        cholesky_in_place(&data.mass, &mut data.chol)?;
        cholesky_solve(&data.chol, &mut data.qdd);
        Ok(())
    }

    /// Forward dynamics: joint accelerations q̈ = M(q)⁻¹(τ − h(q, q̇) + Jᵀw) (rad/s², m/s²) under
    /// joint torques `tau` (N·m, N), `gravity` (m/s², base frame) and an optional tool `wrench`;
    /// no friction (subtract [`Dynamics::friction`] from `tau` to include it). Cholesky solve of
    /// the mass matrix; the inverse of [`Dynamics::rnea`].
    pub fn forward_dynamics<'d>(
        &self,
        data: &'d mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
    ) -> Result<&'d DVector<f64>> {
        self.check_state(data, q, qd)?;
        check_vector("tau", tau, self.dof())?;
        let g = vec3("gravity", gravity)?;
        self.forward_unchecked(data, q, qd, tau, &g, wrench)?;
        Ok(&data.qdd)
    }

    /// One semi-implicit (symplectic) Euler step of length `dt` s under joint torques `tau`:
    /// q̇ ← q̇ + dt·q̈(q, q̇, τ − friction), then q ← q + dt·q̇ (the new speed). Friction is applied
    /// when `friction` is true (Coulomb friction as b·q̇ + f_c·sign(q̇): expect chatter near rest).
    /// The energy error of a frictionless, torque-free motion stays O(dt) without drift.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &self,
        data: &mut DynamicsData,
        q: &mut [f64],
        qd: &mut [f64],
        tau: &[f64],
        dt: f64,
        gravity: &[f64; 3],
        friction: bool,
    ) -> Result<()> {
        self.check_state(data, q, qd)?;
        check_vector("tau", tau, self.dof())?;
        let g = vec3("gravity", gravity)?;
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(Error::invalid(
                "dt",
                format!("time step must be finite and > 0 s, got {dt}"),
            ));
        }
        self.step_unchecked(data, q, qd, tau, dt, &g, friction)
    }

    #[allow(clippy::too_many_arguments)]
    fn step_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &mut [f64],
        qd: &mut [f64],
        tau: &[f64],
        dt: f64,
        gravity: &Vector3<f64>,
        friction: bool,
    ) -> Result<()> {
        let n = self.dof();
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, qd, zeros.as_slice(), gravity, None);
        data.zeros = zeros;
        for i in 0..n {
            let tf = if friction {
                self.drives[i].map_or(0.0, |d| d.friction(qd[i]))
            } else {
                0.0
            };
            data.qdd[i] = tau[i] - tf - data.tau[i];
        }
        self.crba_unchecked(data, q);
        cholesky_in_place(&data.mass, &mut data.chol)?;
        cholesky_solve(&data.chol, &mut data.qdd);
        for i in 0..n {
            qd[i] += dt * data.qdd[i];
            q[i] += dt * qd[i];
        }
        Ok(())
    }

    /// Simulates N semi-implicit Euler steps of `dt` s from (`q0`, `qd0`) under the torques `taus`
    /// (N × n row-major, N·m or N, held over each step). Returns (q, q̇) at the N + 1 instants
    /// 0, dt, …, N·dt, each (N + 1) × n row-major.
    pub fn simulate(
        &self,
        q0: &[f64],
        qd0: &[f64],
        taus: &[f64],
        dt: f64,
        gravity: &[f64; 3],
        friction: bool,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let n = self.dof();
        let mut data = DynamicsData::new(self);
        self.check_state(&data, q0, qd0)?;
        let steps = batch_count("tau", taus, n)?;
        let g = vec3("gravity", gravity)?;
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(Error::invalid(
                "dt",
                format!("time step must be finite and > 0 s, got {dt}"),
            ));
        }
        let (mut q, mut qd) = (q0.to_vec(), qd0.to_vec());
        let mut qs = Vec::with_capacity((steps + 1) * n);
        let mut qds = Vec::with_capacity((steps + 1) * n);
        qs.extend_from_slice(&q);
        qds.extend_from_slice(&qd);
        for tau in taus.chunks_exact(n) {
            self.step_unchecked(&mut data, &mut q, &mut qd, tau, dt, &g, friction)?;
            if let Err(e) = check_finite("simulated state", &q).and_then(|_| check_finite("simulated state", &qd)) {
                return Err(Error::invalid(
                    "dt",
                    format!("the simulation diverged ({e}); use a smaller step"),
                ));
            }
            qs.extend_from_slice(&q);
            qds.extend_from_slice(&qd);
        }
        Ok((qs, qds))
    }

    /// Kinetic energy ½·q̇ᵀ·M(q)·q̇ (J), armature included.
    pub fn kinetic_energy(&self, data: &mut DynamicsData, q: &[f64], qd: &[f64]) -> Result<f64> {
        self.check_state(data, q, qd)?;
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, qd, zeros.as_slice(), &Vector3::zeros(), None);
        data.zeros = zeros;
        let mut e = 0.0;
        for i in 0..self.dof() {
            let (m, f) = self.bodies[i].apply(&data.w[i], &data.v[i]);
            e += 0.5 * (data.w[i].dot(&m) + data.v[i].dot(&f)) + 0.5 * self.armature[i] * qd[i] * qd[i];
        }
        Ok(e)
    }

    /// Potential energy −Σ m_i·g·c_i (J) of the links in the field `gravity` (m/s², base frame),
    /// zero with every centre of mass at the base origin.
    pub fn potential_energy(&self, q: &[f64], gravity: &[f64; 3]) -> Result<f64> {
        let g = vec3("gravity", gravity)?;
        let frames = self.chain.fk_all(q)?;
        Ok(frames
            .iter()
            .zip(&self.links)
            .map(|(t, l)| -l.mass * g.dot(&(t * nalgebra::Point3::from(l.com)).coords))
            .sum())
    }

    /// Torque profile of a planned motion sampled at N instants: `q`, `qd`, `qdd` are N × n
    /// row-major. Joint torques include friction; motor torques are τ/G; currents τ_motor/k_t.
    /// Every |τ| above a joint's effort limit is listed (not an error: the plan is infeasible).
    pub fn torque_profile(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
    ) -> Result<TorqueProfile> {
        let n = self.dof();
        let mut joint = vec![0.0; q.len()];
        self.rnea_batch(q, qd, qdd, gravity, wrench, &mut joint)?;
        let count = joint.len() / n;
        let mut motor = joint.clone();
        let mut current = vec![f64::NAN; joint.len()];
        let mut peak = vec![0.0f64; n];
        let mut violations = Vec::new();
        let limits = self.chain.limits();
        for k in 0..count {
            for i in 0..n {
                let idx = k * n + i;
                let drive = self.drives[i];
                if let Some(d) = drive {
                    joint[idx] += d.friction(qd[idx]);
                    motor[idx] = joint[idx] / d.gear_ratio;
                    if let Some(kt) = d.torque_constant {
                        current[idx] = motor[idx] / kt;
                    }
                } else {
                    motor[idx] = joint[idx];
                }
                let t = joint[idx];
                peak[i] = peak[i].max(t.abs());
                if let Some(limit) = limits[i].effort {
                    if t.abs() > limit {
                        violations.push(EffortViolation {
                            sample: k,
                            joint: i,
                            torque: t,
                            limit,
                        });
                    }
                }
            }
        }
        Ok(TorqueProfile {
            dof: n,
            joint,
            motor,
            current,
            peak,
            violations,
        })
    }

    /// Batch [`Dynamics::rnea`]: `q`, `qd`, `qdd` are N × n row-major, `out` receives N × n
    /// torques. Runs in parallel; everything is checked first.
    pub fn rnea_batch(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
        out: &mut [f64],
    ) -> Result<()> {
        let g = vec3("gravity", gravity)?;
        self.batch3(["qd", "qdd"], q, qd, qdd, out, |data, q, qd, qdd| {
            self.rnea_unchecked(data, q, qd, qdd, &g, wrench);
            Ok(data.tau.as_slice())
        })
    }

    /// Batch [`Dynamics::mass_matrix`]: `q` is N × n, `out` receives N row-major n × n matrices.
    pub fn mass_matrix_batch(&self, q: &[f64], out: &mut [f64]) -> Result<()> {
        let n = self.dof();
        let count = batch_count("q", q, n)?;
        same_count("output buffer", out, count, n * n)?;
        out.par_chunks_mut(n * n * BATCH_CHUNK)
            .zip(q.par_chunks(n * BATCH_CHUNK))
            .for_each(|(o, q)| {
                let mut data = DynamicsData::new(self);
                for (o, q) in o.chunks_exact_mut(n * n).zip(q.chunks_exact(n)) {
                    self.crba_unchecked(&mut data, q);
                    // Symmetric: column-major storage is also row-major.
                    o.copy_from_slice(data.mass.as_slice());
                }
            });
        Ok(())
    }

    /// Batch [`Dynamics::gravity`]: `q` is N × n, `out` receives N × n torques.
    pub fn gravity_batch(&self, q: &[f64], gravity: &[f64; 3], out: &mut [f64]) -> Result<()> {
        let zeros = vec![0.0; q.len()];
        self.rnea_batch(q, &zeros, &zeros, gravity, None, out)
    }

    /// Batch [`Dynamics::forward_dynamics`]: `q`, `qd`, `tau` N × n, `out` receives N × n
    /// accelerations.
    pub fn forward_dynamics_batch(
        &self,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
        out: &mut [f64],
    ) -> Result<()> {
        let g = vec3("gravity", gravity)?;
        self.batch3(["qd", "tau"], q, qd, tau, out, |data, q, qd, tau| {
            self.forward_unchecked(data, q, qd, tau, &g, wrench)?;
            Ok(data.qdd.as_slice())
        })
    }

    /// Runs `f` on every row of three N × n inputs in parallel (one scratch per rayon task) and
    /// copies the n values it returns into row k of `out`; checks shapes and finiteness first.
    fn batch3<F>(&self, names: [&str; 2], q: &[f64], b: &[f64], c: &[f64], out: &mut [f64], f: F) -> Result<()>
    where
        F: for<'d> Fn(&'d mut DynamicsData, &[f64], &[f64], &[f64]) -> Result<&'d [f64]> + Sync,
    {
        let n = self.dof();
        let count = batch_count("q", q, n)?;
        same_count(names[0], b, count, n)?;
        same_count(names[1], c, count, n)?;
        same_count("output buffer", out, count, n)?;
        check_finite(names[0], b)?;
        check_finite(names[1], c)?;
        let chunk = n * BATCH_CHUNK;
        out.par_chunks_mut(chunk)
            .zip(q.par_chunks(chunk).zip(b.par_chunks(chunk).zip(c.par_chunks(chunk))))
            .try_for_each(|(o, (q, (b, c)))| {
                let mut data = DynamicsData::new(self);
                for (k, o) in o.chunks_exact_mut(n).enumerate() {
                    let r = k * n..(k + 1) * n;
                    o.copy_from_slice(f(&mut data, &q[r.clone()], &b[r.clone()], &c[r])?);
                }
                Ok(())
            })
    }
}

/// Checks that `values` holds N × n finite values and returns N.
fn batch_count(what: &str, values: &[f64], n: usize) -> Result<usize> {
    if !values.len().is_multiple_of(n) {
        return Err(Error::shape(
            what,
            format!("N × {n} values"),
            format!("{} values", values.len()),
        ));
    }
    check_finite(what, values)?;
    Ok(values.len() / n)
}

fn same_count(what: &str, values: &[f64], count: usize, per_item: usize) -> Result<()> {
    if values.len() != count * per_item {
        return Err(Error::shape(what, count * per_item, values.len()));
    }
    Ok(())
}

/// Lower-triangular L with L·Lᵀ = `m` into `l` (no allocation); an error when `m` is not
/// positive definite.
fn cholesky_in_place(m: &DMatrix<f64>, l: &mut DMatrix<f64>) -> Result<()> {
    let n = m.nrows();
    for j in 0..n {
        let mut d = m[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if !(d > 0.0) {
            return Err(Error::Singular(format!(
                "mass matrix is not positive definite (pivot {j} is {d:e})"
            )));
        }
        let d = d.sqrt();
        l[(j, j)] = d;
        for i in j + 1..n {
            let mut s = m[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / d;
        }
    }
    Ok(())
}

/// Solves L·Lᵀ·x = b in place.
fn cholesky_solve(l: &DMatrix<f64>, b: &mut DVector<f64>) {
    let n = l.nrows();
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[(i, k)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}
