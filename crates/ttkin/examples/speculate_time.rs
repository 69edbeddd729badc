//! The controller's speculative decisions, off-line and in release: `speculate_time [N] [SEED]
//! [FRAMES]` (defaults 1000, 0, 3). For the rally's balls (`observe_ball`, the rally's camera),
//! two deciders side by side: the rally's (every decision a full search) and one that searches
//! `FRAMES` observations ahead of each decision (`BallDecider::speculate`) and at the deciding
//! observation only plans that hit again (`ReturnPlanner::plan_same_hit`), as
//! `ttctl --online ball` does. Prints the thread CPU time of the speculation and of the deciding
//! observation on both, how often the held hit was used, and how the two deciders' hits
//! compare (hit or none, hit time, landing point).
mod common;

use common::{cpu_us, row, state_of};
use ttkin::ball::decide::{BallDecider, DecideConfig, Decision};
use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::{ReturnHit, ReturnPlanner, ReturnStatus};
use ttkin::ball::rally::{self, observe_ball, RallyConfig};
use ttkin::traj::{JointState, JointTrajectory};

/// One decider over one ball's observations: the decisions' hits (first, correction; absolute
/// time), CPU times, and the held hits' use.
#[derive(Default)]
struct Run {
    hits: Vec<Option<(ReturnHit, f64)>>,
    decide_us: Vec<f64>,
    speculate_us: Vec<f64>,
    used: Vec<Option<bool>>,
}

fn run(pl: &ReturnPlanner, dc: DecideConfig, times: &[f64], pos: &[[f64; 3]], latency: f64, frames: usize) -> Run {
    let ready = JointState::rest(&pl.ready);
    let mut d = BallDecider::new(pl, dc);
    let mut stroke: Option<(f64, JointTrajectory)> = None;
    let mut out = Run::default();
    for (&t, &p) in times.iter().zip(pos) {
        if d.done() {
            break;
        }
        let now = t + latency;
        let (decision, us) = cpu_us(|| d.observe(pl, t, p, now, &|tc| state_of(&stroke, &ready, tc)));
        let hit = match decision {
            Some(Decision::Planned { now, plan, .. }) => {
                let h = plan.hit.filter(|_| plan.status == ReturnStatus::Ok);
                if let Some(h) = &h {
                    stroke = Some((now, rally::execution(h, &ready)));
                }
                Some(h.map(|h| (now + h.hit.t, h)))
            }
            Some(Decision::Corrected { now, hit }) => Some(hit.map(|h| (now + h.hit.t, *h))),
            _ => None,
        };
        if let Some(h) = hit {
            out.hits.push(h.map(|(t, h)| (h, t)));
            out.decide_us.push(us);
            out.used.push(d.speculation_used());
        } else if d.speculation_due(frames) {
            let start = state_of(&stroke, &ready, now);
            let (_, us) = cpu_us(|| d.speculate(pl, now, &start));
            out.speculate_us.push(us);
        }
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = args.get(1).map_or(1000, |a| a.parse().expect("N"));
    let seed: u64 = args.get(2).map_or(0, |a| a.parse().expect("SEED"));
    let frames: usize = args.get(3).map_or(3, |a| a.parse().expect("FRAMES"));
    let pl = ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).expect("gantry6");
    let cfg = RallyConfig {
        seed,
        ..RallyConfig::default()
    };
    let truth = Flight {
        step: rally::TRUTH_STEP,
        ..pl.flight
    };
    let dc = DecideConfig::of(&cfg);
    let latency = cfg.camera.latency;
    let (mut full_us, mut spec_us) = (vec![], vec![]);
    let (mut used_us, mut unused_us, mut none_us) = (vec![], vec![], vec![]);
    let (mut used, mut unused, mut none_held) = (0usize, 0usize, 0usize);
    let (mut both, mut only_full, mut only_spec, mut neither) = (0usize, 0usize, 0usize, 0usize);
    let (mut dt, mut dland) = (vec![], vec![]);
    for i in 0..n {
        let o = observe_ball(&truth, &cfg, i, None);
        let full = run(&pl, dc, &o.times, &o.positions, latency, 0);
        let spec = run(&pl, dc, &o.times, &o.positions, latency, frames);
        full_us.extend(&full.decide_us);
        spec_us.extend(&spec.speculate_us);
        for (u, us) in spec.used.iter().zip(&spec.decide_us) {
            match u {
                Some(true) => (used += 1, used_us.push(*us)),
                Some(false) => (unused += 1, unused_us.push(*us)),
                None => (none_held += 1, none_us.push(*us)),
            };
        }
        // the last hit in force of each (the correction's when it made one)
        let last = |r: &Run| r.hits.iter().rev().flatten().next().cloned();
        match (last(&full), last(&spec)) {
            (Some((a, ta)), Some((b, tb))) => {
                both += 1;
                dt.push((ta - tb).abs() * 1e6);
                dland.push((a.landing - b.landing).norm() * 1e6);
            }
            (Some(_), None) => only_full += 1,
            (None, Some(_)) => only_spec += 1,
            (None, None) => neither += 1,
        }
    }
    println!("{n} balls, seed {seed}, speculation {frames} frames ahead: thread CPU time (release)");
    row("decision, full search (rally)", &mut full_us);
    row("speculation (search, ahead)", &mut spec_us);
    row("decision, held hit used", &mut used_us);
    row("decision, held hit not used", &mut unused_us);
    row("decision, no hit held", &mut none_us);
    println!("held hit used by {used} decisions, not used by {unused}, none held for {none_held}");
    println!("final hit: both {both}, rally only {only_full}, speculative only {only_spec}, neither {neither}");
    row("|hit time difference| (µs)", &mut dt);
    row("|landing difference| (µm)", &mut dland);
}
