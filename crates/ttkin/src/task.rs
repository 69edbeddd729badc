//! Task spaces: what part of the tool pose a solver controls, with a residual and its Jacobian.
//!
//! Every task compares the current tool pose `T` (base frame) with a target pose `T*` and returns
//! a residual `e` (target minus current, base-frame axes) of `dim()` rows, and a task Jacobian
//! `J_e` (dim × n) with `ė = −J_e q̇` for a fixed target: a solver drives `e` to zero with
//! `q̇ = J_e⁺ (K e)`. The 5-D racket task of seed 000 uses a 2-D tangent-plane error for the face
//! normal, so it has no singularity when the normal points along ±z (where the seed's polar and
//! azimuth angles are singular); [`racket_coordinates`] gives the seed's angle form for display.

use nalgebra::{DMatrix, DVector, IsometryMatrix3, Matrix3, Matrix6xX, Rotation3, Translation3, Unit, Vector3};

use crate::chain::{Chain, JacobianFrame};
use crate::error::{Error, Result};

/// Distance of the racket centre along the z axis of the last frame in seed 000 (m).
pub const SEED_RACKET_OFFSET: f64 = 0.15;

/// The part of the tool pose a solver controls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Task {
    /// Full 6-D pose: position (m) and orientation (rad, rotation vector).
    Pose,
    /// 3-D position of the tool point (m); orientation free.
    Position,
    /// Seed 000's 5-D racket task: centre at `offset` m along the tool z axis, and the direction of
    /// the face normal (the tool x axis); rotation about the normal is free.
    Racket {
        /// Distance of the racket centre from the tool origin along tool z (m).
        offset: f64,
    },
}

impl std::str::FromStr for Task {
    type Err = Error;

    /// [`Task::from_name`].
    fn from_str(s: &str) -> Result<Task> {
        Task::from_name(s)
    }
}

impl Task {
    /// Parses `"pose"`, `"position"` or `"racket5"` (seed offset 0.15 m).
    pub fn from_name(name: &str) -> Result<Task> {
        match name {
            "pose" => Ok(Task::Pose),
            "position" => Ok(Task::Position),
            "racket5" => Ok(Task::Racket {
                offset: SEED_RACKET_OFFSET,
            }),
            other => Err(Error::invalid(
                "task",
                format!("unknown task '{other}'; choose 'pose', 'position' or 'racket5'"),
            )),
        }
    }

    /// Parses a task name as [`Task::from_name`], with an optional racket-centre offset (m along
    /// tool z) that only `"racket5"` accepts.
    pub fn from_name_with_offset(name: &str, racket_offset: Option<f64>) -> Result<Task> {
        match (Task::from_name(name)?, racket_offset) {
            (Task::Racket { .. }, Some(offset)) => {
                crate::error::check_finite("racket_offset", &[offset])?;
                Ok(Task::Racket { offset })
            }
            (_, Some(_)) => Err(Error::invalid("racket_offset", "only for task='racket5'")),
            (t, None) => Ok(t),
        }
    }

    /// Number of residual rows: 6, 3 or 5.
    pub fn dim(&self) -> usize {
        match self {
            Task::Pose => 6,
            Task::Position => 3,
            Task::Racket { .. } => 5,
        }
    }

    /// Checks that a robot with `inputs` joint inputs can follow the task (at least `dim()`).
    pub(crate) fn check_inputs(&self, inputs: usize) -> Result<()> {
        let m = self.dim();
        if inputs < m {
            return Err(Error::invalid(
                "task",
                format!("the task has {m} rows but the robot only {inputs} inputs"),
            ));
        }
        Ok(())
    }

    /// Residual target − current (base-frame axes): see the module doc for each task.
    pub fn error(&self, current: &IsometryMatrix3<f64>, target: &IsometryMatrix3<f64>) -> DVector<f64> {
        let mut e = DVector::zeros(self.dim());
        self.error_into(current, target, e.as_mut_slice());
        e
    }

