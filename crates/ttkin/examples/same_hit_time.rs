//! The deciding frame's re-plan of a held hit, off-line and in release: `same_hit_time [N] [SEED]
//! [REPEAT]` (defaults 200, 0, 1). For the rally's balls (`observe_ball`), the hit searched 3
//! observations ahead of the first decision (`BallDecider::speculate`) is planned again from the
//! decision's own estimate (`ReturnPlanner::plan_same_hit`, a stroke from rest at ready), `REPEAT`
//! times each. Prints the least thread CPU time of each ball's runs (its cost without the
//! machine's load) and how often it gave a hit, at the held hit's return time.
mod common;

use common::{cpu_us, row};
use ttkin::ball::decide::{BallDecider, DecideConfig, Decision};
use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::ReturnPlanner;
use ttkin::ball::rally::{self, observe_ball, RallyConfig};
use ttkin::traj::JointState;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = args.get(1).map_or(200, |a| a.parse().expect("N"));
    let seed: u64 = args.get(2).map_or(0, |a| a.parse().expect("SEED"));
    let repeat: usize = args.get(3).map_or(1, |a| a.parse().expect("REPEAT"));
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
    let ready = JointState::rest(&pl.ready);
    let (mut ok_us, mut fail_us) = (vec![], vec![]);
    let mut same = 0usize;
    for i in 0..n {
        let o = observe_ball(&truth, &cfg, i, None);
        let mut d = BallDecider::new(&pl, dc);
        let mut held = None;
        for (&t, &p) in o.times.iter().zip(&o.positions) {
            let now = t + cfg.camera.latency;
            let decision = d.observe(&pl, t, p, now, &|_| ready.clone());
            if d.speculation_due(3) {
                if d.speculate(&pl, now, &ready) {
                    held = d.held().cloned();
                }
                continue;
            }
            let Some(Decision::Planned { now, estimate, .. }) = decision else {
                continue;
            };
            let Some(h) = held.take() else {
                break;
            };
            // the least of `repeat` runs: the input's own cost, without the machine's load
            let mut least = f64::INFINITY;
            let mut again = None;
            for _ in 0..repeat.max(1) {
                let (p, us) = cpu_us(|| pl.plan_same_hit(&estimate.state, now, &ready, false, &h.hit, h.t_hit));
                least = least.min(us);
                again = Some(p);
            }
            match again.and_then(|p| p.ok()).and_then(|p| p.hit) {
                Some(a) => {
                    ok_us.push(least);
                    // the held hit's return time: its shot within 0.5 m/s of the held one's
                    if (a.v_out - h.hit.v_out).norm() < 0.5 {
                        same += 1;
                    }
                }
                None => fail_us.push(least),
            }
            break;
        }
    }
    println!("{n} balls, seed {seed}: plan_same_hit thread CPU time (release, least of {repeat} runs)");
    row("plan_same_hit, a hit", &mut ok_us);
    row("plan_same_hit, none", &mut fail_us);
    println!("{same} of {} hits at the held hit's return time", ok_us.len());
}
