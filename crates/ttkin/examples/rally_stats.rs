//! The 10k-ball rally in release, with the in-reach failures classified, for iterating on the
//! hit planner in seconds: `rally_stats [N] [SEED]` (defaults 10000, 0).
//!
//! Prints the counts of `ttmanip rally` (in reach, returned, return rate, statuses of the in-reach
//! failures) and, for every in-reach ball the planner called `infeasible`, the deepest stage any
//! candidate reached when every 10 ms sample of the estimated flight in the search volume, every
//! return time and the planner's rolls are tried with the planner's own pieces (shooting, racket
//! inverse, IK, q̇ = J⁻¹V, the hit leg): `no_candidate`, `no_shot`, `no_ik`, `singular`, `speed`
//! (some |q̇_i| above its limit on every solution), `time_bound` (the region's per-joint minimum
//! time exceeds the time left), `leg` (no hit leg within the limits), `feasible` (a hit exists
//! that the planner's search did not try; with the effort check on, mostly a hit whose stroke exceeds
//! the drives' torque). Also the median planning CPU time.
use nalgebra::Vector3;
use rayon::prelude::*;
use ttkin::ball::flight::{BallState, Flight};
use ttkin::ball::hitplan::{shoot, ReturnPlanner};
use ttkin::ball::rally::{self, RallyConfig, WorldSpread};
use ttkin::ball::reach::{min_joint_time, walk_after_bounce, Reach, ReachRegion};
use ttkin::hit::leg::hit_leg;
use ttkin::ik::{joint_velocity, Analytic, LimitFilter};
use ttkin::traj::JointState;

thread_local! {
    /// Smallest joint-limit excess (m or rad) of any IK branch of the shots seen by `deepest`.
    static EXCESS: std::cell::Cell<f64> = const { std::cell::Cell::new(f64::INFINITY) };
}

const STAGES: [&str; 8] = [
    "no_candidate",
    "no_shot",
    "no_ik",
    "singular",
    "speed",
    "time_bound",
    "leg",
    "feasible",
];