    /// [`Task::error`] into a slice of `dim()` values.
    pub fn error_into(&self, current: &IsometryMatrix3<f64>, target: &IsometryMatrix3<f64>, e: &mut [f64]) {
        self.error_in_basis_into(current, target, target, e);
    }

    /// [`Task::error_into`] with the racket normal residual expressed in the tangent basis of
    /// `basis`'s normal instead of `target`'s (m, rad): the residual that matches a Jacobian built
    /// against `basis` (a corrector toward the next sample that reuses the current Jacobian; the
    /// tangent basis switches its helper axis at |n_x| = 0.9). Pose and position ignore `basis`.
    pub fn error_in_basis_into(
        &self,
        current: &IsometryMatrix3<f64>,
        target: &IsometryMatrix3<f64>,
        basis: &IsometryMatrix3<f64>,
        e: &mut [f64],
    ) {
        match self {
            Task::Pose => {
                let dp = target.translation.vector - current.translation.vector;
                let dr = rotation_log(&(target.rotation * current.rotation.inverse()).into_inner());
                e[..3].copy_from_slice(dp.as_slice());
                e[3..6].copy_from_slice(dr.as_slice());
            }
            Task::Position => {
                let dp = target.translation.vector - current.translation.vector;
                e[..3].copy_from_slice(dp.as_slice());
            }
            Task::Racket { offset } => {
                let dc = racket_centre(target, *offset) - racket_centre(current, *offset);
                let r = racket_normal(current).cross(&racket_normal(target));
                let (u1, u2) = tangent_basis(&racket_normal(basis));
                e[..3].copy_from_slice(dc.as_slice());
                e[3] = u1.dot(&r);
                e[4] = u2.dot(&r);
            }
        }
    }

