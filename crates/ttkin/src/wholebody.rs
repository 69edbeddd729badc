//! Whole-body model of a mobile manipulator: a base carrying an arm [`Chain`].
//!
//! Two bases: [`Base::Fixed`] (the arm chain alone, e.g. seed 000's experimental `mobile8`, whose
//! joint 1 is a prismatic joint standing for the base rolling on a fixed heading), and
//! [`Base::DiffDrive`], a nonholonomic differential-drive base with pose (x, y, θ) on the floor.
//!
//! Configuration q (nq values): [x m, y m, θ rad, arm joints] for the diff-drive base, the arm
//! joints otherwise. Inputs u (nu values): [v m/s, ω rad/s, arm joint rates] for the diff-drive
//! base (the base cannot move sideways), the arm joint rates otherwise. The whole-body Jacobian
//! (6 × nu) maps u to the tool twist [v; ω] at the tool point in world axes:
//! column v = [cos θ, sin θ, 0; 0], column ω = [ẑ × (p − p_b); ẑ], arm columns = R_wb R_mount J_arm.

use std::sync::Arc;

use nalgebra::{IsometryMatrix3, Matrix6xX, Rotation3, Translation3, Vector3};

use crate::chain::{Chain, JacobianFrame};
use crate::diffdrive::{arc_step, DiffDrive};
use crate::error::{check_vector, Error, Result};

/// What carries the arm.
#[derive(Debug, Clone, PartialEq)]
pub enum Base {
    /// Nothing: the chain's base frame is the world frame.
    Fixed,
    /// A differential-drive base; `mount` maps the base frame (axle midpoint on the floor, x
    /// forward, z up) to the arm's base frame.
    DiffDrive {
        /// Wheel geometry and limits.
        drive: DiffDrive,
        /// Base frame → arm base frame.
        mount: IsometryMatrix3<f64>,
    },
}

/// A base and an arm; immutable model, scratch lives in [`WholeBodyData`].
#[derive(Debug, Clone, PartialEq)]
pub struct WholeBody {
    base: Base,
    arm: Arc<Chain>,
}

/// Scratch of a [`WholeBody`] (one per thread): the arm Jacobian.
#[derive(Debug, Clone)]
pub struct WholeBodyData {
    arm_jac: Matrix6xX<f64>,
}

impl WholeBody {
    /// The arm alone on a fixed base.
    pub fn fixed(arm: impl Into<Arc<Chain>>) -> Self {
        WholeBody {
            base: Base::Fixed,
            arm: arm.into(),
        }
    }

    /// The arm mounted (`mount`: base frame → arm base frame) on a differential-drive base.
    pub fn on_diff_drive(drive: DiffDrive, mount: IsometryMatrix3<f64>, arm: impl Into<Arc<Chain>>) -> Self {
        WholeBody {
            base: Base::DiffDrive { drive, mount },
            arm: arm.into(),
        }
    }

    /// The base.
    pub fn base(&self) -> &Base {
        &self.base
    }

    /// The arm chain.
    pub fn arm(&self) -> &Chain {
        &self.arm
    }

    /// Scratch for the algorithms of this model.
    pub fn data(&self) -> WholeBodyData {
        WholeBodyData {
            arm_jac: Matrix6xX::zeros(self.arm.dof()),
        }
    }

    /// Number of base coordinates in q (0 or 3).
    pub fn base_coordinates(&self) -> usize {
        match self.base {
            Base::Fixed => 0,
            Base::DiffDrive { .. } => 3,
        }
    }

    /// Number of base inputs in u (0 or 2).
    pub fn base_inputs(&self) -> usize {
        match self.base {
            Base::Fixed => 0,
            Base::DiffDrive { .. } => 2,
        }
    }

    /// Configuration size nq.
    pub fn nq(&self) -> usize {
        self.base_coordinates() + self.arm.dof()
    }

    /// Input size nu.
    pub fn nu(&self) -> usize {
        self.base_inputs() + self.arm.dof()
    }

    /// Checks that `q` has nq finite values.
    pub fn check_q(&self, what: &str, q: &[f64]) -> Result<()> {
        check_vector(what, q, self.nq())
    }

    /// Base frame → world (identity for a fixed base), from the base coordinates of `q`.
    fn base_to_arm(&self, q: &[f64]) -> Option<IsometryMatrix3<f64>> {
        match &self.base {
            Base::Fixed => None,
            Base::DiffDrive { mount, .. } => {
                let b = IsometryMatrix3::from_parts(
                    Translation3::new(q[0], q[1], 0.0),
                    Rotation3::from_axis_angle(&Vector3::z_axis(), q[2]),
                );
                Some(b * mount)
            }
        }
    }

    /// Tool pose in the world frame at `q` (m, rad).
    pub fn tool_pose(&self, q: &[f64]) -> Result<IsometryMatrix3<f64>> {
        self.check_q("q", q)?;
        Ok(self.tool_pose_unchecked(q))
    }

    /// [`WholeBody::tool_pose`] without the check (`q.len()` must be nq).
    pub fn tool_pose_unchecked(&self, q: &[f64]) -> IsometryMatrix3<f64> {
        let nb = self.base_coordinates();
        let t = self.arm.fk_unchecked(&q[nb..]);
        match self.base_to_arm(q) {
            None => t,
            Some(b) => b * t,
        }
    }

