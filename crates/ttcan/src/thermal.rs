//! Motor temperature: the winding/housing two-time-constant model of motor datasheets, and the
//! gradual current derating it drives (in place of an I²t integrator with a cliff).
//!
//! ```text
//! C_w dT_w/dt = R(T_w) i² − (T_w − T_h)/R_wh          C_w = τ_w / R_wh
//! C_h dT_h/dt = (T_w − T_h)/R_wh − (T_h − T_a)/R_ha   C_h = τ_h / R_ha
//! R(T) = R₂₅ (1 + α (T − 25 °C)),  α = 0.0039/K for copper
//! ```
//!
//! Datasheets give R_wh, R_ha ("thermal resistance winding–housing, housing–ambient"), τ_w and τ_h
//! ("thermal time constant winding, motor") and the largest winding temperature. The current
//! limit is the peak current up to `derating_start` below the largest winding temperature, falls
//! linearly to the continuous rating at it, and to zero 10 K above it; the limit is "active"
//! whenever it is below the peak. Integrated by explicit Euler at the current-loop rate
//! (T = 50 µs against τ_w ≈ 10 s: stable and accurate to 1e-5 relative per step).

use serde::{Deserialize, Serialize};

use crate::error::{positive, Error, Result};

/// Datasheet thermal values of a motor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalModel {
    /// Thermal resistance winding–housing R_wh, K/W.
    pub winding_housing_resistance: f64,
    /// Thermal resistance housing–ambient R_ha, K/W.
    pub housing_ambient_resistance: f64,
    /// Thermal time constant of the winding τ_w, s.
    pub winding_time_constant: f64,
    /// Thermal time constant of the motor (housing) τ_h, s.
    pub housing_time_constant: f64,
    /// Largest permissible winding temperature, °C.
    pub max_winding_temperature: f64,
    /// Ambient temperature, °C.
    pub ambient_temperature: f64,
    /// Kelvin below the largest winding temperature where derating starts, K (> 0).
    pub derating_start: f64,
}

impl ThermalModel {
    /// A Ø25 mm graphite-brush DC motor of the maxon RE 25 class: R_wh 4.0 K/W, R_ha 13.2 K/W,
    /// τ_w 12.5 s, τ_h 700 s, 125 °C winding, 25 °C ambient, derating over the last 20 K.
    /// Catalogue-class values, read from the RE 25 class drive of the built-in robots
    /// (`ttkin::robots::drives::maxon_re25`, the one copy): check them against the datasheet of the
    /// motor actually fitted.
    pub fn maxon_re25() -> Self {
        let drive = ttkin::robots::drives::maxon_re25(1.0, 1.0, crate::motor::NO_JOINT_FRICTION);
        let values = drive
            .thermal_values()
            .map(|(_, v)| v.expect("the RE 25 class drive carries its thermal data"));
        ThermalModel::from_datasheet(values)
    }

    /// The model of a drive's five datasheet values in the order of
    /// `ttkin::joint::Drive::thermal_values` (R_wh, R_ha in K/W; τ_w, τ_h in s; largest winding
    /// temperature in °C), at 25 °C ambient with derating over the last 20 K. Not checked: see
    /// [`ThermalModel::validate`].
    pub fn from_datasheet(values: [f64; 5]) -> Self {
        let [r_wh, r_ha, tau_w, tau_h, t_max] = values;
        ThermalModel {
            winding_housing_resistance: r_wh,
            housing_ambient_resistance: r_ha,
            winding_time_constant: tau_w,
            housing_time_constant: tau_h,
            max_winding_temperature: t_max,
            ambient_temperature: DATASHEET_AMBIENT,
            derating_start: DATASHEET_DERATING_START,
        }
    }

    /// Checks every value; the error names the field.
    pub fn validate(&self) -> Result<()> {
        positive(
            "thermal resistance winding-housing (K/W)",
            self.winding_housing_resistance,
        )?;
        positive(
            "thermal resistance housing-ambient (K/W)",
            self.housing_ambient_resistance,
        )?;
        positive("thermal time constant winding (s)", self.winding_time_constant)?;
        positive("thermal time constant housing (s)", self.housing_time_constant)?;
        positive("derating start (K)", self.derating_start)?;
        crate::error::finite("ambient temperature (°C)", self.ambient_temperature)?;
        crate::error::finite("max winding temperature (°C)", self.max_winding_temperature)?;
        if self.max_winding_temperature <= self.ambient_temperature + self.derating_start {
            return Err(Error::InvalidParameter {
                what: "max winding temperature (°C)".into(),
                value: self.max_winding_temperature,
                reason: "must be above the ambient temperature plus the derating band".into(),
            });
        }
        Ok(())
    }

