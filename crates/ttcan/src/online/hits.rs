//! Planning hits into what runs: an upper computer's hit planned with `ttkin::hit::HitPlanner`
//! from the state scheduled at its splice deadline ([`Splicer::hit`]), a brain's stroke handed
//! over as it is ([`Splicer::stroke`]), and the replacement rules (a newer hit of the same stroke
//! replaces the pending one while that is still ahead; a hit of another stroke is spliced into
//! the return leg after it).

use std::sync::atomic::Ordering;

use ttkin::hit::{Hit, HitStatus};

use super::brain::PlannedStroke;
use super::counters::Counters;
use super::receiver::controller_time;
use super::schedule::Splice;
use super::splicer::{hit_pose, status, Committed, HitOutcome, Splicer, StrokeMiss};
use super::wire::{HitMsg, PlanStatus};

impl Splicer {
    /// Plans and splices one hit received at controller time `arrival` (s).
    pub fn hit(&mut self, h: &HitMsg, arrival: f64, counters: &Counters) -> HitOutcome {
        let reject = |t: f64| HitOutcome {
            status: status(h.id, PlanStatus::Rejected, f64::NAN, f64::NAN, controller_time() - t),
            replaced: None,
        };
        let now = controller_time();
        let (Some(pose), true) = (hit_pose(h), h.t_hit > now) else {
            return reject(arrival);
        };
        if self.schedules.is_none() || self.stopped() {
            return reject(arrival);
        }
        let tl = self.timeline.clone();
        let mut factor: f64 = 1.0;
        for _ in 0..3 {
            let began = controller_time();
            let mut sp = self.splice(factor);
            let mut replaces = None;
            let mut after = None;
            // a hit some channel has not commanded by the splice is still ahead
            if let Some(last) = self
                .last
                .clone()
                .filter(|l| Self::span_with(l, &sp.skips).1 >= sp.deadline)
            {
                if last.stroke == h.stroke && Self::span_with(&last, &sp.skips).0 <= sp.deadline {
                    // a channel commands it before the splice: being done, nothing to replace
                    return reject(arrival);
                }
                if last.stroke == h.stroke {
                    // spliced after the hit the replaced stroke was spliced after, while that
                    // one is still ahead (a replacement from the present state cut it off)
                    if let Some(e) = self
                        .earlier
                        .clone()
                        .filter(|e| Self::span_with(e, &sp.skips).1 >= sp.deadline)
                    {
                        let e_end = Self::span_with(&e, &sp.skips).1;
                        if h.t_hit <= tl.time_of(e_end) + 2.0 * tl.period() {
                            return reject(arrival);
                        }
                        sp.deadline = sp.deadline.max(e_end + 1);
                        after = Some(e);
                    }
                    replaces = Some(last);
                } else {
                    let l_end = Self::span_with(&last, &sp.skips).1;
                    if h.t_hit <= tl.time_of(l_end) + 2.0 * tl.period() {
                        // another stroke's hit comes first
                        return reject(arrival);
                    }
                    sp.deadline = sp.deadline.max(l_end + 1);
                    after = Some(last);
                }
            } else if self.last.as_ref().is_some_and(|l| l.stroke == h.stroke) {
                // that stroke's hit is done: nothing left to replace
                return reject(arrival);
            }
            let Some(state) = self.state_of(&sp) else {
                return reject(arrival);
            };
            let t_s = tl.time_of(sp.deadline);
            let t_rel = (h.t_hit - t_s).max(1e-3);
            let hit = Hit {
                pose,
                twist: h.twist,
                t: t_rel,
            };
            tl.planning.store(true, Ordering::Relaxed);
            let plan = self.planner.plan(&hit, Some(&state), Some(&self.ready));
            tl.planning.store(false, Ordering::Relaxed);
            Counters::bump(&counters.plans);
            let plan = match plan {
                Ok(p) => p,
                Err(_) => return reject(arrival),
            };
            let code = match plan.status {
                HitStatus::Ok => PlanStatus::Accepted,
                HitStatus::TooEarly => PlanStatus::TooEarly,
                HitStatus::Unreachable | HitStatus::Singular => PlanStatus::Unreachable,
                _ => PlanStatus::Infeasible,
            };
            let elapsed = controller_time() - arrival;
            if code != PlanStatus::Accepted {
                let earliest = match code {
                    PlanStatus::TooEarly => t_s + self.planner.earliest_t_hit(&plan),
                    _ => f64::NAN,
                };
                return HitOutcome {
                    status: status(h.id, code, earliest, f64::NAN, elapsed),
                    replaced: None,
                };
            }
            let Some(traj) = plan.trajectory.as_ref() else {
                return reject(arrival);
            };
            if self.is_late(&sp) {
                // planning took longer than the lead: again, twice as far ahead or twice the
                // planning time, whichever is further
                factor = (2.0 * factor).max(2.0 * (controller_time() - began) / self.cfg.splice_lead);
                continue;
            }
            let n = (plan.t_hit / tl.period()).round() as u64;
            let Some(seq) = self.hand_over(&sp, traj, Some(n)) else {
                Counters::bump(&counters.splices_late);
                return reject(arrival);
            };
            Counters::bump(&counters.splices);
            counters.latency.record(t_s - arrival);
            let t_hit = t_s + plan.t_hit;
            self.watch_hit(seq, t_hit);
            self.earlier = after;
            self.last = Some(Committed {
                id: h.id,
                stroke: h.stroke,
                t_hit,
                hit: (0..sp.skips.len()).map(|c| sp.start(c) + n).collect(),
                skips: sp.skips.clone(),
                q_hit: plan.q_hit.clone(),
                twist: self.planner.tool_twist(&hit),
            });
            let elapsed = controller_time() - arrival;
            let us = (elapsed * 1e6) as u64;
            counters.plan_time_max_us.fetch_max(us, Ordering::Relaxed);
            return HitOutcome {
                status: status(h.id, PlanStatus::Accepted, f64::NAN, t_hit, elapsed),
                replaced: replaces.map(|r| status(r.id, PlanStatus::Replaced, f64::NAN, f64::NAN, elapsed)),
            };
        }
        reject(arrival)
    }

