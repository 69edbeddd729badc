//! The IK front end that Python, the controller binary and the planners share: method choice
//! (analytic nearest branch within limits where the chain has a closed form, numeric otherwise,
//! with fallback), one start per target (or one for all), seed `seed + i` for target i, the
//! success test, the time budget, one scratch space per thread, and a rayon batch whose every
//! element carries an [`IkStatus`]: one unreachable target never fails the batch.
//!
//! [`IkStatus::Unreachable`] is said only when it is proven: the analytic solver found no branch
//! within the limits, or the target lies beyond [`Chain::reach`]. A numeric solve that merely ran
//! out of restarts or time is [`IkStatus::NotConverged`].

use std::cell::RefCell;
use std::fmt;
use std::str::FromStr;

use nalgebra::IsometryMatrix3;
use rayon::prelude::*;

use super::numeric::{check_batch, measure, residual_dim};
use super::{Analytic, IkResult, IkScratch, IkSolver, LimitFilter};
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::task::Task;

thread_local! {
    /// Buffers of the numeric solver, one per thread (the caller's and each rayon worker's),
    /// resized when the chain or task changes.
    static SCRATCH: RefCell<Option<IkScratch>> = const { RefCell::new(None) };
}

/// Which solver answers a target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IkMethod {
    /// The analytic nearest branch within limits for the pose task on a chain with a closed form
    /// (falling back to the numeric solver when none is within limits); numeric otherwise.
    #[default]
    Auto,
    /// Always the numeric solver.
    Numeric,
    /// Only the analytic solver (pose task; an error for a chain without closed form).
    Analytic,
}

impl FromStr for IkMethod {
    type Err = Error;

    /// Parses `"auto"`, `"numeric"` or `"analytic"`.
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "auto" => Ok(IkMethod::Auto),
            "numeric" => Ok(IkMethod::Numeric),
            "analytic" => Ok(IkMethod::Analytic),
            other => Err(Error::invalid(
                "method",
                format!("expected 'auto', 'numeric' or 'analytic', got '{other}'"),
            )),
        }
    }
}

/// Outcome of one target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IkStatus {
    /// Both errors within the tolerances.
    Solved,
    /// Proven out of reach (no analytic branch within limits, or beyond [`Chain::reach`]).
    Unreachable,
    /// Not solved within the iterations, restarts or time budget; perhaps reachable.
    NotConverged,
}

impl IkStatus {
    /// The status as Python and logs spell it: `"solved"`, `"unreachable"`, `"not_converged"`.
    pub fn as_str(self) -> &'static str {
        match self {
            IkStatus::Solved => "solved",
            IkStatus::Unreachable => "unreachable",
            IkStatus::NotConverged => "not_converged",
        }
    }
}

impl fmt::Display for IkStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One target's answer: the solver's result and what it means.
#[derive(Debug, Clone, PartialEq)]
pub struct IkOutcome {
    /// What happened.
    pub status: IkStatus,
    /// Best configuration (m, rad) and its errors; for an unreachable target with
    /// [`IkMethod::Analytic`], the start configuration and its errors.
    pub result: IkResult,
}

impl IkOutcome {
    /// A sentence on a target that was not solved, for an error raised on failure: target
    /// `index` of its batch, the status and the errors (m, rad) of the best configuration.
    pub fn failure_message(&self, index: usize) -> String {
        let what = match self.status {
            IkStatus::Unreachable => "failed, target unreachable,",
            _ => "did not converge",
        };
        let r = &self.result;
        format!(
            "IK {what} for target {index}: position error {:.3e} m, orientation error {:.3e} rad",
            r.position_error, r.orientation_error
        )
    }
}

/// The IK front end: solver settings, method, and the analytic solver found for the chain.
#[derive(Debug, Clone)]
pub struct IkBatchSolver {
    solver: IkSolver,
    method: IkMethod,
    analytic: Option<Analytic>,
}

impl IkBatchSolver {
    /// A front end for `chain` with the numeric `solver` settings and `method`; checks the
    /// settings, and that `method` fits the task and the chain.
    pub fn new(chain: &Chain, solver: IkSolver, method: IkMethod) -> Result<Self> {
        solver.validate()?;
        let analytic = match method {
            IkMethod::Numeric => None,
            IkMethod::Auto if solver.task != Task::Pose => None,
            IkMethod::Auto => Analytic::for_chain(chain),
            IkMethod::Analytic if solver.task != Task::Pose => {
                return Err(Error::invalid("method", "method='analytic' solves task='pose' only"));
            }
            IkMethod::Analytic => Some(analytic_for(chain)?),
        };
        Ok(IkBatchSolver {
            solver,
            method,
            analytic,
        })
    }

