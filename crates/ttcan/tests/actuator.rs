//! One source of truth per actuator (issue 10, scope 5): the robot file's drive section becomes
//! the axis configuration, armature counted once, fallbacks only for values the file leaves out.

use ttcan::actuator::axis_config;
use ttcan::coupled::axis_configs_from_chain;
use ttcan::{CoupledOptions, CoupledSim};
use ttkin::{Drive, Dynamics, DynamicsData};

#[test]
fn gantry6s_axes_take_every_datasheet_value_from_the_robot_file() {
    let chain = ttkin::robots::gantry6();
    let configs = axis_configs_from_chain(&chain, &[0.0; 6], &CoupledOptions::default()).unwrap();
    for (j, c) in chain.joints().iter().zip(&configs) {
        let d = j.drive().unwrap();
        let m = &c.model;
        assert_eq!(Some(m.motor.resistance), d.resistance, "{}", j.name());
        assert_eq!(Some(m.motor.inductance), d.inductance);
        assert_eq!(Some(m.motor.torque_constant), d.torque_constant);
        assert_eq!(m.motor.rotor_inertia, d.rotor_inertia);
        assert_eq!(m.gearbox.ratio, d.gear_ratio);
        assert_eq!(Some(m.encoder_counts_per_rev), d.encoder_counts);
        assert_eq!(Some(m.bus_voltage), d.bus_voltage);
        assert_eq!(Some(c.continuous_current), d.nominal_current);
        assert_eq!(Some(c.peak_current), d.peak_current);
        assert_eq!(Some(c.thermal.winding_time_constant), d.thermal_time_constant_winding);
        assert_eq!(Some(c.thermal.max_winding_temperature), d.max_winding_temperature);
        assert!(c.max_speed * d.gear_ratio <= d.max_motor_speed.unwrap() * (1.0 + 1e-12));
    }
}

#[test]
fn the_armature_is_counted_once() {
    let chain = ttkin::robots::gantry6();
    let q0 = [0.1, -0.2, 0.3, 0.6, 0.6, 0.0];
    let configs = axis_configs_from_chain(&chain, &q0, &CoupledOptions::default()).unwrap();
    let dynamics = Dynamics::new(&chain).unwrap();
    let mut data = DynamicsData::new(&dynamics);
    let m = dynamics.mass_matrix(&mut data, &q0).unwrap();
    for (k, (c, j)) in configs.iter().zip(chain.joints()).enumerate() {
        let armature = j.drive().unwrap().armature();
        assert!(armature > 0.0);
        // the axis' model: link-only load plus its own rotor, G²·(J_rotor + J_load/G²) = M_kk
        let g = c.model.gearbox.ratio;
        let reflected = g * g * c.model.motor_side_inertia();
        assert!(
            (reflected - m[(k, k)]).abs() < 1e-12 * m[(k, k)],
            "joint {k}: {reflected} vs M_kk {}",
            m[(k, k)]
        );
        assert!((c.model.load.inertia + armature - m[(k, k)]).abs() < 1e-12 * m[(k, k)]);
    }
    // the coupled plant is ttkin's M (armature on its diagonal): a joint pushed by a known torque
    // from rest, ideal current loop, accelerates by M⁻¹τ, not by a doubled armature
    let options = CoupledOptions {
        ideal_current: true,
        gravity: Some([0.0; 3]),
        refresh_ticks: 1,
        ..CoupledOptions::default()
    };
    let mut sim = CoupledSim::from_chain(&chain, &q0, options).unwrap();
    let zero = [0.0; 6];
    let mut tau = [0.0; 6];
    tau[4] = 0.5;
    let before = sim.qd().to_vec();
    sim.set_setpoint(&q0, &zero, &zero, Some(&tau)).unwrap();
    sim.tick();
    let qdd4 = (sim.qd()[4] - before[4]) / 5e-5;
    let torque = sim.torque().to_vec();
    let tau_v = nalgebra::DVector::from_column_slice(&torque);
    let expect = m.clone().cholesky().unwrap().solve(&tau_v)[4];
    assert!(
        (qdd4 - expect).abs() < 1e-6 * expect.abs().max(1.0),
        "{qdd4} vs {expect}"
    );
}

#[test]
fn a_drive_without_datasheet_values_gets_the_documented_fallbacks() {
    let chain = ttkin::robots::arm4();
    let configs = axis_configs_from_chain(&chain, &[0.0; 4], &CoupledOptions::default()).unwrap();
    let re25 = ttcan::DcMotor::maxon_re25();
    for (j, c) in chain.joints().iter().zip(&configs) {
        let d = j.drive().unwrap();
        assert!(d.resistance.is_none() && d.nominal_current.is_none());
        let s = d.torque_constant.unwrap() / re25.torque_constant;
        assert!((c.model.motor.resistance - re25.resistance * s).abs() < 1e-12);
        assert_eq!(c.model.encoder_counts_per_rev, 4096);
        assert!((c.continuous_current - c.peak_current / 3.0).abs() < 1e-12);
        assert_eq!(c.thermal, ttcan::thermal::ThermalModel::maxon_re25());
        let e = j.limits().effort.unwrap();
        assert!((c.peak_current - e / (d.gear_ratio * d.torque_constant.unwrap())).abs() < 1e-9);
    }
}

#[test]
fn an_incomplete_thermal_set_is_rejected_with_the_missing_value_named() {
    let chain = ttkin::robots::gantry6();
    let mut drive: Drive = *chain.joints()[4].drive().unwrap();
    drive.thermal_time_constant_housing = None;
    let joint = chain.joints()[4].clone().with_drive(drive).unwrap();
    let e = axis_config(&joint, 0.01).unwrap_err().to_string();
    assert!(
        e.contains("theta5") && e.contains("thermal_time_constant_housing"),
        "{e}"
    );
}

#[test]
fn bad_drive_values_are_rejected_with_the_field_named() {
    let joint = ttkin::robots::gantry6().joints()[4].clone();
    let good = *joint.drive().unwrap();
    for (field, bad) in [
        (
            "inductance",
            Drive {
                inductance: Some(0.0),
                ..good
            },
        ),
        (
            "encoder_counts",
            Drive {
                encoder_counts: Some(0),
                ..good
            },
        ),
        (
            "gear_efficiency",
            Drive {
                gear_efficiency: Some(1.5),
                ..good
            },
        ),
        (
            "peak_current",
            Drive {
                peak_current: Some(1.0),
                ..good
            },
        ),
    ] {
        let e = joint.clone().with_drive(bad).unwrap_err().to_string();
        assert!(e.contains(field), "{field}: {e}");
    }
}

#[test]
fn the_robot_file_of_gantry6_holds_the_built_in_drives() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/gantry6.toml");
    let file = ttkin::description::load(path).unwrap();
    let builtin = ttkin::robots::gantry6();
    for (a, b) in file.joints().iter().zip(builtin.joints()) {
        assert_eq!(a.drive(), b.drive(), "{}", a.name());
    }
}
