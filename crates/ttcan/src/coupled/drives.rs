//! Axis configurations for the joints of a robot from its drive section (until robot files carry
//! full motor data).

use ttkin::{Chain, Dynamics, DynamicsData};

use super::{model_error, CoupledOptions};
use crate::axis::AxisConfig;
use crate::error::{Error, Result};
use crate::motor::{DcMotor, Gearbox, Load, MotorModel};

/// Axis configuration for a joint from its drive section, until robot files carry full motor
/// data: a motor of the RE 25's class scaled to the drive's torque constant s = k_t/k_t,RE25 (R,
/// L ∝ s, between a rewound frame, ∝ s², and a larger frame of the same winding), peak current
/// the joint's effort limit through gear and k_t (3.6 A/s without one), continuous a third of the
/// peak, over-current trip 5/3 of it, the drive's gear ratio (efficiency 1:
/// the losses are the drive's friction), rotor inertia and `link_inertia` as the load, a 4096-count
/// encoder, the tracking observer without acceleration input at 100 Hz (the joints are coupled),
/// and the smallest of the 24 V, 48 V and 325 V (rectified 230 V AC) buses whose 80 %
/// covers the back-EMF at `speed_limit` (joint rad/s or m/s).
pub fn axis_config_from_drive(
    drive: &ttkin::Drive,
    link_inertia: f64,
    speed_limit: f64,
    effort_limit: Option<f64>,
) -> AxisConfig {
    let re25 = DcMotor::maxon_re25();
    let kt = drive.torque_constant.unwrap_or(re25.torque_constant);
    let s = kt / re25.torque_constant;
    let emf = kt * drive.gear_ratio * speed_limit.abs();
    let bus_voltage = [24.0, 48.0, 325.0]
        .into_iter()
        .find(|v| emf <= 0.8 * 0.95 * v)
        .unwrap_or(325.0);
    let model = MotorModel {
        motor: DcMotor {
            resistance: re25.resistance * s,
            inductance: re25.inductance * s,
            torque_constant: kt,
            back_emf_constant: kt,
            rotor_inertia: drive.rotor_inertia.max(1e-9),
            viscous_friction: 0.0,
            coulomb_friction: 0.0,
        },
        gearbox: Gearbox {
            ratio: drive.gear_ratio,
            efficiency: 1.0,
            inertia: 0.0,
        },
        load: Load {
            inertia: link_inertia.max(0.0),
            viscous_friction: drive.viscous,
        },
        bus_voltage,
        max_duty: 0.95,
        encoder_counts_per_rev: 4096,
        current_noise: 0.005,
    };
    let mut c = AxisConfig::new(model);
    c.peak_current = effort_limit.map_or(3.6 / s, |e| e.abs() / (drive.gear_ratio * kt));
    c.continuous_current = c.peak_current / 3.0;
    c.overcurrent_trip = c.peak_current * 5.0 / 3.0;
    c.max_speed = 0.9 * (model.max_voltage() - model.motor.resistance * c.continuous_current) / (kt * drive.gear_ratio);
    c.following_error_limit = 0.01;
    c.following_error_per_speed = 0.005;
    c.overspeed_limit = 1.2 * c.max_speed;
    c.bus_overvoltage = 1.25 * bus_voltage;
    c.bus_undervoltage = 0.7 * bus_voltage;
    // Coupled joints: the observer must not trust the axis' own acceleration model (see
    // `TuningTargets::observer_acceleration_input`): PLL alone, 100 Hz.
    c.tuning.observer_acceleration_input = false;
    c.tuning.observer_bandwidth_hz = 100.0;
    c
}

/// One [`axis_config_from_drive`] per joint of `chain`, each joint's link inertia at `q0` as its
/// load, with the setpoint period and noise scale of `options`.
pub fn axis_configs_from_chain(chain: &Chain, q0: &[f64], options: &CoupledOptions) -> Result<Vec<AxisConfig>> {
    let dynamics = Dynamics::new(chain).map_err(model_error)?;
    let mut data = DynamicsData::new(&dynamics);
    let m = dynamics.mass_matrix(&mut data, q0).map_err(model_error)?;
    crate::error::non_negative("noise scale", options.noise_scale)?;
    let mut configs = Vec::with_capacity(dynamics.dof());
    for (k, j) in chain.joints().iter().enumerate() {
        let drive = j
            .drive()
            .ok_or_else(|| Error::Model(format!("joint '{}' has no drive", j.name())))?;
        let v = j.limits().velocity.unwrap_or(10.0);
        let mut c = axis_config_from_drive(drive, m[(k, k)] - dynamics.armature()[k], v, j.limits().effort);
        c.setpoint_period = options.setpoint_period;
        c.model.current_noise *= options.noise_scale;
        configs.push(c);
    }
    Ok(configs)
}
