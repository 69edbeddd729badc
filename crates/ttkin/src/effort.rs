//! What a joint can deliver: the effective effort limit of every joint, the smaller of the robot
//! file's effort limit and what its drive can deliver at peak current, G·k_t·I_peak·η, reduced
//! at speed by the bus voltage, G·k_t·η·(U_bus − k_e·G·|q̇|)/R (k_e = k_t in SI units, a DC
//! motor's back-EMF constant). One home for the limit the planners, the torque profile and
//! `ttmanip info` use.
//!
//! The voltage limit is the steady-state winding equation U = R·I + k_e·ω_motor at the bus voltage,
//! taken for the worse direction (driving, τ·q̇ > 0) at both signs of the torque: braking has
//! more headroom (U + k_e·|ω|), which the limit does not count, so it is conservative. The
//! winding's inductance and the power stage's largest duty are left out (both belong to the
//! controller, `ttcan::actuator`).
//!
//! **The gear efficiency η is in the limit, as a physical loss** (issue 28's decision). A gearhead's
//! losses are mostly tooth and bearing friction under load, about proportional to the transmitted
//! torque: the catalogue's η (at the rated point) says the joint gets η·G·τ_motor when the motor
//! drives the load (maxon's sizing rule, and `ttcan::motor`, whose gearbox loses the factor η in
//! whichever direction the power flows). The joint-side friction of the drive data (Coulomb f_c and
//! viscous b, in the inverse dynamics the planners check) is the load-independent part, fitted at
//! no load: gantry6's θ3 has f_c = 0.3 N·m, while its gear loses (1 − η)·G·k_t·I_peak = 0.28 ·
//! 27.1 = 7.6 N·m at peak current. Leaving η out would treat the gear as lossless at full load
//! and let plans ask for 27.1 N·m that a real θ3 does not deliver. The coupled drive simulation
//! (`ttcan::coupled`) is the lossless case (its plant passes G·k_t·I to the joint, minus that
//! friction): against it a plan at its limit leaves the current loop's feedback 1/η − 1 of the
//! current (39 % on θ3/θ4, 33 % on θ5/θ6), and a plan at G·k_t·I_peak would leave it none. When the load drives the motor
//! (braking, τ·q̇ < 0) a real gear needs only η·|τ|/G of the motor, so it could brake with
//! G·k_t·I_peak/η; the limit does not count that (conservative: the lossless coupled plant brakes
//! with G·k_t·I_peak at most).

use crate::chain::Chain;
use crate::joint::Joint;

/// The smallest of the given limits and the source that sets it (the first on a tie), or
/// (+∞, `none`) when none is given: "limit + which governs", for efforts and speeds alike.
pub(crate) fn governing<S: Copy>(limits: impl IntoIterator<Item = (Option<f64>, S)>, none: S) -> (f64, S) {
    let mut best = (f64::INFINITY, none);
    for (v, s) in limits {
        if let Some(v) = v {
            if v < best.0 {
                best = (v, s);
            }
        }
    }
    best
}

/// Which limit governs a joint's effort.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EffortSource {
    /// Neither the robot file nor the drive limits the effort.
    None,
    /// The robot file's effort limit.
    RobotFile,
    /// The drive at peak current, G·k_t·I_peak·η.
    DrivePeak,
    /// The drive's bus voltage at this speed, G·k_t·η·(U_bus − k_e·G·|q̇|)/R.
    DriveVoltage,
}

impl EffortSource {
    /// Lower-case name: "none", "robot file", "drive peak current", "drive voltage".
    pub fn name(&self) -> &'static str {
        match self {
            EffortSource::None => "none",
            EffortSource::RobotFile => "robot file",
            EffortSource::DrivePeak => "drive peak current",
            EffortSource::DriveVoltage => "drive voltage",
        }
    }
}

/// One joint's effort limits (joint side, N·m or N); each `None` where the data to compute it is
/// missing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointEffort {
    /// The robot file's effort limit.
    pub file: Option<f64>,
    /// G·k_t·I_peak·η (η = 1 when the drive gives no gear efficiency).
    pub peak: Option<f64>,
    /// The voltage limit a − b·|q̇|: a = G·k_t·η·U_bus/R (N·m or N at standstill), b =
    /// G²·k_t·k_e·η/R (N·m·s/rad or N·s/m).
    pub voltage: Option<(f64, f64)>,
}

impl JointEffort {
    /// The limits of `joint`: its file limit and, when its drive has k_t and I_peak, the peak
    /// limit; with k_t, R and U_bus also the voltage limit.
    pub fn of(joint: &Joint) -> Self {
        let file = joint.limits().effort;
        let Some(d) = joint.drive() else {
            return JointEffort {
                file,
                peak: None,
                voltage: None,
            };
        };
        let eta = d.gear_efficiency.unwrap_or(1.0);
        let g = d.gear_ratio;
        let peak = d.torque_constant.zip(d.peak_current).map(|(kt, i)| g * kt * i * eta);
        let voltage = match (d.torque_constant, d.resistance, d.bus_voltage) {
            (Some(kt), Some(r), Some(u)) if r > 0.0 => Some((g * kt * eta * u / r, g * g * kt * kt * eta / r)),
            _ => None,
        };
        JointEffort { file, peak, voltage }
    }

