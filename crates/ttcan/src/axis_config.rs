//! What an axis is built from: the controller's model of its actuator, loop rates, tuning
//! targets, ratings, limits, monitors and the holding brake. Plain data, serde-described (the
//! same types read a controller's TOML file); the axis ([`crate::axis::Axis::new`]) checks it
//! once when it is built.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::motor::MotorModel;
use crate::schedule::Rates;
use crate::thermal::ThermalModel;
use crate::tuning::TuningTargets;

/// Everything an axis is built from. Start from [`AxisConfig::new`] and change fields; every
/// field is checked when the axis is built ([`crate::axis::Axis::new`]), never in the loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisConfig {
    /// The controller's model of the actuator (used for tuning and unit conversions).
    pub model: MotorModel,
    /// Loop rates.
    pub rates: Rates,
    /// Tuning targets.
    pub tuning: TuningTargets,
    /// Speed reference filter cut-off, Hz; `None`: 1/(2π a T_σ) from the tuning.
    pub speed_reference_filter_hz: Option<f64>,
    /// Continuous current rating, A.
    pub continuous_current: f64,
    /// Peak current, A (≥ continuous).
    pub peak_current: f64,
    /// Winding/housing thermal model (datasheet values) that derates the current limit.
    pub thermal: ThermalModel,
    /// Measured current that trips an over-current fault, A (> peak).
    pub overcurrent_trip: f64,
    /// Largest output speed, rad/s (the bus must be able to overcome its back-EMF).
    pub max_speed: f64,
    /// Largest allowed |position reference − position|, rad.
    pub following_error_limit: f64,
    /// Deceleration of the controlled stop, rad/s² at the output.
    pub quick_stop_deceleration: f64,
    /// Velocity feedforward in position mode.
    pub velocity_feedforward: bool,
    /// Acceleration feedforward (through inertia and torque constant to current) in position mode.
    pub acceleration_feedforward: bool,
    /// Back-EMF feedforward in the current loop (from the estimated speed).
    pub emf_feedforward: bool,
    /// Anti-windup in the current and speed PIs.
    pub anti_windup: bool,
    /// Cut-off of the low-pass on the speed estimate used by the back-EMF feedforward, Hz: the
    /// estimate moves in whole encoder counts per speed period, and unfiltered those steps would
    /// kick the current.
    pub emf_filter_hz: f64,
    /// Largest RMS current-reference ripple from encoder quantisation (the tuning's
    /// `quantisation_ripple_rms`), as a share of the continuous current; a configuration above it
    /// is refused (lower the observer bandwidth or use a finer encoder).
    pub max_quantisation_ripple_share: f64,
    /// Period of cyclic position setpoints, s (CiA 402 interpolation time, 0x60C2): `Some` makes
    /// the axis interpolate them at the speed-loop rate (see [`crate::setpoint`]) and watch their
    /// age; `None` uses each setpoint as it comes, with no watchdog.
    pub setpoint_period: Option<f64>,
    /// Cyclic setpoints missed in a row before the axis quick-stops with [`crate::axis::Fault::SetpointsLost`].
    pub setpoint_max_missed: u32,
    /// Following-error limit growth with the reference speed, s: the limit is
    /// `following_error_limit + following_error_per_speed·|q̇_ref|` (a lag of this many seconds).
    pub following_error_per_speed: f64,
    /// Estimated output speed above which [`crate::axis::Fault::Overspeed`] trips in every mode, rad/s (> max speed).
    pub overspeed_limit: f64,
    /// Software position limits (lower, upper), rad at the output; `None`: none.
    pub position_limits: Option<(f64, f64)>,
    /// Measured bus voltage above which [`crate::axis::Fault::OverVoltage`] trips, V.
    pub bus_overvoltage: f64,
    /// Measured bus voltage below which [`crate::axis::Fault::UnderVoltage`] trips, V.
    pub bus_undervoltage: f64,
    /// Holding brake, if the axis has one.
    pub holding_brake: Option<HoldingBrake>,
}

/// A holding brake (spring applied, released by power): its mechanical delays.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HoldingBrake {
    /// Time from the release command until the brake is free, s.
    pub release_delay: f64,
    /// Time from the engage command until the brake holds, s.
    pub engage_delay: f64,
}

