//! Closed-form IK of seed 002's 6-joint gantry (patent steps S102–S103), every branch.
//!
//! Model (modified DH, rows (α_{i−1}, a_{i−1}, θ_i, d_i)): (90°, 0, 90°, d1), (90°, 0, 90°, d2),
//! (90°, 0, θ3, L1), (90°, 0, θ4, 0), (0, L3, θ5, L2), (90°, 0, θ6, L4). With n, o, a the columns
//! of the tool rotation and p its position (chain frame 0), forward kinematics gives
//! a = (s3·s45, −c3·s45, −c45) and
//! p = (d2 − L2c3 + s3(L3c4 + L4s45), −d1 − L2s3 − c3(L3c4 + L4s45), L1 + L3s4 − L4c45).
//!
//! Inverse, for σ1, σ2 = ±1 (the seeds README, with its corrections: joints 4 and 5 are parallel,
//! the d1 term is L4·c3·s45, and both σ1 branches are kept, not only σ1 = +1):
//! - s45 = σ1·√(ax² + ay²), θ45 = atan2(s45, −az); θ3 = atan2(σ1·ax, −σ1·ay);
//! - s4 = (pz − L1 − L4·az)/L3, θ4 = atan2(s4, σ2·√(1 − s4²)), θ5 = θ45 − θ4;
//! - θ6 from the remaining rotation Rz(θ6) = (C·Rz(θ3)·Rx(90°)·Rz(θ45)·Rx(90°))ᵀ·R, which equals
//!   atan2(−oz/s45, nz/s45) when s45 ≠ 0 but stays exact near s45 = 0;
//! - d1 = −py − L2s3 − c3(L3c4 + L4s45), d2 = px + L2c3 − s3(L3c4 + L4s45).
//!
//! Reach: every orientation; the height band |pz − L1 − L4·az| ≤ L3; the linear-axis strokes
//! (checked when limits are enforced). Singular sets: s45 = 0 (a = ∓z: θ3 and θ6 rotate about the
//! same axis, a one-parameter family; the representative keeps θ3 at the hint's value, 0 without,
//! and [`Solutions::family`] is set) and c4 = 0 (the two σ2 branches coincide).

use std::f64::consts::PI;

use nalgebra::{IsometryMatrix3, Matrix3, Vector3};

use super::{dh_rows, fit_to_limits, same, wrap, ChainInfo, LimitFilter, Solutions};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::joint::{DhConvention, JointType};
use crate::robots::GantryLengths;
use crate::transform::{rot_x, rot_z};

/// Below this √(ax² + ay²) the pose is on the s45 = 0 family.
const FAMILY_EPS: f64 = 1e-13;
/// How far past the height band (as |s4| − 1) a target is still accepted and clamped.
const BAND_SLACK: f64 = 1e-12;

/// Analytic IK of a chain with the gantry6 structure (lengths and joint offsets read from it).
#[derive(Debug, Clone, PartialEq)]
pub struct GantryIk {
    /// L1..L4 of the chain (m).
    pub lengths: GantryLengths,
    /// Joint offsets: d of joints 1–2 (m), θ of joints 3–6 (rad).
    offsets: [f64; 6],
    /// Cᵀ, C the constant rotation of rows 1–3 before θ3.
    c_t: Matrix3<f64>,
    pub(crate) info: ChainInfo,
}

