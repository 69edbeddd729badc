//! The gantry6 hit planner against stored plans: every 20th plan of the three hit sets of
//! `support/gantry_hits.rs` (on time, too early, from a moving state), as main's planner made
//! them before the speed work of issue 12 (`data/hit_plans.txt`; regenerated from that planner with
//! gantry6's issue-10 drives, which change the armatures and so the efforts; regenerated again for
//! issue 28, whose certified effort check and drive effort limits change the efforts and some
//! statuses; regenerated for the certified check's cheap child bounds and same-time leg alternatives, which move
//! some too-early times by up to 0.1 % and efforts within the tolerance, no status or profile:
//! `TTKIN_WRITE_HIT_PLANS=1 cargo test -p ttkin --test hit` rewrites it).
//! Status, branch count, profile and violation count must match exactly, every number to
//! 1e-10·(1 + |value|) (the speed work keeps them bit for bit on the machine that made them).

use ttkin::hit::{HitOptions, HitPlan, HitPlanner};

#[path = "support/gantry_hits.rs"]
mod gantry_hits;

const STORED: &str = include_str!("data/hit_plans.txt");

fn close(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || a == b || (a - b).abs() <= 1e-10 * (1.0 + b.abs())
}

/// The numbers of a plan in the stored order (see the file's header).
fn numbers(p: &HitPlan) -> Vec<f64> {
    let mut v = vec![
        p.t_hit,
        p.earliest_t_hit,
        p.return_duration,
        p.sigma_min,
        p.effort_ratio,
    ];
    v.extend(&p.q_hit);
    v.extend(&p.qd_hit);
    v.extend(&p.peak_effort);
    let mut q = [0.0; 6];
    let (mut qd, mut qdd) = ([0.0; 6], [0.0; 6]);
    for k in 0..5 {
        match &p.trajectory {
            Some(t) => {
                t.sample(t.duration() * k as f64 / 4.0, &mut q, &mut qd, &mut qdd)
                    .unwrap();
                v.extend(&q);
            }
            None => v.extend([f64::NAN; 6]),
        }
    }
    v
}

/// Rewrites `data/hit_plans.txt` from the current planner (the same hits and header).
fn write_stored(planner: &HitPlanner) {
    let mut out: String = STORED
        .lines()
        .take_while(|l| l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    for name in gantry_hits::SETS {
        let hits = gantry_hits::set_hits(name);
        let state = gantry_hits::set(name).1;
        for i in (0..hits.len()).step_by(20) {
            let p = planner.plan(&hits[i], state.as_ref(), None).unwrap();
            out += &format!(
                "{name} {i} {} {} {} {}",
                p.status.name(),
                p.branches,
                p.profile.name(),
                p.violations.len()
            );
            for x in numbers(&p) {
                out += &format!(" {x:?}");
            }
            out += "\n";
        }
    }
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/hit_plans.txt");
    std::fs::write(path, out).unwrap();
}

#[test]
fn plans_match_the_stored_ones() {
    let planner = HitPlanner::new(&ttkin::robots::gantry6(), HitOptions::default()).unwrap();
    if std::env::var_os("TTKIN_WRITE_HIT_PLANS").is_some() {
        write_stored(&planner);
        return;
    }
    let mut checked = 0;
    for name in gantry_hits::SETS {
        let hits = gantry_hits::set_hits(name);
        let state = gantry_hits::set(name).1;
        for line in STORED.lines().filter(|l| l.starts_with(&format!("{name} "))) {
            let f: Vec<&str> = line.split(' ').collect();
            let i: usize = f[1].parse().unwrap();
            let p = planner.plan(&hits[i], state.as_ref(), None).unwrap();
            let what = format!("{name} hit {i}");
            assert_eq!(p.status.name(), f[2], "{what}: status ({})", p.message);
            assert_eq!(p.branches.to_string(), f[3], "{what}: branches");
            assert_eq!(p.profile.name(), f[4], "{what}: profile");
            assert_eq!(p.violations.len().to_string(), f[5], "{what}: violations");
            let stored: Vec<f64> = f[6..].iter().map(|s| s.parse().unwrap()).collect();
            let got = numbers(&p);
            assert_eq!(got.len(), stored.len(), "{what}: number count");
            for (k, (a, b)) in got.iter().zip(&stored).enumerate() {
                assert!(close(*a, *b), "{what}: number {k} is {a}, stored {b}");
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 150);
}

#[test]
fn ok_plans_stay_within_the_speed_the_drives_deliver() {
    // Issue 28, "one truth for what a joint can do", for speed: gantry6's θ6 file limit (20 rad/s)
    // is above what its drive reaches (ttkin::speed, ≈ 13.6 rad/s), so the planner must keep every
    // `ok` stroke (hit leg and return) within the drive's speed, sampled at 10 kHz.
    let chain = ttkin::robots::gantry6();
    let drive = ttkin::speed::drive_velocity_limits(&chain);
    assert!(drive[5] < chain.joints()[5].limits().velocity.unwrap(), "{drive:?}");
    let planner = HitPlanner::new(&chain, HitOptions::default()).unwrap();
    let (mut ok, mut fast) = (0, 0);
    let (mut qd, mut q, mut qdd) = ([0.0; 6], [0.0; 6], [0.0; 6]);
    for name in gantry_hits::SETS {
        let hits = gantry_hits::set_hits(name);
        let state = gantry_hits::set(name).1;
        for hit in hits.iter().step_by(4) {
            let p = planner.plan(hit, state.as_ref(), None).unwrap();
            if !p.ok() {
                continue;
            }
            ok += 1;
            let t = p.trajectory.as_ref().unwrap();
            let steps = (t.duration() * 1e4).ceil() as usize;
            let mut peak = [0.0f64; 6];
            for k in 0..=steps {
                t.sample((k as f64 * 1e-4).min(t.duration()), &mut q, &mut qd, &mut qdd)
                    .unwrap();
                for j in 0..6 {
                    peak[j] = peak[j].max(qd[j].abs());
                }
            }
            for j in 0..6 {
                assert!(
                    peak[j] <= drive[j] * (1.0 + 1e-9),
                    "{name}: joint {j} at {} > {}",
                    peak[j],
                    drive[j]
                );
            }
            if peak[5] > 0.5 * drive[5] {
                fast += 1;
            }
        }
    }
    // Enough plans, some of them driving θ6 fast, for the bound to mean something.
    assert!(
        ok > 200 && fast > 0,
        "{ok} ok plans, {fast} with θ6 above half its drive speed"
    );
}
