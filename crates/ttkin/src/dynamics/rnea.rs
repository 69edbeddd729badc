//! Inverse dynamics by the recursive Newton–Euler algorithm (Featherstone 2008, §5.3) and its
//! special cases: gravity torques, Coriolis torques, nonlinear effects, and with joint friction.

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DVector, Matrix3, Vector3};

use super::model::{check_wrench, vec3, BodyInertia, Dynamics, DynamicsData};
use super::Wrench;
use crate::error::{check_vector, Result};
use crate::joint::JointType;

impl Dynamics {
    /// Recursive Newton–Euler without argument checks; result in `data.tau`.
    pub(super) fn rnea_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &Vector3<f64>,
        wrench: Option<&Wrench>,
    ) {
        // Written out on `data`'s arrays with the motion in locals, not through `forward_step`,
        // `joint_torque` and `to_parent` (the fixed-size path below): the same numbers, but this
        // form is 10 % faster in wall time on this machine (criterion rnea/mobile8 276 against
        // 307 ns, ur5 219 against 238 ns, quiet machine) although it runs more instructions:
        // code layout, not work (docs/refactor-benchmarks.md). Keep the two in step.
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

    /// [`Self::inverse_dynamics_unchecked`] for a chain of exactly `N` joints, the wrenches of the
    /// recursion on the stack: the same numbers, fewer memory round trips. `None` when the chain
    /// has not `N` joints.
    pub(crate) fn inverse_dynamics_fixed<const N: usize>(
        &self,
        data: &mut DynamicsData,
        q: &[f64; N],
        qd: &[f64; N],
        qdd: &[f64; N],
        gravity: &Vector3<f64>,
    ) -> Option<[f64; N]> {
        if self.dof() != N {
            return None;
        }
        self.place(data, q);
        let rot: &[Matrix3<f64>; N] = data.rot[..N].try_into().ok()?;
        let pos: &[Vector3<f64>; N] = data.pos[..N].try_into().ok()?;
        let (kinds, bodies, armature) = (&self.kinds[..N], &self.bodies[..N], &self.armature[..N]);
        let mut m = Motion::base(gravity);
        let mut moment = [Vector3::zeros(); N];
        let mut force = [Vector3::zeros(); N];
        for i in 0..N {
            (moment[i], force[i]) = forward_step(kinds[i], &bodies[i], &rot[i], &pos[i], &mut m, qd[i], qdd[i]);
        }
        let mut tau = [0.0; N];
        for i in (0..N).rev() {
            tau[i] = joint_torque(kinds[i], armature[i], &moment[i], &force[i], qdd[i]);
            if i > 0 {
                let (f, mm) = to_parent(&rot[i], &pos[i], &force[i], &moment[i]);
                force[i - 1] += f;
                moment[i - 1] += mm;
            }
        }
        for ((t, d), &v) in tau.iter_mut().zip(&self.drives).zip(qd) {
            if let Some(d) = d {
                *t += d.friction(v);
            }
        }
        Some(tau)
    }

    /// The bias torques h = C(q, q̇)·q̇ + g(q) − Jᵀw without checks (RNEA at q̈ = 0) in `data.tau`.
    pub(super) fn bias_unchecked(
        &self,
        data: &mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        gravity: &Vector3<f64>,
        wrench: Option<&Wrench>,
    ) {
        let zeros = std::mem::take(&mut data.zeros);
        self.rnea_unchecked(data, q, qd, zeros.as_slice(), gravity, wrench);
        data.zeros = zeros;
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
        let g = self.check_call(data, q, qd, ("qdd", qdd), gravity)?;
        check_wrench(wrench)?;
        self.rnea_unchecked(data, q, qd, qdd, &g, wrench);
        Ok(&data.tau)
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

    /// [`Dynamics::inverse_dynamics`] with no wrench and without argument checks, for callers that
    /// validated `data`, the shapes, finiteness and `gravity` (m/s², base frame) themselves: the
    /// same numbers.
    pub(crate) fn inverse_dynamics_unchecked<'d>(
        &self,
        data: &'d mut DynamicsData,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &Vector3<f64>,
    ) -> &'d DVector<f64> {
        self.rnea_unchecked(data, q, qd, qdd, gravity, None);
        self.add_friction(&mut data.tau, qd);
        &data.tau
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
        self.bias_unchecked(data, q, qd, &Vector3::zeros(), None);
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
        self.bias_unchecked(data, q, qd, &g, None);
        Ok(&data.tau)
    }
}

/// Angular and linear velocity and acceleration of a joint frame, its own axes.
struct Motion {
    w: Vector3<f64>,
    v: Vector3<f64>,
    dw: Vector3<f64>,
    dv: Vector3<f64>,
}

impl Motion {
    /// The fixed base under `gravity`: at rest, accelerating upwards by −g.
    #[inline(always)]
    fn base(gravity: &Vector3<f64>) -> Motion {
        Motion {
            w: Vector3::zeros(),
            v: Vector3::zeros(),
            dw: Vector3::zeros(),
            dv: -gravity,
        }
    }
}

/// One joint of the outward pass: the motion `m` of the parent carried into the frame of a joint
/// of type `kind` moving `body` (rotation `r`, origin `p` in the parent) plus the joint's own, and
/// the net body wrench (moment, force) that motion needs.
#[inline(always)]
fn forward_step(
    kind: JointType,
    body: &BodyInertia,
    r: &Matrix3<f64>,
    p: &Vector3<f64>,
    m: &mut Motion,
    qd: f64,
    qdd: f64,
) -> (Vector3<f64>, Vector3<f64>) {
    let rt = r.transpose();
    let dv_parent = m.dv + m.dw.cross(p);
    let v_parent = m.v + m.w.cross(p);
    m.w = rt * m.w;
    m.v = rt * v_parent;
    m.dw = rt * m.dw;
    m.dv = rt * dv_parent;
    let z = Vector3::z();
    match kind {
        JointType::Revolute => {
            m.w.z += qd;
            // a_i += S·q̈ + v_i ×ₘ S·q̇, S = (ẑ; 0).
            m.dw += m.w.cross(&z) * qd;
            m.dw.z += qdd;
            m.dv += m.v.cross(&z) * qd;
        }
        JointType::Prismatic => {
            m.v.z += qd;
            // a_i += S·q̈ + v_i ×ₘ S·q̇, S = (0; ẑ).
            m.dv += m.w.cross(&z) * qd;
            m.dv.z += qdd;
        }
    }
    // f_i = I·a + v ×* (I·v).
    let (ia_n, ia_f) = body.apply(&m.dw, &m.dv);
    let (iv_n, iv_f) = body.apply(&m.w, &m.v);
    (ia_n + m.w.cross(&iv_n) + m.v.cross(&iv_f), ia_f + m.w.cross(&iv_f))
}

/// The torque (or force) of a joint of type `kind` with `armature` from its body wrench.
#[inline(always)]
fn joint_torque(kind: JointType, armature: f64, moment: &Vector3<f64>, force: &Vector3<f64>, qdd: f64) -> f64 {
    let own = match kind {
        JointType::Revolute => moment.z,
        JointType::Prismatic => force.z,
    };
    own + armature * qdd
}

/// A body wrench (force, moment) of a frame with rotation `r` and origin `p` in its parent, in
/// the parent's axes about its origin.
#[inline(always)]
fn to_parent(
    r: &Matrix3<f64>,
    p: &Vector3<f64>,
    force: &Vector3<f64>,
    moment: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let f = r * force;
    (f, r * moment + p.cross(&f))
}