    /// Task Jacobian (dim × n) from the base-frame geometric Jacobian `j` at pose `current`, such
    /// that the residual against `target` changes as ė = −J_e q̇.
    pub fn jacobian(
        &self,
        j: &Matrix6xX<f64>,
        current: &IsometryMatrix3<f64>,
        target: &IsometryMatrix3<f64>,
    ) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(self.dim(), j.ncols());
        self.jacobian_into(j, current, target, out.as_mut_slice());
        out
    }

    /// [`Task::jacobian`] into a column-major slice of dim × n values; allocates nothing.
    pub fn jacobian_into(
        &self,
        j: &Matrix6xX<f64>,
        current: &IsometryMatrix3<f64>,
        target: &IsometryMatrix3<f64>,
        out: &mut [f64],
    ) {
        let m = self.dim();
        match self {
            Task::Pose | Task::Position => {
                for (c, col) in j.column_iter().enumerate() {
                    out[c * m..(c + 1) * m].copy_from_slice(&col.as_slice()[..m]);
                }
            }
            Task::Racket { offset } => {
                let oz = current.rotation.matrix().column(2) * *offset;
                // e_n = Bᵀ(n × n*), ė_n = Bᵀ [n*]× [n]× ω  ⇒  J_n = −Bᵀ [n*]× [n]× J_ω
                let (n_cur, nt) = (racket_normal(current), racket_normal(target));
                let (u1, u2) = tangent_basis(&nt);
                for (c, col) in j.column_iter().enumerate() {
                    let v = Vector3::new(col[0], col[1], col[2]);
                    let w = Vector3::new(col[3], col[4], col[5]);
                    // ċ = v + ω × (offset·z) = v − (offset·z) × ω
                    let jc = v - oz.cross(&w);
                    let jn = nt.cross(&n_cur.cross(&w));
                    let o = &mut out[c * 5..(c + 1) * 5];
                    o[..3].copy_from_slice(jc.as_slice());
                    o[3] = -u1.dot(&jn);
                    o[4] = -u2.dot(&jn);
                }
            }
        }
    }

    /// Task Jacobian (dim × n) of `chain` at `q` (checked) against `target` (`None`: the current
    /// tool pose, so that J_e q̇ is the task velocity); see [`Task::jacobian`].
    pub fn jacobian_at(&self, chain: &Chain, q: &[f64], target: Option<&IsometryMatrix3<f64>>) -> Result<DMatrix<f64>> {
        let j = chain.jacobian(q, JacobianFrame::Base)?;
        let t = chain.fk_unchecked(q);
        Ok(self.jacobian(&j, &t, target.unwrap_or(&t)))
    }

    /// Task coordinates (`dim()` values, see [`Task::coordinates`]) of `chain`'s tool at `q`.
    pub fn coordinates_at(&self, chain: &Chain, q: &[f64]) -> Result<Vec<f64>> {
        let t = chain.fk(q)?;
        let mut x = vec![0.0; self.dim()];
        self.coordinates(&t, &mut x);
        Ok(x)
    }

    /// [`Task::coordinates_at`] of N configurations `qs` (N × n values, row-major; m, rad) into
    /// `out` (N × `dim()` values), in parallel over fixed chunks (results independent of the
    /// thread count).
    pub fn coordinates_batch(&self, chain: &Chain, qs: &[f64], out: &mut [f64]) -> Result<()> {
        chain.for_each_row(
            qs,
            out,
            self.dim(),
            || (),
            |_, q, o| {
                self.coordinates(&chain.fk_unchecked(q), o);
                Ok(())
            },
        )
    }

    /// [`Task::jacobian_at`] of N configurations `qs` (N × n values, row-major; m, rad) against
    /// `target` (the same for every row; `None`: each row's own tool pose) into `out`: N row-major
    /// dim × n matrices, in parallel over fixed chunks.
    pub fn jacobian_batch(
        &self,
        chain: &Chain,
        qs: &[f64],
        target: Option<&IsometryMatrix3<f64>>,
        out: &mut [f64],
    ) -> Result<()> {
        let (m, n) = (self.dim(), chain.dof());
        let scratch = || (Matrix6xX::zeros(n), vec![0.0; m * n]);
        chain.for_each_row(qs, out, m * n, scratch, |(j, je), q, o| {
            let t = chain.jacobian_into(q, JacobianFrame::Base, j);
            self.jacobian_into(j, &t, target.unwrap_or(&t), je);
            // column-major dim × n → row-major
            for (c, col) in je.chunks_exact(m).enumerate() {
                for (r, v) in col.iter().enumerate() {
                    o[r * n + c] = *v;
                }
            }
            Ok(())
        })
    }

    /// Task coordinates of a tool pose (base frame), `dim()` values: position (m); position (m)
    /// and rotation vector (rad); or seed 000's 5-vector [centre (m), polar, azimuth (rad)].
    pub fn coordinates(&self, pose: &IsometryMatrix3<f64>, out: &mut [f64]) {
        match self {
            Task::Position => out[..3].copy_from_slice(pose.translation.vector.as_slice()),
            Task::Pose => {
                out[..3].copy_from_slice(pose.translation.vector.as_slice());
                out[3..6].copy_from_slice(rotation_log(pose.rotation.matrix()).as_slice());
            }
            Task::Racket { offset } => out[..5].copy_from_slice(&racket_coordinates(pose, *offset)),
        }
    }

    /// A target pose with task coordinates `x` (as in [`Task::coordinates`]); what the task leaves
    /// free is taken from `hint` (orientation for the position task, rotation about the normal
    /// for the racket task).
    pub fn target_pose(&self, x: &[f64], hint: &IsometryMatrix3<f64>) -> IsometryMatrix3<f64> {
        match self {
            Task::Position => IsometryMatrix3::from_parts(Translation3::new(x[0], x[1], x[2]), hint.rotation),
            Task::Pose => IsometryMatrix3::from_parts(
                Translation3::new(x[0], x[1], x[2]),
                Rotation3::new(Vector3::new(x[3], x[4], x[5])),
            ),
            Task::Racket { offset } => {
                let z = hint.rotation.matrix().column(2).into_owned();
                racket_pose(&[x[0], x[1], x[2], x[3], x[4]], *offset, &z)
            }
        }
    }

    /// Feed-forward velocity in residual coordinates (what ė = f − J_e q̇ needs) of a target moving
    /// with coordinates `x` and rates `xdot`. Position: ẋ. Pose: rows 3–5 of `xdot` are taken as
    /// the angular velocity (rad/s, base axes), not rotation-vector rates. Racket: ċ and
    /// Bᵀ(n* × ṅ*), with ṅ* from the polar and azimuth rates (B the tangent basis of n*).
    pub fn feedforward(&self, x: &[f64], xdot: &[f64], out: &mut [f64]) {
        self.feedforward_in_basis(x, xdot, x, out);
    }

    /// [`Task::feedforward`] with the racket normal rows in the tangent basis of the normal of the
    /// coordinates `basis_x` (so that feed-forwards of neighbouring samples can be averaged: the
    /// tangent basis switches its helper axis at |n_x| = 0.9). Pose and position ignore `basis_x`.
    pub fn feedforward_in_basis(&self, x: &[f64], xdot: &[f64], basis_x: &[f64], out: &mut [f64]) {
        match self {
            Task::Position | Task::Pose => out[..self.dim()].copy_from_slice(&xdot[..self.dim()]),
            Task::Racket { .. } => {
                let (sp, cp) = x[3].sin_cos();
                let (sa, ca) = x[4].sin_cos();
                let n = Vector3::new(sp * ca, sp * sa, cp);
                let dn_dp = Vector3::new(cp * ca, cp * sa, -sp);
                let dn_da = Vector3::new(-sp * sa, sp * ca, 0.0);
                let ndot = dn_dp * xdot[3] + dn_da * xdot[4];
                let (sbp, cbp) = basis_x[3].sin_cos();
                let (sba, cba) = basis_x[4].sin_cos();
                let (u1, u2) = tangent_basis(&Vector3::new(sbp * cba, sbp * sba, cbp));
                let r = n.cross(&ndot);
                out[..3].copy_from_slice(&xdot[..3]);
                out[3] = u1.dot(&r);
                out[4] = u2.dot(&r);
            }
        }
    }
}