    /// Splices a stroke a brain built for its splice deadline (decided on a datagram received at
    /// controller time `arrival`, s): handed over as it is when that deadline is still ahead and
    /// the stroke starts from the state scheduled there; otherwise nothing changes and the error
    /// says why (the caller decides again or re-plans the hit, [`Splicer::replan`]). The
    /// replacement rules are [`Splicer::hit`]'s; while another stroke's hit is still to come,
    /// the hit is planned into that one's return leg.
    pub fn stroke(&mut self, st: &PlannedStroke, arrival: f64, counters: &Counters) -> Result<HitOutcome, StrokeMiss> {
        let h = &st.hit;
        let reject = |t: f64| HitOutcome {
            status: status(h.id, PlanStatus::Rejected, f64::NAN, f64::NAN, controller_time() - t),
            replaced: None,
        };
        let now = controller_time();
        let pose = hit_pose(h);
        if pose.is_none() || h.t_hit <= now || self.stopped() {
            return Ok(reject(arrival));
        }
        let tl = self.timeline.clone();
        let sp = Splice {
            deadline: st.cycle,
            skips: tl.skips(),
        };
        let mut replaces = None;
        if let Some(last) = self
            .last
            .clone()
            .filter(|l| Self::span_with(l, &sp.skips).1 >= sp.deadline)
        {
            let before = self
                .earlier
                .as_ref()
                .is_none_or(|e| Self::span_with(e, &sp.skips).1 < sp.deadline);
            if last.stroke == h.stroke && before && Self::span_with(&last, &sp.skips).0 > sp.deadline {
                replaces = Some(last);
            } else {
                // another stroke's hit is still to come: spliced into its return leg as a hit
                return Ok(self.replan(h, arrival, counters));
            }
        } else if self.last.as_ref().is_some_and(|l| l.stroke == h.stroke) {
            return Ok(reject(arrival));
        }
        // Continuous with what runs: the stroke starts from the state scheduled at its splice.
        let Some(from) = self.state_of(&sp) else {
            return Ok(reject(arrival));
        };
        let Ok(start) = st.traj.state(0.0) else {
            return Err(StrokeMiss::Discontinuous);
        };
        let close =
            |a: &[f64], b: &[f64], tol: f64| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol);
        let continuous =
            close(&start.q, &from.q, 1e-9) && close(&start.qd, &from.qd, 1e-7) && close(&start.qdd, &from.qdd, 1e-5);
        if !continuous {
            return Err(StrokeMiss::Discontinuous);
        }
        if self.is_late(&sp) || (tl.time_of(sp.deadline) - st.start).abs() > 0.25 * tl.period() {
            return Err(StrokeMiss::Late);
        }
        let t_rel = (h.t_hit - st.start).max(0.0);
        let n = (t_rel / tl.period()).round() as u64;
        let Some(seq) = self.hand_over(&sp, &st.traj, Some(n)) else {
            Counters::bump(&counters.splices_late);
            return Err(StrokeMiss::Late);
        };
        Counters::bump(&counters.splices);
        counters.latency.record(tl.time_of(sp.deadline) - arrival);
        self.watch_hit(seq, h.t_hit);
        self.earlier = None;
        let q_hit = st.traj.state(t_rel).map(|s| s.q).unwrap_or_default();
        let twist = pose.map_or([0.0; 6], |pose| {
            self.planner.tool_twist(&Hit {
                pose,
                twist: h.twist,
                t: t_rel,
            })
        });
        self.last = Some(Committed {
            id: h.id,
            stroke: h.stroke,
            t_hit: h.t_hit,
            hit: (0..sp.skips.len()).map(|c| sp.start(c) + n).collect(),
            skips: sp.skips.clone(),
            q_hit,
            twist,
        });
        let elapsed = controller_time() - arrival;
        counters
            .plan_time_max_us
            .fetch_max((elapsed * 1e6) as u64, Ordering::Relaxed);
        Ok(HitOutcome {
            status: status(h.id, PlanStatus::Accepted, f64::NAN, h.t_hit, elapsed),
            replaced: replaces.map(|r| status(r.id, PlanStatus::Replaced, f64::NAN, f64::NAN, elapsed)),
        })
    }

    /// Plans a brain's hit `h` again like an upper computer's hit ([`Splicer::hit`]), counted.
    pub fn replan(&mut self, h: &HitMsg, arrival: f64, counters: &Counters) -> HitOutcome {
        Counters::bump(&counters.splices_replanned);
        self.hit(h, arrival, counters)
    }
}