    /// The numeric solver settings.
    pub fn solver(&self) -> &IkSolver {
        &self.solver
    }

    /// Solves every target (base-frame tool poses, m) from `q0s[i]`, or from `q0s[0]` for all
    /// when one start is given (empty: [`Chain::mid_range`]); in parallel when there is more than
    /// one target. Errors only for bad input; each element carries its status.
    pub fn solve(&self, chain: &Chain, targets: &[IsometryMatrix3<f64>], q0s: &[Vec<f64>]) -> Result<Vec<IkOutcome>> {
        self.solve_until(chain, targets, q0s, &|| false)
    }

    /// [`Self::solve`] that ends early with [`crate::budget::stopped`]'s error when `stop()`
    /// turns true (polled before each target; one target is bounded by the solver's iterations,
    /// restarts and time budget).
    pub fn solve_until(
        &self,
        chain: &Chain,
        targets: &[IsometryMatrix3<f64>],
        q0s: &[Vec<f64>],
        stop: crate::budget::Stop<'_>,
    ) -> Result<Vec<IkOutcome>> {
        let mid;
        let q0s = if q0s.is_empty() {
            mid = vec![chain.mid_range()];
            &mid[..]
        } else {
            q0s
        };
        check_batch(chain, targets, q0s)?;
        let one = |i: usize, t: &IsometryMatrix3<f64>| {
            if stop() {
                return Err(crate::budget::stopped("T"));
            }
            let q0 = if q0s.len() == 1 { &q0s[0] } else { &q0s[i] };
            self.solve_one(chain, i, t, q0)
        };
        if targets.len() == 1 {
            return Ok(vec![one(0, &targets[0])?]);
        }
        targets.par_iter().enumerate().map(|(i, t)| one(i, t)).collect()
    }

    /// Target `i` (seed `seed + i`) from `q0`.
    fn solve_one(&self, chain: &Chain, i: usize, t: &IsometryMatrix3<f64>, q0: &[f64]) -> Result<IkOutcome> {
        let mut proven_unreachable = false;
        if let Some(ik) = &self.analytic {
            match ik.nearest(t, q0, LimitFilter::Enforce) {
                Ok(q) => return Ok(self.analytic_outcome(chain, t, q)),
                Err(Error::Unreachable(_)) if self.method == IkMethod::Analytic => {
                    let mut out = self.analytic_outcome(chain, t, q0.to_vec());
                    out.status = IkStatus::Unreachable;
                    out.result.success = false;
                    return Ok(out);
                }
                Err(e) if self.method == IkMethod::Analytic => return Err(e),
                // Auto: the numeric solver makes its best effort.
                Err(e) => proven_unreachable = matches!(e, Error::Unreachable(_)),
            }
        }
        let seeded = IkSolver {
            seed: self.solver.seed.wrapping_add(i as u64),
            ..self.solver.clone()
        };
        let result = SCRATCH.with(|cell| {
            let mut slot = cell.borrow_mut();
            let scratch = slot.get_or_insert_with(|| IkScratch::new(chain, residual_dim(&seeded.task)));
            seeded.solve_with(chain, t, q0, scratch)
        })?;
        let status = if result.success {
            IkStatus::Solved
        } else if proven_unreachable || self.beyond_reach(chain, t) {
            IkStatus::Unreachable
        } else {
            IkStatus::NotConverged
        };
        Ok(IkOutcome { status, result })
    }

    /// An outcome for an analytic configuration `q` of the pose task.
    fn analytic_outcome(&self, chain: &Chain, t: &IsometryMatrix3<f64>, q: Vec<f64>) -> IkOutcome {
        let (p, o) = measure(&Task::Pose, &chain.fk_unchecked(&q), t);
        let success = p <= self.solver.position_tolerance && o <= self.solver.orientation_tolerance;
        IkOutcome {
            status: if success {
                IkStatus::Solved
            } else {
                IkStatus::NotConverged
            },
            result: IkResult {
                q,
                success,
                position_error: p,
                orientation_error: o,
                iterations: 0,
                restarts: 0,
            },
        }
    }

    /// True when the task point of `t` lies farther from the chain than it can ever reach.
    fn beyond_reach(&self, chain: &Chain, t: &IsometryMatrix3<f64>) -> bool {
        let (point, slack) = match self.solver.task {
            Task::Racket { offset } => (
                t.translation.vector + t.rotation.matrix().column(2) * offset,
                offset.abs(),
            ),
            Task::Pose | Task::Position => (t.translation.vector, 0.0),
        };
        let reach = chain.reach() + slack;
        (point - chain.reach_centre()).norm() > reach * (1.0 + 1e-9) + self.solver.position_tolerance
    }
}

