//! `ttdrive-sim`: virtual CiA 402 drives on CAN interfaces. Each drive is the drive layer (the
//! axis cascade with sensing and fault machine) on the maxon RE 25 + GP 26 A motor model behind
//! the CANopen node of `ttcan::vdrive`; physics advance one period per SYNC. One thread per
//! interface. `--fail` injects faults. Exits after `--idle-exit` seconds without traffic (once
//! traffic was seen) or after `--duration`; prints every drive's final state. The interface
//! `stdio` carries the frames as text lines on standard input/output (`ttcan::bus::stdio`, for
//! bridges to other CAN stacks).

use std::time::{Duration, Instant};
use ttcan::bus::socketcan::SocketCanBus;
use ttcan::bus::stdio::StdioBus;
use ttcan::bus::{BusEvent, CanBus};
use ttcan::canopen::{Frames, Units};
use ttcan::runtime::rt;
use ttcan::vdrive::{Failure, VirtualDrive};
use ttcan::{AxisConfig, MotorModel};

/// Virtual CiA 402 drives (drive layer + motor model) on SocketCAN interfaces.
#[derive(clap::Parser, Debug)]
#[command(name = "ttdrive-sim", version)]
struct Args {
    /// A channel: INTERFACE:NODE[,NODE...], e.g. vcan0:1,2 (repeat for more channels); the
    /// interface `stdio` reads and writes frames as `CAN <id>#<hex>` lines on stdin/stdout.
    #[arg(long = "channel", required = true)]
    channels: Vec<String>,
    /// Inject a fault: KIND:INTERFACE:NODE@SECONDS (seconds after that channel's first SYNC);
    /// KIND is silent (stops answering, as unplugged), emcy (EMCY 0x2310 and Fault),
    /// leave-enabled (drops out of Operation Enabled), malformed (3-byte TPDOs) or
    /// out-of-range (impossible statusword). Repeatable.
    #[arg(long = "fail")]
    fail: Vec<String>,
    /// SYNC period the drives expect, s, in [1e-6, 1] (sets the physics step).
    #[arg(long, default_value_t = 1e-3)]
    period: f64,
    /// Milliseconds without SYNC (power stage on) before a drive faults and stops.
    #[arg(long, default_value_t = 20)]
    sync_timeout_ms: u32,
    /// Position increments per joint unit (CiA 402 scaling, must match the controller).
    #[arg(long, default_value_t = 1e5)]
    increments_per_unit: f64,
    /// Exit after this many seconds without any received frame, once traffic has been seen.
    #[arg(long, default_value_t = 2.0)]
    idle_exit: f64,
    /// Exit after this many seconds in any case.
    #[arg(long, default_value_t = 120.0)]
    duration: f64,
}

struct Injection {
    interface: String,
    node: u8,
    at: f64,
    failure: Failure,
}

fn fail(msg: impl std::fmt::Display) -> ! {
    eprintln!("ttdrive-sim: {msg}");
    std::process::exit(ttcan::runtime::exit::BAD_INPUT)
}

fn parse_channel(s: &str) -> (String, Vec<u8>) {
    let (iface, nodes) = s
        .split_once(':')
        .unwrap_or_else(|| fail(format!("--channel {s}: expected INTERFACE:NODE[,NODE...]")));
    let nodes: Vec<u8> = nodes
        .split(',')
        .map(|n| {
            n.trim()
                .parse::<u8>()
                .ok()
                .filter(|n| (1..=127).contains(n))
                .unwrap_or_else(|| fail(format!("--channel {s}: node {n:?} is not 1..=127")))
        })
        .collect();
    (iface.to_string(), nodes)
}

