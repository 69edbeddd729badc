//! `ttctl`: the embedded controller. Loads the controller configuration (TOML), checks it (keys,
//! values, bus budget), opens one SocketCAN interface per channel, and runs one real-time thread
//! per channel that boots, configures and enables the CiA 402 drives and then follows a joint
//! trajectory file (written by `ttmanip.ctl.write_trajectory`) or the built-in demo motion, or
//! (`--online hit`) takes hits over UDP and executes them (`ttcan::online`, docs/online.md).
//! `--virtual-drives` runs the same controller on in-process virtual drives (no CAN needed).
//! SIGINT/SIGTERM bring every axis to a controlled stop. Prints and saves latency statistics,
//! writes telemetry CSV. Exit status (`ttcan::runtime::exit`): 0 motion completed, 1 bad input
//! (usage errors included), 2 stopped by a fault.

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use ttcan::bus::socketcan::SocketCanBus;
use ttcan::bus::stdio::StdioBus;
use ttcan::bus::CanBus;
use ttcan::online::counters::CountersSnapshot;
use ttcan::online::handoff::StrokeFollower;
use ttcan::online::receiver::Mode;
use ttcan::online::session::{self, Endpoints};
use ttcan::runtime::channel::{run_channel, run_channel_with, ChannelPlan, ChannelReport, Shared};
use ttcan::runtime::config::ControllerConfig;
use ttcan::runtime::master::{ChannelMaster, StopReason, MAX_AXES_PER_CHANNEL};
use ttcan::runtime::rt;
use ttcan::runtime::stats::CycleStats;
use ttcan::runtime::trajectory::Trajectory;
use ttcan::runtime::vdrives::{VirtualBus, VirtualChannel};

/// Embedded controller: CiA 402 drives over SocketCAN, one real-time thread per channel.
#[derive(clap::Parser, Debug)]
#[command(name = "ttctl", version)]
struct Args {
    /// Controller configuration (TOML: cycle_hz, bitrate, mode, approach_s, priority, a watchdog
    /// table, channel tables with an interface and axis tables of node, joint, units, limits; see
    /// docs/can.md). Default: 4 channels vcan0..vcan3 × 2 axes (nodes 1, 2), joints 0–7.
    #[arg(long, short)]
    config: Option<PathBuf>,
    /// Joint trajectory CSV (t,q…,qd…,qdd…,tau…), as written by ttmanip.ctl.write_trajectory.
    #[arg(long, short, conflicts_with = "demo")]
    trajectory: Option<PathBuf>,
    /// Run the built-in demo motion (every axis ±AMPLITUDE and back over 2 s) instead of a file.
    #[arg(long)]
    demo: bool,
    /// Amplitude of the demo motion, joint units (rad or m).
    #[arg(long, default_value_t = 0.3)]
    amplitude: f64,
    /// Write telemetry (one row per channel and cycle) to this CSV file.
    #[arg(long)]
    telemetry: Option<PathBuf>,
    /// Write the latency statistics and the result (key=value lines) to this file.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Stop (controlled) after this many seconds whatever happens.
    #[arg(long, default_value_t = 60.0)]
    max_seconds: f64,
    /// Run on in-process virtual drives (one in-memory bus per channel, the drives of
    /// ttdrive-sim) instead of the channels' CAN interfaces: no SocketCAN needed.
    #[arg(long)]
    virtual_drives: bool,
    /// Online mode: `hit` takes hits over UDP (docs/online.md) and executes them; `ball` takes
    /// camera observations and plays the balls (the ball brain, `ttcan::online::ball`); needs `robot`
    /// in the configuration with an axis for every joint. Runs until SIGINT/SIGTERM or
    /// --max-seconds.
    #[arg(long, value_parser = ["hit", "ball"], conflicts_with_all = ["trajectory", "demo"])]
    online: Option<String>,
    /// Address the online mode listens on (UDP).
    #[arg(long, default_value = "127.0.0.1:5005")]
    listen: std::net::SocketAddr,
    /// Address the online mode sends statuses and telemetry to (UDP).
    #[arg(long, default_value = "127.0.0.1:5006")]
    reply: std::net::SocketAddr,
    /// Only check the configuration (syntax, values, bus budget) and the trajectory file if given,
    /// print the bus loads and exit.
    #[arg(long)]
    check: bool,
}

