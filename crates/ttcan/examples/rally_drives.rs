//! The acceptance rally of issue 28 in release without Python: `rally_drives [N] [SEED]`
//! (defaults 1000, 0) plays the same balls in the planner's own world and in the mismatched one
//! (`WorldSpread::measured`), every stroke through the coupled drive simulation, and prints the
//! in-reach outcomes side by side (what `ttmanip rally --world both --execution drives` reports),
//! the balls lost only in the mismatched world by outcome, and, for every `execution_failed`,
//! why the drive simulation refused or faulted (for a fault: where each faulted axis's following
//! error peaked, the reference and the currents (`TRACE_FAULTS=1`: their whole record); the failed
//! balls' indices; `IDEAL=1`: exact
//! execution instead; `START=k`: balls k..k+N; `ROLLS`, `CANDIDATES`, `MAX_CANDIDATES`,
//! `FALLBACK_ATTEMPTS`, `CONTACT_OFFSET`, `RETURN_TIMES`, `LAST_RESORT`, `LAST_RESORT_ATTEMPTS`: the ball planner's settings, `WIDEN=0`: no wider
//! correction search, for experiments; `DUMP=file`: every ball's outcome, one row per ball and world).
use std::collections::BTreeMap;
use std::sync::Mutex;
use ttcan::coupled::{CoupledOptions, CoupledSim, SETPOINT_HZ};
use ttkin::ball::rally::{BallOutcome, Executed, Executor, Rally, RallyConfig, WorldSpread};
use ttkin::chain::Chain;

/// [`ttcan::coupled::execute::DriveExecutor`]'s execution, recording why a stroke failed.
struct Diagnosing {
    chain: Chain,
    options: CoupledOptions,
    failures: Mutex<Vec<String>>,
}

impl Executor for Diagnosing {
    fn execute(&self, times: &[f64], q: &[f64], qd: &[f64], qdd: &[f64]) -> Option<Executed> {
        let n = self.chain.dof();
        let fail = |why: String| {
            self.failures.lock().unwrap().push(why);
            None
        };
        let mut sim = match CoupledSim::from_chain(&self.chain, &q[..n], self.options) {
            Ok(s) => s,
            Err(e) => return fail(format!("build: {e}")),
        };
        let mut tau = vec![0.0; q.len()];
        if let Err(e) =
            sim.dynamics()
                .inverse_dynamics_batch(q, qd, qdd, &self.options.gravity_on(&self.chain), None, &mut tau)
        {
            return fail(format!("inverse dynamics: {e}"));
        }
        let tr = match sim.run(times, q, qd, qdd, Some(&tau), 1.0 / SETPOINT_HZ) {
            Ok(t) => t,
            Err(e) => return fail(format!("run refused: {e}")),
        };
        if tr.faults.iter().any(|f| !f.is_empty()) {
            // the largest feed-forward per joint over the stroke, against the drive's torque
            let peak: Vec<String> = (0..n)
                .map(|j| {
                    let m = tau.chunks_exact(n).map(|r| r[j].abs()).fold(0.0, f64::max);
                    format!("{m:.1}")
                })
                .collect();
            // Each faulted axis: where its following error |q − q_ref| peaked, with the
            // reference's speed and acceleration there, the current against its reference and the
            // end of the record (the fault's tick).
            let mut detail = String::new();
            for (j, f) in tr.faults.iter().enumerate().filter(|(_, f)| !f.is_empty()) {
                let rows = tr.t.len();
                let (k, e) = (0..rows)
                    .map(|k| (k, (tr.q[k * n + j] - tr.q_ref[k * n + j]).abs()))
                    .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
                // The input reference at the time of the worst error (nearest sample).
                let tk = tr.t[k];
                let i = times.partition_point(|&x| x < tk).min(times.len() - 1);
                let (qd_ref, qdd_ref) = (qd[i * n + j], qdd[i * n + j]);
                let max_qd = (0..times.len()).map(|i| qd[i * n + j].abs()).fold(0.0, f64::max);
                let max_qdd = (0..times.len()).map(|i| qdd[i * n + j].abs()).fold(0.0, f64::max);
                let max_cur = (0..rows).map(|k| tr.current[k * n + j].abs()).fold(0.0, f64::max);
                let max_cur_ref = (0..rows).map(|k| tr.current_ref[k * n + j].abs()).fold(0.0, f64::max);
                detail += &format!(
                    "; axis {j} {f}: worst |q-q_ref| {e:.4} at {tk:.4} s of {:.4} s (rows {rows}), reference there qd {qd_ref:.2} qdd {qdd_ref:.1}; \
                     stroke max |qd| {max_qd:.2} |qdd| {max_qdd:.1} (of {:.3} s), max |I| {max_cur:.2} A, max |I_ref| {max_cur_ref:.2} A",
                    tr.t.last().copied().unwrap_or(0.0),
                    times.last().copied().unwrap_or(0.0)
                );
            }
            if std::env::var_os("TRACE_FAULTS").is_some() {
                // The faulted axes: the reference every 5 ms (input samples) and the record every 100 ticks.
                let rows = tr.t.len();
                for (j, _) in tr.faults.iter().enumerate().filter(|(_, f)| !f.is_empty()) {
                    for i in (0..times.len()).step_by(5) {
                        println!(
                            "ref axis {j} t {:.4} q {:.5} qd {:.4} qdd {:.3}",
                            times[i],
                            q[i * n + j],
                            qd[i * n + j],
                            qdd[i * n + j]
                        );
                    }
                    for k in (0..rows).step_by(100) {
                        println!(
                            "rec axis {j} t {:.5} q {:.5} q_ref {:.5} qd {:.4} I {:.3} I_ref {:.3}",
                            tr.t[k],
                            tr.q[k * n + j],
                            tr.q_ref[k * n + j],
                            tr.qd[k * n + j],
                            tr.current[k * n + j],
                            tr.current_ref[k * n + j]
                        );
                    }
                }
            }
            return fail(format!("faults {:?}; |tau_ff| peaks {peak:?}{detail}", tr.faults));
        }
        Some(Executed {
            dof: n,
            t: tr.t,
            q: tr.q,
            qd: tr.qd,
        })
    }
}

