//! The ball mode's brain (`ttcan::online::ball`): the rally's decisions on the rally's
//! observations, the clock relation, the latency budget, ready after the hit and on a lost ball.

use ttcan::online::ball::{BallBrain, BallBrainConfig, ClockRelation};
use ttcan::online::brain::{Brain, Command, DecisionPath, SpliceAt};
use ttcan::online::wire::{HitMsg, ObservationMsg, PlanStatus, StatusMsg};
use ttkin::ball::decide::DecideConfig;
use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::ReturnPlanner;
use ttkin::ball::rally::{self, RallyConfig};
use ttkin::ball::reach::ReachRegion;
use ttkin::traj::JointState;

fn planner() -> ReturnPlanner {
    ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap()
}

fn truth() -> Flight {
    Flight {
        step: 0.001,
        ..Flight::default()
    }
}

/// The brain of the rally `cfg` on the rally's own clock (offset 0), budget wide open, each
/// decision searched when its observation comes (as the rally does).
fn brain(pl: &ReturnPlanner, cfg: &RallyConfig) -> BallBrain {
    speculating_brain(pl, cfg, 0)
}

/// [`brain`] with each decision's search made `frames` observations ahead of it.
fn speculating_brain(pl: &ReturnPlanner, cfg: &RallyConfig, frames: usize) -> BallBrain {
    BallBrain::with_planner(
        pl.clone(),
        BallBrainConfig {
            decide: DecideConfig::of(cfg),
            clock: ClockRelation::Offset(0.0),
            latency_budget: 1.0,
            speculate_frames: frames,
            ..BallBrainConfig::default()
        },
    )
    .unwrap()
}

/// The joint state the rally commands at `t` (s) for the brain's hit in force: its stroke from
/// rest at the ready configuration, as `rally::execution` runs it; ready without a hit.
fn commanded(pl: &ReturnPlanner, brain: &BallBrain, t: f64) -> JointState {
    let ready = JointState::rest(&pl.ready);
    match brain.hit() {
        Some((hit, t_abs)) => {
            let exec = rally::execution(hit, &ready);
            let t0 = t_abs - hit.hit.t;
            let n = pl.chain().dof();
            let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            exec.sample((t - t0).clamp(0.0, exec.duration()), &mut q, &mut qd, &mut qdd)
                .unwrap();
            JointState { q, qd, qdd }
        }
        None => ready,
    }
}

/// Feeds ball `index`'s observations at their delivery; the hits the brain sent.
fn feed(pl: &ReturnPlanner, cfg: &RallyConfig, b: &mut BallBrain, index: u64, id: u32) -> Vec<HitMsg> {
    let seen = rally::observe_ball(&truth(), cfg, index, None);
    let mut hits = Vec::new();
    for (&t, p) in seen.times.iter().zip(&seen.positions) {
        let now = t + cfg.camera.latency;
        let state = commanded(pl, b, now);
        let obs = ObservationMsg {
            id,
            camera_time: t,
            position: *p,
        };
        match b.observe(&obs, f64::NAN, now, &SpliceAt::at(now, state.clone())) {
            Some(Command::Stroke(st)) => {
                // The stroke starts at the decision (the splice instant offered) from its state.
                assert_eq!(st.start, now);
                let s0 = st.traj.state(0.0).unwrap();
                let gap = [(&s0.q, &state.q), (&s0.qd, &state.qd), (&s0.qdd, &state.qdd)]
                    .iter()
                    .flat_map(|(a, b)| a.iter().zip(b.iter()).map(|(x, y)| (x - y).abs()))
                    .fold(0.0f64, f64::max);
                assert!(
                    gap < 1e-9,
                    "ball {index}: the stroke starts {gap} away from the commanded state"
                );
                hits.push(st.hit)
            }
            Some(c) => panic!("{c:?} in the middle of ball {index}"),
            None => {}
        }
    }
    hits
}

