//! One joint of a serial chain: its type, its geometry (DH parameters or a URDF-style origin and
//! axis), its limits and the inertia of the link it moves.
//!
//! Every joint is stored as `pre · M(q) · post`, where `M(q)` is a rotation about (revolute) or a
//! translation along (prismatic) the local z axis by `q`. The DH offsets and the URDF origin are
//! folded into `pre` and `post`, so forward kinematics is one code path for every description.

use nalgebra::{IsometryMatrix3, Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::inertial::Inertial;
use crate::transform::{rot_x, rot_z, trans};

pub mod drive;
pub use drive::{Drive, COULOMB_DEADBAND};

/// The motion a joint allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointType {
    /// Rotation about the joint axis; q in rad.
    Revolute,
    /// Translation along the joint axis; q in m.
    Prismatic,
}

/// Denavit–Hartenberg convention of a parameter row.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DhConvention {
    /// Standard (distal) DH: T = Rz(θ)·Tz(d)·Tx(a)·Rx(α); the joint moves about z of the previous frame.
    Standard,
    /// Modified (proximal, Craig) DH: T = Rx(α_{i−1})·Tx(a_{i−1})·Rz(θ)·Tz(d); the joint moves about its own z.
    Modified,
}

/// One DH row, lengths in m and angles in rad. `theta` (revolute) or `d` (prismatic) is the value
/// at q = 0, i.e. the joint offset: θ = theta + q, or d = d + q. In the modified convention `a` and
/// `alpha` are a_{i−1} and α_{i−1}.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Dh {
    /// Link length a (m).
    pub a: f64,
    /// Link twist α (rad).
    pub alpha: f64,
    /// Link offset d (m); the joint offset for a prismatic joint.
    pub d: f64,
    /// Joint angle θ (rad); the joint offset for a revolute joint.
    pub theta: f64,
}

/// Where the joint sits relative to the previous link frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Geometry {
    /// A DH row in the given convention.
    Dh(DhConvention, Dh),
    /// A URDF-style joint: fixed `origin` (previous link frame → joint frame at q = 0) and a unit
    /// `axis` in the joint frame; the link frame is `origin · motion(axis, q)`.
    Origin {
        /// Previous link frame → joint frame at q = 0.
        origin: IsometryMatrix3<f64>,
        /// Unit joint axis in the joint frame.
        axis: Unit<Vector3<f64>>,
    },
}

/// Position limits (m or rad) and optional velocity, acceleration and effort limits (per second,
/// per second², N or N·m) of one joint. Limits are for solvers and planners; forward kinematics
/// never enforces them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// Lower position limit (m or rad).
    pub lower: f64,
    /// Upper position limit (m or rad).
    pub upper: f64,
    /// Maximal speed (m/s or rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<f64>,
    /// Maximal acceleration (m/s² or rad/s²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acceleration: Option<f64>,
    /// Maximal force (N) or torque (N·m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effort: Option<f64>,
}

impl Limits {
    /// Position limits only.
    pub fn position(lower: f64, upper: f64) -> Self {
        Limits {
            lower,
            upper,
            velocity: None,
            acceleration: None,
            effort: None,
        }
    }

    /// No position limit at all (±∞).
    pub fn unbounded() -> Self {
        Self::position(f64::NEG_INFINITY, f64::INFINITY)
    }

    /// Distance (m or rad) from `q` to the nearer limit; negative when `q` is outside.
    pub fn margin(&self, q: f64) -> f64 {
        (q - self.lower).min(self.upper - q)
    }

    fn validate(&self, joint: &str) -> Result<()> {
        if self.lower.is_nan() || self.upper.is_nan() || self.lower > self.upper {
            return Err(Error::Model(format!(
                "joint '{joint}': position limits must satisfy lower ≤ upper, got [{}, {}]",
                self.lower, self.upper
            )));
        }
        for (name, v) in [
            ("velocity", self.velocity),
            ("acceleration", self.acceleration),
            ("effort", self.effort),
        ] {
            if let Some(v) = v {
                if !(v > 0.0) {
                    return Err(Error::Model(format!(
                        "joint '{joint}': {name} limit must be > 0, got {v}"
                    )));
                }
            }
        }
        Ok(())
    }
}

/// One joint and the link it moves.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Joint {
    name: String,
    kind: JointType,
    geometry: Geometry,
    limits: Limits,
    inertial: Option<Inertial>,
    drive: Option<Drive>,
    pre: IsometryMatrix3<f64>,
    post: IsometryMatrix3<f64>,
}

impl Joint {
    /// A joint from its type and geometry, unbounded, without inertia.
    pub fn new(name: impl Into<String>, kind: JointType, geometry: Geometry) -> Result<Self> {
        let name = name.into();
        let (pre, post) = split(&geometry, &name)?;
        Ok(Joint {
            name,
            kind,
            geometry,
            limits: Limits::unbounded(),
            inertial: None,
            drive: None,
            pre,
            post,
        })
    }