/// Start configurations (m, rad) for a batch of `targets` poses from `q0` as a caller hands it
/// over, row-major with `dof` values a row: one start (`rows` = None, shape (dof,)) serves every
/// target; `rows` = Some(N) starts (shape (N, dof)) need a batch (`batch`) of exactly N targets.
/// Checks finiteness first, then the shape; the result feeds [`IkBatchSolver::solve_until`].
pub fn starts(q0: &[f64], dof: usize, rows: Option<usize>, targets: usize, batch: bool) -> Result<Vec<Vec<f64>>> {
    crate::error::check_finite("q0", q0)?;
    if let Some(c) = rows {
        if !batch || c != targets {
            return Err(Error::shape(
                "q0",
                format!("shape ({dof},) or ({targets}, {dof})"),
                format!("({c}, {dof})"),
            ));
        }
    }
    if dof == 0 || !q0.len().is_multiple_of(dof) {
        return Err(Error::shape(
            "q0",
            format!("rows of {dof} values"),
            format!("{} values", q0.len()),
        ));
    }
    Ok(q0.chunks_exact(dof).map(<[f64]>::to_vec).collect())
}

/// The first outcome of a batch that is not solved, with its index (for `raise_on_failure`).
pub fn first_failure(outcomes: &[IkOutcome]) -> Option<(usize, &IkOutcome)> {
    outcomes.iter().enumerate().find(|(_, o)| o.status != IkStatus::Solved)
}

/// A time budget from seconds as users give it: `None` for unlimited, else finite and > 0.
pub fn time_budget(seconds: Option<f64>) -> Result<Option<std::time::Duration>> {
    match seconds {
        None => Ok(None),
        Some(s) if s > 0.0 && s.is_finite() => Ok(Some(std::time::Duration::from_secs_f64(s))),
        Some(s) => Err(Error::invalid(
            "time_budget",
            format!("expected seconds > 0 or None, got {s}"),
        )),
    }
}