#[test]
fn brain_makes_the_rally_decisions_on_the_rally_observations() {
    let pl = planner();
    let truth = truth();
    let region = ReachRegion::new(pl.chain(), pl.placement, pl.ready.clone(), truth.model.radius).unwrap();
    let cfg = RallyConfig::default();
    let mut b = brain(&pl, &cfg);
    let (mut hit_balls, mut corrected) = (0, 0);
    for i in 0..10u64 {
        let outcome = rally::play(&pl, &region, &truth, &cfg, i);
        let before = b.stats();
        let hits = feed(&pl, &cfg, &mut b, i, 100 + i as u32);
        let after = b.stats();
        // The ball is over (each ball starts at t = 0 on the rally's clock): ready after a hit.
        let over = b.tick(1e3, &JointState::rest(&pl.ready));
        assert_eq!(over.is_some(), !hits.is_empty(), "ball {i}: {over:?}");
        match outcome.planned {
            Some((ball, normal)) => {
                hit_balls += 1;
                let last = hits.last().expect("the rally hit this ball: so must the brain");
                let (hit, t_abs) = b.hit().unwrap();
                // The same hit: the predicted ball at the impact, the face normal, the time.
                assert_eq!(hit.ball, ball, "ball {i}");
                assert_eq!(hit.racket.normal, normal, "ball {i}");
                assert!((t_abs - ball.t).abs() < 1e-12 && (last.t_hit - ball.t).abs() < 1e-12);
                // Sent in the base frame: the racket pose and twist of the planner's hit.
                let r = hit.hit.pose.rotation.matrix();
                assert_eq!(last.rotation[5], r[(1, 2)]);
                assert_eq!(last.centre, <[f64; 3]>::from(hit.hit.pose.translation.vector));
                assert_eq!(last.twist, hit.hit.twist);
                // The correction after the bounce where the rally made one, in the same stroke.
                let sent = (after.planned - before.planned) + (after.corrected - before.corrected);
                assert_eq!(hits.len() as u64, sent);
                assert_eq!(after.corrected - before.corrected, outcome.replans as u64, "ball {i}");
                // (up to two corrections: the rally's second one, `second_correction`)
                if hits.len() >= 2 {
                    corrected += 1;
                    assert!(hits.len() <= 3, "ball {i}: {} hits", hits.len());
                    for h in &hits[1..] {
                        assert_eq!(hits[0].stroke, h.stroke);
                        assert_ne!(hits[0].id, h.id);
                    }
                }
            }
            None => assert!(hits.is_empty(), "ball {i}: {} ({:?})", outcome.status, hits),
        }
        assert_eq!(after.balls - before.balls, 1);
    }
    // The sample exercises both decisions.
    assert!(
        hit_balls >= 6 && corrected >= 3,
        "{hit_balls} balls hit, {corrected} corrected"
    );
    // A new ball id starts a new stroke.
    assert_eq!(b.stats().stale, 0);
}

#[test]
fn a_speculating_brain_decides_from_the_hits_it_found_ahead() {
    let pl = planner();
    let truth = truth();
    let region = ReachRegion::new(pl.chain(), pl.placement, pl.ready.clone(), truth.model.radius).unwrap();
    let cfg = RallyConfig::default();
    let mut b = speculating_brain(&pl, &cfg, 3);
    let mut agree = 0;
    for i in 0..10u64 {
        let outcome = rally::play(&pl, &region, &truth, &cfg, i);
        let hits = feed(&pl, &cfg, &mut b, i, 200 + i as u32);
        agree += (hits.is_empty() == outcome.planned.is_none()) as u32;
        if let (Some((ball, _)), Some(last)) = (outcome.planned, hits.last()) {
            // found ahead and planned again: the rally's hit time but for another candidate
            assert!(
                (last.t_hit - ball.t).abs() < 0.05,
                "ball {i}: {} vs {}",
                last.t_hit,
                ball.t
            );
        }
        b.tick(1e3, &JointState::rest(&pl.ready));
    }
    let s = b.stats();
    // Every decision after a search ahead counted one way or the other; most used its hit.
    let decisions = s.planned + s.corrected;
    assert!(s.speculated >= s.planned && s.planned > 0, "{s:?}");
    assert!(s.speculation_used + s.speculation_unused <= s.speculated, "{s:?}");
    assert!(s.speculation_used * 10 >= decisions * 7, "{s:?}");
    assert!(agree >= 8, "{agree} of 10 balls hit or not as the rally");
    // Without speculation nothing is counted.
    let mut plain = brain(&pl, &cfg);
    feed(&pl, &cfg, &mut plain, 0, 1);
    let p = plain.stats();
    assert_eq!((p.speculated, p.speculation_used, p.speculation_unused), (0, 0, 0));
}