/// Deepest stage (index into `STAGES`) any candidate of `ball` planned at `now` reaches.
fn deepest(pl: &ReturnPlanner, ik: &Analytic, ball: &BallState, now: f64, target: [f64; 2]) -> usize {
    let m = pl.search_margin;
    let reach = Reach {
        lo: pl.reach.lo - Vector3::repeat(m),
        hi: pl.reach.hi + Vector3::repeat(m),
    };
    let mut list = Vec::new();
    walk_after_bounce(&pl.flight, ball, 0.01, false, |s| {
        if s.t >= now + pl.min_stroke_time && reach.contains(&s.p) {
            list.push(*s);
        }
        s.p.x >= pl.reach.lo.x - 0.05
    });
    let lim = pl.limits();
    let start = JointState::rest(&pl.ready);
    let f = &pl.flight;
    let goal = Vector3::new(target[0], target[1], f.model.radius);
    let rot_bw = pl.placement.world_from_base().rotation.inverse();
    let mut best = 0;
    for s in &list {
        for &tf in &pl.return_times {
            let spin = |v: &Vector3<f64>| pl.impact.solve(&f.model, &s.v, &s.w, v).ok().map(|r| r.spin_out);
            let Some(v_out) = shoot(f, &s.p, &goal, tf, spin) else {
                best = best.max(1);
                continue;
            };
            let Ok(racket) = pl.impact.solve(&f.model, &s.v, &s.w, &v_out) else {
                best = best.max(1);
                continue;
            };
            best = best.max(2);
            let c = s.p - f.model.radius * racket.normal;
            if let Ok(all) = ik.solve(&pl.base_pose_rolled(&c, &racket.normal, 0.0), None, LimitFilter::Off) {
                for q in all.iter() {
                    let over = (0..q.len())
                        .map(|i| (q[i] - lim.upper[i]).max(lim.lower[i] - q[i]).max(0.0))
                        .fold(0.0, f64::max);
                    EXCESS.with(|e| e.set(e.get().min(over)));
                }
            }
            let vb = rot_bw * racket.velocity;
            let twist = [vb.x, vb.y, vb.z, 0.0, 0.0, 0.0];
            let t = s.t - now;
            for &roll in &pl.rolls {
                let pose = pl.base_pose_rolled(&c, &racket.normal, roll);
                let Ok(sols) = ik.solve(&pose, Some(&pl.ready), LimitFilter::Enforce) else {
                    continue;
                };
                for q in sols.iter() {
                    best = best.max(3);
                    let Ok(jv) = joint_velocity(pl.chain(), q, &twist) else {
                        continue;
                    };
                    if jv.singular {
                        continue;
                    }
                    best = best.max(4);
                    if (0..q.len()).any(|i| jv.qd[i].abs() > lim.velocity[i]) {
                        continue;
                    }
                    best = best.max(5);
                    let tmin = (0..q.len())
                        .map(|i| min_joint_time(q[i] - pl.ready[i], lim.velocity[i], lim.acceleration[i]))
                        .fold(0.0, f64::max);
                    if tmin > t {
                        continue;
                    }
                    best = best.max(6);
                    if hit_leg(&start, q, &jv.qd, t, lim).is_some() {
                        return 7;
                    }
                }
            }
        }
    }
    best
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(10_000, |a| a.parse().expect("N"));
    let seed: u64 = args.get(2).map_or(0, |a| a.parse().expect("SEED"));
    let mut pl = ReturnPlanner::new(ttkin::robots::gantry6(), Flight::default()).expect("gantry6");
    // Experiments: ROLLS="0,30,-30" (degrees), RETURN_TIMES="0.8,0.55,1.05" (s), CONTACT_OFFSET=0.03 (m), CANDIDATES=3, GOOD_MARGIN=0.25,
    // READY=-1.85,0,0.255 (racket centre facing forward, m, world; also the region's), BUDGET_US.
    if let Ok(r) = std::env::var("ROLLS") {
        pl.rolls = r
            .split(',')
            .map(|d| d.parse::<f64>().expect("ROLLS").to_radians())
            .collect();
    }
    if let Ok(r) = std::env::var("READY") {
        let c: Vec<f64> = r
            .split(',')
            .map(|d| d.parse().expect("READY x,y,z (m, world)"))
            .collect();
        let pose = pl.base_pose(&Vector3::new(c[0], c[1], c[2]), &Vector3::x());
        let ik = Analytic::for_chain(pl.chain()).expect("analytic IK");
        pl.ready = ik.nearest(&pose, &pl.ready, LimitFilter::Enforce).expect("ready IK");
    }
    // BUDGET_US: every plan's budget in thread CPU time (the controller's anytime search, issue 26).
    if let Ok(r) = std::env::var("BUDGET_US") {
        let us: u64 = r.parse().expect("BUDGET_US (µs of thread CPU time)");
        pl.budget = Some(ttkin::ball::hitplan::PlanBudget::ThreadCpu(
            std::time::Duration::from_micros(us),
        ));
    }
    if let Ok(r) = std::env::var("CANDIDATES") {
        pl.candidates = r.parse().expect("CANDIDATES");
    }
    if let Ok(r) = std::env::var("GOOD_MARGIN") {
        pl.good_margin = r.parse().expect("GOOD_MARGIN");
    }
    if let Ok(r) = std::env::var("CONTACT_OFFSET") {
        pl.contact_offset = r.parse().expect("CONTACT_OFFSET (m)");
    }
    if let Ok(r) = std::env::var("RETURN_TIMES") {
        let v: Vec<f64> = r.split(',').map(|d| d.parse().expect("RETURN_TIMES")).collect();
        pl.return_times = v.try_into().expect("three return times");
    }
    let truth = Flight {
        step: 0.001,
        ..Flight::default()
    };
    let cfg = RallyConfig {
        seed,
        paths: 0,
        replan_period: std::env::var("REPLAN").map_or(0.0, |r| r.parse().expect("REPLAN (s)")),
        ..RallyConfig::default()
    };
    let cfg = RallyConfig {
        correction_delay: std::env::var("CORRECT").map_or(cfg.correction_delay, |r| r.parse().expect("CORRECT (s)")),
        // WORLD=mismatch: every ball in a world of its own (`ttmanip rally --world mismatch`).
        world: std::env::var("WORLD").is_ok_and(|w| w == "mismatch").then(|| {
            // Parts of the mismatch alone: SPREAD_KD, SPREAD_KM, SPREAD_E, SPREAD_MU, JITTER (s)
            // override the measured spreads.
            let m = WorldSpread::measured();
            let get = |k: &str, d: f64| std::env::var(k).map_or(d, |v| v.parse().expect(k));
            WorldSpread {
                k_drag: get("SPREAD_KD", m.k_drag),
                k_magnus: get("SPREAD_KM", m.k_magnus),
                restitution: get("SPREAD_E", m.restitution),
                friction: get("SPREAD_MU", m.friction),
                latency_jitter: get("JITTER", m.latency_jitter),
            }
        }),
        ..cfg
    };
    let region = ReachRegion::new(pl.chain(), pl.placement, pl.ready.clone(), truth.model.radius).expect("region");
    let clock = std::time::Instant::now();
    let out = rally::rally(&pl, &region, &truth, &cfg, n);
    let wall = clock.elapsed().as_secs_f64();
    let in_reach: Vec<_> = out.iter().filter(|o| o.in_reach).collect();
    let returned = in_reach.iter().filter(|o| o.returned).count();
    let mut statuses = std::collections::BTreeMap::new();
    for o in in_reach.iter().filter(|o| !o.returned) {
        *statuses.entry(o.status.clone()).or_insert(0usize) += 1;
    }
    let mut reach = std::collections::BTreeMap::new();
    for o in &out {
        *reach.entry(o.reach).or_insert(0usize) += 1;
    }
    let mut profiles = std::collections::BTreeMap::new();
    for o in in_reach.iter().filter(|o| o.returned) {
        *profiles.entry(o.profile).or_insert(0usize) += 1;
    }
    let mut times: Vec<f64> = out.iter().map(|o| o.plan_time_us).filter(|t| t.is_finite()).collect();
    times.sort_by(f64::total_cmp);
    let returned_out = out.iter().filter(|o| !o.in_reach && o.returned).count();
    let mut returned_out_by = std::collections::BTreeMap::new();
    for o in out.iter().filter(|o| !o.in_reach && o.returned) {
        *returned_out_by.entry(o.reach).or_insert(0usize) += 1;
    }
    println!(
        "balls {n} seed {seed}: in reach {}, returned {returned} -> return rate {:.2} %, returned out of reach {returned_out}",
        in_reach.len(),
        100.0 * returned as f64 / in_reach.len().max(1) as f64
    );
    println!("reach {reach:?}");
    println!("returned out of reach by reason {returned_out_by:?}");
    // The touch region (the region before the return conditions) on the same balls, for comparison.
    let touch: Vec<_> = out
        .par_iter()
        .map(|o| region.classify_touch(&truth, &o.incoming, o.now))
        .collect();
    let mut touch_counts = std::collections::BTreeMap::new();
    for r in &touch {
        *touch_counts.entry(r.name()).or_insert(0usize) += 1;
    }
    let touch_in = touch.iter().filter(|r| r.in_reach()).count();
    let touch_returned = out
        .iter()
        .zip(&touch)
        .filter(|(o, r)| r.in_reach() && o.returned)
        .count();
    println!(
        "touch region: in reach {touch_in}, returned {touch_returned} -> return rate {:.2} %, {touch_counts:?}",
        100.0 * touch_returned as f64 / touch_in.max(1) as f64
    );
    println!("returned by profile {profiles:?}");
    println!("in-reach failures {statuses:?}");
    println!(
        "plan CPU time median {:.0} us, mean {:.0} us (rally wall {wall:.1} s)",
        times.get(times.len() / 2).copied().unwrap_or(f64::NAN),
        times.iter().sum::<f64>() / times.len().max(1) as f64
    );
    let mut corr: Vec<f64> = out
        .iter()
        .map(|o| o.correction_time_us)
        .filter(|t| t.is_finite())
        .collect();
    corr.sort_by(f64::total_cmp);
    let mut total: Vec<f64> = out
        .iter()
        .filter(|o| o.plan_time_us.is_finite())
        .map(|o| {
            o.plan_time_us
                + if o.correction_time_us.is_finite() {
                    o.correction_time_us
                } else {
                    0.0
                }
        })
        .collect();
    total.sort_by(f64::total_cmp);
    println!(
        "correction after the bounce: {} balls, {} adopted; CPU time median {:.0} us; plan + correction median {:.0} us",
        corr.len(),
        out.iter().filter(|o| o.replans > 0).count(),
        corr.get(corr.len() / 2).copied().unwrap_or(f64::NAN),
        total.get(total.len() / 2).copied().unwrap_or(f64::NAN)
    );
    // The tail the controller's decision latency sees (issue 26): the first plans that found a hit
    // and the corrections, thread CPU time.
    let tail = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let q = |p: f64| {
            v.get(((v.len() as f64 * p) as usize).min(v.len().saturating_sub(1)))
                .copied()
        };
        let q = |p: f64| q(p).unwrap_or(f64::NAN);
        format!(
            "n {} p50 {:.0} p90 {:.0} p99 {:.0} max {:.0} us",
            v.len(),
            q(0.5),
            q(0.9),
            q(0.99),
            v.last().copied().unwrap_or(f64::NAN)
        )
    };
    let mut hit_plans: Vec<f64> = out
        .iter()
        .filter(|o| !o.profile.is_empty() && o.plan_time_us.is_finite())
        .map(|o| o.plan_time_us)
        .collect();
    println!("first plans with a hit: CPU {}", tail(&mut hit_plans));
    println!("corrections: CPU {}", tail(&mut corr.clone()));
    let median = |f: &dyn Fn(&rally::BallOutcome) -> f64| {
        let mut v: Vec<f64> = out
            .iter()
            .filter(|o| o.returned)
            .map(f)
            .filter(|x| x.is_finite())
            .collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "returned: racket-centre error median {:.1} mm, landing error median {:.0} mm",
        1e3 * median(&|o| o.racket_error),
        1e3 * median(&|o| o.landing_error)
    );
    if std::env::var_os("NO_DIAG").is_some() {
        return;
    }
    miss_diagnosis(&truth, &cfg, &out);
    // The infeasible balls planned again from their true state (same time, same `now`): what the
    // estimate's error costs, against what the search itself misses.
    let mut from_truth = std::collections::BTreeMap::new();
    for o in in_reach.iter().filter(|o| o.status == "infeasible") {
        let Some(est) = o.estimate else { continue };
        let (s, _) = truth.run(&o.incoming, est.t, None);
        let st = pl.plan(&s, o.now, cfg.target).map_or("error", |p| p.status.name());
        *from_truth.entry(st).or_insert(0usize) += 1;
        if std::env::var_os("SHOW").is_some() && st == "infeasible" {
            if let ttkin::ball::reach::Reachability::InReach { p, t, min_time } =
                region.classify(&truth, &o.incoming, o.now)
            {
                println!(
                    "  region point {p:.2?} at {:.3} s after now, min time {min_time:.3} s; y0 {:.2}",
                    t - o.now,
                    o.incoming.p.y
                );
            }
        }
    }
    println!("infeasible, planned from the true state: {from_truth:?}");
    let ik = Analytic::for_chain(pl.chain()).expect("analytic IK");
    let mut stages = [0usize; STAGES.len()];
    let mut excess = Vec::new();
    for o in in_reach.iter().filter(|o| o.status == "infeasible") {
        let Some(est) = o.estimate else { continue };
        EXCESS.with(|e| e.set(f64::INFINITY));
        let d = deepest(&pl, &ik, &est, o.now, cfg.target);
        stages[d] += 1;
        if d == 2 {
            excess.push(EXCESS.with(|e| e.get()));
        }
    }
    let named: Vec<String> = STAGES
        .iter()
        .zip(stages)
        .filter(|(_, c)| *c > 0)
        .map(|(s, c)| format!("{s} {c}"))
        .collect();
    println!("infeasible by deepest stage: {}", named.join(", "));
    excess.sort_by(f64::total_cmp);
    let below = |x: f64| excess.iter().filter(|e| **e <= x).count();
    println!(
        "no_ik: smallest joint-limit excess of any shot's IK branch ≤ 2 cm {}, ≤ 4 cm {}, ≤ 8 cm {}, of {}",
        below(0.02),
        below(0.04),
        below(0.08),
        excess.len()
    );
}

