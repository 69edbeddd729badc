//! The racket frame: where the racket sits on a robot's tool flange, and the racket pose of a hit.
//!
//! Racket frame (one convention for every robot): origin at the racket centre, z axis along the
//! face normal (the hitting side), x axis along the handle (from the grip towards the centre),
//! y = z × x. A robot's tool frame carries the racket at a fixed pose
//! [`RacketMount::in_tool`] (the racket frame in the tool frame), data of the robot
//! ([`Chain::racket`], `racket = { xyz, rpy }` in a robot file):
//! - `gantry6` (seed 002): the tool frame *is* the racket frame (identity);
//! - `mobile8` (seed 000): the centre is 0.15 m along tool z and the face normal is tool x
//!   ([`crate::task::SEED_RACKET_OFFSET`], the 5-D task of seed 000), so racket x = tool z,
//!   racket z = tool x, racket y = −tool y;
//! - any other chain: the tool frame is the racket frame.

use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3, Vector3};

use crate::chain::Chain;
use crate::error::{check_finite, Error, Result};
use crate::task::SEED_RACKET_OFFSET;

/// The racket mount: where the robot carries its racket, the racket frame's pose in the tool frame (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacketMount {
    /// Racket frame in the tool frame (m).
    pub in_tool: IsometryMatrix3<f64>,
}

/// Deprecated name of [`RacketMount`] (`Racket` named the mount and the ball's impact model).
#[deprecated(
    note = "one name per concept: use `RacketMount` (the impact model is `ttkin::ball::impact::RacketImpact`)"
)]
pub type Racket = RacketMount;

impl RacketMount {
    /// The racket a chain carries ([`Chain::racket`], data of the robot: see the module doc).
    pub fn for_chain(chain: &Chain) -> RacketMount {
        RacketMount {
            in_tool: *chain.racket(),
        }
    }

    /// The racket frame is the tool frame.
    pub fn at_tool() -> RacketMount {
        RacketMount {
            in_tool: IsometryMatrix3::identity(),
        }
    }

    /// Seed 000's racket: centre 0.15 m along tool z, face normal tool x.
    pub fn seed000() -> RacketMount {
        let r = Matrix3::from_columns(&[Vector3::z(), -Vector3::y(), Vector3::x()]);
        RacketMount {
            in_tool: IsometryMatrix3::from_parts(
                Translation3::new(0.0, 0.0, SEED_RACKET_OFFSET),
                Rotation3::from_matrix_unchecked(r),
            ),
        }
    }

    /// Racket pose (base frame, m) for a tool pose (base frame, m).
    pub fn racket_pose(&self, tool: &IsometryMatrix3<f64>) -> IsometryMatrix3<f64> {
        tool * self.in_tool
    }

    /// Tool pose (base frame, m) that puts the racket at `racket` (base frame, m).
    pub fn tool_pose(&self, racket: &IsometryMatrix3<f64>) -> IsometryMatrix3<f64> {
        if self.in_tool == IsometryMatrix3::identity() {
            // The tool frame is the racket frame (gantry6): the same pose without the products.
            return *racket;
        }
        racket * self.in_tool.inverse()
    }

    /// Distance-vector from the tool origin to the racket centre (m, base axes) at tool pose `tool`.
    pub fn lever(&self, tool: &IsometryMatrix3<f64>) -> Vector3<f64> {
        tool.rotation * self.in_tool.translation.vector
    }

