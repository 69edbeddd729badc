//! The controller's speculative decisions (`BallDecider::speculate`, `hold`): a decision's search
//! made a few observations ahead of it, the decision planning the hit so found again from its own
//! estimate (`ReturnPlanner::plan_same_hit`), and searching in full when that fails.

use ttkin::ball::decide::{BallDecider, DecideConfig, Decision, Speculation};
use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::{ReturnPlanner, ReturnStatus};
use ttkin::ball::rally::{self, observe_ball, RallyConfig};
use ttkin::traj::{JointState, JointTrajectory};

fn setup() -> (ReturnPlanner, RallyConfig, Flight) {
    let pl = ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap();
    let truth = Flight {
        step: rally::TRUTH_STEP,
        ..pl.flight
    };
    (pl, RallyConfig::default(), truth)
}

#[test]
fn the_first_plan_from_a_speculated_hit_is_that_hit_planned_again() {
    let (pl, cfg, truth) = setup();
    let dc = DecideConfig::of(&cfg);
    let ready = JointState::rest(&pl.ready);
    let (mut used, mut balls) = (0, 0);
    for i in 0..12 {
        let o = observe_ball(&truth, &cfg, i, None);
        let mut d = BallDecider::new(&pl, dc);
        let mut held = None;
        for (k, (&t, &p)) in o.times.iter().zip(&o.positions).enumerate() {
            let now = t + cfg.camera.latency;
            let decision = d.observe(&pl, t, p, now, &|_| ready.clone());
            // due exactly 3 observations before the window is full, once
            assert_eq!(
                d.speculation_due(3),
                decision.is_none() && k + 1 + 3 == dc.window_frames,
                "observation {k}"
            );
            assert!(!d.speculation_due(0));
            if d.speculation_due(3) {
                if d.speculate(&pl, now, &ready) {
                    held = d.held().cloned();
                }
                assert!(!d.speculation_due(3), "once per decision");
                continue;
            }
            let Some(Decision::Planned { now, estimate, plan }) = decision else {
                continue;
            };
            balls += 1;
            let Some(h) = held.take() else {
                assert_eq!(d.speculation_used(), None);
                break;
            };
            assert!(!h.correction);
            // Whatever the decision did, it equals one of its two ways, chosen in this order.
            let again = pl
                .plan_same_hit(&estimate.state, now, &ready, false, &h.hit, h.t_hit)
                .unwrap();
            if again.status == ReturnStatus::Ok && again.hit.is_some() {
                assert_eq!(d.speculation_used(), Some(true));
                assert_eq!(*plan, again);
                let hit = plan.hit.as_ref().unwrap();
                assert!((now + hit.hit.t - h.t_hit).abs() < 1e-9);
                assert!((hit.landing - h.hit.landing).xy().norm() < 2e-3);
                used += 1;
            } else {
                assert_eq!(d.speculation_used(), Some(false));
                assert_eq!(*plan, pl.plan(&estimate.state, now, dc.target).unwrap());
            }
            break;
        }
    }
    assert!(balls >= 8, "{balls} first plans");
    assert!(used * 10 >= balls * 7, "{used} of {balls} from the speculated hit");
}

#[test]
fn a_held_hit_that_cannot_be_planned_again_falls_back_to_the_search() {
    let (pl, cfg, truth) = setup();
    let dc = DecideConfig::of(&cfg);
    let ready = JointState::rest(&pl.ready);
    let mut checked = 0;
    for i in 0..12 {
        let o = observe_ball(&truth, &cfg, i, None);
        let (mut plain, mut spec) = (BallDecider::new(&pl, dc), BallDecider::new(&pl, dc));
        for (&t, &p) in o.times.iter().zip(&o.positions) {
            let now = t + cfg.camera.latency;
            if spec.speculation_due(1) {
                // a hit found ahead, held with a hit time already past at the decision, alone
                if spec.speculate(&pl, now, &ready) {
                    let mut h: Speculation = spec.held().unwrap().clone();
                    h.t_hit = now - 0.1;
                    h.others.clear();
                    spec.hold(h);
                }
            }
            let a = plain.observe(&pl, t, p, now, &|_| ready.clone());
            let b = spec.observe(&pl, t, p, now, &|_| ready.clone());
            if let Some(Decision::Planned { .. }) = &a {
                if spec.speculation_used().is_some() {
                    assert_eq!(spec.speculation_used(), Some(false));
                    // the decision searched as the rally's: the same plan
                    assert_eq!(a, b);
                    checked += 1;
                }
                assert_eq!(plain.speculation_used(), None);
                break;
            }
        }
    }
    assert!(checked >= 8, "{checked} fallbacks");
}

