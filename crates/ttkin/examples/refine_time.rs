//! Decision times of the controller's ball mode, off-line and in release: `refine_time [N] [SEED]`
//! (defaults 2000, 0). For the rally's balls (`observe_ball`, the rally's camera), the thread CPU
//! time of the first plan and of the correction (`BallDecider::observe`, the full search), and of
//! each decision planned again from the next frame without a search (`BallDecider::refine`, what
//! `ttctl --online ball` does when a decision came after its splice cycle): percentiles, and how
//! many refinements found the hit again. The stroke under way at the correction is the first
//! hit's (`rally::execution`), as in the rally. `LAST_RESORT=0`: the planner without its last
//! resort (`ReturnPlanner::last_resort_offsets`), for a before/after on the same load.
mod common;

use common::{cpu_us, row, state_of};
use ttkin::ball::decide::{BallDecider, DecideConfig, Decision};
use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::ReturnPlanner;
use ttkin::ball::rally::{self, observe_ball, RallyConfig};
use ttkin::traj::{JointState, JointTrajectory};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = args.get(1).map_or(2000, |a| a.parse().expect("N"));
    let seed: u64 = args.get(2).map_or(0, |a| a.parse().expect("SEED"));
    let mut pl = ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).expect("gantry6");
    if std::env::var("LAST_RESORT").is_ok_and(|v| v == "0") {
        pl.last_resort_offsets.clear();
    }
    let cfg = RallyConfig {
        seed,
        ..RallyConfig::default()
    };
    let truth = Flight {
        step: rally::TRUTH_STEP,
        ..pl.flight
    };
    let latency = cfg.camera.latency;
    let ready = JointState::rest(&pl.ready);
    let (mut first, mut first_refine, mut corr, mut corr_refine) = (vec![], vec![], vec![], vec![]);
    let (mut first_ok, mut corr_ok) = (0usize, 0usize);
    for i in 0..n {
        let o = observe_ball(&truth, &cfg, i, None);
        let mut d = BallDecider::new(&pl, DecideConfig::of(&cfg));
        // the stroke under way: (start time, trajectory) of the first hit
        let mut stroke: Option<(f64, JointTrajectory)> = None;
        for k in 0..o.times.len() {
            if d.done() {
                break;
            }
            let (t, p) = (o.times[k], o.positions[k]);
            let now = t + latency;
            let (decision, us) = cpu_us(|| d.observe(&pl, t, p, now, &|tc| state_of(&stroke, &ready, tc)));
            let (hit, is_first) = match decision {
                Some(Decision::Planned { now, plan, .. }) => {
                    first.push(us);
                    let h = plan
                        .hit
                        .filter(|_| plan.status == ttkin::ball::hitplan::ReturnStatus::Ok);
                    if let Some(h) = &h {
                        stroke = Some((now, rally::execution(h, &ready)));
                    }
                    (h, true)
                }
                Some(Decision::Corrected { hit, .. }) => {
                    corr.push(us);
                    (hit.map(|h| *h), false)
                }
                _ => (None, false),
            };
            // planned again from the next frame, delivered one frame later, 1 ms after it
            if let (Some(_), Some(&tn)) = (hit, o.times.get(k + 1)) {
                let now2 = tn + latency + 1e-3;
                let start = state_of(&stroke, &ready, now2);
                let (again, us) = cpu_us(|| d.refine(&pl, &[(tn, o.positions[k + 1])], now2, &start));
                if is_first {
                    first_refine.push(us);
                    first_ok += again.is_some() as usize;
                } else {
                    corr_refine.push(us);
                    corr_ok += again.is_some() as usize;
                }
            }
        }
    }
    println!("{n} balls, seed {seed}: thread CPU time per decision (release)");
    row("first plan (search)", &mut first);
    row("first plan again (refine)", &mut first_refine);
    row("correction (search)", &mut corr);
    row("correction again (refine)", &mut corr_refine);
    println!(
        "refined: {first_ok} of {} first plans, {corr_ok} of {} corrections found their hit again",
        first_refine.len(),
        corr_refine.len()
    );
}
