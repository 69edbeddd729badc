//! Closed-form IK of seed 001's 4-DOF arm, and the exact set of poses it can reach.
//!
//! Model (standard DH rows (θ, d, a, α)): (θ1, d1, a1, 0), (θ2, 0, a2, 90°), (θ3, 0, 0, 90°),
//! (θ4, d4, 0, 0); joints 1 and 2 vertical and parallel. Forward kinematics, θ12 = θ1 + θ2:
//! R = Rz(θ12)·Rx(90°)·Rz(θ3)·Rx(90°)·Rz(θ4), so the approach axis is a = (c12·s3, s12·s3, −c3),
//! and p = w + d4·a with the wrist w = (a1c1 + a2c12, a1s1 + a2s12, d1).
//!
//! # Reachable poses
//! Four joints cannot reach a 6-D set. A pose (R, p) with approach axis a and wrist point
//! w = p − d4·a is reachable exactly when
//! 1. the wrist is at the shoulder height: w_z = d1, and
//! 2. the horizontal part of a lies along link 2: there is a θ12 with a_xy ∥ (c12, s12) (either
//!    sense) and |w_xy − a2·(c12, s12)| = a1. For a non-vertical a this is
//!    |w_xy − σ·a2·a_xy/|a_xy|| = a1 for σ = +1 or −1; for a vertical a (a = ±z) it is
//!    |a1 − a2| ≤ |w_xy| ≤ a1 + a2.
//!
//! The rotation about a is always free (θ4). So every orientation is reachable, but for a given
//! orientation the reachable tool positions are at most two circles of radius a1 (θ1 free), at
//! height d1 − d4·c3: a 4-D subset of the 6-D pose space. Generic poses of that set have one
//! solution; poses with vertical a have two (elbow left and right).
//!
//! # Inverse (the seed's fragments, made robust)
//! θ12 = atan2(σ·ay, σ·ax) from the orientation, or from the planar two-link IK of w_xy when a is
//! (nearly) vertical; then θ1 = atan2(w_xy − a2·u12), θ2 = θ12 − θ1, θ3 = atan2(c12·ax + s12·ay,
//! −az), and θ4 from the remaining rotation Rz(θ4) = (Rz(θ12)·Rx(90°)·Rz(θ3)·Rx(90°))ᵀ·R (equal to
//! the seed's c4 = s12·ox − c12·oy, s4 = −oz/s3 where s3 ≠ 0). Every candidate is checked against
//! the target; a pose is accepted when position and approach axis match to [`Arm4Ik::tolerance`].

use nalgebra::{IsometryMatrix3, Vector2, Vector3};

use super::{dh_rows, same, wrap, ChainInfo, LimitFilter, Solutions};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::joint::{DhConvention, JointType};
use crate::robots::Arm4Lengths;

/// Analytic IK of a chain with the arm4 structure (lengths and joint offsets read from it).
#[derive(Debug, Clone, PartialEq)]
pub struct Arm4Ik {
    /// d1, a1, a2, d4 of the chain (m).
    pub lengths: Arm4Lengths,
    /// How far (m, and in the unit approach axis) a target may be from the reachable set and still
    /// be accepted; default 1e-12 (raise it for targets rounded or measured elsewhere).
    pub tolerance: f64,
    offsets: [f64; 4],
    pub(crate) info: ChainInfo,
}

impl Arm4Ik {
    /// The solver if `chain` has the arm4 structure: four revolute joints, standard DH rows
    /// (·, d1, a1, 0), (·, 0, a2, 90°), (·, 0, 0, 90°), (·, d4, 0, 0) with a1, a2 > 0.
    pub fn from_chain(chain: &Chain) -> Option<Arm4Ik> {
        let rows = dh_rows(chain, DhConvention::Standard)?;
        if rows.len() != 4 || rows.iter().any(|(k, _)| *k != JointType::Revolute) {
            return None;
        }
        let q90 = std::f64::consts::FRAC_PI_2;
        let r: Vec<_> = rows.iter().map(|(_, dh)| *dh).collect();
        let pattern = same(r[0].alpha, 0.0)
            && same(r[1].d, 0.0)
            && same(r[1].alpha, q90)
            && same(r[2].d, 0.0)
            && same(r[2].a, 0.0)
            && same(r[2].alpha, q90)
            && same(r[3].a, 0.0)
            && same(r[3].alpha, 0.0);
        if !pattern || !(r[0].a > 1e-9) || !(r[1].a > 1e-9) {
            return None;
        }
        Some(Arm4Ik {
            lengths: Arm4Lengths {
                d1: r[0].d,
                a1: r[0].a,
                a2: r[1].a,
                d4: r[3].d,
            },
            tolerance: 1e-12,
            offsets: [r[0].theta, r[1].theta, r[2].theta, r[3].theta],
            info: ChainInfo::of(chain),
        })
    }

    /// Every configuration reaching `target` (tool pose, base frame, m): usually one, two for a
    /// vertical approach axis. Errors: [`Error::Unreachable`] naming the failed condition of the
    /// module doc; [`Error::NonFinite`] for a NaN target.
    pub fn solve(&self, target: &IsometryMatrix3<f64>, filter: LimitFilter) -> Result<Solutions> {
        let mut sols = Solutions::empty(4);
        self.solve_into(target, &mut sols)?;
        sols.apply(filter, &self.info)?;
        Ok(sols)
    }

