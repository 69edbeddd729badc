//! What an axis is built from: the controller's model of its actuator, loop rates, tuning
//! targets, ratings, limits, monitors and the holding brake. Plain data, serde-described (the
//! same types read a controller's TOML file); the axis ([`crate::axis::Axis::new`]) checks it
//! once when it is built.

use serde::{Deserialize, Serialize};

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