impl GantryIk {
    /// The solver if `chain` has the gantry6 structure: joints P P R R R R, modified DH, rows
    /// (90°, 0, 90°, ·), (90°, 0, 90°, ·), (90°, 0, ·, L1), (90°, 0, ·, 0), (0, L3, ·, L2),
    /// (90°, 0, ·, L4) with L3 > 0; base and tool transforms may be anything.
    pub fn from_chain(chain: &Chain) -> Option<GantryIk> {
        use JointType::{Prismatic as P, Revolute as R};
        let rows = dh_rows(chain, DhConvention::Modified)?;
        if rows.len() != 6 {
            return None;
        }
        let q90 = std::f64::consts::FRAC_PI_2;
        let kinds = [P, P, R, R, R, R];
        let alphas = [q90, q90, q90, q90, 0.0, q90];
        for (i, (k, dh)) in rows.iter().enumerate() {
            if *k != kinds[i] || !same(dh.alpha, alphas[i]) {
                return None;
            }
            if i != 4 && !same(dh.a, 0.0) {
                return None;
            }
        }
        let ok = same(rows[0].1.theta, q90) && same(rows[1].1.theta, q90) && same(rows[3].1.d, 0.0);
        let l3 = rows[4].1.a;
        if !ok || !(l3 > 1e-9) {
            return None;
        }
        let lengths = GantryLengths {
            l1: rows[2].1.d,
            l2: rows[4].1.d,
            l3,
            l4: rows[5].1.d,
        };
        let offsets = [
            rows[0].1.d,
            rows[1].1.d,
            rows[2].1.theta,
            rows[3].1.theta,
            rows[4].1.theta,
            rows[5].1.theta,
        ];
        let c = rot_x(q90) * rot_z(q90) * rot_x(q90) * rot_z(q90) * rot_x(q90);
        Some(GantryIk {
            lengths,
            offsets,
            c_t: c.rotation.matrix().transpose(),
            info: ChainInfo::of(chain),
        })
    }

    /// Every branch reaching `target` (tool pose in the base frame, m): up to 4 (σ1, σ2), 2 on the
    /// s45 = 0 family (whose θ3 is `hint[2]`, or 0), fewer where branches coincide or limits are
    /// enforced. Revolute angles in (−π, π] unless shifted into the limits.
    /// Errors: [`Error::Unreachable`] outside the height band (or every branch outside the limits
    /// with [`LimitFilter::Enforce`]); [`Error::NonFinite`] for a NaN target.
    pub fn solve(&self, target: &IsometryMatrix3<f64>, hint: Option<&[f64]>, filter: LimitFilter) -> Result<Solutions> {
        let mut sols = Solutions::empty(6);
        self.solve_into(target, hint.map(|h| h.get(2).copied().unwrap_or(0.0)), &mut sols)?;
        sols.apply(filter, &self.info)?;
        Ok(sols)
    }

    /// The branch within the limits nearest to `current` (m, rad; as [`super::Analytic::nearest`]
    /// with [`LimitFilter::Enforce`]) and the number of branches within the limits, from one
    /// solve; the reasons branches were dropped are written only when none is left.
    pub(crate) fn nearest_within_limits(
        &self,
        target: &IsometryMatrix3<f64>,
        current: &[f64],
    ) -> Result<(Vec<f64>, usize)> {
        crate::error::check_vector("current configuration", current, 6)?;
        let mut sols = Solutions::empty(6);
        self.solve_into(target, Some(current[2]), &mut sols)?;
        let all = sols;
        let mut kept = 0;
        for b in 0..sols.count {
            let mut q = sols.q[b];
            let fits = (0..6).all(
                |i| match fit_to_limits(q[i], self.info.kinds[i], &self.info.limits[i]) {
                    Some(v) => {
                        q[i] = v;
                        true
                    }
                    None => false,
                },
            );
            if fits {
                sols.q[kept] = q;
                kept += 1;
            }
        }
        sols.count = kept;
        if kept == 0 {
            let mut all = all;
            all.apply(LimitFilter::Enforce, &self.info)?;
        }
        Ok((sols.nearest(current, &self.info, LimitFilter::Enforce), kept))
    }

    /// The mathematical branches (no limit filter) into `sols`; `q3_hint` is θ3's joint value on
    /// the s45 = 0 family.
    pub(crate) fn solve_into(
        &self,
        target: &IsometryMatrix3<f64>,
        q3_hint: Option<f64>,
        sols: &mut Solutions,
    ) -> Result<()> {
        let t = self.info.to_chain(target);
        crate::error::check_finite("target pose", t.rotation.matrix().as_slice())?;
        crate::error::check_finite("target pose", t.translation.vector.as_slice())?;
        self.branches_of(&t, q3_hint, sols).map_err(|BandMiss { pz, az, h }| {
            let GantryLengths { l1, l3, l4, .. } = self.lengths;
            Error::Unreachable(format!(
                "gantry height band |pz − L1 − L4·az| ≤ L3 fails: |{pz:.6} − {l1} − {l4}·({az:.6})| = {:.6} m > L3 = {l3} m",
                h.abs()
            ))
        })
    }