impl AxisConfig {
    /// Defaults for `model`: 20/5/1 kHz, 1 kHz current bandwidth, symmetric optimum a = 3, currents
    /// 1.2 A continuous / 3.6 A peak (derated by the RE 25 thermal model) / 6 A trip, 30 rad/s, 0.1 rad following-error limit,
    /// 200 rad/s² quick stop, all feedforwards and anti-windup on. The current and speed values
    /// fit the maxon RE 25 + GP 26 A 14:1 of [`crate::motor::MotorModel::maxon_re25_gp26`].
    pub fn new(model: MotorModel) -> Self {
        AxisConfig {
            model,
            rates: Rates::default(),
            tuning: TuningTargets::default(),
            speed_reference_filter_hz: None,
            continuous_current: 1.2,
            peak_current: 3.6,
            thermal: ThermalModel::maxon_re25(),
            overcurrent_trip: 6.0,
            max_speed: 30.0,
            following_error_limit: 0.1,
            quick_stop_deceleration: 200.0,
            velocity_feedforward: true,
            acceleration_feedforward: true,
            emf_feedforward: true,
            anti_windup: true,
            emf_filter_hz: 100.0,
            max_quantisation_ripple_share: 0.05,
            setpoint_period: None,
            setpoint_max_missed: 3,
            following_error_per_speed: 0.0,
            overspeed_limit: 36.0,
            position_limits: None,
            bus_overvoltage: 1.25 * model.bus_voltage,
            bus_undervoltage: 0.7 * model.bus_voltage,
            holding_brake: None,
        }
    }
}

/// Nested changes to a configuration as a caller gives them (e.g. a Python dict): a table of
/// entries, a value (NaN and infinities kept for the physical checks), or unset (Python None:
/// the entry is removed, so an optional entry reads as absent).
#[derive(Debug, Clone, PartialEq)]
pub enum Change {
    /// Remove the entry.
    Unset,
    /// Replace the entry.
    Value(toml::Value),
    /// Change the entries of a table, in order.
    Table(Vec<(String, Change)>),
}

impl Change {
    /// The change as a plain value (unset entries of a table dropped), or None when unset.
    fn into_value(self) -> Option<toml::Value> {
        match self {
            Change::Unset => None,
            Change::Value(v) => Some(v),
            Change::Table(entries) => Some(toml::Value::Table(
                entries
                    .into_iter()
                    .filter_map(|(k, c)| c.into_value().map(|v| (k, v)))
                    .collect(),
            )),
        }
    }
}

impl std::fmt::Display for Change {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.clone().into_value() {
            None => write!(f, "None"),
            Some(v) => write!(f, "{v}"),
        }
    }
}

impl<'de> Deserialize<'de> for Change {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = Change;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "a configuration entry (a number, flag, string, list, dict or None)")
            }
            fn visit_unit<E>(self) -> std::result::Result<Change, E> {
                Ok(Change::Unset)
            }
            fn visit_none<E>(self) -> std::result::Result<Change, E> {
                Ok(Change::Unset)
            }
            fn visit_some<D: serde::Deserializer<'de>>(self, d: D) -> std::result::Result<Change, D::Error> {
                Change::deserialize(d)
            }
            fn visit_bool<E>(self, v: bool) -> std::result::Result<Change, E> {
                Ok(Change::Value(toml::Value::Boolean(v)))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<Change, E> {
                Ok(Change::Value(toml::Value::Integer(v)))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Change, E> {
                i64::try_from(v)
                    .map(|v| Change::Value(toml::Value::Integer(v)))
                    .map_err(|_| E::custom(format!("integer {v} out of range")))
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<Change, E> {
                Ok(Change::Value(toml::Value::Float(v)))
            }
            fn visit_str<E>(self, v: &str) -> std::result::Result<Change, E> {
                Ok(Change::Value(toml::Value::String(v.to_string())))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut a: A) -> std::result::Result<Change, A::Error> {
                let mut items = Vec::new();
                while let Some(c) = a.next_element::<Change>()? {
                    items.push(
                        c.into_value()
                            .ok_or_else(|| serde::de::Error::custom("None inside a list"))?,
                    );
                }
                Ok(Change::Value(toml::Value::Array(items)))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut a: A) -> std::result::Result<Change, A::Error> {
                let mut entries = Vec::new();
                while let Some((k, c)) = a.next_entry::<String, Change>()? {
                    entries.push((k, c));
                }
                Ok(Change::Table(entries))
            }
        }
        d.deserialize_any(Visit)
    }
}

