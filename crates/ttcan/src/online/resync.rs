//! Keeping the channels in step for the pending hit: a stall of one channel thread while the
//! joints move leaves its joints behind the others'; the hit leg is planned again from the state
//! each channel commands so that every channel commands the hit at the same deadline
//! ([`Splicer::resync`]), and each executed hit is counted in step or out of step
//! ([`Splicer::check_hits`]).

use std::sync::atomic::Ordering;

use super::counters::Counters;
use super::receiver::controller_time;
use super::splicer::{status, Committed, Splicer};
use super::wire::{PlanStatus, StatusMsg};

/// Fewest cycles from the present to the splice of a re-plan that brings the channels back in
/// step ([`Splicer::resync`]; its lead is also [`RESYNC_PLAN_FACTOR`] × its planning time; the
/// splice lead was used before: a stroke refused as late is now tried again further ahead).
const RESYNC_MIN_CYCLES: u64 = 3;

/// The lead of a re-plan, in multiples of the planning time of the re-plans before (smoothed):
/// the plan and its hand-over done before the splice, with room for a preempted planning thread.
const RESYNC_PLAN_FACTOR: f64 = 4.0;

/// Time (s) after a watched hit's time at which a hit not commanded by every channel is settled:
/// out of step when some channel commanded it, else not executed (replaced, called off).
const HIT_WAIT_S: f64 = 2.0;

/// Re-plans tried per call, each further ahead than the one before when it came too late.
const RESYNC_TRIES: usize = 4;

impl Splicer {
    /// Watches the hit of stroke `seq` (at controller time `t_hit`): [`Splicer::check_hits`].
    pub(super) fn watch_hit(&mut self, seq: u64, t_hit: f64) {
        self.watch.push((seq, t_hit));
    }

    /// Counts the watched hits every channel has commanded: in step (every channel at the same
    /// deadline) or not (`hits_out_of_step`, the largest spread in `hit_skew_max_cycles`); 2 s
    /// after its time, a hit some channels commanded and others not is counted out of step, and
    /// one no channel reached (replaced, called off) is forgotten.
    pub fn check_hits(&mut self, counters: &Counters) {
        let tl = self.timeline.clone();
        let now = controller_time();
        self.watch.retain(|&(seq, t)| match tl.hit_deadlines(seq) {
            Some(d) => {
                let skew = d.iter().max().unwrap_or(&0) - d.iter().min().unwrap_or(&0);
                if skew == 0 {
                    Counters::bump(&counters.hits_in_step);
                } else {
                    Counters::bump(&counters.hits_out_of_step);
                }
                counters.hit_skew_max_cycles.fetch_max(skew, Ordering::Relaxed);
                false
            }
            None if now < t + HIT_WAIT_S => true,
            None => {
                // Commanded by some channels and not by others (a channel did not follow the
                // stroke to its hit): executed out of step.
                if tl.hit_records(seq).iter().any(Option::is_some) {
                    Counters::bump(&counters.hits_out_of_step);
                }
                false
            }
        });
    }