/// Seed 000's analytic Jacobian of the 5-vector [centre, polar, azimuth] (5 × n) from the
/// base-frame geometric Jacobian `j` at tool pose `t`. Singular where the normal is along ±z
/// (sin(polar) = 0): returns [`Error::Singular`] below `sin(polar) < 1e-6`.
pub fn racket_angle_jacobian(j: &Matrix6xX<f64>, t: &IsometryMatrix3<f64>, offset: f64) -> Result<DMatrix<f64>> {
    let n = racket_normal(t);
    let rho2 = n.x * n.x + n.y * n.y;
    if rho2.sqrt() < 1e-6 {
        return Err(Error::Singular(
            "racket normal along ±z: the azimuth angle is undefined (use the 'racket5' residual task)".into(),
        ));
    }
    let oz = t.rotation.matrix().column(2) * offset;
    let mut out = DMatrix::zeros(5, j.ncols());
    for (c, col) in j.column_iter().enumerate() {
        let v = Vector3::new(col[0], col[1], col[2]);
        let w = Vector3::new(col[3], col[4], col[5]);
        let jc = v - oz.cross(&w);
        let nd = w.cross(&n);
        out[(0, c)] = jc.x;
        out[(1, c)] = jc.y;
        out[(2, c)] = jc.z;
        // polar = acos(n_z): −ṅ_z / sin(polar); azimuth = atan2(n_y, n_x): (n_x ṅ_y − n_y ṅ_x)/ρ²
        out[(3, c)] = -nd.z / rho2.sqrt();
        out[(4, c)] = (n.x * nd.y - n.y * nd.x) / rho2;
    }
    Ok(out)
}

/// [`racket_angle_jacobian`] of `chain` at `q` (checked), the racket centre `offset` m along the
/// tool z axis: the rates of [`racket_coordinates`] are ẋ = J q̇ (5 × n, base frame).
pub fn racket_angle_jacobian_at(chain: &Chain, q: &[f64], offset: f64) -> Result<DMatrix<f64>> {
    let j = chain.jacobian(q, JacobianFrame::Base)?;
    racket_angle_jacobian(&j, &chain.fk_unchecked(q), offset)
}

