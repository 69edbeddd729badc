//! The Newton–Euler recursion generic over its scalar ([`Real`]): on `f64` it is inverse
//! dynamics with viscous friction; on interval duals ([`IvDual`](crate::dynamics::interval::IvDual)) it encloses τ and dτ/dt over a
//! box of states, which is what the peak search bisects.

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

use nalgebra::{Matrix3, Vector3};

use crate::dynamics::interval::Real;
use crate::dynamics::model::Dynamics;
use crate::joint::JointType;

/// Scratch of the generic recursion: per joint (cos, sin) of revolute angles, frame origin,
/// moment and force.
pub(super) struct Work<T> {
    cs: Vec<(T, T)>,
    pos: Vec<[T; 3]>,
    moment: Vec<[T; 3]>,
    force: Vec<[T; 3]>,
}

impl<T: Real> Work<T> {
    /// Scratch for a chain of `n` joints.
    pub(super) fn new(n: usize) -> Self {
        let z = [T::cst(0.0); 3];
        Work {
            cs: vec![(T::cst(1.0), T::cst(0.0)); n],
            pos: vec![z; n],
            moment: vec![z; n],
            force: vec![z; n],
        }
    }
}

#[inline(always)]
fn add<T: Real>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
fn cross<T: Real>(a: &[T; 3], b: &[T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// h × a for a constant h.
#[inline(always)]
fn cross_c<T: Real>(h: &Vector3<f64>, a: &[T; 3]) -> [T; 3] {
    [
        a[2].scale(h.y) - a[1].scale(h.z),
        a[0].scale(h.z) - a[2].scale(h.x),
        a[1].scale(h.x) - a[0].scale(h.y),
    ]
}

/// m·x for a constant matrix m.
#[inline(always)]
fn mat<T: Real>(m: &Matrix3<f64>, x: &[T; 3]) -> [T; 3] {
    std::array::from_fn(|r| x[0].scale(m[(r, 0)]) + x[1].scale(m[(r, 1)]) + x[2].scale(m[(r, 2)]))
}

/// mᵀ·x for a constant matrix m.
#[inline(always)]
fn mat_t<T: Real>(m: &Matrix3<f64>, x: &[T; 3]) -> [T; 3] {
    std::array::from_fn(|c| x[0].scale(m[(0, c)]) + x[1].scale(m[(1, c)]) + x[2].scale(m[(2, c)]))
}

impl Dynamics {
    /// Rᵢᵀ·x for joint `i`'s frame rotation Rᵢ = F·Rz(q) (revolute) or F (prismatic).
    #[inline(always)]
    fn rot_t<T: Real>(&self, w: &Work<T>, i: usize, x: &[T; 3]) -> [T; 3] {
        let y = mat_t(self.fixed[i].rotation.matrix(), x);
        match self.kinds[i] {
            JointType::Revolute => {
                let (c, s) = w.cs[i];
                [c * y[0] + s * y[1], c * y[1] - s * y[0], y[2]]
            }
            JointType::Prismatic => y,
        }
    }

    /// Rᵢ·x.
    #[inline(always)]
    fn rot<T: Real>(&self, w: &Work<T>, i: usize, x: &[T; 3]) -> [T; 3] {
        let y = match self.kinds[i] {
            JointType::Revolute => {
                let (c, s) = w.cs[i];
                [c * x[0] - s * x[1], s * x[0] + c * x[1], x[2]]
            }
            JointType::Prismatic => *x,
        };
        mat(self.fixed[i].rotation.matrix(), &y)
    }

    /// Inverse dynamics with viscous friction (no Coulomb term, no wrench) on any [`Real`]: the
    /// recursion of [`Self::rnea_unchecked`] written on 3-arrays, with the joint rotations
    /// factored as F·Rz(q) so that constants multiply constants. With f64 it gives the same numbers
    /// as `rnea` plus b·q̇ to rounding (tested); with [`IvDual`](crate::dynamics::interval::IvDual) it encloses τ and dτ/dt.
    pub(super) fn rnea_smooth<T: Real>(
        &self,
        w: &mut Work<T>,
        q: &[T],
        qd: &[T],
        qdd: &[T],
        gravity: &Vector3<f64>,
        out: &mut [T],
    ) {
        let n = self.dof();
        for i in 0..n {
            let t = self.fixed[i].translation.vector;
            match self.kinds[i] {
                JointType::Revolute => {
                    w.cs[i] = {
                        let (s, c) = q[i].sin_cos();
                        (c, s)
                    };
                    w.pos[i] = [T::cst(t.x), T::cst(t.y), T::cst(t.z)];
                }
                JointType::Prismatic => {
                    let z = self.fixed[i].rotation.matrix().column(2);
                    w.pos[i] = [
                        q[i].scale(z.x) + T::cst(t.x),
                        q[i].scale(z.y) + T::cst(t.y),
                        q[i].scale(z.z) + T::cst(t.z),
                    ];
                }
            }
        }
        let zero = T::cst(0.0);
        let (mut om, mut v, mut dom) = ([zero; 3], [zero; 3], [zero; 3]);
        // x × p, with p a constant for a revolute joint (constants times numbers are cheap).
        let cross_p = |w: &Work<T>, i: usize, x: &[T; 3]| match self.kinds[i] {
            JointType::Revolute => cross_c(&self.fixed[i].translation.vector, x).map(|c| -c),
            JointType::Prismatic => cross(x, &w.pos[i]),
        };
        let mut dv = [T::cst(-gravity.x), T::cst(-gravity.y), T::cst(-gravity.z)];
        for i in 0..n {
            let dv_parent = add(dv, cross_p(w, i, &dom));
            let v_parent = add(v, cross_p(w, i, &om));
            om = self.rot_t(w, i, &om);
            v = self.rot_t(w, i, &v_parent);
            dom = self.rot_t(w, i, &dom);
            dv = self.rot_t(w, i, &dv_parent);
            match self.kinds[i] {
                JointType::Revolute => {
                    om[2] += qd[i];
                    // ω × ẑ = (ω_y, −ω_x, 0).
                    dom[0] += om[1] * qd[i];
                    dom[1] += -(om[0] * qd[i]);
                    dom[2] += qdd[i];
                    dv[0] += v[1] * qd[i];
                    dv[1] += -(v[0] * qd[i]);
                }
                JointType::Prismatic => {
                    v[2] += qd[i];
                    dv[0] += om[1] * qd[i];
                    dv[1] += -(om[0] * qd[i]);
                    dv[2] += qdd[i];
                }
            }
            let body = &self.bodies[i];
            // (I_o·ω + h × v, m·v − h × ω) of (ω̇, v̇) and of (ω, v).
            let ia_n = add(mat(&body.i_o, &dom), cross_c(&body.h, &dv));
            let ia_f = add(dv.map(|x| x.scale(body.mass)), cross_c(&body.h, &dom).map(|x| -x));
            let iv_n = add(mat(&body.i_o, &om), cross_c(&body.h, &v));
            let iv_f = add(v.map(|x| x.scale(body.mass)), cross_c(&body.h, &om).map(|x| -x));
            w.moment[i] = add(add(ia_n, cross(&om, &iv_n)), cross(&v, &iv_f));
            w.force[i] = add(ia_f, cross(&om, &iv_f));
        }
        for i in (0..n).rev() {
            let axis = match self.kinds[i] {
                JointType::Revolute => w.moment[i][2],
                JointType::Prismatic => w.force[i][2],
            };
            let viscous = self.drives[i].map_or(0.0, |d| d.viscous);
            out[i] = axis + qdd[i].scale(self.armature[i]) + qd[i].scale(viscous);
            if i > 0 {
                let f = self.rot(w, i, &w.force[i]);
                let m = add(self.rot(w, i, &w.moment[i]), cross_p(w, i, &f).map(|c| -c));
                w.force[i - 1] = add(w.force[i - 1], f);
                w.moment[i - 1] = add(w.moment[i - 1], m);
            }
        }
    }
}