    /// The mathematical branches into `sols`.
    pub(crate) fn solve_into(&self, target: &IsometryMatrix3<f64>, sols: &mut Solutions) -> Result<()> {
        let t = self.info.to_chain(target);
        let rot = t.rotation.matrix();
        let p = t.translation.vector;
        crate::error::check_finite("target pose", rot.as_slice())?;
        crate::error::check_finite("target pose", p.as_slice())?;
        let Arm4Lengths { d1, a1, a2, d4 } = self.lengths;
        let a: Vector3<f64> = rot.column(2).into_owned();
        let w = p - a * d4;
        let wxy = Vector2::new(w.x, w.y);
        let r = wxy.norm();
        let tol = self.tolerance;
        if (w.z - d1).abs() > tol {
            return Err(Error::Unreachable(format!(
                "arm4 wrist height: pz − d4·az = {:.9} m must equal d1 = {d1} m (a 4-DOF arm keeps its wrist at \
                 shoulder height)",
                w.z
            )));
        }
        // Candidate θ12: from the approach axis (both senses), and from the planar two-link IK.
        let mut th12 = [f64::NAN; 4];
        let sxy = a.x.hypot(a.y);
        if sxy > 1e-12 {
            th12[0] = a.y.atan2(a.x);
            th12[1] = (-a.y).atan2(-a.x);
        }
        let c2 = (r * r - a1 * a1 - a2 * a2) / (2.0 * a1 * a2);
        if c2.abs() <= 1.0 + 1e-12 && r > 0.0 {
            let c2 = c2.clamp(-1.0, 1.0);
            let s2_abs = (1.0 - c2 * c2).sqrt();
            for (k, s2) in [s2_abs, -s2_abs].into_iter().enumerate() {
                th12[2 + k] = w.y.atan2(w.x) - (a2 * s2).atan2(a1 + a2 * c2) + s2.atan2(c2);
            }
        }
        let n0: Vector3<f64> = rot.column(0).into_owned();
        let mut cands: [(f64, [f64; 4]); 4] = [(f64::INFINITY, [0.0; 4]); 4];
        for (slot, &t12) in cands.iter_mut().zip(&th12) {
            if t12.is_nan() {
                continue;
            }
            let (s12, c12) = t12.sin_cos();
            let v = wxy - Vector2::new(c12, s12) * a2;
            let th1 = v.y.atan2(v.x);
            let th3 = (c12 * a.x + s12 * a.y).atan2(-a.z);
            let (s3, c3) = th3.sin_cos();
            let (s1, c1) = th1.sin_cos();
            let a_fk = Vector3::new(c12 * s3, s12 * s3, -c3);
            let p_fk = Vector3::new(a1 * c1 + a2 * c12, a1 * s1 + a2 * s12, d1) + a_fk * d4;
            let err = (p_fk - p).amax().max((a_fk - a).amax());
            if err > tol {
                continue;
            }
            // Undo Rz(θ12), Rx(90°), Rz(θ3), Rx(90°) on n: what is left is Rz(θ4)·x̂.
            let u = rx_m90(&rz_inv(th3, &rx_m90(&rz_inv(t12, &n0))));
            let th4 = u.y.atan2(u.x);
            let off = &self.offsets;
            *slot = (
                err,
                [
                    wrap(th1 - off[0]),
                    wrap(t12 - th1 - off[1]),
                    wrap(th3 - off[2]),
                    wrap(th4 - off[3]),
                ],
            );
        }
        // Best first; candidates equal to 1e-6 rad (orientation- and position-based copies of
        // one branch) are kept once, the more accurate one.
        cands.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut kept: [[f64; 4]; 4] = [[0.0; 4]; 4];
        let mut k = 0;
        for (_, q) in cands.iter().filter(|c| c.0.is_finite()) {
            if kept[..k]
                .iter()
                .any(|o| o.iter().zip(q).all(|(x, y)| wrap(x - y).abs() < 1e-6))
            {
                continue;
            }
            kept[k] = *q;
            k += 1;
        }
        // Fixed order for callers: by θ1 then θ2.
        kept[..k].sort_by(|x, y| x[0].total_cmp(&y[0]).then(x[1].total_cmp(&y[1])));
        for q in &kept[..k] {
            sols.push(q);
        }
        if sols.is_empty() {
            let band = (a1 - a2).abs()..=(a1 + a2);
            let reason = if sxy <= 1e-12 && !band.contains(&r) {
                format!(
                    "arm4 wrist distance |w_xy| = {r:.9} m outside [{:.6}, {:.6}] m",
                    band.start(),
                    band.end()
                )
            } else {
                format!(
                    "arm4 approach axis: a_xy must lie along link 2, i.e. |w_xy ∓ a2·a_xy/|a_xy|| = a1 = {a1} m, \
                     but the wrist w_xy = ({:.6}, {:.6}) m and a = ({:.6}, {:.6}, {:.6}) give no such link 2",
                    w.x, w.y, a.x, a.y, a.z
                )
            };
            return Err(Error::Unreachable(reason));
        }
        Ok(())
    }
}

/// Rz(−θ)·v.
#[inline(always)]
fn rz_inv(theta: f64, v: &Vector3<f64>) -> Vector3<f64> {
    let (s, c) = theta.sin_cos();
    Vector3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)
}

/// Rx(−90°)·v.
#[inline(always)]
fn rx_m90(v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(v.x, v.z, -v.y)
}