    /// Whole-body Jacobian (6 × nu, world axes, tool point) at `q`; see the module doc.
    pub fn jacobian(&self, q: &[f64]) -> Result<Matrix6xX<f64>> {
        self.check_q("q", q)?;
        let mut data = self.data();
        let mut jac = Matrix6xX::zeros(self.nu());
        self.jacobian_into(q, &mut data, &mut jac);
        Ok(jac)
    }

    /// [`WholeBody::jacobian`] into a preallocated 6 × nu matrix, unchecked; returns the tool pose.
    pub fn jacobian_into(&self, q: &[f64], data: &mut WholeBodyData, jac: &mut Matrix6xX<f64>) -> IsometryMatrix3<f64> {
        let nb = self.base_coordinates();
        match self.base_to_arm(q) {
            None => self.arm.jacobian_into(q, JacobianFrame::Base, jac),
            Some(b) => {
                let t = self.arm.jacobian_into(&q[nb..], JacobianFrame::Base, &mut data.arm_jac);
                let r = b.rotation;
                let world = b * t;
                let p = world.translation.vector;
                let (s, c) = q[2].sin_cos();
                let mut col = jac.column_mut(0);
                col.copy_from_slice(&[c, s, 0.0, 0.0, 0.0, 0.0]);
                let mut col = jac.column_mut(1);
                col.copy_from_slice(&[-(p.y - q[1]), p.x - q[0], 0.0, 0.0, 0.0, 1.0]);
                for (i, src) in data.arm_jac.column_iter().enumerate() {
                    let v = r * src.fixed_rows::<3>(0);
                    let w = r * src.fixed_rows::<3>(3);
                    let mut col = jac.column_mut(2 + i);
                    col.fixed_rows_mut::<3>(0).copy_from(&v);
                    col.fixed_rows_mut::<3>(3).copy_from(&w);
                }
                world
            }
        }
    }

    /// Moves `q` in place by inputs `u` held constant for `dt` s: the exact arc for the base
    /// (sinc update), q_arm += u_arm·dt for the arm (exact for constant joint rates). Unchecked.
    pub fn integrate(&self, q: &mut [f64], u: &[f64], dt: f64) {
        let (nb, ni) = (self.base_coordinates(), self.base_inputs());
        if nb == 3 {
            let p = arc_step([q[0], q[1], q[2]], u[0], u[1], dt);
            q[..3].copy_from_slice(&p);
        }
        for (qi, ui) in q[nb..].iter_mut().zip(&u[ni..]) {
            *qi += ui * dt;
        }
    }

    /// Configuration rate q̇ (nq) from inputs u (nu): ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω, arm rates.
    pub fn config_rate(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) -> Result<()> {
        self.check_q("q", q)?;
        check_vector("u", u, self.nu())?;
        check_vector("qdot buffer", qdot, self.nq())?;
        let (nb, ni) = (self.base_coordinates(), self.base_inputs());
        if nb == 3 {
            qdot[0] = u[0] * q[2].cos();
            qdot[1] = u[0] * q[2].sin();
            qdot[2] = u[1];
        }
        qdot[nb..].copy_from_slice(&u[ni..]);
        Ok(())
    }

    /// Per input: the coordinate index in q that it drives, if it has position limits (arm joints).
    pub fn input_coordinate(&self, k: usize) -> Option<usize> {
        let ni = self.base_inputs();
        if k < ni {
            None
        } else {
            Some(k - ni + self.base_coordinates())
        }
    }

    /// Per input: position limits [lower, upper] of its coordinate (m or rad), ±∞ for base inputs.
    pub fn input_position_limits(&self) -> Vec<(f64, f64)> {
        let mut out = vec![(f64::NEG_INFINITY, f64::INFINITY); self.base_inputs()];
        out.extend(self.arm.limits().iter().map(|l| (l.lower, l.upper)));
        out
    }

    /// Per input: speed limit (m/s or rad/s, ∞ when none). The base gets the box of
    /// [`DiffDrive::body_velocity_box`], which keeps both wheels within their speed limit.
    pub fn input_speed_limits(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.nu());
        if let Base::DiffDrive { drive, .. } = &self.base {
            let (v, w) = drive.body_velocity_box();
            out.push(v);
            out.push(w);
        }
        out.extend(self.arm.limits().iter().map(|l| l.velocity.unwrap_or(f64::INFINITY)));
        out
    }

    /// Checks that `q` lies within every position limit; the error names the first violation.
    pub fn check_within_limits(&self, q: &[f64]) -> Result<()> {
        self.check_q("q", q)?;
        let nb = self.base_coordinates();
        for (i, l) in self.arm.limits().iter().enumerate() {
            let v = q[nb + i];
            if v < l.lower || v > l.upper {
                return Err(Error::invalid(
                    "q",
                    format!(
                        "joint {} ('{}') = {v} is outside its limits [{}, {}]",
                        i,
                        self.arm.joints()[i].name(),
                        l.lower,
                        l.upper
                    ),
                ));
            }
        }
        Ok(())
    }
}