#[test]
fn the_searches_ahead_on_a_worker_thread_give_the_hits_of_those_made_in_line() {
    let pl = planner();
    let cfg = RallyConfig::default();
    let mut inline = speculating_brain(&pl, &cfg, 3);
    // without the search made again a frame before the decision (the worker's own, below)
    let mut worker = BallBrain::with_planner(
        pl.clone(),
        BallBrainConfig {
            decide: DecideConfig::of(&cfg),
            clock: ClockRelation::Offset(0.0),
            latency_budget: 1.0,
            speculate_frames: 3,
            refresh_ahead: false,
            ..BallBrainConfig::default()
        },
    )
    .unwrap();
    assert!(!worker.has_worker());
    worker.spawn_worker(0).unwrap();
    assert!(worker.has_worker());
    let mut same = 0;
    let mut paths = Vec::new();
    for i in 0..10u64 {
        let a = feed(&pl, &cfg, &mut inline, i, 300 + i as u32);
        let b = feed(&pl, &cfg, &mut worker, i, 300 + i as u32);
        let close = a.len() == b.len() && a.iter().zip(&b).all(|(x, y)| (x.t_hit - y.t_hit).abs() < 1e-9);
        same += close as u32;
        paths.extend(worker.decision_path());
        for br in [&mut inline, &mut worker] {
            br.tick(1e3, &JointState::rest(&pl.ready));
        }
    }
    let (s, w) = (inline.stats(), worker.stats());
    // The observations are fed at once: the deciding ones come while the worker still searches,
    // and, without a splice deadline, wait for it to the end.
    assert!(w.speculation_waited >= 1, "{w:?}");
    assert_eq!(w.speculation_pending, 0, "{w:?}");
    assert_eq!((s.speculation_waited, s.speculation_pending), (0, 0), "{s:?}");
    assert_eq!(w.speculated, s.speculated, "{w:?} vs {s:?}");
    assert!(w.speculation_used * 10 >= (w.planned + w.corrected) * 7, "{w:?}");
    // The same searches from the same observations (no budget without a splice deadline): the
    // same hits.
    assert_eq!(same, 10, "{same} of 10 balls with the same hits");
    assert!(paths.contains(&DecisionPath::Held), "{paths:?}");
}

#[test]
fn stale_observations_are_dropped_and_counted() {
    let pl = planner();
    let cfg = RallyConfig::default();
    let mut b = BallBrain::with_planner(
        pl.clone(),
        BallBrainConfig {
            decide: DecideConfig::of(&cfg),
            clock: ClockRelation::Offset(5.0),
            latency_budget: 0.02,
            ..BallBrainConfig::default()
        },
    )
    .unwrap();
    let seen = rally::observe_ball(&truth(), &cfg, 0, None);
    let ready = JointState::rest(&pl.ready);
    // Every observation arrives 25 ms after its exposure (controller = camera + 5 s): all stale,
    // nothing planned.
    for (&t, p) in seen.times.iter().zip(&seen.positions) {
        let obs = ObservationMsg {
            id: 1,
            camera_time: t,
            position: *p,
        };
        assert_eq!(
            b.observe(&obs, f64::NAN, t + 5.025, &SpliceAt::at(t + 5.025, ready.clone())),
            None
        );
    }
    let s = b.stats();
    assert_eq!(
        (s.stale, s.observations, s.planned, s.balls),
        (seen.times.len() as u64, seen.times.len() as u64, 0, 0)
    );
}

