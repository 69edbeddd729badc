//! The residual the numeric solver minimises ([`super::numeric`]), its Jacobian, and the position
//! and orientation errors of a pose against a target for each [`Task`]. The racket task uses the
//! chord form [c* − c; n* − n] rather than [`Task::error`]'s tangent form (see
//! [`super::numeric`]'s module doc for why).

// Index loops over joints read like the maths here: keep them.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, IsometryMatrix3, Matrix6xX};

use crate::task::{racket_centre, racket_normal, rotation_log, Task};

/// Rows of the solver's residual for `task`: 6 for the pose and the racket, 3 for the position.
pub fn residual_dim(task: &Task) -> usize {
    match task {
        Task::Racket { .. } => 6,
        other => other.dim(),
    }
}

/// The solver's residual (target − current): [`Task::error_into`], except for the racket task's
/// chord form [c* − c; n* − n] (see the module doc).
pub(crate) fn residual_into(task: &Task, t: &IsometryMatrix3<f64>, target: &IsometryMatrix3<f64>, e: &mut [f64]) {
    match task {
        Task::Racket { offset } => {
            let dc = racket_centre(target, *offset) - racket_centre(t, *offset);
            let dn = racket_normal(target) - racket_normal(t);
            e[..3].copy_from_slice(dc.as_slice());
            e[3..6].copy_from_slice(dn.as_slice());
        }
        other => other.error_into(t, target, e),
    }
}

/// Jacobian of [`residual_into`] with ė = −J_e q̇: for the chord rows ṅ = ω × n, so J_n = −[n]× J_ω.
pub(crate) fn residual_jacobian_into(
    task: &Task,
    j: &Matrix6xX<f64>,
    t: &IsometryMatrix3<f64>,
    target: &IsometryMatrix3<f64>,
    out: &mut DMatrix<f64>,
) {
    match task {
        Task::Racket { offset } => {
            let zo = t.rotation.matrix().column(2) * *offset;
            let n = racket_normal(t);
            for c in 0..j.ncols() {
                let v = nalgebra::Vector3::new(j[(0, c)], j[(1, c)], j[(2, c)]);
                let w = nalgebra::Vector3::new(j[(3, c)], j[(4, c)], j[(5, c)]);
                let jc = v - zo.cross(&w);
                let jn = w.cross(&n);
                for r in 0..3 {
                    out[(r, c)] = jc[r];
                    out[(3 + r, c)] = jn[r];
                }
            }
        }
        other => other.jacobian_into(j, t, target, out.as_mut_slice()),
    }
}

/// Position error (m) and orientation error (rad) read from the solver's residual: the same values
/// as [`measure`] (the pose residual's rotation part is the exact rotation vector; the racket's
/// chord |n* − n| = 2·sin(θ/2)), without recomputing the pose difference.
pub(crate) fn residual_errors(task: &Task, e: &[f64]) -> (f64, f64) {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    match task {
        Task::Pose => (norm(&e[..3]), norm(&e[3..6])),
        Task::Position => (norm(&e[..3]), 0.0),
        Task::Racket { .. } => (norm(&e[..3]), 2.0 * (0.5 * norm(&e[3..6])).min(1.0).asin()),
    }
}

/// Position error (m) and orientation error (rad) of pose `t` against `target` for `task`:
/// distance of the tool points (racket centres) and rotation angle (angle between racket normals).
pub fn measure(task: &Task, t: &IsometryMatrix3<f64>, target: &IsometryMatrix3<f64>) -> (f64, f64) {
    match task {
        Task::Pose => {
            let dp = (target.translation.vector - t.translation.vector).norm();
            let r = (target.rotation * t.rotation.inverse()).into_inner();
            (dp, rotation_log(&r).norm())
        }
        Task::Position => ((target.translation.vector - t.translation.vector).norm(), 0.0),
        Task::Racket { offset } => {
            let dc = racket_centre(target, *offset) - racket_centre(t, *offset);
            let (n, nt) = (racket_normal(t), racket_normal(target));
            (dc.norm(), n.cross(&nt).norm().atan2(n.dot(&nt)))
        }
    }
}
