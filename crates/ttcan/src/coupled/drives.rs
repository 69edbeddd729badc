//! Axis configurations for every joint of a robot, from its drive sections
//! ([`crate::actuator`]), with the coupled simulation's options.

use ttkin::{Chain, Dynamics, DynamicsData};

use super::{model_error, CoupledOptions};
use crate::axis::AxisConfig;
use crate::error::Result;

/// One [`axis_config`](crate::actuator::axis_config) per joint of `chain`, each joint's link-only inertia M_kk − G²J at `q0` as
/// its load, with the setpoint period and noise scale of `options`.
pub fn axis_configs_from_chain(chain: &Chain, q0: &[f64], options: &CoupledOptions) -> Result<Vec<AxisConfig>> {
    let dynamics = Dynamics::new(chain).map_err(model_error)?;
    let mut data = DynamicsData::new(&dynamics);
    let m = dynamics.mass_matrix(&mut data, q0).map_err(model_error)?;
    crate::error::non_negative("noise scale", options.noise_scale)?;
    let mut configs = Vec::with_capacity(dynamics.dof());
    for (k, j) in chain.joints().iter().enumerate() {
        let mut c = crate::actuator::axis_config(j, m[(k, k)] - dynamics.armature()[k])?;
        c.setpoint_period = options.setpoint_period;
        c.model.current_noise *= options.noise_scale;
        configs.push(c);
    }
    Ok(configs)
}

/// One joint's actuator as [`axis_configs_from_chain`] builds it (at q = 0, default options):
/// the robot file's drive section as given, and the axis' ratings.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ActuatorSummary<'a> {
    /// Joint name.
    pub joint: &'a str,
    /// The joint's drive section (SI units, motor side), None without one.
    pub drive: Option<&'a ttkin::joint::Drive>,
    /// Continuous current, A.
    pub continuous_current: f64,
    /// Peak current, A.
    pub peak_current: f64,
    /// Largest speed at the joint, rad/s or m/s.
    pub max_speed: f64,
    /// Bus voltage, V.
    pub bus_voltage: f64,
    /// Encoder counts per motor revolution.
    pub encoder_counts: u32,
    /// Gear ratio (motor turns per joint turn).
    pub gear_ratio: f64,
}

/// Every joint's [`ActuatorSummary`] of `chain`, in joint order.
pub fn actuator_summaries(chain: &Chain) -> Result<Vec<ActuatorSummary<'_>>> {
    let configs = axis_configs_from_chain(chain, &vec![0.0; chain.dof()], &CoupledOptions::default())?;
    Ok(chain
        .joints()
        .iter()
        .zip(configs)
        .map(|(j, c)| ActuatorSummary {
            joint: j.name(),
            drive: j.drive(),
            continuous_current: c.continuous_current,
            peak_current: c.peak_current,
            max_speed: c.max_speed,
            bus_voltage: c.model.bus_voltage,
            encoder_counts: c.model.encoder_counts_per_rev,
            gear_ratio: c.model.gearbox.ratio,
        })
        .collect())
}

impl CoupledOptions {
    /// These options with the current-sense noise of the axes [`CoupledSim::from_chain`](super::CoupledSim::from_chain) builds
    /// set to `amps` (standard deviation, A; ≥ 0, checked when the axes are built): the scale
    /// `amps` / [`DEFAULT_CURRENT_NOISE`](crate::motor::DEFAULT_CURRENT_NOISE), the noise every
    /// drive section gets.
    pub fn with_current_noise(self, amps: f64) -> Self {
        CoupledOptions {
            noise_scale: amps / crate::motor::DEFAULT_CURRENT_NOISE,
            ..self
        }
    }
}

#[cfg(test)]
mod summary_tests {
    use super::*;

    /// One summary per joint, in order, with the ratings of the axis configuration.
    #[test]
    fn summaries_follow_the_axis_configurations() {
        let chain = ttkin::robots::gantry6();
        let s = actuator_summaries(&chain).unwrap();
        let c = axis_configs_from_chain(&chain, &vec![0.0; chain.dof()], &CoupledOptions::default()).unwrap();
        assert_eq!(s.len(), chain.dof());
        for ((s, c), j) in s.iter().zip(&c).zip(chain.joints()) {
            assert_eq!(s.joint, j.name());
            assert_eq!(s.drive, j.drive());
            assert_eq!((s.peak_current, s.gear_ratio), (c.peak_current, c.model.gearbox.ratio));
        }
    }
}
