//! The journal of a [`CoupledSim`]: the last reset and every call that advanced or commanded it
//! since, in order. The simulation is deterministic, so replaying the journal on a fresh
//! simulation of the same chain and options rebuilds it exactly (the Python `DriveSim`'s pickle
//! state, issue 31).

use ttkin::Chain;

use super::{CoupledOptions, CoupledSim};
use crate::error::Result;

/// The calls that changed a [`CoupledSim`] since it was built or reset.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Journal {
    /// `reset(q0, qd0)`'s arguments (m, rad; m/s, rad/s); None: still at rest at q = 0.
    reset: Option<(Vec<f64>, Option<Vec<f64>>)>,
    /// The calls since, in order.
    calls: Vec<Call>,
}

/// One call that advanced or commanded the simulation (joint space, SI units).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
enum Call {
    /// `set_setpoint(q, qd, qdd, tau_ff)`.
    Setpoint(Vec<f64>, Vec<f64>, Vec<f64>, Option<Vec<f64>>),
    /// `tick_n(n)`; consecutive ticks merge.
    Tick(u64),
    /// `run(t, q, qd, qdd, tau_ff)` with the setpoint period.
    Run(Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Option<Vec<f64>>),
    /// A run that its stop ended, with how many times it had polled the stop (the last poll
    /// stopped it): replayed to the same tick.
    RunStopped(Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Option<Vec<f64>>, u64),
}

/// The arguments of a whole-trajectory run: times (K,) (s) and q, qd, qdd, tau_ff (K × n,
/// row-major, SI), as [`CoupledSim::run`] takes them.
pub type RunArgs = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Option<Vec<f64>>);

impl Journal {
    /// A journal that starts from `reset(q0, qd0)` (rest when `qd0` is None).
    pub fn from_reset(q0: Vec<f64>, qd0: Option<Vec<f64>>) -> Journal {
        Journal {
            reset: Some((q0, qd0)),
            calls: Vec::new(),
        }
    }

    /// A fresh simulation of `chain` with `options` at the journal's start: at rest at q = 0, or
    /// reset to its (q0, qd0).
    pub fn start(&self, chain: &Chain, options: CoupledOptions) -> Result<CoupledSim> {
        match &self.reset {
            None => CoupledSim::from_chain(chain, &vec![0.0; chain.dof()], options),
            Some((q0, qd0)) => {
                let mut sim = CoupledSim::from_chain(chain, q0, options)?;
                sim.reset(q0, qd0.as_deref())?;
                Ok(sim)
            }
        }
    }

    /// The simulation the journal describes: [`Journal::start`], then every call replayed (runs
    /// with `setpoint_period`, s). A call that failed was journaled too (it may have changed the
    /// state before failing): its replay fails alike, at the same point, and goes on.
    pub fn replay(&self, chain: &Chain, options: CoupledOptions, setpoint_period: f64) -> Result<CoupledSim> {
        self.replay_until(chain, options, setpoint_period, &|| false)
    }

    /// [`Journal::replay`] that `stop` ends early (polled before each call and within ticks and
    /// runs; a caller's cancellation, e.g. Ctrl-C): the simulation is then left part-way.
    pub fn replay_until(
        &self,
        chain: &Chain,
        options: CoupledOptions,
        setpoint_period: f64,
        stop: ttkin::budget::Stop<'_>,
    ) -> Result<CoupledSim> {
        let mut sim = self.start(chain, options)?;
        for call in &self.calls {
            if stop() {
                break;
            }
            match call {
                Call::Setpoint(q, qd, qdd, tau) => {
                    let _ = sim.set_setpoint(q, qd, qdd, tau.as_deref());
                }
                Call::Tick(n) => {
                    sim.tick_n_until(*n, stop);
                }
                Call::Run(t, q, qd, qdd, tau) => {
                    let _ = sim.run_until(t, q, qd, qdd, tau.as_deref(), setpoint_period, stop);
                }
                Call::RunStopped(t, q, qd, qdd, tau, polls) => {
                    let seen = std::sync::atomic::AtomicU64::new(0);
                    let until = || stop() || seen.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1 >= *polls;
                    let _ = sim.run_until(t, q, qd, qdd, tau.as_deref(), setpoint_period, &until);
                }
            }
        }
        Ok(sim)
    }

    /// Records `set_setpoint(q, qd, qdd, tau_ff)` (failed or not).
    pub fn setpoint(&mut self, q: Vec<f64>, qd: Vec<f64>, qdd: Vec<f64>, tau_ff: Option<Vec<f64>>) {
        self.calls.push(Call::Setpoint(q, qd, qdd, tau_ff));
    }

    /// Records `ran` ticks, merged with ticks recorded just before.
    pub fn ticks(&mut self, ran: u64) {
        match self.calls.last_mut() {
            Some(Call::Tick(m)) => *m += ran,
            _ => self.calls.push(Call::Tick(ran)),
        }
    }

    /// Records a run (failed or not); `stopped_after` is the number of stop polls after which
    /// its stop ended it, 0 when it ran to its end.
    pub fn run(&mut self, args: RunArgs, stopped_after: u64) {
        let (t, q, qd, qdd, tau) = args;
        self.calls.push(match stopped_after {
            0 => Call::Run(t, q, qd, qdd, tau),
            k => Call::RunStopped(t, q, qd, qdd, tau, k),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A journaled sequence of calls replays to the same state as the simulation it recorded,
    /// a stopped run to the same tick.
    #[test]
    fn replay_rebuilds_the_recorded_simulation() {
        let chain = ttkin::robots::arm4();
        let options = CoupledOptions::default();
        let period = 1e-3;
        let n = chain.dof();
        let mut journal = Journal::from_reset(vec![0.1; n], None);
        let mut sim = journal.start(&chain, options).unwrap();
        let (q, z) = (vec![0.15; n], vec![0.0; n]);
        sim.set_setpoint(&q, &z, &z, None).unwrap();
        journal.setpoint(q.clone(), z.clone(), z.clone(), None);
        sim.tick_n(30);
        journal.ticks(30);
        sim.tick_n(20);
        journal.ticks(20);
        assert_eq!(journal.calls.len(), 2, "consecutive ticks merge");
        let t = vec![0.0, 0.01, 0.02];
        let (qs, zs) = (vec![0.15; 3 * n], vec![0.0; 3 * n]);
        let seen = std::sync::atomic::AtomicU64::new(0);
        let stop = || seen.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1 >= 2;
        let _ = sim.run_until(&t, &qs, &zs, &zs, None, period, &stop);
        let polls = seen.load(std::sync::atomic::Ordering::Relaxed);
        journal.run((t, qs, zs.clone(), zs, None), polls);
        let copy = journal.replay(&chain, options, period).unwrap();
        assert_eq!(copy.q(), sim.q());
        assert_eq!(copy.qd(), sim.qd());
        assert_eq!(copy.time(), sim.time());
        assert_ne!(Journal::default().replay(&chain, options, period).unwrap().q(), sim.q());
    }
}