#[test]
fn clock_offset_is_the_smallest_delay() {
    let pl = planner();
    let cfg = RallyConfig::default();
    let make = |clock| {
        BallBrain::with_planner(
            pl.clone(),
            BallBrainConfig {
                decide: DecideConfig::of(&cfg),
                clock,
                ..BallBrainConfig::default()
            },
        )
        .unwrap()
    };
    let mut by_send = make(ClockRelation::SendTime);
    let mut by_delay = make(ClockRelation::MinDelay { latency: 0.010 });
    let ready = JointState::rest(&pl.ready);
    // Controller = camera + 100 s; sent 10 ms after the exposure; transit 0.2–1.2 ms.
    let mut smallest = f64::INFINITY;
    for k in 0..50 {
        let t = 0.005 * k as f64;
        let transit = 0.0002 + 0.001 * ((k * 7919 + 13) % 97) as f64 / 97.0;
        smallest = smallest.min(transit);
        let obs = ObservationMsg {
            id: 1,
            camera_time: t,
            position: [1.0, 0.0, 0.2],
        };
        let now = 100.0 + t + 0.010 + transit;
        by_send.observe(&obs, t + 0.010, now, &SpliceAt::at(now, ready.clone()));
        by_delay.observe(&obs, f64::NAN, now, &SpliceAt::at(now, ready.clone()));
    }
    for b in [&by_send, &by_delay] {
        assert!((b.offset().unwrap() - (100.0 + smallest)).abs() < 1e-9);
    }
    // Without a send time, the send-time relation has nothing to go by: nothing is used.
    let mut blind = make(ClockRelation::SendTime);
    let obs = ObservationMsg {
        id: 1,
        camera_time: 0.0,
        position: [1.0, 0.0, 0.2],
    };
    assert_eq!(
        blind.observe(&obs, f64::NAN, 1.0, &SpliceAt::at(1.0, ready.clone())),
        None
    );
    assert_eq!(blind.offset(), None);
}

#[test]
fn ready_after_the_hit_and_when_the_ball_is_lost() {
    let pl = planner();
    let cfg = RallyConfig::default();
    let mut b = brain(&pl, &cfg);
    let ready = JointState::rest(&pl.ready);
    // Ball 0 is hit (see the rally test): ready `ready_after` past the hit, once.
    let hits = feed(&pl, &cfg, &mut b, 0, 7);
    let t_hit = hits.last().expect("ball 0 is hit").t_hit;
    assert_eq!(b.tick(t_hit + 0.05, &ready), None);
    assert_eq!(b.tick(t_hit + 0.061, &ready), Some(Command::Ready));
    assert_eq!(b.tick(t_hit + 0.07, &ready), None);
    // Late observations of a finished ball change nothing.
    let obs = ObservationMsg {
        id: 7,
        camera_time: t_hit + 0.07,
        position: [-1.5, 0.0, 0.2],
    };
    let ignored = b.stats().ignored;
    assert_eq!(
        b.observe(&obs, f64::NAN, t_hit + 0.08, &SpliceAt::at(t_hit + 0.08, ready.clone())),
        None
    );
    assert_eq!(b.stats().ignored, ignored + 1);
    // A new ball seen for 10 frames, then silence: lost after `lost_after`, ready, counted.
    let seen = rally::observe_ball(&truth(), &cfg, 1, None);
    let base = 10.0;
    for (&t, p) in seen.times.iter().zip(&seen.positions).take(10) {
        let obs = ObservationMsg {
            id: 8,
            camera_time: base + t,
            position: *p,
        };
        assert_eq!(
            b.observe(
                &obs,
                f64::NAN,
                base + t + 0.01,
                &SpliceAt::at(base + t + 0.01, ready.clone())
            ),
            None
        );
    }
    let last = base + seen.times[9] + 0.01;
    assert_eq!(b.tick(last + 0.04, &ready), None);
    assert_eq!(b.tick(last + 0.051, &ready), Some(Command::Ready));
    assert_eq!(b.stats().lost, 1);
    // Statuses of the brain's hits other than accepted are counted.
    b.outcome(&StatusMsg {
        id: hits[0].id,
        status: PlanStatus::TooEarly,
        earliest_t_hit: t_hit + 0.1,
        t_hit: f64::NAN,
        planning_time: 1e-4,
    });
    b.outcome(&StatusMsg {
        id: 9999,
        status: PlanStatus::Rejected,
        earliest_t_hit: f64::NAN,
        t_hit: f64::NAN,
        planning_time: 1e-4,
    });
    assert_eq!(b.stats().refused, 1);
}