#[test]
fn the_next_best_hit_held_is_tried_when_the_best_cannot_be_planned_again() {
    let (pl, cfg, truth) = setup();
    let dc = DecideConfig::of(&cfg);
    let ready = JointState::rest(&pl.ready);
    let (mut second, mut with_others) = (0, 0);
    for i in 0..12 {
        let o = observe_ball(&truth, &cfg, i, None);
        let mut d = BallDecider::new(&pl, dc);
        let mut held: Option<Speculation> = None;
        for (&t, &p) in o.times.iter().zip(&o.positions) {
            let now = t + cfg.camera.latency;
            if d.speculation_due(1) && d.speculate(&pl, now, &ready) {
                // the best hit found ahead made infeasible (its time already past at the
                // decision), the search's own best put second
                let found = d.held().unwrap().clone();
                let h = Speculation {
                    t_hit: now - 0.1,
                    others: vec![(found.hit.clone(), found.t_hit)],
                    ..found
                };
                d.hold(h.clone());
                held = Some(h);
            }
            if let Some(Decision::Planned { plan, .. }) = d.observe(&pl, t, p, now, &|_| ready.clone()) {
                let Some(h) = held.take() else { break };
                with_others += 1;
                if d.speculation_rank() == Some(1) {
                    // planned again from the second: its hit time, not the past one
                    assert_eq!(d.speculation_used(), Some(true));
                    let hit = plan.hit.expect("a hit");
                    assert!((now + hit.hit.t - h.others[0].1).abs() < 1e-9, "ball {i}");
                    second += 1;
                } else {
                    // never the first (its time is past): the second, or the full search
                    assert_eq!(d.speculation_rank(), None, "ball {i}");
                    assert_eq!(d.speculation_used(), Some(false), "ball {i}");
                }
                break;
            }
        }
    }
    assert!(with_others >= 8, "{with_others} decisions with a hit held");
    assert!(
        second * 10 >= with_others * 7,
        "{second} of {with_others} from the second hit"
    );
}

#[test]
fn the_correction_uses_the_hit_speculated_before_it() {
    let (pl, cfg, truth) = setup();
    let dc = DecideConfig::of(&cfg);
    let ready = JointState::rest(&pl.ready);
    let (mut corrections, mut used) = (0, 0);
    for i in 0..16 {
        let o = observe_ball(&truth, &cfg, i, None);
        let mut d = BallDecider::new(&pl, dc);
        let mut stroke: Option<(f64, JointTrajectory)> = None;
        let mut held: Option<Speculation> = None;
        for (&t, &p) in o.times.iter().zip(&o.positions) {
            let now = t + cfg.camera.latency;
            let state = |tc: f64| match &stroke {
                Some((t0, tr)) => tr.state((tc - t0).clamp(0.0, tr.duration())).unwrap(),
                None => ready.clone(),
            };
            match d.observe(&pl, t, p, now, &state) {
                Some(Decision::Planned { now, plan, .. }) => {
                    held = None;
                    if let Some(h) = plan.hit.filter(|_| plan.status == ReturnStatus::Ok) {
                        stroke = Some((now, rally::execution(&h, &ready)));
                    }
                }
                Some(Decision::Corrected { now, hit }) => {
                    corrections += 1;
                    if d.speculation_used() == Some(true) {
                        used += 1;
                        // the hit found ahead, at its time, planned again
                        let hit = hit.expect("a hit when the held one was used");
                        let h = held.as_ref().expect("held");
                        assert!((now + hit.hit.t - h.t_hit).abs() < 1e-9);
                        assert!((hit.landing - h.hit.landing).xy().norm() < 2e-3);
                    } else {
                        assert_eq!(d.speculation_used().is_some(), held.is_some());
                    }
                    break;
                }
                None => {
                    if d.speculation_due(3) {
                        let s = state(now);
                        let first_done = d.estimate().is_some();
                        if d.speculate(&pl, now, &s) {
                            assert_eq!(d.held().unwrap().correction, first_done);
                            held = d.held().cloned();
                        } else {
                            held = None;
                        }
                    }
                }
                Some(_) => break,
            }
        }
    }
    assert!(corrections >= 8, "{corrections} corrections");
    assert!(
        used * 10 >= corrections * 6,
        "{used} of {corrections} from the speculated hit"
    );
}