    /// A revolute joint from a DH row (θ = dh.theta + q).
    pub fn revolute(name: impl Into<String>, convention: DhConvention, dh: Dh) -> Result<Self> {
        Self::new(name, JointType::Revolute, Geometry::Dh(convention, dh))
    }

    /// A prismatic joint from a DH row (d = dh.d + q).
    pub fn prismatic(name: impl Into<String>, convention: DhConvention, dh: Dh) -> Result<Self> {
        Self::new(name, JointType::Prismatic, Geometry::Dh(convention, dh))
    }

    /// The same joint with the given limits.
    pub fn with_limits(mut self, limits: Limits) -> Result<Self> {
        limits.validate(&self.name)?;
        self.limits = limits;
        Ok(self)
    }

    /// The same joint whose link carries the given inertia (link frame).
    pub fn with_inertial(mut self, inertial: Inertial) -> Result<Self> {
        inertial.validate(&self.name)?;
        self.inertial = Some(inertial);
        Ok(self)
    }

    /// The same joint driven by the given motor and gearbox.
    pub fn with_drive(mut self, drive: Drive) -> Result<Self> {
        drive.validate(&self.name)?;
        self.drive = Some(drive);
        Ok(self)
    }

    /// Joint name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Revolute or prismatic.
    pub fn kind(&self) -> JointType {
        self.kind
    }

    /// The geometry this joint was described with.
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// Position and optional derivative limits.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Inertia of the link this joint moves, in the link frame, if known.
    pub fn inertial(&self) -> Option<&Inertial> {
        self.inertial.as_ref()
    }

    /// Motor, gearbox and friction of this joint, if known.
    pub fn drive(&self) -> Option<&Drive> {
        self.drive.as_ref()
    }

    /// Previous link frame → joint-axis frame (z is the axis).
    pub fn pre(&self) -> &IsometryMatrix3<f64> {
        &self.pre
    }

    /// Joint-axis frame after the motion → this joint's link frame.
    pub fn post(&self) -> &IsometryMatrix3<f64> {
        &self.post
    }

    /// Transform from the previous link frame to this link frame at joint value `q` (m or rad).
    pub fn transform(&self, q: f64) -> IsometryMatrix3<f64> {
        let m = match self.kind {
            JointType::Revolute => rot_z(q),
            JointType::Prismatic => trans(0.0, 0.0, q),
        };
        self.pre * m * self.post
    }
}

/// Splits a geometry into (pre, post) around the z motion.
fn split(g: &Geometry, name: &str) -> Result<(IsometryMatrix3<f64>, IsometryMatrix3<f64>)> {
    let id = IsometryMatrix3::identity();
    match g {
        Geometry::Dh(conv, dh) => {
            crate::error::check_finite(
                &format!("DH row of joint '{name}' (a, alpha, d, theta)"),
                &[dh.a, dh.alpha, dh.d, dh.theta],
            )?;
            // Rz(θ0 + q)·Tz(d) = Rz(θ0)·Tz(d)·Rz(q) and Rz(θ)·Tz(d0 + q) = Rz(θ)·Tz(d0)·Tz(q):
            // the fixed part of the row commutes with the z motion, so it goes before or after it.
            let z_part = rot_z(dh.theta) * trans(0.0, 0.0, dh.d);
            Ok(match conv {
                DhConvention::Modified => (rot_x(dh.alpha) * trans(dh.a, 0.0, 0.0) * z_part, id),
                DhConvention::Standard => (id, z_part * trans(dh.a, 0.0, 0.0) * rot_x(dh.alpha)),
            })
        }
        Geometry::Origin { origin, axis } => {
            let o = origin.translation.vector;
            crate::error::check_finite(&format!("origin of joint '{name}'"), &[o.x, o.y, o.z])?;
            crate::error::check_finite(
                &format!("origin rotation of joint '{name}'"),
                origin.rotation.matrix().as_slice(),
            )?;
            let a = axis.into_inner();
            if !(a.iter().all(|v| v.is_finite()) && (a.norm() - 1.0).abs() < 1e-9) {
                return Err(Error::Model(format!(
                    "joint '{name}': axis must be a finite unit vector, got {a:?}"
                )));
            }
            // Align local z with the axis; the link frame is origin·Rot(axis, q) = origin·A·Rz(q)·Aᵀ.
            let align = Rotation3::rotation_between(&Vector3::z(), &a)
                .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI));
            let a_iso = IsometryMatrix3::from_parts(nalgebra::Translation3::identity(), align);
            Ok((origin * a_iso, a_iso.inverse()))
        }
    }
}
