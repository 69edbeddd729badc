//! Drive sizing: does each joint's motor carry a planned motion? From the inverse dynamics of the
//! motion (gravity and friction included) to each motor's current, its RMS over the motion against
//! the continuous rating, its peak against the peak rating, and the joint's largest speed against
//! the axis' speed limit.

use ttkin::{Chain, Dynamics, DynamicsData};

use crate::axis::AxisConfig;
use crate::error::{Error, Result};

/// What one joint's motor needs for a motion, against its ratings.
#[derive(Debug, Clone, PartialEq)]
pub struct JointSizing {
    /// Joint name.
    pub joint: String,
    /// RMS motor current over the motion, A.
    pub rms_current: f64,
    /// Largest |motor current|, A.
    pub peak_current: f64,
    /// Continuous current rating, A.
    pub continuous_rating: f64,
    /// Peak current rating, A.
    pub peak_rating: f64,
    /// Largest |joint speed|, rad/s or m/s.
    pub peak_speed: f64,
    /// The axis' speed limit, rad/s or m/s.
    pub speed_limit: f64,
}

impl JointSizing {
    /// True when RMS, peak current and speed are all within the ratings.
    pub fn passes(&self) -> bool {
        self.rms_current <= self.continuous_rating
            && self.peak_current <= self.peak_rating
            && self.peak_speed <= self.speed_limit
    }
}

/// Sizes the drives `configs` (one per joint of `chain`) for the motion sampled uniformly at K
/// instants, `q`, `qd`, `qdd` K × n row-major, under `gravity` (m/s², base frame). The motor
/// current is the joint torque (rigid bodies, armature, friction) through each axis' gear ratio
/// and torque constant and the robot file's gear efficiency (1 when absent), a margin on top of
/// the friction.
pub fn size_drives(
    chain: &Chain,
    configs: &[AxisConfig],
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    gravity: &[f64; 3],
) -> Result<Vec<JointSizing>> {
    let dynamics = Dynamics::new(chain).map_err(|e| Error::Model(e.to_string()))?;
    let n = dynamics.dof();
    if configs.len() != n {
        return Err(Error::Stepper(format!(
            "{} axis configurations for {n} joints",
            configs.len()
        )));
    }
    if q.is_empty() || !q.len().is_multiple_of(n) || qd.len() != q.len() || qdd.len() != q.len() {
        return Err(Error::InvalidParameter {
            what: "motion samples".into(),
            value: q.len() as f64,
            reason: format!("q, qd, qdd must be K × {n} row-major with K ≥ 1"),
        });
    }
    let k = q.len() / n;
    let efficiency: Vec<f64> = chain
        .joints()
        .iter()
        .map(|j| j.drive().and_then(|d| d.gear_efficiency).unwrap_or(1.0))
        .collect();
    let mut data = DynamicsData::new(&dynamics);
    let (mut sum_sq, mut peak, mut speed) = (vec![0.0; n], vec![0.0f64; n], vec![0.0f64; n]);
    for s in 0..k {
        let r = s * n..(s + 1) * n;
        let tau = dynamics
            .inverse_dynamics(&mut data, &q[r.clone()], &qd[r.clone()], &qdd[r.clone()], gravity, None)
            .map_err(|e| Error::Model(e.to_string()))?;
        for (j, eta) in efficiency.iter().enumerate() {
            let m = &configs[j].model;
            let i = tau[j] / (m.gearbox.ratio * m.motor.torque_constant * eta);
            sum_sq[j] += i * i;
            peak[j] = peak[j].max(i.abs());
            speed[j] = speed[j].max(qd[s * n + j].abs());
        }
    }
    Ok(chain
        .joints()
        .iter()
        .enumerate()
        .map(|(j, joint)| JointSizing {
            joint: joint.name().to_string(),
            rms_current: (sum_sq[j] / k as f64).sqrt(),
            peak_current: peak[j],
            continuous_rating: configs[j].continuous_current,
            peak_rating: configs[j].peak_current,
            peak_speed: speed[j],
            speed_limit: configs[j].max_speed,
        })
        .collect())
}

/// Ok when every joint of `sizing` passes; otherwise an error naming the first joint that does
/// not and what it exceeds (RMS against continuous, peak against peak, speed against limit).
pub fn check(sizing: &[JointSizing]) -> Result<()> {
    for s in sizing {
        let why = if s.rms_current > s.continuous_rating {
            format!(
                "RMS current {:.3} A above the continuous rating {:.3} A",
                s.rms_current, s.continuous_rating
            )
        } else if s.peak_current > s.peak_rating {
            format!(
                "peak current {:.3} A above the peak rating {:.3} A",
                s.peak_current, s.peak_rating
            )
        } else if s.peak_speed > s.speed_limit {
            format!("speed {:.3} above the limit {:.3}", s.peak_speed, s.speed_limit)
        } else {
            continue;
        };
        return Err(Error::Model(format!("joint '{}' is undersized: {why}", s.joint)));
    }
    Ok(())
}
