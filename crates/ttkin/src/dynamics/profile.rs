//! The torque profile of a planned motion: joint, motor-side and current, peaks and the
//! effort-limit check (the patent's step S105).

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

use super::model::Dynamics;
use super::Wrench;
use crate::effort::EffortLimits;
use crate::error::Result;

/// Torques along a planned motion: joint side (rigid body + armature + friction), motor side and
/// current, with the effort-limit check of the patent's step S105.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TorqueProfile {
    /// Number of joints n.
    pub dof: usize,
    /// Joint torques (N·m) or forces (N), N × n row-major.
    pub joint: Vec<f64>,
    /// Motor torques τ/G, N·m, N × n row-major (equal to `joint` for a joint without drive).
    pub motor: Vec<f64>,
    /// Motor currents τ_motor/k_t, A, N × n row-major; NaN for a joint without torque constant.
    pub current: Vec<f64>,
    /// Largest |joint torque| per joint over the profile (N·m or N).
    pub peak: Vec<f64>,
    /// Every (sample, joint) whose |joint torque| exceeds the joint's effective effort limit at
    /// the sample's speed ([`crate::effort`]).
    pub violations: Vec<EffortViolation>,
}

impl TorqueProfile {
    /// True when no sample exceeds any effort limit.
    pub fn within_limits(&self) -> bool {
        self.violations.is_empty()
    }
}

/// One sample at which a joint needs more than its effort limit.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EffortViolation {
    /// Index of the sample in the trajectory.
    pub sample: usize,
    /// Index of the joint.
    pub joint: usize,
    /// Required joint torque (N·m) or force (N).
    pub torque: f64,
    /// The joint's effective effort limit at the sample's speed (N·m or N).
    pub limit: f64,
}

impl Dynamics {
    /// Torque profile of a planned motion sampled at N instants: `q`, `qd`, `qdd` are N × n
    /// row-major. Joint torques include friction; motor torques are τ/G; currents τ_motor/k_t.
    /// Every |τ| above a joint's effective effort limit at the sample's speed is listed (not an
    /// error: the plan is infeasible). Only the samples are checked: for a bound over every
    /// instant of a trajectory see [`Dynamics::effort_peak`].
    pub fn torque_profile(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
    ) -> Result<TorqueProfile> {
        let n = self.dof();
        let mut joint = vec![0.0; q.len()];
        self.rnea_batch(q, qd, qdd, gravity, wrench, &mut joint)?;
        let count = joint.len() / n;
        let mut motor = joint.clone();
        let mut current = vec![f64::NAN; joint.len()];
        let mut peak = vec![0.0f64; n];
        let mut violations = Vec::new();
        let limits = EffortLimits::of(&self.chain);
        for k in 0..count {
            for i in 0..n {
                let idx = k * n + i;
                let drive = self.drives[i];
                if let Some(d) = drive {
                    joint[idx] += d.friction(qd[idx]);
                    motor[idx] = joint[idx] / d.gear_ratio;
                    if let Some(kt) = d.torque_constant {
                        current[idx] = motor[idx] / kt;
                    }
                } else {
                    motor[idx] = joint[idx];
                }
                let t = joint[idx];
                peak[i] = peak[i].max(t.abs());
                let limit = limits.at(i, qd[idx]);
                if limit.is_finite() && t.abs() > limit {
                    violations.push(EffortViolation {
                        sample: k,
                        joint: i,
                        torque: t,
                        limit,
                    });
                }
            }
        }
        Ok(TorqueProfile {
            dof: n,
            joint,
            motor,
            current,
            peak,
            violations,
        })
    }
}
