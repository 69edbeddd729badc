//! The ball brain's search-ahead worker: a thread of its own (neither a cycle thread nor the
//! planning thread) that makes each decision's search a few observations before the decision
//! ([`BallDecider::speculate`] on a clone of the ball's decider), and again one frame before it
//! ([`BallDecider::refresh`]: the hit found planned again from the newest estimate, searched
//! again only when not feasible any more), and hands the hit found back
//! over a channel, so that the planning thread is free when the deciding observation comes. The
//! planning thread may block on the channel (it waits for a search still running when its
//! decision is due, up to its splice deadline); the cycle threads never see it.

use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::thread::JoinHandle;
use std::time::Instant;

use ttkin::ball::decide::{BallDecider, Speculation};
use ttkin::ball::hitplan::{PlanBudget, ReturnPlanner};
use ttkin::traj::JointState;

/// Which decision a search is for: the ball (observation id) and the number of decisions made
/// for it before (0: the first plan, 1: the correction, 2: the second correction).
pub type SpecKey = (u32, u32);

/// A search to make ahead of a decision.
#[derive(Debug)]
pub struct SpecJob {
    /// The decision it is for.
    pub key: SpecKey,
    /// The ball's decider as it is now (its observations so far), cloned.
    pub decider: BallDecider,
    /// The decision's time (s, controller clock) the search plans for.
    pub now: f64,
    /// The state (m or rad) a correction's stroke starts from.
    pub start: JointState,
    /// When the search is given up ([`PlanBudget::Abandon`]); `None`: no budget.
    pub abandon: Option<Instant>,
    /// The search made again one frame before the decision ([`BallDecider::refresh`]: the
    /// held hits planned again from the newest estimate first) instead of the search ahead
    /// ([`BallDecider::speculate`]).
    pub refresh: bool,
}

/// What a search ahead found: the hit to hold for the decision `key`, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecDone {
    /// The decision it is for.
    pub key: SpecKey,
    /// The hit found (`None`: the search found none, or was given up without one).
    pub spec: Option<Speculation>,
}

/// The worker thread and its two channels (see the module doc). Dropping it ends the thread.
#[derive(Debug)]
pub struct Speculator {
    jobs: Option<Sender<SpecJob>>,
    done: Receiver<SpecDone>,
    handle: Option<JoinHandle<()>>,
    in_flight: Option<SpecKey>,
    /// Jobs submitted for `in_flight` whose results were not taken yet.
    outstanding: usize,
}

impl Speculator {
    /// Starts the worker searching with its own copy of `planner`; at SCHED_FIFO `priority` when
    /// it is > 0 and the system allows it (else normal scheduling).
    pub fn spawn(planner: ReturnPlanner, priority: u8) -> std::io::Result<Self> {
        let (jobs, rx) = channel::<SpecJob>();
        let (tx, done) = channel::<SpecDone>();
        let handle = std::thread::Builder::new()
            .name("ttctl-speculate".into())
            .spawn(move || {
                if priority > 0 {
                    // refused: normal scheduling, the searches come later
                    let _ = crate::runtime::rt::make_thread_realtime(priority);
                }
                let mut planner = planner;
                for mut job in rx {
                    planner.budget = job.abandon.map(PlanBudget::Abandon);
                    if job.refresh {
                        job.decider.refresh(&planner, job.now, &job.start);
                    } else {
                        job.decider.speculate(&planner, job.now, &job.start);
                    }
                    let spec = job.decider.held().cloned();
                    if tx.send(SpecDone { key: job.key, spec }).is_err() {
                        return;
                    }
                }
            })?;
        Ok(Speculator {
            jobs: Some(jobs),
            done,
            handle: Some(handle),
            in_flight: None,
            outstanding: 0,
        })
    }

    /// Hands `job` to the worker (a job still running for another decision is superseded: its
    /// result will be dropped; the results of jobs for the same decision all come, in order).
    /// False when the worker has ended.
    pub fn submit(&mut self, job: SpecJob) -> bool {
        let key = job.key;
        let sent = self.jobs.as_ref().is_some_and(|j| j.send(job).is_ok());
        if !sent {
            self.in_flight = None;
            self.outstanding = 0;
        } else if self.in_flight == Some(key) {
            self.outstanding += 1;
        } else {
            self.in_flight = Some(key);
            self.outstanding = 1;
        }
        sent
    }

    /// A result for the decision in flight taken: the decision is no longer in flight once
    /// every job submitted for it has answered.
    fn took(&mut self) {
        self.outstanding = self.outstanding.saturating_sub(1);
        if self.outstanding == 0 {
            self.in_flight = None;
        }
    }

    /// The decision whose search is running (submitted, a result not taken yet).
    pub fn in_flight(&self) -> Option<SpecKey> {
        self.in_flight
    }

    /// The result of the running search if it is there, without waiting (results of superseded
    /// searches are dropped).
    pub fn poll(&mut self) -> Option<SpecDone> {
        while let Ok(d) = self.done.try_recv() {
            if self.in_flight == Some(d.key) {
                self.took();
                return Some(d);
            }
        }
        None
    }

    /// The result of the running search, waiting for it until `until` (`None`: as long as it
    /// takes); `None` when nothing runs or it did not come in time.
    pub fn wait(&mut self, until: Option<Instant>) -> Option<SpecDone> {
        self.in_flight?;
        if let Some(d) = self.poll() {
            return Some(d);
        }
        loop {
            let got = match until {
                Some(u) => {
                    let left = u.saturating_duration_since(Instant::now());
                    if left.is_zero() {
                        return None;
                    }
                    self.done.recv_timeout(left)
                }
                None => self.done.recv().map_err(|_| RecvTimeoutError::Disconnected),
            };
            match got {
                Ok(d) if self.in_flight == Some(d.key) => {
                    self.took();
                    return Some(d);
                }
                Ok(_) => {}
                Err(_) => return None,
            }
        }
    }
}

impl Drop for Speculator {
    fn drop(&mut self) {
        // Closing the job channel ends the worker after its current search.
        self.jobs = None;
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}