/// [`racket_angle_jacobian_at`] of N configurations `qs` (N × n values, row-major; m, rad) into
/// `out` (N row-major 5 × n matrices), in parallel over fixed chunks; the error of the first
/// singular row (normal along ±z) otherwise.
pub fn racket_angle_jacobian_batch(chain: &Chain, qs: &[f64], offset: f64, out: &mut [f64]) -> Result<()> {
    let n = chain.dof();
    chain.for_each_row(
        qs,
        out,
        5 * n,
        || Matrix6xX::zeros(n),
        |j, q, o| {
            let t = chain.jacobian_into(q, JacobianFrame::Base, j);
            o.copy_from_slice(racket_angle_jacobian(j, &t, offset)?.transpose().as_slice());
            Ok(())
        },
    )
}

/// Rotation vector θ·axis (rad) of a rotation matrix: the SO(3) logarithm, accurate at θ → 0 and
/// θ → π. (nalgebra's `Rotation3::angle` is an unclamped acos: NaN when rounding pushes
/// (tr R − 1)/2 past 1, and only √ε-accurate near 0.)
pub fn rotation_log(r: &Matrix3<f64>) -> Vector3<f64> {
    // sin θ·axis from the skew part, cos θ from the trace.
    let v = Vector3::new(r[(2, 1)] - r[(1, 2)], r[(0, 2)] - r[(2, 0)], r[(1, 0)] - r[(0, 1)]) * 0.5;
    let c = 0.5 * (r.trace() - 1.0);
    let s = v.norm();
    let theta = s.atan2(c);
    if c >= 0.0 || s > 1e-3 {
        return if s < 1e-300 { v } else { v * (theta / s) };
    }
    // Near π: (R + Rᵀ)/2 = c·I + (1 − c)·a·aᵀ; take the largest column of a·aᵀ, sign from v.
    let b = (r + r.transpose()) * 0.5 - Matrix3::identity() * c;
    let k = (0..3).max_by(|&i, &j| b[(i, i)].total_cmp(&b[(j, j)])).unwrap_or(0);
    let mut a = b.column(k).normalize();
    if a.dot(&v) < 0.0 {
        a = -a;
    }
    a * theta
}

/// Skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Racket centre (m, base frame): tool origin plus `offset` along tool z.
pub fn racket_centre(t: &IsometryMatrix3<f64>, offset: f64) -> Vector3<f64> {
    t.translation.vector + t.rotation.matrix().column(2) * offset
}

/// Racket face normal (unit, base frame): the tool x axis.
pub fn racket_normal(t: &IsometryMatrix3<f64>) -> Vector3<f64> {
    t.rotation.matrix().column(0).into_owned()
}

/// Two unit vectors that complete `n` to a right-handed orthonormal basis (u1, u2, n).
pub fn tangent_basis(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let u1 = helper.cross(n).normalize();
    let u2 = n.cross(&u1);
    (u1, u2)
}

/// Seed 000's 5-D task vector of a tool pose: [centre x, y, z (m), polar angle acos(n_z),
/// azimuth atan2(n_y, n_x) (rad)] of the racket normal n.
pub fn racket_coordinates(t: &IsometryMatrix3<f64>, offset: f64) -> [f64; 5] {
    let c = racket_centre(t, offset);
    let n = racket_normal(t);
    [c.x, c.y, c.z, n.z.clamp(-1.0, 1.0).acos(), n.y.atan2(n.x)]
}

/// A tool pose whose racket centre and normal have the seed-000 coordinates `x` (m, rad); the
/// rotation about the normal, which the task leaves free, is chosen so that tool z is as close
/// as possible to `z_hint` (pass the current tool z to stay near the current pose).
pub fn racket_pose(x: &[f64; 5], offset: f64, z_hint: &Vector3<f64>) -> IsometryMatrix3<f64> {
    let (sp, cp) = x[3].sin_cos();
    let (sa, ca) = x[4].sin_cos();
    let n = Vector3::new(sp * ca, sp * sa, cp);
    let mut z = z_hint - n * n.dot(z_hint);
    if z.norm() < 1e-9 {
        z = tangent_basis(&n).0;
    }
    let z = z.normalize();
    let y = z.cross(&n);
    let r = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[n, y, z]));
    let c = Vector3::new(x[0], x[1], x[2]);
    IsometryMatrix3::from_parts(Translation3::from(c - z * offset), r)
}