fn fail(msg: impl std::fmt::Display) -> ! {
    eprintln!("ttctl: {msg}");
    std::process::exit(ttcan::runtime::exit::BAD_INPUT)
}

fn main() {
    let args: Args = ttcan::runtime::exit::parse_args();
    if !(args.amplitude.is_finite() && args.amplitude.abs() <= 1e3) {
        fail(format!(
            "--amplitude {}: must be finite, |a| ≤ 1000 joint units",
            args.amplitude
        ));
    }
    if !(args.max_seconds.is_finite() && args.max_seconds > 0.0) {
        fail(format!("--max-seconds {}: must be finite and > 0", args.max_seconds));
    }
    let cfg = match &args.config {
        Some(p) => {
            let text = ttkin::budget::read_text_limited(p).unwrap_or_else(|e| fail(format!("{}: {e}", p.display())));
            ControllerConfig::from_toml(&text, &p.display().to_string()).unwrap_or_else(|e| fail(e))
        }
        None => ControllerConfig::default_layout(),
    };
    let source = args
        .config
        .as_ref()
        .map_or_else(|| "configuration".to_string(), |p| p.display().to_string());
    let loads = cfg.check(&source).unwrap_or_else(|e| fail(e));
    let plans: Vec<_> = (0..cfg.channel.len())
        .map(|c| cfg.channel_plans(c, &source).unwrap_or_else(|e| fail(e)))
        .collect();
    for ((ch, l), plans) in cfg.channel.iter().zip(&loads).zip(&plans) {
        println!(
            "ttctl: channel {} {} axes, bus load {:.1}–{:.1} % (limit {:.0} %)",
            ch.interface,
            ch.axis.len(),
            l.nominal * 100.0,
            l.worst * 100.0,
            ttcan::canopen::budget::MAX_BUS_LOAD * 100.0
        );
        for (a, p) in ch.axis.iter().zip(plans) {
            let list = |m: &ttcan::canopen::pdo::PdoMapping| {
                m.entries().iter().map(|e| e.to_string()).collect::<Vec<_>>().join(" ")
            };
            println!(
                "ttctl: {} node {}: {}, {:?}, RPDO1 [{}] {} B, TPDO1 [{}] {} B, {} SDO steps at boot-up",
                ch.interface,
                a.node,
                a.device_file
                    .as_ref()
                    .map_or_else(|| "ttdrive-sim.eds".to_string(), |f| f.display().to_string()),
                p.mode,
                list(&p.rpdo),
                p.rpdo.len(),
                list(&p.tpdo),
                p.tpdo.len(),
                p.len()
            );
        }
    }
    let traj = match &args.trajectory {
        Some(p) => {
            let text = ttkin::budget::read_text_limited(p).unwrap_or_else(|e| fail(format!("{}: {e}", p.display())));
            Trajectory::parse(&text).unwrap_or_else(|e| fail(format!("{}: {e}", p.display())))
        }
        None if args.demo => {
            let n = cfg
                .channel
                .iter()
                .flat_map(|c| c.axis.iter())
                .filter_map(|a| a.joint)
                .max()
                .map_or(1, |j| j + 1);
            Trajectory::demo(n, args.amplitude, 2.0)
        }
        None if args.check || args.online.is_some() => Trajectory::demo(1, 0.0, 1.0),
        None => fail("give --trajectory FILE, --demo or --online hit"),
    };
    if let Some(n) = cfg.joints.filter(|_| args.online.is_none()) {
        if traj.joints() != n {
            fail(format!(
                "trajectory has {} joints, the configuration's robot {} has {n}",
                traj.joints(),
                cfg.robot.as_deref().unwrap_or("")
            ));
        }
    }
    if args.trajectory.is_some() {
        // an axis whose joint is beyond the file's columns would hold still while the motion
        // "completes": a mismatch of file and configuration, refused before anything moves
        for ch in &cfg.channel {
            for a in &ch.axis {
                if let Some(j) = a.joint.filter(|&j| j >= traj.joints()) {
                    fail(format!(
                        "{} node {} follows joint {j}, but the trajectory has {} joints (0..{})",
                        ch.interface,
                        a.node,
                        traj.joints(),
                        traj.joints()
                    ));
                }
                // every target must fit the drive's integers (a position of 1e300 rad passed the
                // check and faulted the drive at the first cycle)
                if let Some(j) = a.joint {
                    for (k, s) in traj.samples(j).enumerate() {
                        let fits = a
                            .units
                            .position_to_increments(s.q)
                            .and(a.units.velocity_to_increments(s.qd));
                        if let Err(e) = fits {
                            fail(format!(
                                "trajectory sample {k}, joint {j} (q = {}, qd = {}): {e} for {} node {} \
                                 ({} increments per unit, 32-bit targets)",
                                s.q, s.qd, ch.interface, a.node, a.units.increments_per_unit
                            ));
                        }
                    }
                }
            }
        }
    }
    let online_planner = args.online.as_ref().map(|_| {
        let name = cfg
            .robot
            .as_deref()
            .unwrap_or_else(|| fail("--online needs `robot = \"NAME\"` in the configuration"));
        let chain = ttkin::robots::by_name(name).unwrap_or_else(|e| fail(e));
        ttkin::hit::HitPlanner::new(&chain, ttkin::hit::HitOptions::default()).unwrap_or_else(|e| fail(e))
    });
    if args.check {
        // The configuration, and the trajectory when one is given, are fine: nothing is moved.
        return;
    }
    let interrupt = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        if let Err(e) = signal_hook::flag::register(sig, interrupt.clone()) {
            eprintln!("ttctl: warning: cannot handle signal {sig}: {e}");
        }
    }
    if let Err(w) = rt::lock_memory() {
        eprintln!("ttctl: warning: {w}");
    }
    if cfg.channel.iter().filter(|c| c.interface == "stdio").count() > 1 {
        fail("only one channel can use the interface stdio");
    }
    let mut buses: Vec<Box<dyn CanBus>> = Vec::new();
    if args.virtual_drives {
        for c in &cfg.channel {
            let ch = VirtualChannel {
                axes: c.axis.iter().map(|a| (a.node, a.units)).collect(),
            };
            let bus = VirtualBus::new(&ch, 1.0 / cfg.cycle_hz, 100).unwrap_or_else(|e| fail(e));
            buses.push(Box::new(bus));
        }
    }
    for ch in cfg.channel.iter().filter(|_| !args.virtual_drives) {
        if ch.interface == "stdio" {
            buses.push(Box::new(StdioBus::open()));
        } else {
            buses.push(Box::new(SocketCanBus::open(&ch.interface).unwrap_or_else(|e| {
                fail(format!("cannot open CAN interface {}: {e}", ch.interface))
            })));
        }
    }
    let period_ns = (1e9 / cfg.cycle_hz).round() as u64;
    let shared = Shared::new(cfg.channel.len(), interrupt);
    let start_usage = (rt::Usage::process(), rt::steal_ms());
    let t0 = rt::now_ns() + 20 * period_ns;
    let max_cycles = (args.max_seconds * cfg.cycle_hz) as u64;
    let joint_map: Vec<[Option<usize>; MAX_AXES_PER_CHANNEL]> = cfg
        .channel
        .iter()
        .map(|ch| {
            let mut joints = [None; MAX_AXES_PER_CHANNEL];
            for (k, a) in ch.axis.iter().enumerate() {
                joints[k] = a.joint;
            }
            joints
        })
        .collect();
    let (session, followers) = match online_planner {
        Some(planner) => {
            let ends = Endpoints {
                mode: if args.online.as_deref() == Some("ball") {
                    Mode::Ball
                } else {
                    Mode::Hit
                },
                listen: args.listen,
                reply: args.reply,
            };
            let (s, f) = session::start(ends, planner, &joint_map, period_ns, t0, &cfg.online)
                .unwrap_or_else(|e| fail(format!("online mode: {e}")));
            println!(
                "ttctl: online {} mode: listening on {}, statuses and telemetry to {}",
                args.online.as_deref().unwrap_or("hit"),
                s.local,
                args.reply
            );
            (Some(s), f.into_iter().map(Some).collect())
        }
        None => (None, Vec::new()),
    };
    let mut followers: Vec<Option<StrokeFollower>> = followers;
    followers.resize_with(cfg.channel.len(), || None);
    let reports: Vec<ChannelReport> = std::thread::scope(|s| {
        let handles: Vec<_> = cfg
            .channel
            .iter()
            .zip(buses.iter_mut())
            .zip(&plans)
            .zip(followers.iter_mut())
            .map(|(((ch, bus), plans), follower)| {
                let links: Vec<_> = ch.axis.iter().map(|a| a.link()).collect();
                let master = ChannelMaster::with_plans(&links, plans, cfg.watchdog)
                    .unwrap_or_else(|e| fail(format!("{}: {e}", ch.interface)));
                let mut joints = [None; MAX_AXES_PER_CHANNEL];
                for (k, a) in ch.axis.iter().enumerate() {
                    joints[k] = a.joint;
                }
                let plan = ChannelPlan {
                    joints,
                    approach_s: cfg.approach_s,
                    period_ns,
                    t0_ns: t0,
                    max_cycles,
                    telemetry_rows: if args.telemetry.is_some() { max_cycles + 16 } else { 0 },
                };
                let (traj, shared, prio) = (&traj, &shared, cfg.priority);
                s.spawn(move || {
                    if let Err(w) = rt::make_thread_realtime(prio) {
                        eprintln!("ttctl: warning: {}: {w}", ch.interface);
                    }
                    match follower.as_mut() {
                        Some(f) => run_channel_with(&ch.interface, bus, master, f, &plan, shared),
                        None => run_channel(&ch.interface, bus, master, traj, &plan, shared),
                    }
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|_| fail("a channel thread panicked")))
            .collect()
    });
    let online = session.map(|s| s.stop());
    report(&args, &reports, online.as_ref(), start_usage);
}

/// Prints and writes the run's statistics; `start` is the process's usage and the host's steal
/// time (ms) read before the channel threads started.
fn report(args: &Args, reports: &[ChannelReport], online: Option<&CountersSnapshot>, start: (rt::Usage, Option<f64>)) {
    let mut all = CycleStats::new();
    let mut quiet = CycleStats::new();
    let mut planning = CycleStats::new();
    let mut lines = Vec::new();
    let mut fault: Option<(String, StopReason)> = None;
    let mut worst_err: f64 = 0.0;
    let mut stop_cycles = 0u32;
    let (mut missed, mut bad, mut skipped, mut lost, mut tx_full) = (0u64, 0u64, 0u64, 0u64, 0u64);
    // online: no motion to complete; a stop without fault (signal, --max-seconds) is the end
    let completed = reports.iter().all(|r| r.completed) || online.is_some();
    for r in reports {
        all.merge(&r.stats);
        quiet.merge(&r.stats_quiet);
        planning.merge(&r.stats_planning);
        let s = r.stats.summary();
        let e = r.max_tracking_error.iter().fold(0.0f64, |m, x| m.max(*x));
        worst_err = worst_err.max(e);
        stop_cycles = stop_cycles.max(r.stopped_after.unwrap_or(0));
        missed += r.counters.missed_feedback;
        lost += r.counters.tpdo_lost();
        tx_full += r.tx_full;
        bad += r.counters.malformed + r.counters.out_of_range;
        skipped += r.skipped;
        for (k, name) in r.device_names.iter().enumerate() {
            if let Some(name) = name {
                println!("ttctl: {} axis {k}: device name (0x1008) {name:?}", r.name);
            }
        }
        let reason = r.stop_reason.map(|x| x.to_string()).unwrap_or_else(|| "none".into());
        println!(
            "ttctl: {}: {} cycles, stop: {reason} (all axes stopped after {} cycles), max tracking error {:.2e}, \
             latency p50 {:.0} µs p99 {:.0} µs max {:.0} µs, deadline misses {}, skipped {}, late/missed feedback {}, TPDO lost {}, rx {}",
            r.name,
            s.cycles,
            r.stopped_after.unwrap_or(0),
            e,
            s.p50_us,
            s.p99_us,
            s.max_us,
            s.deadline_misses,
            r.skipped,
            r.counters.missed_feedback,
            r.counters.tpdo_lost(),
            r.counters.rx
        );
        if let Some(x) = r.stop_reason {
            if !matches!(x, StopReason::Requested | StopReason::OtherChannel) && fault.is_none() {
                fault = Some((r.name.clone(), x));
            }
        }
    }
    let s = all.summary();
    if let Some((ch, x)) = &fault {
        println!("ttctl: controlled stop of every axis: {ch}: {x}");
    }
    lines.push(format!("completed={}", completed as u8));
    lines.push(format!(
        "fault={}",
        fault
            .as_ref()
            .map(|(c, x)| format!("{c}: {x}"))
            .unwrap_or_else(|| "none".into())
    ));
    lines.push(format!("max_tracking_error={worst_err:.3e}"));
    lines.push(format!("stop_cycles={stop_cycles}"));
    lines.push(format!("missed_feedback={missed}"));
    lines.push(format!("frames_lost={lost}"));
    lines.push(format!("tx_full={tx_full}"));
    lines.push(format!("bad_frames={bad}"));
    lines.push(format!("cycles={}", s.cycles));
    lines.push(format!("skipped={skipped}"));
    lines.push(format!("latency_p50_us={:.1}", s.p50_us));
    lines.push(format!("latency_p99_us={:.1}", s.p99_us));
    lines.push(format!("latency_max_us={:.1}", s.max_us));
    lines.push(format!("deadline_misses={}", s.deadline_misses));
    lines.push(format!("work_mean_us={:.1}", s.mean_work_us));
    // What the system did to the cycles: page faults and preemptions of the channel threads in
    // their loops, of the whole process, and the host's steal time over the run (a virtual
    // machine's CPUs held by the hypervisor), to tell the controller's stalls from the machine's.
    let cycle = reports.iter().fold(rt::Usage::default(), |a, r| rt::Usage {
        minor_faults: a.minor_faults + r.usage.minor_faults,
        major_faults: a.major_faults + r.usage.major_faults,
        preempted: a.preempted + r.usage.preempted,
    });
    let process = rt::Usage::process().since(&start.0);
    for (who, u) in [("cycle", cycle), ("process", process)] {
        lines.push(format!("{who}_minor_faults={}", u.minor_faults));
        lines.push(format!("{who}_major_faults={}", u.major_faults));
        lines.push(format!("{who}_preempted={}", u.preempted));
    }
    if let (Some(a), Some(b)) = (start.1, rt::steal_ms()) {
        lines.push(format!("host_steal_ms={:.0}", b - a));
    }
    for (name, st) in [("quiet", quiet.summary()), ("planning", planning.summary())] {
        lines.push(format!("cycles_{name}={}", st.cycles));
        lines.push(format!("latency_p50_us_{name}={:.1}", st.p50_us));
        lines.push(format!("latency_p99_us_{name}={:.1}", st.p99_us));
        lines.push(format!("latency_max_us_{name}={:.1}", st.max_us));
        lines.push(format!("deadline_misses_{name}={}", st.deadline_misses));
    }
    if let Some(c) = online {
        for (name, v) in c.entries() {
            lines.push(format!("online_{name}={v}"));
        }
    }
    println!("ttctl: RESULT {}", lines.join(" "));
    if let Some(p) = &args.stats {
        if let Err(e) = std::fs::write(p, lines.join("\n") + "\n") {
            eprintln!("ttctl: cannot write {}: {e}", p.display());
        }
    }
    if let Some(p) = &args.telemetry {
        if let Err(e) = write_telemetry(p, reports) {
            eprintln!("ttctl: cannot write {}: {e}", p.display());
        }
    }
    if fault.is_some() {
        std::process::exit(ttcan::runtime::exit::NOT_DONE);
    }
}

fn write_telemetry(p: &std::path::Path, reports: &[ChannelReport]) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(std::fs::File::create(p)?);
    write!(w, "channel,cycle,t,phase,latency_us")?;
    for a in 0..MAX_AXES_PER_CHANNEL {
        write!(w, ",q_ref{a},q{a},current{a}")?;
    }
    writeln!(w)?;
    for r in reports {
        for row in &r.telemetry {
            write!(
                w,
                "{},{},{:.4},{},{:.1}",
                r.name, row.cycle, row.t, row.phase, row.latency_us
            )?;
            for a in 0..MAX_AXES_PER_CHANNEL {
                write!(w, ",{:.6},{:.6},{:.4}", row.q_ref[a], row.q[a], row.current[a])?;
            }
            writeln!(w)?;
        }
    }
    w.flush()
}
