//! The dynamic model of a chain ([`Dynamics`]: joint frames, link inertias moved into the joint
//! frames, drives; immutable) and the scratch space of the algorithms ([`DynamicsData`]), with
//! the joint placement and the argument checks every algorithm shares.

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector, IsometryMatrix3, Matrix3, Vector3};

use crate::chain::Chain;
use crate::error::{check_finite, check_vector, Error, Result};
use crate::inertial::Inertial;
use crate::joint::{Drive, JointType};
use crate::linalg::cholesky::{factor_in_place, solve_in_place};

/// Spatial inertia of a body about the origin of its joint frame: mass m (kg), first moment
/// h = m·c (kg·m) and rotational inertia about the origin I_o (kg·m²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct BodyInertia {
    pub(super) mass: f64,
    pub(super) h: Vector3<f64>,
    pub(super) i_o: Matrix3<f64>,
}

/// m·(|x|²·1 − x·xᵀ): the parallel-axis term of a point mass m at x.
#[inline(always)]
fn shift(m: f64, x: &Vector3<f64>) -> Matrix3<f64> {
    m * (Matrix3::identity() * x.dot(x) - x * x.transpose())
}

impl BodyInertia {
    pub(super) const ZERO: BodyInertia = BodyInertia {
        mass: 0.0,
        h: Vector3::new(0.0, 0.0, 0.0),
        i_o: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    };

    /// The inertia of `i` (given in the link frame) about the origin of the frame in which the link
    /// frame has pose `link`.
    pub(super) fn from_inertial(i: &Inertial, link: &IsometryMatrix3<f64>) -> Self {
        let moved = i.transformed(link);
        BodyInertia {
            mass: moved.mass,
            h: moved.com * moved.mass,
            i_o: moved.inertia + shift(moved.mass, &moved.com),
        }
    }

    /// Momentum (moment about the origin; force) of the body moving with spatial velocity (ω; v).
    #[inline(always)]
    pub(super) fn apply(&self, w: &Vector3<f64>, v: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        (self.i_o * w + self.h.cross(v), v * self.mass - self.h.cross(w))
    }

    /// The same body seen from the parent frame, in which this frame has rotation `r`, origin `p`.
    /// I_o' = R·I_o·Rᵀ + 2(y·p)·1 − (y·pᵀ + p·yᵀ) + m(|p|²·1 − p·pᵀ), y = R·h.
    #[inline(always)]
    pub(super) fn in_parent(&self, r: &Matrix3<f64>, p: &Vector3<f64>) -> Self {
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
    pub(super) fn add(&mut self, other: &BodyInertia) {
        self.mass += other.mass;
        self.h += other.h;
        self.i_o += other.i_o;
    }
}

/// The dynamic model of a chain: joint frames, link inertias in joint frames, drives. Built once
/// with [`Dynamics::new`]; immutable.
#[derive(Debug, Clone, PartialEq)]
pub struct Dynamics {
    pub(super) chain: Chain,
    pub(super) kinds: Vec<JointType>,
    /// fixed[0] = base·pre_0, fixed[i] = post_{i−1}·pre_i, fixed[n] = post_{n−1}·tool.
    pub(super) fixed: Vec<IsometryMatrix3<f64>>,
    pub(super) bodies: Vec<BodyInertia>,
    /// Link inertias in link frames (for the potential energy).
    pub(super) links: Vec<Inertial>,
    pub(super) armature: Vec<f64>,
    pub(super) drives: Vec<Option<Drive>>,
}

/// Scratch space of the dynamics algorithms for one [`Dynamics`] model (no allocation per call).
#[derive(Debug, Clone)]
pub struct DynamicsData {
    pub(super) rot: Vec<Matrix3<f64>>,
    pub(super) pos: Vec<Vector3<f64>>,
    pub(super) w: Vec<Vector3<f64>>,
    pub(super) v: Vec<Vector3<f64>>,
    pub(super) moment: Vec<Vector3<f64>>,
    pub(super) force: Vec<Vector3<f64>>,
    pub(super) composite: Vec<BodyInertia>,
    pub(super) tau: DVector<f64>,
    pub(super) mass: DMatrix<f64>,
    pub(super) chol: DMatrix<f64>,
    pub(super) qdd: DVector<f64>,
    pub(super) zeros: DVector<f64>,
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

    /// Solves M·x = `qdd` in place (M in `mass`, x into `qdd`) with the shared Cholesky; an error
    /// when M is not positive definite.
    pub(super) fn solve_mass_matrix(&mut self) -> Result<()> {
        let n = self.dof();
        self.chol.copy_from(&self.mass);
        factor_in_place(self.chol.as_mut_slice(), n).map_err(|e| {
            Error::Singular(format!(
                "mass matrix is not positive definite (pivot {} is {:e})",
                e.pivot, e.value
            ))
        })?;
        solve_in_place(self.chol.as_slice(), n, self.qdd.as_mut_slice());
        Ok(())
    }

    /// Number of joints this scratch space was made for.
    pub fn dof(&self) -> usize {
        self.tau.len()
    }
}

/// Checks a 3-vector argument and turns it into a `Vector3`.
#[inline]
pub(super) fn vec3(what: &str, v: &[f64; 3]) -> Result<Vector3<f64>> {
    check_finite(what, v)?;
    Ok(Vector3::from(*v))
}

/// Checks that an optional tool wrench is finite (an error names `wrench`).
pub(super) fn check_wrench(wrench: Option<&super::Wrench>) -> Result<()> {
    match wrench {
        Some(w) => check_finite(
            "wrench",
            &[w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z],
        ),
        None => Ok(()),
    }
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
    #[inline]
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

    #[inline]
    pub(super) fn check_data(&self, data: &DynamicsData) -> Result<()> {
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
    pub(super) fn place(&self, data: &mut DynamicsData, q: &[f64]) {
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

    #[inline]
    pub(super) fn check_state(&self, data: &DynamicsData, q: &[f64], qd: &[f64]) -> Result<()> {
        self.check_data(data)?;
        check_vector("q", q, self.dof())?;
        check_vector("qd", qd, self.dof())
    }

    /// [`Dynamics::check_state`], then a third per-joint vector `x` (named `what`: qdd or tau)
    /// and the gravity vector (m/s², base frame), which it returns: the checks of every call at
    /// one state.
    #[inline]
    pub(super) fn check_call(
        &self,
        data: &DynamicsData,
        q: &[f64],
        qd: &[f64],
        (what, x): (&str, &[f64]),
        gravity: &[f64; 3],
    ) -> Result<Vector3<f64>> {
        self.check_state(data, q, qd)?;
        check_vector(what, x, self.dof())?;
        vec3("gravity", gravity)
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

    #[inline]
    pub(super) fn add_friction(&self, tau: &mut DVector<f64>, qd: &[f64]) {
        for ((t, d), &v) in tau.iter_mut().zip(&self.drives).zip(qd) {
            if let Some(d) = d {
                *t += d.friction(v);
            }
        }
    }
}