/// Unit vector helper used by callers that build targets from a normal direction.
pub fn unit(v: Vector3<f64>) -> Result<Unit<Vector3<f64>>> {
    Unit::try_new(v, 1e-12).ok_or_else(|| Error::invalid("normal", "must be a non-zero vector"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chain-level forms equal the pose-level ones, and a bad q is an error, not a panic.
    #[test]
    fn chain_forms_match_pose_forms() {
        let chain = crate::robots::mobile8();
        let q = [0.1, -0.2, 0.3, 0.2, -0.4, 0.5, 0.3, -0.1];
        let t = chain.fk(&q).unwrap();
        let j = chain.jacobian(&q, JacobianFrame::Base).unwrap();
        let task = Task::from_name("racket5").unwrap();
        assert_eq!(task.jacobian_at(&chain, &q, None).unwrap(), task.jacobian(&j, &t, &t));
        let mut x = [0.0; 5];
        task.coordinates(&t, &mut x);
        assert_eq!(task.coordinates_at(&chain, &q).unwrap(), x.to_vec());
        assert!(task.jacobian_at(&chain, &q[..3], None).is_err());
        assert!(task.coordinates_at(&chain, &[f64::NAN; 8]).is_err());
    }

    /// Each row of a batch (more rows than one chunk) equals the single call, bit for bit; a
    /// ragged or non-finite batch is an error.
    #[test]
    fn batches_equal_single_calls_row_by_row() {
        let chain = crate::robots::mobile8();
        let n = chain.dof();
        let rows = 2 * crate::chain::BATCH_CHUNK + 3;
        let qs: Vec<f64> = (0..rows * n)
            .map(|k| ((k * 37 % 101) as f64 / 101.0 - 0.5) * 2.0)
            .collect();
        let target = chain.fk(&qs[..n]).unwrap();
        for task in [
            Task::Pose,
            Task::Position,
            Task::Racket {
                offset: SEED_RACKET_OFFSET,
            },
        ] {
            let m = task.dim();
            let mut x = vec![0.0; rows * m];
            task.coordinates_batch(&chain, &qs, &mut x).unwrap();
            let (mut je, mut jt) = (vec![0.0; rows * m * n], vec![0.0; rows * m * n]);
            task.jacobian_batch(&chain, &qs, None, &mut je).unwrap();
            task.jacobian_batch(&chain, &qs, Some(&target), &mut jt).unwrap();
            for (r, q) in qs.chunks_exact(n).enumerate() {
                assert_eq!(x[r * m..(r + 1) * m], task.coordinates_at(&chain, q).unwrap()[..]);
                for (out, tg) in [(&je, None), (&jt, Some(&target))] {
                    let single = task.jacobian_at(&chain, q, tg).unwrap();
                    let row_major: Vec<f64> = single.transpose().as_slice().to_vec();
                    assert_eq!(out[r * m * n..(r + 1) * m * n], row_major[..], "{task:?} row {r}");
                }
            }
            assert!(task.coordinates_batch(&chain, &qs[..n + 1], &mut x[..m]).is_err());
            let mut bad = qs[..n].to_vec();
            bad[2] = f64::NAN;
            assert!(task.jacobian_batch(&chain, &bad, None, &mut je[..m * n]).is_err());
        }
        let mut ja = vec![0.0; rows * 5 * n];
        racket_angle_jacobian_batch(&chain, &qs, SEED_RACKET_OFFSET, &mut ja).unwrap();
        for (r, q) in qs.chunks_exact(n).enumerate() {
            let single = racket_angle_jacobian_at(&chain, q, SEED_RACKET_OFFSET).unwrap();
            let row_major: Vec<f64> = single.transpose().as_slice().to_vec();
            assert_eq!(ja[r * 5 * n..(r + 1) * 5 * n], row_major[..], "row {r}");
        }
    }
}