    /// Brings the channels back in step for the pending hit: when their skips have drifted apart
    /// since its stroke was handed over (a channel thread stalled while the joints moved, so its
    /// joints follow the stroke later than the others'), the hit leg is planned again from the
    /// state each channel commands at one splice deadline (each channel's joints at its own start
    /// cycle: continuous on every channel) to the same hit state, at the hit time answered when
    /// that is feasible (the lagging joints catch up), else when the channel furthest behind
    /// would reach it; handed to each channel with its own start cycle, so that every channel
    /// commands the hit at the same deadline. Not while an earlier stroke's hit is still to come
    /// (the pending stroke is spliced after it), nor within a few cycles of the hit. A re-plan
    /// refused as late (it reached a channel after that channel commanded its start) is tried
    /// again further ahead. Counted
    /// `resyncs`, or `resyncs_failed` when no leg is feasible (the channels stay apart: the hit
    /// is counted out of step when it comes), and the hit, still ahead, is answered again
    /// `out_of_step` (returned, once per hit).
    pub fn resync(&mut self, counters: &Counters) -> Option<StatusMsg> {
        let last = self.last.clone()?;
        let tl = self.timeline.clone();
        let now_skips = tl.skips();
        let drift: Vec<i64> = now_skips
            .iter()
            .zip(&last.skips)
            .map(|(a, b)| *a as i64 - *b as i64)
            .collect();
        if drift.iter().all(|d| *d == drift[0]) || self.stopped() {
            return None;
        }
        if let Some(e) = self.earlier.as_ref() {
            if self.hit_span(e).1 >= tl.present_deadline() {
                return None;
            }
        }
        // One re-plan waiting at a time: a channel holds few strokes waiting for their start
        // ([`super::handoff::MAX_PENDING`]); re-plans a lead apart, none superseding the one
        // before, filled them (the first channel took a stroke another had no room for).
        if self.last_starts.iter().enumerate().any(|(c, &s)| tl.clock_of(c).1 < s) {
            return None;
        }
        if self.hit_span(&last).0 <= tl.present_deadline() {
            // the hit is done (or being done): nothing to bring in step
            self.settle(&now_skips);
            return None;
        }
        // A short lead (a re-plan is one leg: a few ms in a debug build, tens of µs optimised):
        // the window before the hit in which a stall cannot be made good shrinks with it. A
        // stroke that came too late is refused by the channels as a whole (none follows it
        // late, `super::handoff`), so a short lead risks a retry, not a split.
        let period = tl.period();
        let mut lead = (RESYNC_MIN_CYCLES as f64 * period).max(RESYNC_PLAN_FACTOR * self.resync_plan_s);
        let mut late = false;
        for _ in 0..RESYNC_TRIES {
            late = false;
            let began = controller_time();
            let sp = self.splice_in(lead);
            let (first, latest) = Self::span_with(&last, &sp.skips);
            if sp.deadline + 2 >= first {
                // too close to the hit: the channels stay apart
                break;
            }
            let state = self.state_of(&sp)?;
            let t_s = tl.time_of(sp.deadline);
            tl.planning.store(true, Ordering::Relaxed);
            let mut found = None;
            for t in [last.t_hit, tl.time_of(latest)] {
                let rel = t - t_s;
                if rel <= 2.0 * period {
                    continue;
                }
                let b =
                    self.planner
                        .branch_leg_to(&last.q_hit, &state, &last.twist, rel, &self.ready, f64::NEG_INFINITY);
                if let Some(b) = b {
                    found = Some((b, t, rel));
                    break;
                }
            }
            tl.planning.store(false, Ordering::Relaxed);
            Counters::bump(&counters.plans);
            let planned_in = controller_time() - began;
            self.resync_plan_s = (0.5 * (self.resync_plan_s + planned_in)).max(planned_in);
            let Some((b, t, rel)) = found else {
                break;
            };
            let Ok(traj) = b.leg.trajectory.then(b.follow) else {
                break;
            };
            let n = (rel / period).round() as u64;
            if self.is_late(&sp) {
                // planning took longer than the lead: twice as far ahead or twice the planning time
                lead = (2.0 * lead).max(2.0 * planned_in);
                late = true;
                continue;
            }
            let Some(seq) = self.hand_over(&sp, &traj, Some(n)) else {
                // refused: a channel commanded its start before the stroke reached it (the
                // planning thread was preempted after its late check); again, further ahead
                lead = (2.0 * lead).max(2.0 * (controller_time() - began));
                late = true;
                continue;
            };
            Counters::bump(&counters.resyncs);
            self.watch_hit(seq, t);
            self.last = Some(Committed {
                t_hit: t,
                hit: (0..sp.skips.len()).map(|c| sp.start(c) + n).collect(),
                skips: sp.skips,
                ..last
            });
            return None;
        }
        if late {
            // every try came too late (a preempted planning thread): again at the next turn,
            // from the lead of the planning time (the hit's closeness ends it)
            return None;
        }
        Counters::bump(&counters.resyncs_failed);
        self.settle(&now_skips);
        // the hit still ahead will be out of step: said now, once
        if self.announced == Some(last.id) || self.hit_span(&last).0 <= tl.present_deadline() {
            return None;
        }
        self.announced = Some(last.id);
        Some(status(last.id, PlanStatus::OutOfStep, f64::NAN, last.t_hit, 0.0))
    }

    /// The pending hit's channels taken as they are (no re-plan until their skips drift again).
    fn settle(&mut self, skips: &[u64]) {
        if let Some(l) = self.last.as_mut() {
            l.skips = skips.to_vec();
        }
    }
}