/// The search ahead made again one frame before the first plan (`refresh_due`, `refresh`): a
/// held hit still feasible from the newer estimate is kept (same absolute hit time), one that is
/// not is searched again (the same hit as a fresh search ahead), and the first plan then plans
/// the refreshed hit again.
#[test]
fn the_search_ahead_made_again_a_frame_before_the_decision_keeps_or_replaces_the_held_hit() {
    let (pl, cfg, truth) = setup();
    let dc = DecideConfig::of(&cfg);
    let ready = JointState::rest(&pl.ready);
    let (mut kept, mut searched, mut used, mut balls) = (0, 0, 0, 0);
    for i in 0..16 {
        let o = observe_ball(&truth, &cfg, i, None);
        let mut d = BallDecider::new(&pl, dc);
        let mut spoil = i % 2 == 1;
        for (k, (&t, &p)) in o.times.iter().zip(&o.positions).enumerate() {
            let now = t + cfg.camera.latency;
            let decision = d.observe(&pl, t, p, now, &|_| ready.clone());
            if d.speculation_due(3) {
                d.speculate(&pl, now, &ready);
                assert!(!d.refresh_due(), "not at the search ahead's own observation");
                continue;
            }
            if d.refresh_due() {
                assert!(decision.is_none() && k + 1 + 1 == dc.window_frames, "observation {k}");
                let Some(mut h) = d.held().cloned() else { break };
                if spoil {
                    // not feasible any more: a hit time already past, alone
                    h.t_hit = now - 0.1;
                    h.others.clear();
                    d.hold(h.clone());
                }
                let found = d.refresh(&pl, now, &ready);
                assert!(!d.refresh_due(), "once per decision");
                // what a search ahead from here finds
                let fresh = || {
                    let mut again = BallDecider::new(&pl, dc);
                    for (&t2, &p2) in o.times[..=k].iter().zip(&o.positions[..=k]) {
                        again.observe(&pl, t2, p2, t2 + cfg.camera.latency, &|_| ready.clone());
                    }
                    again.speculate(&pl, now, &ready);
                    again.held().cloned()
                };
                if spoil {
                    // searched again
                    assert_eq!(d.held().cloned(), fresh());
                    searched += 1;
                } else if found {
                    let r = d.held().unwrap().clone();
                    assert!(!r.correction);
                    if h.others.iter().map(|o| o.1).chain([h.t_hit]).any(|t| t == r.t_hit) {
                        // kept: a held try planned again, its absolute hit time unchanged
                        kept += 1;
                    } else {
                        // no held try feasible from the newer estimate: searched again
                        assert_eq!(Some(r), fresh());
                        searched += 1;
                    }
                }
                spoil = false;
                continue;
            }
            if let Some(Decision::Planned { .. }) = decision {
                balls += 1;
                used += usize::from(d.speculation_used() == Some(true));
                break;
            }
        }
    }
    assert!(kept >= 4 && searched >= 4, "kept {kept}, searched {searched}");
    assert!(
        used * 10 >= balls * 7,
        "{used} of {balls} planned again from the refreshed hit"
    );
}
