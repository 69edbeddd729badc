use ttkin::ball::flight::Flight;
use ttkin::ball::hitplan::HitPlanner;
use ttkin::ball::rally::{self, RallyConfig};
#[test]
fn dbg() {
    let pl = HitPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap();
    let truth = Flight { step: 0.001, ..Flight::default() };
    for period in [0.0, 0.04] {
        let cfg = RallyConfig { seed: 5, replan_period: period, ..RallyConfig::default() };
        let out = rally::rally(&pl, &truth, &cfg, 60);
        let ir = out.iter().filter(|o| o.in_reach).count();
        let ret = out.iter().filter(|o| o.in_reach && o.returned).count();
        eprintln!("period {period}: {ret}/{ir}");
        for (i, o) in out.iter().enumerate().filter(|(_, o)| o.in_reach && !o.returned) {
            eprintln!("  {i} {} replans {} racket_err {:.3} verr {:.3}", o.status, o.replans, o.racket_error, o.velocity_error);
        }
    }
}