/// The analytic solver of `chain`, or an error naming the structures that have one.
pub fn analytic_for(chain: &Chain) -> Result<Analytic> {
    Analytic::for_chain(chain).ok_or_else(|| {
        Error::invalid(
            "method",
            format!(
                "robot '{}' has no analytic IK (gantry6 and arm4 structures have one); use robot.ik(T)",
                chain.name()
            ),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_broadcast_one_and_match_a_batch() {
        let one = starts(&[0.1, 0.2], 2, None, 3, true).unwrap();
        assert_eq!(one, vec![vec![0.1, 0.2]]);
        let per = starts(&[1.0, 2.0, 3.0, 4.0], 2, Some(2), 2, true).unwrap();
        assert_eq!(per, vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
        // N starts for a single pose, or for a batch of another size: a shape error naming q0
        let e = starts(&[1.0, 2.0, 3.0, 4.0], 2, Some(2), 1, false).unwrap_err();
        assert!(matches!(e, Error::Shape { .. }), "{e}");
        assert_eq!(e.to_string(), "q0: expected shape (2,) or (1, 2), got (2, 2)");
        assert!(matches!(
            starts(&[1.0, 2.0, 3.0, 4.0], 2, Some(2), 3, true),
            Err(Error::Shape { .. })
        ));
        assert!(matches!(
            starts(&[f64::NAN, 0.0], 2, None, 1, false),
            Err(Error::NonFinite { .. })
        ));
    }

    #[test]
    fn first_failure_names_the_first_unsolved_target() {
        let ok = IkOutcome {
            status: IkStatus::Solved,
            result: IkResult {
                q: vec![0.0],
                success: true,
                position_error: 0.0,
                orientation_error: 0.0,
                iterations: 1,
                restarts: 0,
            },
        };
        let bad = IkOutcome {
            status: IkStatus::NotConverged,
            ..ok.clone()
        };
        assert!(first_failure(&[ok.clone(), ok.clone()]).is_none());
        let batch = [ok.clone(), bad.clone(), ok];
        let (i, o) = first_failure(&batch).unwrap();
        assert_eq!((i, o.status), (1, IkStatus::NotConverged));
    }

    fn far() -> IsometryMatrix3<f64> {
        IsometryMatrix3::translation(5.0, 0.0, 0.0)
    }

    /// A batch asked to stop ends with the stop's error; one never asked gives `solve`'s outcomes.
    #[test]
    fn solve_until_stops_on_request_and_is_solve_otherwise() {
        let chain = crate::robots::ur5();
        let t = chain.fk(&[0.3, -0.9, 1.1, -0.4, 0.8, 0.2]).unwrap();
        let s = IkSolver {
            time_budget: None, // deterministic: iterations and restarts only
            ..IkSolver::default()
        };
        let b = IkBatchSolver::new(&chain, s, IkMethod::Numeric).unwrap();
        let err = b.solve_until(&chain, &[t, t], &[], &|| true).unwrap_err();
        assert!(err.to_string().contains("stopped by the caller"), "{err}");
        let a = b.solve(&chain, &[t, t], &[]).unwrap();
        let c = b.solve_until(&chain, &[t, t], &[], &|| false).unwrap();
        assert_eq!(
            a.iter().map(|o| &o.result.q).collect::<Vec<_>>(),
            c.iter().map(|o| &o.result.q).collect::<Vec<_>>()
        );
    }

    /// One unreachable target in a batch gets its status and does not fail the others.
    #[test]
    fn unreachable_target_does_not_fail_the_batch() {
        let chain = crate::robots::ur5();
        let q = [0.3, -0.9, 1.1, -0.4, 0.8, 0.2];
        let good = chain.fk(&q).unwrap();
        let s = IkSolver {
            time_budget: None,
            max_restarts: 20,
            ..IkSolver::default()
        };
        let b = IkBatchSolver::new(&chain, s, IkMethod::Auto).unwrap();
        let out = b.solve(&chain, &[good, far(), good], &[]).unwrap();
        assert_eq!(out[0].status, IkStatus::Solved);
        assert_eq!(out[1].status, IkStatus::Unreachable);
        assert_eq!(out[2].status, IkStatus::Solved);
        assert!(!out[1].result.success);
    }

    /// A reachable target the solver is not given the steps to solve is "not converged".
    #[test]
    fn starved_solver_is_not_converged_rather_than_unreachable() {
        let chain = crate::robots::ur5();
        let target = chain.fk(&[0.3, -0.9, 1.1, -0.4, 0.8, 0.2]).unwrap();
        let s = IkSolver {
            time_budget: None,
            max_iterations: 1,
            max_restarts: 0,
            ..IkSolver::default()
        };
        let b = IkBatchSolver::new(&chain, s, IkMethod::Numeric).unwrap();
        let out = b
            .solve(&chain, &[target], &[vec![-2.0, 1.0, -1.0, 2.0, -2.0, 2.0]])
            .unwrap();
        assert_eq!(out[0].status, IkStatus::NotConverged);
    }

    /// Gantry6 with method="analytic": an out-of-reach target is Unreachable, others solved.
    #[test]
    fn analytic_batch_marks_unreachable_elements() {
        let chain = crate::robots::gantry6();
        let q = chain.mid_range();
        let good = chain.fk(&q).unwrap();
        let b = IkBatchSolver::new(&chain, IkSolver::default(), IkMethod::Analytic).unwrap();
        let out = b
            .solve(&chain, &[good, IsometryMatrix3::translation(50.0, 0.0, 0.0)], &[])
            .unwrap();
        assert_eq!(out[0].status, IkStatus::Solved);
        assert_eq!(out[1].status, IkStatus::Unreachable);
    }

    /// The reach bound holds: random configurations never put the tool beyond it.
    #[test]
    fn reach_bounds_every_configuration() {
        for chain in [crate::robots::ur5(), crate::robots::gantry6(), crate::robots::mobile8()] {
            let mut rng = fastrand::Rng::with_seed(1);
            for _ in 0..200 {
                let q: Vec<f64> = chain
                    .limits()
                    .iter()
                    .map(|l| {
                        let (lo, hi) = (l.lower.max(-4.0), l.upper.min(4.0));
                        lo + (hi - lo) * rng.f64()
                    })
                    .collect();
                let p = chain.fk(&q).unwrap().translation.vector;
                assert!((p - chain.reach_centre()).norm() <= chain.reach() + 1e-12);
            }
        }
    }

    /// Statuses print as Python spells them, and methods parse.
    #[test]
    fn status_display_and_method_parse() {
        assert_eq!(IkStatus::NotConverged.to_string(), "not_converged");
        assert_eq!("numeric".parse::<IkMethod>().unwrap(), IkMethod::Numeric);
        assert!("fast".parse::<IkMethod>().is_err());
    }
}