    /// The steady continuous current (A) that holds the winding at its largest temperature, at
    /// ambient temperature, for a winding of resistance `resistance_25` Ω at 25 °C.
    pub fn continuous_current(&self, resistance_25: f64) -> f64 {
        let dt = self.max_winding_temperature - self.ambient_temperature;
        let r = resistance_25 * (1.0 + COPPER_ALPHA * (self.max_winding_temperature - 25.0));
        (dt / ((self.winding_housing_resistance + self.housing_ambient_resistance) * r)).sqrt()
    }
}

/// Ambient temperature of a model read from datasheet values, °C.
const DATASHEET_AMBIENT: f64 = 25.0;

/// Derating band below the largest winding temperature of a model read from datasheet values, K.
const DATASHEET_DERATING_START: f64 = 20.0;

/// Temperature coefficient of copper resistance, 1/K.
pub const COPPER_ALPHA: f64 = 0.0039;

/// Winding and housing temperatures of one motor, and the current limit they allow.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalState {
    model: ThermalModel,
    resistance_25: f64,
    /// 1/R_wh, 1/R_ha (W/K), 1/C_w, 1/C_h (K/J): computed once.
    g_wh: f64,
    g_ha: f64,
    inv_c_w: f64,
    inv_c_h: f64,
    winding: f64,
    housing: f64,
}

impl ThermalState {
    /// A cold motor (at ambient) with winding resistance `resistance_25` Ω at 25 °C.
    pub fn new(model: &ThermalModel, resistance_25: f64) -> Result<Self> {
        model.validate()?;
        positive("motor resistance (Ω)", resistance_25)?;
        Ok(ThermalState {
            model: *model,
            resistance_25,
            g_wh: 1.0 / model.winding_housing_resistance,
            g_ha: 1.0 / model.housing_ambient_resistance,
            inv_c_w: model.winding_housing_resistance / model.winding_time_constant,
            inv_c_h: model.housing_ambient_resistance / model.housing_time_constant,
            winding: model.ambient_temperature,
            housing: model.ambient_temperature,
        })
    }

    /// Advances `dt` s with winding current `current` A (NaN counts as 0).
    #[inline]
    pub fn step(&mut self, current: f64, dt: f64) {
        let i2 = if current.is_finite() { current * current } else { 0.0 };
        let r = self.resistance_25 * (1.0 + COPPER_ALPHA * (self.winding - 25.0));
        let to_housing = (self.winding - self.housing) * self.g_wh;
        let to_ambient = (self.housing - self.model.ambient_temperature) * self.g_ha;
        self.winding += dt * (r * i2 - to_housing) * self.inv_c_w;
        self.housing += dt * (to_housing - to_ambient) * self.inv_c_h;
    }

    /// Current limit at the present winding temperature, A, between `peak` and zero.
    #[inline]
    pub fn limit(&self, peak: f64, continuous: f64) -> f64 {
        let m = &self.model;
        let start = m.max_winding_temperature - m.derating_start;
        if self.winding <= start {
            peak
        } else if self.winding <= m.max_winding_temperature {
            let s = (self.winding - start) / m.derating_start;
            peak + s * (continuous - peak)
        } else {
            continuous * (1.0 - (self.winding - m.max_winding_temperature) / 10.0).max(0.0)
        }
    }

    /// Winding temperature, °C.
    pub fn winding_temperature(&self) -> f64 {
        self.winding
    }

    /// Housing temperature, °C.
    pub fn housing_temperature(&self) -> f64 {
        self.housing
    }

    /// Sets both temperatures (a motor that is already warm), °C.
    pub fn set_temperatures(&mut self, winding: f64, housing: f64) {
        if winding.is_finite() && housing.is_finite() {
            self.winding = winding;
            self.housing = housing;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_re25_model_is_the_re25_drives_datasheet() {
        let m = ThermalModel::maxon_re25();
        let drive = ttkin::robots::drives::maxon_re25(30.0, 0.75, crate::motor::NO_JOINT_FRICTION);
        let from_drive = drive.thermal_values().map(|(_, v)| v.unwrap());
        let of_model = [
            m.winding_housing_resistance,
            m.housing_ambient_resistance,
            m.winding_time_constant,
            m.housing_time_constant,
            m.max_winding_temperature,
        ];
        assert_eq!(of_model, from_drive);
        // the catalogue values this model always had (unchanged by reading them from the drive)
        assert_eq!(of_model, [4.0, 13.2, 12.5, 700.0, 125.0]);
        assert_eq!((m.ambient_temperature, m.derating_start), (25.0, 20.0));
        m.validate().unwrap();
    }
}