fn counts(out: &[BallOutcome]) -> (usize, usize, BTreeMap<String, usize>) {
    let mut m = BTreeMap::new();
    let in_reach: Vec<_> = out.iter().filter(|o| o.in_reach).collect();
    for o in &in_reach {
        let k = if o.returned {
            "returned".to_string()
        } else {
            o.status.clone()
        };
        *m.entry(k).or_insert(0) += 1;
    }
    (in_reach.len(), in_reach.iter().filter(|o| o.returned).count(), m)
}

/// Experiment settings of the ball planner from the environment (both worlds alike): `ROLLS`
/// (degrees, comma-separated), `CANDIDATES`, `MAX_CANDIDATES`, `FALLBACK_ATTEMPTS`,
/// `CONTACT_OFFSET` (m), `RETURN_TIMES` (three, s), `LAST_RESORT` (the last resort's contact
/// offsets, m; 0: none), `LAST_RESORT_ATTEMPTS`.
fn tweak(p: &mut ttkin::ball::hitplan::ReturnPlanner) {
    let list = |name: &str| -> Option<Vec<f64>> {
        std::env::var(name)
            .ok()
            .map(|s| s.split(',').map(|x| x.trim().parse().expect(name)).collect())
    };
    if let Some(r) = list("ROLLS") {
        p.rolls = r.iter().map(|d| d.to_radians()).collect();
    }
    if let Some(c) = list("CANDIDATES") {
        p.candidates = c[0] as usize;
    }
    if let Some(c) = list("MAX_CANDIDATES") {
        p.max_candidates = c[0] as usize;
    }
    if let Some(c) = list("FALLBACK_ATTEMPTS") {
        p.fallback_attempts = c[0] as usize;
    }
    if let Some(c) = list("CONTACT_OFFSET") {
        p.contact_offset = c[0];
    }
    if let Some(t) = list("RETURN_TIMES") {
        p.return_times = [t[0], t[1], t[2]];
    }
    // LAST_RESORT=0: no last resort; else its contact offsets (m, comma-separated).
    if let Some(o) = list("LAST_RESORT") {
        p.last_resort_offsets = o.into_iter().filter(|&x| x > 0.0).collect();
    }
    if let Some(c) = list("LAST_RESORT_ATTEMPTS") {
        p.last_resort_attempts = c[0] as usize;
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(1000, |a| a.parse().expect("N"));
    let seed: u64 = args.get(2).map_or(0, |a| a.parse().expect("SEED"));
    let mut cfg = RallyConfig {
        seed,
        paths: 0,
        ..RallyConfig::default()
    };
    // SECOND=s: a second correction s after the first, for experiments.
    if let Ok(t) = std::env::var("SECOND") {
        cfg.second_correction = t.parse().expect("SECOND");
    }
    // TARGET=x,y: the landing target (m, world), for experiments.
    if let Ok(t) = std::env::var("TARGET") {
        let v: Vec<f64> = t.split(',').map(|x| x.trim().parse().expect("TARGET")).collect();
        cfg.target = [v[0], v[1]];
    }
    // WIDEN=0: no full search when a correction's near search fails (before issue 28's eighth stop).
    if std::env::var("WIDEN").is_ok_and(|w| w == "0") {
        cfg.widen_correction = false;
    }
    let mut matched = Rally::new(cfg).expect("rally");
    let mut mismatched = Rally::new(RallyConfig {
        world: Some(WorldSpread::measured()),
        ..cfg
    })
    .expect("rally");
    tweak(&mut matched.planner);
    tweak(&mut mismatched.planner);
    let ex = Diagnosing {
        chain: matched.planner.chain().clone(),
        options: CoupledOptions::default(),
        failures: Mutex::new(Vec::new()),
    };
    let ideal = std::env::var_os("IDEAL").is_some();
    let exr = (!ideal).then_some(&ex as &dyn Executor);
    let clock = std::time::Instant::now();
    // START=k: balls k..k+N (one ball's diagnosis).
    let first: u64 = std::env::var("START").map_or(0, |s| s.parse().expect("START"));
    let a = matched.play_range(first, n, None, exr, &|| false).expect("matched");
    let b = mismatched
        .play_range(first, n, None, exr, &|| false)
        .expect("mismatched");
    let wall = clock.elapsed().as_secs_f64();
    let (ra, rb) = (counts(&a), counts(&b));
    println!(
        "balls {n} seed {seed} ({}; {wall:.0} s wall)",
        if ideal { "ideal execution" } else { "drives" }
    );
    for (name, (inr, ret, m)) in [("matched", &ra), ("mismatched", &rb)] {
        println!(
            "{name:>10}: in reach {inr}, returned {ret} ({:.2} %), {m:?}",
            100.0 * *ret as f64 / (*inr).max(1) as f64
        );
    }
    // Balls in reach in both worlds: returned in the model world, lost in the mismatched one.
    let mut lost = BTreeMap::new();
    for (x, y) in a.iter().zip(&b) {
        if x.in_reach && y.in_reach && x.returned && !y.returned {
            *lost.entry(y.status.clone()).or_insert(0) += 1;
        }
    }
    println!("returned in the model world, lost in the mismatched one: {lost:?}");
    let med = |o: &[BallOutcome], f: &dyn Fn(&BallOutcome) -> f64| {
        let mut v: Vec<f64> = o.iter().map(f).filter(|x| x.is_finite()).collect();
        v.sort_by(f64::total_cmp);
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        (v.get(v.len() / 2).copied().unwrap_or(f64::NAN), mean)
    };
    for (name, o) in [("matched", &a), ("mismatched", &b)] {
        let (pm, pa) = med(o, &|o| o.plan_time_us);
        let (cm, ca) = med(o, &|o| o.correction_time_us);
        println!("{name:>10}: plan CPU median {pm:.0} (mean {pa:.0}) us, correction {cm:.0} ({ca:.0}) us");
    }
    // DUMP=file: one row per ball and world (index, world, in reach, status, returned, replans,
    // landing x y, racket error m), to compare variants ball by ball.
    if let Ok(path) = std::env::var("DUMP") {
        let mut rows = String::from("ball\tworld\tin_reach\tstatus\treturned\treplans\tland_x\tland_y\tracket_error\n");
        for (name, o) in [("matched", &a), ("mismatched", &b)] {
            for (i, x) in o.iter().enumerate() {
                rows += &format!(
                    "{}\t{name}\t{}\t{}\t{}\t{}\t{:.4}\t{:.4}\t{:.4}\n",
                    first + i as u64,
                    x.in_reach,
                    x.status,
                    x.returned,
                    x.replans,
                    x.landing[0],
                    x.landing[1],
                    x.racket_error
                );
            }
        }
        std::fs::write(&path, rows).expect("DUMP");
    }
    for (name, o) in [("matched", &a), ("mismatched", &b)] {
        let idx: Vec<u64> = (0..o.len())
            .filter(|&i| o[i].status == "execution_failed")
            .map(|i| first + i as u64)
            .collect();
        if !idx.is_empty() {
            println!("{name:>10}: execution_failed balls {idx:?}");
        }
    }
    for f in ex.failures.lock().unwrap().iter() {
        println!("execution failed: {f}");
    }
}