fn parse_fail(s: &str) -> Injection {
    let bad = || -> ! { fail(format!("--fail {s}: expected KIND:INTERFACE:NODE@SECONDS")) };
    let (spec, at) = s.split_once('@').unwrap_or_else(|| bad());
    let mut parts = spec.split(':');
    let (Some(kind), Some(iface), Some(node), None) = (parts.next(), parts.next(), parts.next(), parts.next()) else {
        bad()
    };
    let failure = match kind {
        "silent" => Failure::Silent,
        "emcy" => Failure::Emcy,
        "leave-enabled" => Failure::LeaveEnabled,
        "malformed" => Failure::Malformed,
        "out-of-range" => Failure::OutOfRange,
        k => fail(format!(
            "--fail {s}: unknown kind {k:?} (silent, emcy, leave-enabled, malformed, out-of-range)"
        )),
    };
    let node = node.parse::<u8>().unwrap_or_else(|_| bad());
    let at = at
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && *x >= 0.0)
        .unwrap_or_else(|| bad());
    Injection {
        interface: iface.to_string(),
        node,
        at,
        failure,
    }
}

fn main() {
    let args: Args = ttcan::runtime::exit::parse_args();
    let channels: Vec<_> = args.channels.iter().map(|s| parse_channel(s)).collect();
    for (c, (iface, nodes)) in channels.iter().enumerate() {
        if channels[..c].iter().any(|(other, _)| other == iface) {
            fail(format!(
                "--channel {iface}: interface given twice; list its nodes once (IFACE:1,2)"
            ));
        }
        if let Some(n) = nodes
            .iter()
            .enumerate()
            .find_map(|(k, n)| nodes[..k].contains(n).then_some(n))
        {
            fail(format!("--channel {iface}: node {n} given twice"));
        }
    }
    for (flag, v) in [("--duration", args.duration), ("--idle-exit", args.idle_exit)] {
        if !(v.is_finite() && v > 0.0) {
            fail(format!("{flag} {v}: must be finite and > 0 s"));
        }
    }
    let injections: Vec<_> = args.fail.iter().map(|s| parse_fail(s)).collect();
    for i in &injections {
        if !channels.iter().any(|(c, n)| *c == i.interface && n.contains(&i.node)) {
            fail(format!("--fail: no node {} on interface {}", i.node, i.interface));
        }
    }
    // CiA 301's communication cycle period (0x1006) is in µs; a SYNC period of 1e300 s passed
    // and never stepped the physics
    if !(args.period.is_finite() && (1e-6..=1.0).contains(&args.period)) {
        fail(format!("--period {}: must be in [1e-6, 1] s", args.period));
    }
    let units = Units {
        increments_per_unit: args.increments_per_unit,
        ..Units::default()
    };
    if units.validate().is_err() {
        fail(format!(
            "--increments-per-unit {}: must be finite and > 0",
            args.increments_per_unit
        ));
    }
    let model = MotorModel::maxon_re25_gp26();
    let config = AxisConfig::new(model);
    std::thread::scope(|s| {
        for (iface, nodes) in &channels {
            let inj: Vec<&Injection> = injections.iter().filter(|i| i.interface == *iface).collect();
            let args = &args;
            s.spawn(move || run(iface, nodes, inj, &model, &config, units, args));
        }
    });
}

/// A bus the drive loop can sleep on until a frame arrives.
trait Port: CanBus {
    /// Waits up to `ms` for a frame.
    fn wait(&mut self, ms: u16);
    /// True when no frame can come any more (stdio: input closed).
    fn ended(&self) -> bool {
        false
    }
}

impl Port for SocketCanBus {
    fn wait(&mut self, ms: u16) {
        self.wait_readable(ms);
    }
}

impl Port for StdioBus {
    fn wait(&mut self, ms: u16) {
        self.wait_readable(ms);
    }

    fn ended(&self) -> bool {
        self.closed()
    }
}

fn run(
    iface: &str,
    nodes: &[u8],
    inj: Vec<&Injection>,
    model: &MotorModel,
    config: &AxisConfig,
    units: Units,
    args: &Args,
) {
    if iface == "stdio" {
        run_on(StdioBus::open(), iface, nodes, inj, model, config, units, args)
    } else {
        let bus = SocketCanBus::open(iface).unwrap_or_else(|e| fail(format!("cannot open CAN interface {iface}: {e}")));
        run_on(bus, iface, nodes, inj, model, config, units, args)
    }
}