/// `base` with `changes` put in (in `base`'s serde shape): a table merges into a table entry by
/// entry, a value replaces the entry, unset removes it; a flag (bool) takes only a bool. The
/// result is read back through serde, so a key or value the type does not take is an
/// [`Error::Config`] naming its dotted path (`model.motor.resistance`). Physical checks are not
/// made here (building a simulation makes them).
pub fn overlay<T: Serialize + serde::de::DeserializeOwned>(base: &T, changes: Change) -> Result<T> {
    let config = |path: &str, reason: String| Error::Config {
        path: path.to_string(),
        reason,
    };
    let mut merged = toml::Value::try_from(base).map_err(|e| config("", e.to_string()))?;
    let Change::Table(entries) = changes else {
        return Err(config(".", format!("expected a map of entries, got {changes}")));
    };
    put(&mut merged, entries, "")?;
    serde_path_to_error::deserialize(merged).map_err(|e| config(&e.path().to_string(), e.inner().to_string()))
}

/// Writes `entries` into the table `into`, recursing where both hold a table; `path` names `into`.
fn put(into: &mut toml::Value, entries: Vec<(String, Change)>, path: &str) -> Result<()> {
    let toml::Value::Table(table) = into else {
        return Ok(());
    };
    for (key, change) in entries {
        let here = if path.is_empty() {
            key.clone()
        } else {
            format!("{path}.{key}")
        };
        match (table.get_mut(&key), change) {
            (Some(old @ toml::Value::Table(_)), Change::Table(inner)) => put(old, inner, &here)?,
            (Some(toml::Value::Boolean(_)), c) if !matches!(c, Change::Value(toml::Value::Boolean(_))) => {
                return Err(Error::Config {
                    path: here,
                    reason: format!("expected True or False, got {c}"),
                })
            }
            (_, c) => match c.into_value() {
                Some(v) => {
                    table.insert(key, v);
                }
                None => {
                    table.remove(&key);
                }
            },
        }
    }
    Ok(())
}

#[cfg(test)]
mod overlay_tests {
    use super::*;

    fn change(text: &str) -> Change {
        Change::deserialize(text.parse::<toml::Table>().unwrap()).unwrap()
    }

    /// `leaf` at the dotted `path` of nested tables.
    fn nested(path: &[&str], leaf: Change) -> Change {
        path.iter()
            .rev()
            .fold(leaf, |inner, key| Change::Table(vec![(key.to_string(), inner)]))
    }

    fn base() -> AxisConfig {
        AxisConfig::new(MotorModel::maxon_re25_gp26())
    }

    #[test]
    fn overlay_changes_only_the_named_entries() {
        let b = base();
        let r = b.model.motor.resistance;
        let c: AxisConfig = overlay(&b, change(&format!("model.motor.resistance = {}", 2.0 * r))).unwrap();
        assert_eq!(c.model.motor.resistance, 2.0 * r);
        assert_eq!(c.model.motor.inductance, b.model.motor.inductance);
        assert_eq!(c.rates, b.rates);
        let same: AxisConfig = overlay(&b, Change::Table(Vec::new())).unwrap();
        assert_eq!(toml::Value::try_from(same).unwrap(), toml::Value::try_from(b).unwrap());
        // NaN passes through to the physical checks
        let nan = nested(
            &["model", "motor", "inductance"],
            Change::Value(toml::Value::Float(f64::NAN)),
        );
        assert!(overlay::<AxisConfig>(&b, nan).unwrap().model.motor.inductance.is_nan());
    }

    #[test]
    fn overlay_names_the_path_of_a_bad_entry() {
        let b = base();
        let e = overlay::<AxisConfig>(&b, change("model.motor.no_such = 1.0")).unwrap_err();
        assert!(e.to_string().contains("model.motor"), "{e}");
        let e = overlay::<AxisConfig>(&b, change("model.gearbox.ratio = \"x\"")).unwrap_err();
        assert!(e.to_string().starts_with("model.gearbox.ratio"), "{e}");
        assert!(overlay::<AxisConfig>(&b, Change::Value(toml::Value::Integer(1))).is_err());
        // a flag takes a bool only, and unset is not a bool
        let e = overlay::<AxisConfig>(&b, change("anti_windup = 1")).unwrap_err();
        assert_eq!(e.to_string(), "anti_windup: expected True or False, got 1");
        let unset = Change::Table(vec![("anti_windup".into(), Change::Unset)]);
        assert!(overlay::<AxisConfig>(&b, unset).is_err());
        let c: AxisConfig = overlay(&b, change(&format!("anti_windup = {}", !b.anti_windup))).unwrap();
        assert_eq!(c.anti_windup, !b.anti_windup);
        // a required number unset is missing, named by its path
        let unset = nested(&["model", "motor", "resistance"], Change::Unset);
        let e = overlay::<AxisConfig>(&b, unset).unwrap_err();
        assert!(e.to_string().contains("resistance"), "{e}");
    }
}
