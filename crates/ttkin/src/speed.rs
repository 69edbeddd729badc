//! What speed a joint can reach: the effective velocity limit of every joint, the smaller of the
//! robot file's velocity limit and the largest speed its drive delivers (issue 28, "one truth for
//! what a joint can do", for speed as [`crate::effort`] is for effort). One home for the formula:
//! the planners ([`crate::traj::limits::KinematicLimits::from_chain`]), `ttcan::actuator`'s speed
//! clamp and `ttmanip info` all read it.
//!
//! The drive's largest joint speed is
//!
//! ```text
//! ω_max = min(ω_motor,max, m·(U_bus·d_max − R·I_cont)/k_e) / G
//! ```
//!
//! the steady winding equation at full duty with the continuous current flowing (k_e = k_t in SI
//! units), with the speed margin m = [`DRIVE_SPEED_MARGIN`] so that the current loop keeps voltage
//! to accelerate, and the motor's own speed rating where the datasheet gives one. I_cont is the
//! nominal current, or a third of the peak current when only that is given (`ttcan::actuator`'s
//! fallback). Without k_t, R and U_bus only the motor's speed rating bounds the drive.

use crate::chain::Chain;
use crate::effort::governing;
use crate::joint::{Drive, Joint};

/// Largest PWM duty of a drive's power stage: the winding sees at most d_max·U_bus.
pub const DRIVE_MAX_DUTY: f64 = 0.95;

/// Share of the back-EMF headroom a drive's speed clamp uses (the rest accelerates).
pub const DRIVE_SPEED_MARGIN: f64 = 0.9;

/// The drive's largest joint speed (rad/s or m/s) from its datasheet values: gear ratio `g`
/// (motor rad per joint rad or m), torque constant `kt` (N·m/A, = k_e in V·s/rad), winding
/// resistance `r` (Ω), bus voltage `u` (V), continuous current `i_cont` (A) and the motor's speed
/// rating `max_motor_speed` (rad/s, motor side), the formula of the module doc; at least 0.
pub fn drive_speed_limit(g: f64, kt: f64, r: f64, u: f64, i_cont: f64, max_motor_speed: Option<f64>) -> f64 {
    let bus = DRIVE_SPEED_MARGIN * (u * DRIVE_MAX_DUTY - r * i_cont) / kt;
    (max_motor_speed.map_or(bus, |w| w.min(bus)) / g).max(0.0)
}

/// The drive's continuous current (A): the nominal current, else a third of the peak current.
pub fn continuous_current(drive: &Drive) -> Option<f64> {
    drive.nominal_current.or(drive.peak_current.map(|i| i / 3.0))
}

/// The largest joint speed `drive` delivers (rad/s or m/s), from the data it gives: the bus
/// formula when it has k_t, R, U_bus and a current, else the motor's speed rating over G, else
/// `None`.
pub fn drive_speed(drive: &Drive) -> Option<f64> {
    let g = drive.gear_ratio;
    match (
        drive.torque_constant,
        drive.resistance,
        drive.bus_voltage,
        continuous_current(drive),
    ) {
        (Some(kt), Some(r), Some(u), Some(i)) => Some(drive_speed_limit(g, kt, r, u, i, drive.max_motor_speed)),
        _ => drive.max_motor_speed.map(|w| w / g),
    }
}

/// Which limit governs a joint's speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpeedSource {
    /// Neither the robot file nor the drive limits the speed.
    None,
    /// The robot file's velocity limit.
    RobotFile,
    /// The drive's largest speed ([`drive_speed`]).
    Drive,
}

impl SpeedSource {
    /// Lower-case name: "none", "robot file", "drive".
    pub fn name(&self) -> &'static str {
        match self {
            SpeedSource::None => "none",
            SpeedSource::RobotFile => "robot file",
            SpeedSource::Drive => "drive",
        }
    }
}

/// One joint's speed limits (rad/s or m/s); `None` where the data is missing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSpeed {
    /// The robot file's velocity limit.
    pub file: Option<f64>,
    /// The drive's largest speed ([`drive_speed`]).
    pub drive: Option<f64>,
}

impl JointSpeed {
    /// The speed limits of `joint` (its file limit and its drive's).
    pub fn of(joint: &Joint) -> Self {
        JointSpeed {
            file: joint.limits().velocity.map(f64::abs),
            drive: joint.drive().and_then(drive_speed),
        }
    }

    /// The effective limit (rad/s or m/s; +∞ when none) and which governs (the file's on a tie).
    pub fn with_source(&self) -> (f64, SpeedSource) {
        governing(
            [(self.file, SpeedSource::RobotFile), (self.drive, SpeedSource::Drive)],
            SpeedSource::None,
        )
    }

    /// The effective limit (rad/s or m/s; +∞ when none).
    pub fn effective(&self) -> f64 {
        self.with_source().0
    }
}

/// Every joint's speed limits of `chain`, base to tool.
pub fn joint_speeds(chain: &Chain) -> Vec<JointSpeed> {
    chain.joints().iter().map(JointSpeed::of).collect()
}

/// Every joint's effective velocity limit (rad/s or m/s; +∞ where none): what the planners use.
pub fn effective_velocity_limits(chain: &Chain) -> Vec<f64> {
    joint_speeds(chain).iter().map(JointSpeed::effective).collect()
}

/// Every joint's drive speed (rad/s or m/s; +∞ where the drive data lacks it).
pub fn drive_velocity_limits(chain: &Chain) -> Vec<f64> {
    joint_speeds(chain)
        .iter()
        .map(|s| s.drive.unwrap_or(f64::INFINITY))
        .collect()
}

/// Which limit governs each joint's speed ([`SpeedSource::name`]).
pub fn velocity_limit_sources(chain: &Chain) -> Vec<&'static str> {
    joint_speeds(chain).iter().map(|s| s.with_source().1.name()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gantry6_theta6_is_limited_by_its_drive_below_the_file() {
        let chain = crate::robots::gantry6();
        let v = effective_velocity_limits(&chain);
        // θ6: RE 25 on 24 V behind 30:1, R 2.32 Ω, I_nom 1.2 A.
        let d = crate::robots::drives::gantry6()[5];
        let (kt, r) = (d.torque_constant.unwrap(), d.resistance.unwrap());
        let expect = 0.9 * (24.0 * 0.95 - r * d.nominal_current.unwrap()) / kt / 30.0;
        assert!((v[5] - expect).abs() < 1e-12, "{} vs {expect}", v[5]);
        assert!(v[5] < 20.0 && v[5] > 13.0, "θ6 drive speed {}", v[5]);
        assert_eq!(velocity_limit_sources(&chain)[5], "drive");
        for (j, joint) in chain.joints().iter().enumerate() {
            let file = joint.limits().velocity.unwrap();
            assert!(v[j] <= file + 1e-12, "joint {j}");
            assert!(v[j] <= drive_velocity_limits(&chain)[j] + 1e-12, "joint {j}");
        }
    }

    #[test]
    fn a_joint_without_drive_keeps_its_file_limit_and_a_rating_alone_bounds_it() {
        let chain = crate::robots::arm4();
        for (j, joint) in chain.joints().iter().enumerate() {
            if joint.drive().is_none() {
                let file = joint.limits().velocity.unwrap_or(f64::INFINITY);
                assert_eq!(effective_velocity_limits(&chain)[j], file);
            }
        }
        let mut d = crate::robots::drives::gantry6()[5];
        d.torque_constant = None;
        d.max_motor_speed = Some(300.0);
        assert_eq!(drive_speed(&d), Some(10.0));
        d.max_motor_speed = None;
        assert_eq!(drive_speed(&d), None);
    }
}