#[allow(clippy::too_many_arguments)] // the channel's whole setup, passed once
fn run_on<B: Port>(
    mut bus: B,
    iface: &str,
    nodes: &[u8],
    mut inj: Vec<&Injection>,
    model: &MotorModel,
    config: &AxisConfig,
    units: Units,
    args: &Args,
) {
    let mut out = Frames::new();
    let mut drives: Vec<VirtualDrive> = nodes
        .iter()
        .map(|&n| {
            let mut d = VirtualDrive::new(n, model, config, units, args.period, &mut out).unwrap_or_else(|e| fail(e));
            d.sync_timeout_ms = args.sync_timeout_ms;
            d
        })
        .collect();
    send(&mut bus, &mut out);
    let start = Instant::now();
    let mut last_rx = Instant::now();
    let mut first_sync: Option<Instant> = None;
    let mut next_ms = rt::now_ns() + 1_000_000;
    let mut seen = false;
    loop {
        let mut got = false;
        loop {
            match bus.poll() {
                Ok(Some(BusEvent::Frame { frame, .. })) => {
                    got = true;
                    if frame.id() == 0x080 && first_sync.is_none() {
                        first_sync = Some(Instant::now());
                    }
                    for d in drives.iter_mut() {
                        let missed = d.node().counters().missed_rpdo;
                        d.on_frame(&frame, &mut out);
                        send(&mut bus, &mut out);
                        let now = d.node().counters().missed_rpdo;
                        if now > missed && now <= 3 {
                            eprintln!(
                                "ttdrive-sim: {iface} node {}: SYNC period {} without RPDO ({:?}, {:?})",
                                d.node().node(),
                                d.cycles(),
                                d.node().nmt_state(),
                                d.node().cia402.state()
                            );
                        }
                    }
                }
                Ok(Some(BusEvent::Fault(f))) => eprintln!("ttdrive-sim: {iface}: bus fault {f:?}"),
                Ok(None) => break,
                Err(e) => {
                    eprintln!("ttdrive-sim: {iface}: {e}");
                    std::thread::sleep(Duration::from_millis(1));
                    break;
                }
            }
        }
        if got {
            last_rx = Instant::now();
            seen = true;
        }
        if let Some(t0) = first_sync {
            let t = t0.elapsed().as_secs_f64();
            inj.retain(|i| {
                if t >= i.at {
                    if let Some(d) = drives.iter_mut().find(|d| d.node().node() == i.node) {
                        eprintln!(
                            "ttdrive-sim: {iface}: node {} fails: {:?} at {t:.3} s",
                            i.node, i.failure
                        );
                        d.inject(i.failure, &mut out);
                    }
                    false
                } else {
                    true
                }
            });
            send(&mut bus, &mut out);
        }
        let now = rt::now_ns();
        if now >= next_ms {
            for d in drives.iter_mut() {
                d.tick_ms(&mut out);
            }
            send(&mut bus, &mut out);
            next_ms += 1_000_000;
            if now > next_ms + 10_000_000 {
                next_ms = now + 1_000_000; // after a stall: no burst of heartbeats
            }
        }
        if seen && last_rx.elapsed().as_secs_f64() > args.idle_exit
            || start.elapsed().as_secs_f64() > args.duration
            || bus.ended()
        {
            break;
        }
        // sleep in the kernel until a frame arrives or the 1 ms time base is due
        // (poll has 1 ms resolution: the time base may run up to 1 ms late, which only delays
        // a heartbeat or the SYNC watchdog)
        if rt::now_ns() < next_ms {
            bus.wait(1);
        }
    }
    for d in &drives {
        let c = d.node().counters();
        println!(
            "ttdrive-sim: {iface} node {}: state {:?}, position {:.6}, max tracking error {:.3e}, SYNC periods {}, missed RPDO {}, refused {}, malformed {}, RPDO replaced before its SYNC {}",
            d.node().node(),
            d.node().cia402.state(),
            d.position(),
            d.max_tracking_error(),
            d.cycles(),
            c.missed_rpdo,
            c.out_of_range,
            c.malformed,
            c.replaced_rpdo
        );
    }
}

fn send<B: CanBus>(bus: &mut B, out: &mut Frames) {
    for f in out.as_slice() {
        if let Err(e) = bus.send(f) {
            eprintln!("ttdrive-sim: send {:#05x}: {e}", f.id());
        }
    }
    out.clear();
}
