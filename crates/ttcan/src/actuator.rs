//! One joint's actuator from its robot file: the drive section ([`ttkin::Drive`], the actuator's
//! one description) becomes the axis configuration ([`AxisConfig`], its [`MotorModel`], ratings,
//! limits, thermal model) that tuning, simulation and sizing use.
//!
//! Every datasheet value the drive gives is used as given. Where the file leaves a value out (old
//! robot files give only gear, rotor inertia, friction and k_t) a documented fallback fills it:
//!
//! | absent | fallback |
//! | --- | --- |
//! | `torque_constant` | the RE 25's 43.9 mN·m/A |
//! | `resistance`, `inductance` | the RE 25's scaled by s = k_t / k_t,RE25 (between a rewound frame, ∝ s², and a larger frame of the same winding) |
//! | `peak_current` | the joint's effort limit through gear and k_t (3.6 A / s without one) |
//! | `nominal_current` | a third of the peak current |
//! | `bus_voltage` | the smallest of 24, 48 and 325 V whose 76 % covers the back-EMF at the joint's velocity limit (10 rad/s or m/s without one) |
//! | `encoder_counts` | 4096 |
//! | `max_motor_speed` | no motor limit: the bus alone limits the speed |
//! | all five thermal values | the RE 25 class thermal model ([`ThermalModel::maxon_re25`]); some but not all is an error naming the missing one |
//!
//! Always derived (not datasheet values): the over-current trip 5/3 of the peak current; the
//! largest output speed min(motor limit, 0.9·(V_bus d_max − R I_nom)/K_e)/G
//! ([`ttkin::speed::drive_speed_limit`], the planners' drive speed: one formula); overspeed at 1.2× it;
//! the following-error limit 10 mrad + 5 ms × speed; bus over/under-voltage at 125 % / 70 %.
//!
//! Armature: the motor model holds the drive's rotor inertia and the load is the caller's
//! link-only inertia, so G²·J_rotor is counted exactly once — in [`CoupledSim`](crate::CoupledSim)
//! the plant is ttkin's mass matrix, which holds the armature on its diagonal, and the axis only
//! uses the model for its tuning. The gear efficiency enters the controller model as 1: the rigid
//! body plant models the gear's losses as the drive's joint-side friction; [`crate::sizing`] uses
//! it as a margin on the current.

use ttkin::Joint;

use crate::axis::AxisConfig;
use crate::error::{Error, Result};
use crate::motor::{DcMotor, Gearbox, Load, MotorModel};
use crate::thermal::ThermalModel;

fn missing(joint: &str, field: &str, why: &str) -> Error {
    Error::Model(format!("drive of joint '{joint}': {field} missing ({why})"))
}

/// The thermal model of `drive`: its five datasheet values, the RE 25 class model when it gives
/// none, an error naming the first missing value when it gives some.
pub fn thermal_model(joint: &str, drive: &ttkin::Drive) -> Result<ThermalModel> {
    let values = drive.thermal_values();
    if values.iter().all(|(_, v)| v.is_none()) {
        return Ok(ThermalModel::maxon_re25());
    }
    if let Some((name, _)) = values.iter().find(|(_, v)| v.is_none()) {
        return Err(missing(joint, name, "give all five thermal values or none"));
    }
    let model = ThermalModel::from_datasheet(values.map(|(_, v)| v.unwrap_or(f64::NAN)));
    model
        .validate()
        .map_err(|e| Error::Model(format!("drive of joint '{joint}': {e}")))?;
    Ok(model)
}

/// Axis configuration of `joint` (which needs a drive) with `link_inertia` (kg·m² or kg, the
/// joint's link-only inertia, armature excluded) as its load; fallbacks as in the module doc.
/// Coupled joints: the tracking observer runs without acceleration input at 100 Hz (see
/// [`crate::tuning::TuningTargets::observer_acceleration_input`]).
pub fn axis_config(joint: &Joint, link_inertia: f64) -> Result<AxisConfig> {
    let name = joint.name();
    let drive = joint
        .drive()
        .ok_or_else(|| Error::Model(format!("joint '{name}' has no drive")))?;
    drive.validate(name).map_err(|e| Error::Model(e.to_string()))?;
    let g = drive.gear_ratio;
    let re25 = DcMotor::maxon_re25();
    let kt = drive.torque_constant.unwrap_or(re25.torque_constant);
    let s = kt / re25.torque_constant;
    let speed_limit = joint.limits().velocity.unwrap_or(10.0).abs();
    let max_duty = ttkin::speed::DRIVE_MAX_DUTY;
    let bus_voltage = drive.bus_voltage.unwrap_or_else(|| {
        let emf = kt * g * speed_limit;
        [24.0, 48.0, 325.0]
            .into_iter()
            .find(|v| emf <= 0.8 * max_duty * v)
            .unwrap_or(325.0)
    });
    let model = MotorModel {
        motor: DcMotor {
            resistance: drive.resistance.unwrap_or(re25.resistance * s),
            inductance: drive.inductance.unwrap_or(re25.inductance * s),
            torque_constant: kt,
            back_emf_constant: kt,
            rotor_inertia: drive.rotor_inertia.max(1e-9),
            viscous_friction: 0.0,
            coulomb_friction: 0.0,
        },
        gearbox: Gearbox {
            ratio: g,
            efficiency: 1.0,
            inertia: 0.0,
        },
        load: Load {
            inertia: link_inertia.max(0.0),
            viscous_friction: drive.viscous,
        },
        bus_voltage,
        max_duty,
        encoder_counts_per_rev: drive.encoder_counts.unwrap_or(4096),
        current_noise: crate::motor::DEFAULT_CURRENT_NOISE,
    };
    let mut c = AxisConfig::new(model);
    c.peak_current = drive
        .peak_current
        .unwrap_or_else(|| joint.limits().effort.map_or(3.6 / s, |e| e.abs() / (g * kt)));
    c.continuous_current = drive.nominal_current.unwrap_or(c.peak_current / 3.0);
    c.overcurrent_trip = c.peak_current * 5.0 / 3.0;
    c.thermal = thermal_model(name, drive)?;
    // ttkin's formula, the planners' velocity limit (`ttkin::speed`), on the filled-in values.
    c.max_speed = ttkin::speed::drive_speed_limit(
        g,
        kt,
        model.motor.resistance,
        bus_voltage,
        c.continuous_current,
        drive.max_motor_speed,
    );
    c.following_error_limit = 0.01;
    c.following_error_per_speed = 0.005;
    c.overspeed_limit = 1.2 * c.max_speed;
    c.bus_overvoltage = 1.25 * bus_voltage;
    c.bus_undervoltage = 0.7 * bus_voltage;
    c.tuning.observer_acceleration_input = false;
    c.tuning.observer_bandwidth_hz = 100.0;
    Ok(c)
}
