//! The rally's execution hook ([`ttkin::ball::rally::Executor`]): every stroke run through a fresh
//! coupled drive simulation of the robot, with its inverse-dynamics torques as feed-forward (as
//! `ttmanip.simulate` does), so that the racket meets the ball where the driven joints put it.

use super::{CoupledOptions, CoupledSim};
use crate::error::Result;
use ttkin::ball::rally::{Executed, Executor};
use ttkin::chain::Chain;

/// Executes rally strokes on the coupled drive simulation of a chain.
#[derive(Debug, Clone)]
pub struct DriveExecutor {
    chain: Chain,
    options: CoupledOptions,
    setpoint_period: f64,
}

/// Period (s) of the setpoints handed to the drives by [`DriveExecutor::with_defaults`].
pub const SETPOINT_PERIOD: f64 = 1.0 / super::SETPOINT_HZ;

impl DriveExecutor {
    /// For `chain` with the default simulation options and setpoints every [`SETPOINT_PERIOD`].
    pub fn with_defaults(chain: &Chain) -> Result<Self> {
        Self::new(chain, CoupledOptions::default(), SETPOINT_PERIOD)
    }

    /// For `chain` (with drive sections on every joint) with `options` and setpoints handed to
    /// the drives every `setpoint_period` s. Checks that a simulation of the chain can be built.
    pub fn new(chain: &Chain, options: CoupledOptions, setpoint_period: f64) -> Result<Self> {
        crate::error::positive("setpoint period (s)", setpoint_period)?;
        CoupledSim::from_chain(chain, &vec![0.0; chain.dof()], options)?;
        Ok(DriveExecutor {
            chain: chain.clone(),
            options,
            setpoint_period,
        })
    }
}

impl Executor for DriveExecutor {
    fn execute(&self, times: &[f64], q: &[f64], qd: &[f64], qdd: &[f64]) -> Option<Executed> {
        let n = self.chain.dof();
        let mut sim = CoupledSim::from_chain(&self.chain, q.get(..n)?, self.options).ok()?;
        let mut tau = vec![0.0; q.len()];
        sim.dynamics()
            .inverse_dynamics_batch(q, qd, qdd, &self.options.gravity_on(&self.chain), None, &mut tau)
            .ok()?;
        let tr = sim.run(times, q, qd, qdd, Some(&tau), self.setpoint_period).ok()?;
        if tr.faults.iter().any(|f| !f.is_empty()) {
            return None;
        }
        Some(Executed {
            dof: n,
            t: tr.t,
            q: tr.q,
            qd: tr.qd,
        })
    }
}
