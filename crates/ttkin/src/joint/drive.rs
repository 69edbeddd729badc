//! A joint's drive ([`Drive`]): gear ratio, joint-side friction and the motor's datasheet values,
//! with their checks; plain data, converted into an axis configuration by `ttcan::actuator`.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

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
