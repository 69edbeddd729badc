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
