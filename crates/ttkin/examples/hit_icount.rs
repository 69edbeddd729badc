//! Fixed work of the gantry6 hit planner for instruction counts under valgrind and for comparing
//! plans bit for bit: `hit_icount plan N` plans N on-time hits (single thread),
//! `hit_icount dump SET` prints every product of 1,000 plans of set `ontime`, `early` or `moving`
//! with round-trip floats.
use std::hint::black_box;
use ttkin::hit::{HitOptions, HitPlan, HitPlanner};

#[path = "../tests/support/gantry_hits.rs"]
mod gantry_hits;

fn dump(p: &HitPlan) {
    print!(
        "{} {} {:?} {:?} {} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        p.status.name(),
        p.branches,
        p.t_hit,
        p.earliest_t_hit,
        p.profile.name(),
        p.return_duration,
        p.q_hit,
        p.qd_hit,
        p.sigma_min,
        p.peak_effort,
        p.effort_ratio,
        p.violations,
        p.message,
        p.ready,
    );
    if let Some(t) = &p.trajectory {
        print!(" knots {:?}", t.knots());
        for s in 0..t.segments() {
            for j in 0..t.dof() {
                print!(" {:?}", t.coefficients(s, j));
            }
        }
    }
    println!();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let planner = HitPlanner::new(&ttkin::robots::gantry6(), HitOptions::default()).unwrap();
    match args[1].as_str() {
        "plan" => {
            let n: usize = args[2].parse().unwrap();
            let hs = gantry_hits::hits(256, 0.6, 7);
            for i in 0..n {
                black_box(planner.plan(black_box(&hs[i % hs.len()]), None, None).unwrap());
            }
        }
        "dump" => {
            let state = gantry_hits::set(&args[2]).1;
            for h in gantry_hits::set_hits(&args[2]) {
                dump(&planner.plan(&h, state.as_ref(), None).unwrap());
            }
        }
        other => panic!("unknown op {other}"),
    }
}