    /// Tool-point twist [v; ω] (base axes, m/s, rad/s) for a racket-centre twist `racket`
    /// (base axes) at tool pose `tool`: v_tool = v_centre − ω × (c − p_tool).
    pub fn tool_twist(&self, tool: &IsometryMatrix3<f64>, racket: &[f64; 6]) -> [f64; 6] {
        let w = Vector3::new(racket[3], racket[4], racket[5]);
        let v = Vector3::new(racket[0], racket[1], racket[2]) - w.cross(&self.lever(tool));
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// Racket-centre twist (base axes) from a tool-point twist `tool_twist` at tool pose `tool`.
    pub fn racket_twist(&self, tool: &IsometryMatrix3<f64>, tool_twist: &[f64]) -> [f64; 6] {
        let w = Vector3::new(tool_twist[3], tool_twist[4], tool_twist[5]);
        let v = Vector3::new(tool_twist[0], tool_twist[1], tool_twist[2]) + w.cross(&self.lever(tool));
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }
}

/// The handle direction a racket frame takes when none is given (base axes): base +z, the handle
/// pointing up, as a player holds a shake-hand racket at the hit.
pub const DEFAULT_HANDLE: [f64; 3] = [0.0, 0.0, 1.0];

/// The racket frame (base axes) of the unit face normal `z` with the handle x along the part of
/// `handle` orthogonal to `z` (Gram–Schmidt): columns [x, z × x, z]. The one construction every
/// racket frame uses; `handle` must not be parallel to `z` ([`racket_frame`] checks and falls back).
pub fn racket_axes(z: &Vector3<f64>, handle: &Vector3<f64>) -> Rotation3<f64> {
    let x = (handle - z * z.dot(handle)).normalize();
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, z.cross(&x), *z]))
}

/// The racket orientation (base axes) whose z axis is the face `normal` and whose x axis (the
/// handle) is as close as possible to `handle` (base axes; any vector not parallel to the
/// normal). When `handle` is (nearly) parallel to the normal, base +z, then base +x, is used.
pub fn racket_frame(normal: &Vector3<f64>, handle: &Vector3<f64>) -> Result<Rotation3<f64>> {
    check_finite("normal", normal.as_slice())?;
    check_finite("handle", handle.as_slice())?;
    let nn = normal.norm();
    if !(nn > 1e-12) {
        return Err(Error::invalid("normal", "the face normal must be a nonzero vector"));
    }
    // Scaled by the largest component before normalising: |normal| of 1e300 components is inf
    // (z was then the zero vector and the frame rank 1), and a subnormal one underflows.
    let unit = |v: &Vector3<f64>| {
        let m = v.amax();
        if m > 0.0 {
            (v / m).normalize()
        } else {
            *v
        }
    };
    let z = unit(normal);
    let h = [unit(handle), Vector3::z(), Vector3::x()]
        .into_iter()
        .find(|h| (h - z * z.dot(h)).norm() > 1e-6 * h.norm().max(1e-300))
        .unwrap_or_else(Vector3::zeros);
    Ok(racket_axes(&z, &h))
}

/// Values per joint state in [`racket_state_batch`]: the racket pose (16, row-major 4×4) and the
/// racket-centre twist (6).
pub const RACKET_STATE_LEN: usize = 22;