    /// [`GantryIk::solve_into`] without error messages: `None` outside the height band or for a
    /// non-finite target (the hit planner's search asks for thousands of poses beyond the arm).
    pub(crate) fn solve_quiet(&self, target: &IsometryMatrix3<f64>, q3_hint: Option<f64>) -> Option<Solutions> {
        let t = self.info.to_chain(target);
        let finite = t
            .rotation
            .matrix()
            .iter()
            .chain(t.translation.vector.iter())
            .all(|x| x.is_finite());
        let mut sols = Solutions::empty(6);
        (finite && self.branches_of(&t, q3_hint, &mut sols).is_ok()).then_some(sols)
    }

    /// The branches of the finite chain-frame pose `t` into `sols`, or the height band's values
    /// when it fails.
    fn branches_of(
        &self,
        t: &IsometryMatrix3<f64>,
        q3_hint: Option<f64>,
        sols: &mut Solutions,
    ) -> std::result::Result<(), BandMiss> {
        let r = t.rotation.matrix();
        let p = t.translation.vector;
        let GantryLengths { l1, l2, l3, l4 } = self.lengths;
        let a: Vector3<f64> = r.column(2).into_owned();
        let h = p.z - l1 - l4 * a.z;
        let s4 = h / l3;
        if !(s4.abs() <= 1.0 + BAND_SLACK) {
            return Err(BandMiss { pz: p.z, az: a.z, h });
        }
        let s4 = s4.clamp(-1.0, 1.0);
        let c4_abs = (1.0 - s4 * s4).max(0.0).sqrt();
        let th4 = s4.atan2(c4_abs);
        let sxy = a.x.hypot(a.y);
        sols.family = sxy <= FAMILY_EPS;
        // Branch σ1 = +1: s45 = √(ax² + ay²) ≥ 0, (s3, c3) = (ax, −ay)/s45.
        let (th3, s3, c3) = if sols.family {
            let th3 = q3_hint.unwrap_or(0.0) + self.offsets[2];
            let (s3, c3) = th3.sin_cos();
            (th3, s3, c3)
        } else {
            (a.x.atan2(-a.y), a.x / sxy, -a.y / sxy)
        };
        let (s45, c45) = (sxy, -a.z);
        let th45 = s45.atan2(c45);
        // Undo Rz(θ3), Rx(90°), Rz(θ45), Rx(90°) on Cᵀ·n: what is left is Rz(θ6)·x̂.
        let n0 = self.c_t * r.column(0);
        let v = rx_m90(&rz_inv(s45, c45, &rx_m90(&rz_inv(s3, c3, &n0))));
        let th6 = v.y.atan2(v.x);
        let branch = |sols: &mut Solutions, sigma: f64, th3: f64, th45: f64, th6: f64| {
            // σ1 = −1 is (θ3 + π, −θ45, θ6 + π): s3, c3, s45 change sign.
            let (s3, c3, s45) = (sigma * s3, sigma * c3, sigma * s45);
            for (c4, th4) in [(c4_abs, th4), (-c4_abs, PI - th4)] {
                let k = l3 * c4 + l4 * s45;
                let d1 = -p.y - l2 * s3 - c3 * k;
                let d2 = p.x + l2 * c3 - s3 * k;
                let off = &self.offsets;
                sols.push(&[
                    d1 - off[0],
                    d2 - off[1],
                    wrap(th3 - off[2]),
                    wrap(th4 - off[3]),
                    wrap(th45 - th4 - off[4]),
                    wrap(th6 - off[5]),
                ]);
            }
        };
        branch(sols, 1.0, th3, th45, th6);
        if !sols.family {
            branch(sols, -1.0, th3 + PI, -th45, th6 + PI);
        }
        Ok(())
    }
}

/// The values of a failed height band test (m; `az` the tool axis' z component), for its message.
struct BandMiss {
    pz: f64,
    az: f64,
    h: f64,
}

/// Rz(−θ)·v from s = sin θ, c = cos θ.
#[inline(always)]
fn rz_inv(s: f64, c: f64, v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)
}

/// Rx(−90°)·v.
#[inline(always)]
fn rx_m90(v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(v.x, v.z, -v.y)
}
