//! Rigid transforms: elementary rotations and translations, roll-pitch-yaw, and the check that
//! turns a user's 4×4 matrix into a rigid transform.

use nalgebra::{IsometryMatrix3, Matrix3, Matrix4, Rotation3, Translation3, Vector3};

use crate::error::{Error, Result};

/// Tolerance on orthonormality and on the bottom row when a 4×4 matrix is accepted as rigid.
pub const RIGID_TOLERANCE: f64 = 1e-9;

/// Pure rotation about x by `angle` rad.
pub fn rot_x(angle: f64) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(
        Translation3::identity(),
        Rotation3::from_axis_angle(&Vector3::x_axis(), angle),
    )
}

/// Pure rotation about z by `angle` rad.
pub fn rot_z(angle: f64) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(
        Translation3::identity(),
        Rotation3::from_axis_angle(&Vector3::z_axis(), angle),
    )
}

/// Pure translation by (x, y, z) m.
pub fn trans(x: f64, y: f64, z: f64) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(Translation3::new(x, y, z), Rotation3::identity())
}

/// Transform from a translation (m) and URDF roll-pitch-yaw angles (rad): R = Rz(yaw)·Ry(pitch)·Rx(roll).
pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> IsometryMatrix3<f64> {
    IsometryMatrix3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

/// Translation (m) and URDF roll-pitch-yaw angles (rad) of a transform.
pub fn to_xyz_rpy(t: &IsometryMatrix3<f64>) -> ([f64; 3], [f64; 3]) {
    let (r, p, y) = t.rotation.euler_angles();
    let v = t.translation.vector;
    ([v.x, v.y, v.z], [r, p, y])
}

/// Accepts a 4×4 homogeneous matrix as a rigid transform: finite, rotation block orthonormal with
/// determinant +1 and bottom row (0, 0, 0, 1), each to [`RIGID_TOLERANCE`].
pub fn isometry_from_matrix(what: &str, m: &Matrix4<f64>) -> Result<IsometryMatrix3<f64>> {
    isometry_from_matrix_within(what, m, RIGID_TOLERANCE)
}

/// [`isometry_from_matrix`] with a tolerance of one's own, for data of a coarser precision than
/// float64 (a float32 rotation is orthonormal to about 1e-7, not 1e-9). With `tolerance` above
/// [`RIGID_TOLERANCE`] the accepted rotation block is re-orthonormalised (the nearest rotation,
/// from its polar decomposition), so that every later product stays rigid to float64 precision.
pub fn isometry_from_matrix_within(what: &str, m: &Matrix4<f64>, tolerance: f64) -> Result<IsometryMatrix3<f64>> {
    crate::error::check_finite(what, m.transpose().as_slice())?;
    let bottom = [m[(3, 0)], m[(3, 1)], m[(3, 2)], m[(3, 3)] - 1.0];
    if bottom.iter().any(|v| v.abs() > tolerance) {
        return Err(Error::invalid(
            what,
            format!(
                "bottom row must be [0, 0, 0, 1], got [{}, {}, {}, {}]",
                m[(3, 0)],
                m[(3, 1)],
                m[(3, 2)],
                m[(3, 3)]
            ),
        ));
    }
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let err = (r.transpose() * r - Matrix3::identity()).abs().max();
    if err > tolerance {
        return Err(Error::invalid(
            what,
            format!("rotation block is not orthonormal (|RᵀR − I| = {err:.3e} > {tolerance:e})"),
        ));
    }
    if r.determinant() < 0.0 {
        return Err(Error::invalid(
            what,
            "rotation block has determinant −1 (a reflection, not a rotation)",
        ));
    }
    let rotation = if tolerance > RIGID_TOLERANCE {
        nearest_rotation(&r)
    } else {
        Rotation3::from_matrix_unchecked(r)
    };
    Ok(IsometryMatrix3::from_parts(
        Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
        rotation,
    ))
}

/// The rotation nearest (Frobenius norm) to `r`, a matrix close to a rotation: U·Vᵀ of its SVD.
fn nearest_rotation(r: &Matrix3<f64>) -> Rotation3<f64> {
    let svd = r.svd(true, true);
    match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => Rotation3::from_matrix_unchecked(u * v_t),
        _ => Rotation3::from_matrix(r),
    }
}

/// Writes the 4×4 homogeneous matrix of `t` row-major into `out` (16 values).
pub fn write_row_major(t: &IsometryMatrix3<f64>, out: &mut [f64]) {
    let r = t.rotation.matrix();
    let p = &t.translation.vector;
    for i in 0..3 {
        out[4 * i] = r[(i, 0)];
        out[4 * i + 1] = r[(i, 1)];
        out[4 * i + 2] = r[(i, 2)];
        out[4 * i + 3] = p[i];
    }
    out[12] = 0.0;
    out[13] = 0.0;
    out[14] = 0.0;
    out[15] = 1.0;
}