/// Racket states of a chain's joint states: for each of the N rows of `qs` (positions, m or rad)
/// and `qds` (velocities), `out` receives the racket pose (base frame, m; row-major 4×4) and the
/// racket-centre twist [v (m/s); ω (rad/s)] (base axes): N × [`RACKET_STATE_LEN`] values, in
/// parallel. The racket is the one the chain carries ([`Chain::racket`]).
pub fn racket_state_batch(chain: &Chain, qs: &[f64], qds: &[f64], out: &mut [f64]) -> Result<()> {
    use rayon::prelude::*;
    let n = chain.dof();
    if !qs.len().is_multiple_of(n) || qds.len() != qs.len() {
        return Err(Error::shape(
            "q, qd",
            format!("two N × {n} arrays of the same N"),
            format!("{} and {} values", qs.len(), qds.len()),
        ));
    }
    check_finite("q", qs)?;
    check_finite("qd", qds)?;
    if out.len() != qs.len() / n * RACKET_STATE_LEN {
        return Err(Error::shape(
            "output buffer",
            qs.len() / n * RACKET_STATE_LEN,
            out.len(),
        ));
    }
    let racket = RacketMount::for_chain(chain);
    const CHUNK: usize = 64;
    out.par_chunks_mut(RACKET_STATE_LEN * CHUNK)
        .zip(qs.par_chunks(n * CHUNK).zip(qds.par_chunks(n * CHUNK)))
        .for_each(|(o, (q, qd))| {
            let mut jac = nalgebra::Matrix6xX::zeros(n);
            for ((oi, qi), qdi) in o
                .chunks_exact_mut(RACKET_STATE_LEN)
                .zip(q.chunks_exact(n))
                .zip(qd.chunks_exact(n))
            {
                let tool = chain.jacobian_into(qi, crate::chain::JacobianFrame::Base, &mut jac);
                let twist = &jac * nalgebra::DVector::from_column_slice(qdi);
                crate::transform::write_row_major(&racket.racket_pose(&tool), &mut oi[..16]);
                oi[16..].copy_from_slice(&racket.racket_twist(&tool, twist.as_slice()));
            }
        });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(deprecated)]
    fn deprecated_racket_is_the_mount() {
        // Issue 30: `Racket` was the mount here and the impact model in `ball::impact`; the old
        // names stay one release as aliases of the new ones.
        assert_eq!(Racket::seed000(), RacketMount::seed000());
        let impact: crate::ball::impact::Racket = crate::ball::impact::RacketImpact::default();
        assert_eq!(impact.restitution, 0.85);
        assert_ne!(RacketMount::seed000(), RacketMount::at_tool());
    }

    #[test]
    fn racket_frame_of_huge_or_tiny_vectors_is_a_rotation() {
        for (n, h) in [
            (Vector3::new(1e300, -1e300, 1e300), Vector3::z()),
            (Vector3::new(0.3, -1.0, -0.2), Vector3::new(1e308, 1e308, 0.0)),
            (Vector3::new(0.0, 0.0, 1e308), Vector3::new(1e-310, 0.0, 0.0)),
        ] {
            let m = *racket_frame(&n, &h).unwrap().matrix();
            assert!((m.determinant() - 1.0).abs() < 1e-12, "{n:?} {h:?}");
            assert!((m.transpose() * m - Matrix3::identity()).norm() < 1e-12);
        }
    }

    #[test]
    fn racket_frame_is_a_rotation_with_z_along_the_normal() {
        let n = Vector3::new(0.3, -1.0, -0.2);
        let r = racket_frame(&n, &Vector3::z()).unwrap();
        let m = r.matrix();
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!((m.transpose() * m - Matrix3::identity()).norm() < 1e-12);
        assert!((m.column(2) - n.normalize()).norm() < 1e-12);
        // Handle parallel to the normal falls back to base z.
        let r = racket_frame(&Vector3::z(), &Vector3::z()).unwrap();
        assert!((r.matrix().column(0) - Vector3::x()).norm() < 1e-12);
    }

    #[test]
    fn seed000_racket_matches_the_five_d_task() {
        let tool = IsometryMatrix3::from_parts(
            Translation3::new(0.2, 0.3, 0.4),
            Rotation3::from_euler_angles(0.3, -0.2, 1.1),
        );
        let racket = RacketMount::seed000().racket_pose(&tool);
        let c = crate::task::racket_centre(&tool, SEED_RACKET_OFFSET);
        let n = crate::task::racket_normal(&tool);
        assert!((racket.translation.vector - c).norm() < 1e-12);
        assert!((racket.rotation.matrix().column(2) - n).norm() < 1e-12);
        assert!((racket.rotation.matrix().determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn tool_and_racket_twists_are_inverse() {
        let tool = IsometryMatrix3::from_parts(
            Translation3::new(0.2, 0.3, 0.4),
            Rotation3::from_euler_angles(0.3, -0.2, 1.1),
        );
        let r = RacketMount::seed000();
        let t = [1.0, -2.0, 0.5, 3.0, -1.0, 2.0];
        let back = r.racket_twist(&tool, &r.tool_twist(&tool, &t));
        for k in 0..6 {
            assert!((back[k] - t[k]).abs() < 1e-12);
        }
    }
}