/// Why the in-reach balls the racket missed were missed: the true ball at the planned impact time
/// against the prediction the plan hit, split into the error in the planned face plane (beyond the
/// racket radius the face cannot meet it) and along the normal (the impact happens earlier or
/// later, elsewhere on the face), with the time from the bounce to the hit.
fn miss_diagnosis(truth: &Flight, cfg: &RallyConfig, out: &[rally::BallOutcome]) {
    // Each ball's own world (the planner's model unless `WORLD=mismatch`).
    let worlds: Vec<Flight> = (0..out.len())
        .map(|i| {
            if cfg.world.is_some() {
                rally::observe_ball(truth, cfg, i as u64, None).world
            } else {
                *truth
            }
        })
        .collect();
    let in_reach: Vec<(usize, &rally::BallOutcome)> = out.iter().enumerate().filter(|(_, o)| o.in_reach).collect();
    let bounce = |i: usize, o: &rally::BallOutcome| {
        let (_, ev) = worlds[i].run(&o.incoming, 1.5, None);
        ev.first().map_or(f64::NAN, |e| e.before.t)
    };
    let stats = |pick: &dyn Fn(&rally::BallOutcome) -> bool| {
        let (mut plane, mut normal, mut after) = (Vec::new(), Vec::new(), Vec::new());
        for (i, o) in in_reach.iter().filter(|(_, o)| pick(o)) {
            let Some((b, n)) = o.planned else { continue };
            let (t, _) = worlds[*i].run(&o.incoming, b.t, None);
            let e = t.p - b.p;
            if std::env::var_os("SHOW_E").is_some() && o.status == "missed" {
                println!(
                    "  miss {i}: e = {:.3?} (m, world), in plane {:.3}, n = {:.2?}, v_true {:.2?}, v_pred {:.2?}, racket_error {:.3}, replans {}, bounce to hit {:.3} s",
                    e, (e - n * n.dot(&e)).norm(), n, t.v, b.v, o.racket_error, o.replans, b.t - bounce(*i, o)
                );
            }
            normal.push(n.dot(&e).abs());
            plane.push((e - n * n.dot(&e)).norm());
            after.push(b.t - bounce(*i, o));
        }
        for v in [&mut plane, &mut normal, &mut after] {
            v.sort_by(f64::total_cmp);
        }
        (plane, normal, after)
    };
    let med = |v: &[f64]| v.get(v.len() / 2).copied().unwrap_or(f64::NAN);
    if std::env::var_os("MISS_HISTOGRAM").is_some() {
        let mut bins = std::collections::BTreeMap::new();
        for (i, o) in &in_reach {
            let Some((b, _)) = o.planned else { continue };
            let k = ((b.t - bounce(*i, o)) / 0.05).floor() as i64 * 50;
            let e = bins.entry(k).or_insert((0usize, 0usize));
            e.0 += usize::from(o.returned);
            e.1 += usize::from(o.status == "missed");
        }
        println!("bounce to hit (ms bin): (returned, missed) {bins:?}");
    }
    let (mp, mn, ma) = stats(&|o| o.status == "missed");
    let (rp, rn, ra) = stats(&|o| o.returned);
    let far = mp.iter().filter(|e| **e > 0.075).count();
    println!(
        "missed {}: prediction error at the planned impact in the face plane > 75 mm {far}, median {:.0} mm \
         (returned {:.0} mm), along the normal median {:.0} mm (returned {:.0} mm); bounce to hit median \
         {:.0} ms (returned {:.0} ms)",
        mp.len(),
        1e3 * med(&mp),
        1e3 * med(&rp),
        1e3 * med(&mn),
        1e3 * med(&rn),
        1e3 * med(&ma),
        1e3 * med(&ra)
    );
}