    /// The effective limit (N·m or N) at joint speed `speed` (rad/s or m/s): the smallest of the
    /// three, at least 0; +∞ when none is given.
    pub fn at(&self, speed: f64) -> f64 {
        self.with_source(speed).0
    }

    /// The effective limit at `speed` and the limit that governs it (the file's on a tie).
    pub fn with_source(&self, speed: f64) -> (f64, EffortSource) {
        let voltage = self.voltage.map(|(a, b)| (a - b * speed.abs()).max(0.0));
        governing(
            [
                (self.file, EffortSource::RobotFile),
                (self.peak, EffortSource::DrivePeak),
                (voltage, EffortSource::DriveVoltage),
            ],
            EffortSource::None,
        )
    }
}

/// The effective effort limits of a chain's joints ([`JointEffort`] per joint).
#[derive(Debug, Clone, PartialEq)]
pub struct EffortLimits {
    /// One entry per joint, base to tool.
    pub joints: Vec<JointEffort>,
}

impl EffortLimits {
    /// The limits of every joint of `chain` (robot file and drive data).
    pub fn of(chain: &Chain) -> Self {
        EffortLimits {
            joints: chain.joints().iter().map(JointEffort::of).collect(),
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Joint `j`'s effective limit (N·m or N) at speed `speed` (rad/s or m/s); `j` < dof.
    pub fn at(&self, j: usize, speed: f64) -> f64 {
        self.joints[j].at(speed)
    }

    /// Every joint's effective limit at speeds `qd` (rad/s or m/s, one per joint).
    pub fn at_speeds(&self, qd: &[f64]) -> Vec<f64> {
        self.joints.iter().zip(qd).map(|(e, v)| e.at(*v)).collect()
    }

    /// Effective limits at the speeds of `qd`, row-major (sample, joint) with rows of dof
    /// speeds (rad/s or m/s): the limits in the same layout (a trailing partial row is ignored).
    pub fn at_rows(&self, qd: &[f64]) -> Vec<f64> {
        qd.chunks_exact(self.dof())
            .flat_map(|row| self.at_speeds(row))
            .collect()
    }

    /// Every joint's drive peak G·k_t·I_peak·η (N·m or N), +∞ where the drive data lacks it.
    pub fn drive_peaks(&self) -> Vec<f64> {
        self.joints.iter().map(|e| e.peak.unwrap_or(f64::INFINITY)).collect()
    }

    /// Which limit governs each joint at standstill ([`EffortSource::name`]).
    pub fn sources_at_rest(&self) -> Vec<&'static str> {
        self.joints.iter().map(|e| e.with_source(0.0).1.name()).collect()
    }

    /// Every joint's effective limit at standstill (the largest it gets).
    pub fn at_rest(&self) -> Vec<f64> {
        self.joints.iter().map(|e| e.at(0.0)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gantry6_limits_are_its_drives_where_they_are_smaller() {
        let chain = crate::robots::gantry6();
        let e = EffortLimits::of(&chain);
        let drives = crate::robots::drives::gantry6();
        for (j, d) in drives.iter().enumerate() {
            let peak = d.gear_ratio * d.torque_constant.unwrap() * d.peak_current.unwrap() * d.gear_efficiency.unwrap();
            let file = chain.joints()[j].limits().effort.unwrap();
            assert!((e.at(j, 0.0) - file.min(peak)).abs() < 1e-12, "joint {j}");
            assert!(e.at(j, 0.0) <= peak + 1e-12);
        }
        // θ3: 50 · 60.3e-3 · 9 · 0.72 = 19.54 N·m below the file's 30.
        assert!((e.at(2, 0.0) - 50.0 * 60.3e-3 * 9.0 * 0.72).abs() < 1e-12);
        assert_eq!(e.joints[2].with_source(0.0).1, EffortSource::DrivePeak);
        // θ6 (RE 25, 24 V, G 30): no torque left at its no-load speed U/(k_e·G).
        let no_load = 24.0 / (43.9e-3 * 30.0);
        assert_eq!(e.at(5, no_load * 1.0001), 0.0);
        assert_eq!(e.joints[5].with_source(0.9 * no_load).1, EffortSource::DriveVoltage);
        // The voltage limit is a − b|ω| with the documented a, b.
        let (a, b) = e.joints[5].voltage.unwrap();
        let (g, kt, r, eta) = (30.0, 43.9e-3, 2.32, 0.75);
        assert!((a - g * kt * eta * 24.0 / r).abs() < 1e-9 && (b - g * g * kt * kt * eta / r).abs() < 1e-12);
    }

    #[test]
    fn a_joint_without_drive_keeps_its_file_limit() {
        let chain = crate::robots::arm4();
        let e = EffortLimits::of(&chain);
        for (j, joint) in chain.joints().iter().enumerate() {
            if joint.drive().is_none() {
                assert_eq!(e.at(j, 5.0), joint.limits().effort.unwrap_or(f64::INFINITY));
            }
            assert!(e.at(j, 1.0) <= e.at(j, 0.0));
        }
    }
}
