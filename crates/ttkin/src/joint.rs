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

/// The drive of one joint, its actuator's one description (issue 10): gear ratio, joint-side
/// friction and the motor datasheet values (motor side, SI units). Every datasheet value is
/// optional: absent means "not given", and `ttcan::actuator` then falls back to a documented
/// derivation (old robot files, which give only gear, rotor inertia, friction and k_t, still
/// load). The thermal values come as a set: all five or none.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drive {
    /// Gear ratio G = motor angle / joint motion (> 0): rad/rad for a revolute joint, rad/m for a
    /// prismatic one (a ball screw of lead ℓ m/turn has G = 2π/ℓ).
    pub gear_ratio: f64,
    /// Rotor inertia of the motor (and gearbox input) about its axis, motor side, kg·m² (≥ 0).
    /// Reflected to the joint it adds the armature G²·J (kg·m² or kg).
    #[serde(default)]
    pub rotor_inertia: f64,
    /// Viscous friction coefficient b, joint side: τ_f = b·q̇ (N·m·s/rad or N·s/m, ≥ 0).
    #[serde(default)]
    pub viscous: f64,
    /// Coulomb friction level f_c, joint side: τ_f = f_c·sign(q̇) (N·m or N, ≥ 0).
    #[serde(default)]
    pub coulomb: f64,
    /// Motor torque constant k_t, N·m/A (> 0), if known: current = motor torque / k_t.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torque_constant: Option<f64>,
    /// Terminal (winding) resistance at 25 °C, Ω (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resistance: Option<f64>,
    /// Terminal inductance, H (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inductance: Option<f64>,
    /// Nominal (largest continuous) current, A (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nominal_current: Option<f64>,
    /// Peak current the drive may command, A (≥ nominal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_current: Option<f64>,
    /// Largest permissible motor speed, rad/s motor side (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_motor_speed: Option<f64>,
    /// Thermal resistance winding–housing R_wh, K/W (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_resistance_winding_housing: Option<f64>,
    /// Thermal resistance housing–ambient R_ha, K/W (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_resistance_housing_ambient: Option<f64>,
    /// Thermal time constant of the winding τ_w, s (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_time_constant_winding: Option<f64>,
    /// Thermal time constant of the housing (motor) τ_h, s (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thermal_time_constant_housing: Option<f64>,
    /// Largest permissible winding temperature, °C.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_winding_temperature: Option<f64>,
    /// Gearbox (and transmission) efficiency at the rated point, in (0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gear_efficiency: Option<f64>,
    /// Encoder counts per motor revolution after quadrature decoding (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub encoder_counts: Option<u32>,
    /// DC bus (supply) voltage of the drive, V (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bus_voltage: Option<f64>,
}

/// Joint speeds (rad/s or m/s) at or below which Coulomb friction is taken as 0.
pub const COULOMB_DEADBAND: f64 = 1e-9;

impl Drive {
    /// A drive with only a gear ratio: no rotor inertia, no friction, no torque constant.
    pub fn geared(gear_ratio: f64) -> Self {
        Drive {
            gear_ratio,
            rotor_inertia: 0.0,
            viscous: 0.0,
            coulomb: 0.0,
            torque_constant: None,
            resistance: None,
            inductance: None,
            nominal_current: None,
            peak_current: None,
            max_motor_speed: None,
            thermal_resistance_winding_housing: None,
            thermal_resistance_housing_ambient: None,
            thermal_time_constant_winding: None,
            thermal_time_constant_housing: None,
            max_winding_temperature: None,
            gear_efficiency: None,
            encoder_counts: None,
            bus_voltage: None,
        }
    }

    /// Rotor inertia reflected to the joint, G²·J (kg·m² for revolute, kg for prismatic joints).
    pub fn armature(&self) -> f64 {
        self.gear_ratio * self.gear_ratio * self.rotor_inertia
    }

    /// Friction torque (N·m or N) at joint speed `qd` (rad/s or m/s): b·q̇ + f_c·sign(q̇), with the
    /// Coulomb term 0 for |q̇| ≤ [`COULOMB_DEADBAND`] (a joint at rest, whose planned speed is
    /// round-off, has no definite friction direction).
    pub fn friction(&self, qd: f64) -> f64 {
        let sign = if qd > COULOMB_DEADBAND {
            1.0
        } else if qd < -COULOMB_DEADBAND {
            -1.0
        } else {
            0.0
        };
        self.viscous * qd + self.coulomb * sign
    }

    /// The five thermal datasheet values by field name: R_wh, R_ha (K/W), τ_w, τ_h (s), largest
    /// winding temperature (°C); `None` where not given.
    pub fn thermal_values(&self) -> [(&'static str, Option<f64>); 5] {
        [
            (
                "thermal_resistance_winding_housing",
                self.thermal_resistance_winding_housing,
            ),
            (
                "thermal_resistance_housing_ambient",
                self.thermal_resistance_housing_ambient,
            ),
            ("thermal_time_constant_winding", self.thermal_time_constant_winding),
            ("thermal_time_constant_housing", self.thermal_time_constant_housing),
            ("max_winding_temperature", self.max_winding_temperature),
        ]
    }

    /// Checks that every value is finite and in range; `joint` names the joint in the message.
    pub fn validate(&self, joint: &str) -> Result<()> {
        let what = format!("drive of joint '{joint}'");
        crate::error::check_finite(
            &what,
            &[
                self.gear_ratio,
                self.rotor_inertia,
                self.viscous,
                self.coulomb,
                self.torque_constant.unwrap_or(1.0),
            ],
        )?;
        if !(self.gear_ratio > 0.0) {
            return Err(Error::Model(format!(
                "{what}: gear ratio must be > 0, got {}",
                self.gear_ratio
            )));
        }
        for (name, v) in [
            ("rotor inertia", self.rotor_inertia),
            ("viscous friction", self.viscous),
            ("Coulomb friction", self.coulomb),
        ] {
            if v < 0.0 {
                return Err(Error::Model(format!("{what}: {name} must be ≥ 0, got {v}")));
            }
        }
        if let Some(k) = self.torque_constant {
            if !(k > 0.0) {
                return Err(Error::Model(format!(
                    "{what}: torque constant must be > 0 N·m/A, got {k}"
                )));
            }
        }
        for (name, v) in [
            ("resistance", self.resistance),
            ("inductance", self.inductance),
            ("nominal_current", self.nominal_current),
            ("peak_current", self.peak_current),
            ("max_motor_speed", self.max_motor_speed),
            ("gear_efficiency", self.gear_efficiency),
            ("bus_voltage", self.bus_voltage),
            ("encoder_counts", self.encoder_counts.map(f64::from)),
        ]
        .into_iter()
        .chain(self.thermal_values().into_iter().take(4))
        {
            if let Some(v) = v {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(Error::Model(format!("{what}: {name} must be finite and > 0, got {v}")));
                }
            }
        }
        if let Some(t) = self.max_winding_temperature {
            if !t.is_finite() {
                return Err(Error::Model(format!(
                    "{what}: max_winding_temperature must be finite, got {t}"
                )));
            }
        }
        if self.gear_efficiency.is_some_and(|e| e > 1.0) {
            return Err(Error::Model(format!("{what}: gear_efficiency must be <= 1")));
        }
        if let (Some(n), Some(p)) = (self.nominal_current, self.peak_current) {
            if p < n {
                return Err(Error::Model(format!(
                    "{what}: peak_current {p} A must be >= nominal_current {n} A"
                )));
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