#[test]
fn a_new_ball_calls_off_the_stroke_still_to_come() {
    let pl = planner();
    let cfg = RallyConfig::default();
    let mut b = brain(&pl, &cfg);
    let seen = rally::observe_ball(&truth(), &cfg, 0, None);
    let ready = JointState::rest(&pl.ready);
    let first = DecideConfig::of(&cfg).window_frames;
    let mut sent = None;
    for (&t, p) in seen.times.iter().zip(&seen.positions).take(first) {
        let obs = ObservationMsg {
            id: 1,
            camera_time: t,
            position: *p,
        };
        sent = b
            .observe(&obs, f64::NAN, t + 0.01, &SpliceAt::at(t + 0.01, ready.clone()))
            .or(sent);
    }
    assert!(matches!(sent, Some(Command::Stroke(_))), "ball 0's first plan hits");
    let t = seen.times[first];
    let obs = ObservationMsg {
        id: 2,
        camera_time: t,
        position: seen.positions[first],
    };
    assert_eq!(
        b.observe(&obs, f64::NAN, t + 0.01, &SpliceAt::at(t + 0.01, ready.clone())),
        Some(Command::Ready)
    );
    assert_eq!(b.stats().balls, 2);
}

#[test]
fn bad_settings_are_refused_with_their_name() {
    let pl = planner();
    let bad = [
        BallBrainConfig {
            latency_budget: 0.0,
            ..BallBrainConfig::default()
        },
        BallBrainConfig {
            lost_after: f64::NAN,
            ..BallBrainConfig::default()
        },
        BallBrainConfig {
            clock: ClockRelation::Offset(f64::INFINITY),
            ..BallBrainConfig::default()
        },
        BallBrainConfig {
            decide: DecideConfig {
                target: [-0.5, 0.0],
                ..DecideConfig::default()
            },
            ..BallBrainConfig::default()
        },
    ];
    for (cfg, name) in bad.iter().zip(["latency_budget", "lost_after", "clock", "target"]) {
        let e = BallBrain::with_planner(pl.clone(), *cfg).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
    // A robot without analytic IK cannot play balls.
    assert!(BallBrain::new(ttkin::robots::arm4(), BallBrainConfig::default()).is_err());
}

#[test]
fn the_rally_scoring_of_the_brains_strokes_is_the_rallys_outcome() {
    // The HIL rally scores a ball from sampled joint states (`rally::score_executed`); here the
    // samples are the brain's strokes as the rally executes them (1 ms, the first hit's stroke
    // then the correction's from its decision time): the outcome must be the rally's.
    let pl = planner();
    let truth = truth();
    let region = ReachRegion::new(pl.chain(), pl.placement, pl.ready.clone(), truth.model.radius).unwrap();
    let cfg = RallyConfig::default();
    let ready = JointState::rest(&pl.ready);
    let mut b = brain(&pl, &cfg);
    let mut same = 0;
    for i in 0..10u64 {
        let outcome = rally::play(&pl, &region, &truth, &cfg, i);
        let seen = rally::observe_ball(&truth, &cfg, i, None);
        let mut pieces = Vec::new();
        for (&t, p) in seen.times.iter().zip(&seen.positions) {
            let now = t + cfg.camera.latency;
            let state = commanded(&pl, &b, now);
            let obs = ObservationMsg {
                id: 200 + i as u32,
                camera_time: t,
                position: *p,
            };
            if let Some(Command::Stroke(st)) = b.observe(&obs, f64::NAN, now, &SpliceAt::at(now, state.clone())) {
                // The stroke handed to the runtime is the one the rally executes.
                let (hit, t_abs) = b.hit().unwrap();
                assert_eq!(st.traj, rally::execution(hit, &ready));
                assert!((st.start - (t_abs - hit.hit.t)).abs() < 1e-12 && st.hit.t_hit == t_abs);
                pieces.push((st.start, st.traj, t_abs));
            }
        }
        b.tick(1e3, &ready);
        let Some(&(_, _, t_hit)) = pieces.last() else {
            assert!(!outcome.returned);
            same += 1;
            continue;
        };
        let n = pl.chain().dof();
        let t_start = pieces[0].0;
        let k = ((t_hit + 0.07 - t_start) / 1e-3).ceil() as usize;
        let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut ex = rally::Executed {
            dof: n,
            t: Vec::new(),
            q: Vec::new(),
            qd: Vec::new(),
        };
        for j in 0..k {
            let t = t_start + j as f64 * 1e-3;
            let (t0, traj, _) = pieces.iter().rev().find(|p| p.0 <= t).unwrap_or(&pieces[0]);
            traj.sample((t - t0).clamp(0.0, traj.duration()), &mut q, &mut qd, &mut qdd)
                .unwrap();
            ex.t.push(t);
            ex.q.extend_from_slice(&q);
            ex.qd.extend_from_slice(&qd);
        }
        let sc = rally::score_executed(&pl, &seen.world, cfg.target, &seen.incoming, t_hit, &ex, 0.0).unwrap();
        assert_eq!(sc.contact, outcome.contact, "ball {i}");
        if sc.returned == outcome.returned {
            same += 1;
        }
        if sc.returned && outcome.returned {
            let d = (0..2)
                .map(|k| (sc.landing[k] - outcome.landing[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d < 5e-3, "ball {i}: landing {:?} vs {:?}", sc.landing, outcome.landing);
        }
        if sc.contact {
            assert!(
                (sc.racket_error - outcome.racket_error).abs() < 2e-3,
                "ball {i}: {} vs {}",
                sc.racket_error,
                outcome.racket_error
            );
        }
    }
    assert!(same >= 9, "{same}/10 balls scored as the rally did");
    // Bad samples are refused with what to fix.
    let bad = rally::Executed {
        dof: 6,
        t: vec![0.0, 0.0],
        q: vec![0.0; 12],
        qd: vec![0.0; 12],
    };
    let seen = rally::observe_ball(&truth, &cfg, 0, None);
    let e = rally::score_executed(&pl, &seen.world, cfg.target, &seen.incoming, 0.5, &bad, 0.0).unwrap_err();
    assert!(e.to_string().contains("increase"), "{e}");
}

#[test]
fn a_late_decision_waits_for_the_next_frame_and_keeps_its_hit() {
    use ttcan::online::brain::Observed;
    let pl = planner();
    let cfg = RallyConfig::default();
    let mut b = brain(&pl, &cfg);
    let (mut tried, mut refined) = (0, 0);
    for i in 0..10u64 {
        let id = 200 + i as u32;
        let seen = rally::observe_ball(&truth(), &cfg, i, None);
        let frames: Vec<(f64, [f64; 3])> = seen.times.iter().copied().zip(seen.positions.iter().copied()).collect();
        for (k, &(t, p)) in frames.iter().enumerate() {
            let now = t + cfg.camera.latency;
            let state = commanded(&pl, &b, now);
            let obs = ObservationMsg {
                id,
                camera_time: t,
                position: p,
            };
            let Some(Command::Stroke(first)) = b.observe(&obs, f64::NAN, now, &SpliceAt::at(now, state)) else {
                // nothing to wait for without a stroke
                assert!(b.awaits().is_none() || b.hit().is_some());
                continue;
            };
            // The stroke came too late for its splice: the brain waits for this ball's next frame.
            let aw = b.awaits().expect("a decision to plan again");
            assert_eq!(aw.ball, id);
            assert!(aw.wait > 0.0 && aw.wait <= 2.0 / cfg.camera.rate_hz);
            let Some(&(tn, pn)) = frames.get(k + 1) else { break };
            tried += 1;
            let arrival = tn + cfg.camera.latency;
            let other = Observed {
                obs: ObservationMsg {
                    id: id + 1000,
                    camera_time: tn,
                    position: pn,
                },
                sent: f64::NAN,
                arrival,
            };
            let next = Observed {
                obs: ObservationMsg {
                    id,
                    camera_time: tn,
                    position: pn,
                },
                sent: f64::NAN,
                arrival,
            };
            let at = arrival + 1e-3;
            let state = commanded(&pl, &b, at);
            let before = b.stats().refined;
            match b.refine(&[other, next], &SpliceAt::at(at, state.clone())) {
                Some((Command::Stroke(st), used)) => {
                    refined += 1;
                    // decided on the next frame of this ball (not the other ball's)
                    assert_eq!(used, 1);
                    assert_eq!(b.stats().refined, before + 1);
                    // the same hit time, the same stroke; from the state at the new splice
                    assert!((st.hit.t_hit - first.hit.t_hit).abs() < 1e-9);
                    assert_eq!(st.hit.stroke, first.hit.stroke);
                    assert_ne!(st.hit.id, first.hit.id);
                    assert_eq!(st.start, at);
                    let s0 = st.traj.state(0.0).unwrap();
                    for j in 0..s0.q.len() {
                        assert!((s0.q[j] - state.q[j]).abs() < 1e-9 && (s0.qd[j] - state.qd[j]).abs() < 1e-9);
                    }
                    // planned again once: a second late stroke is retried, not refined
                    assert!(b.awaits().is_none());
                }
                other => assert!(other.is_none(), "{other:?}"),
            }
            assert!(b.refine(&[next], &SpliceAt::at(at, commanded(&pl, &b, at))).is_none());
        }
        b.tick(1e3, &JointState::rest(&pl.ready));
    }
    assert!(
        tried >= 6 && refined * 10 >= tried * 7,
        "{refined} of {tried} planned again"
    );
}

/// The search ahead made again one frame before each decision (`BallDecider::refresh`) on the
/// worker thread only, once per decision that had a search ahead, and counted.
#[test]
fn the_worker_makes_each_search_ahead_again_a_frame_before_its_decision() {
    let pl = planner();
    let cfg = RallyConfig::default();
    let mut inline = speculating_brain(&pl, &cfg, 3);
    let mut worker = speculating_brain(&pl, &cfg, 3);
    worker.spawn_worker(0).unwrap();
    let mut one = speculating_brain(&pl, &cfg, 1);
    one.spawn_worker(0).unwrap();
    for i in 0..6u64 {
        for br in [&mut inline, &mut worker, &mut one] {
            feed(&pl, &cfg, br, i, 500 + i as u32);
            br.tick(1e3, &JointState::rest(&pl.ready));
        }
    }
    let (s, w, o) = (inline.stats(), worker.stats(), one.stats());
    assert_eq!(s.refreshed, 0, "in line: never {s:?}");
    assert_eq!(
        o.refreshed, 0,
        "a search ahead one frame before: nothing to make again {o:?}"
    );
    // one per decision with a search ahead (first plans and corrections)
    assert!(w.refreshed >= w.planned && w.refreshed <= w.speculated, "{w:?}");
    assert!(w.speculation_used * 10 >= (w.planned + w.corrected) * 7, "{w:?}");
}
