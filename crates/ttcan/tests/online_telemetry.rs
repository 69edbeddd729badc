//! Telemetry is never silent: an online session whose channel stops before every channel runs
//! (two of its four drives never boot) still sends telemetry, with the fault bits of that
//! channel's joints, so that the upper computer hears the fault instead of silence.

use std::net::UdpSocket;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

use ttcan::canopen::cia402::OpMode;
use ttcan::canopen::Units;
use ttcan::online::receiver::{controller_time, Mode};
use ttcan::online::session::{self, Endpoints, OnlineConfig};
use ttcan::online::wire::{self, Message, TelemetryMsg};
use ttcan::runtime::channel::{run_channel_with, ChannelPlan, Shared};
use ttcan::runtime::master::{ChannelMaster, LinkConfig, StopReason, WatchdogConfig, MAX_AXES_PER_CHANNEL};
use ttcan::runtime::rt;
use ttcan::runtime::vdrives::{VirtualBus, VirtualChannel};
use ttkin::hit::{HitOptions, HitPlanner};

const PERIOD_NS: u64 = 1_000_000;

/// gantry6 on two channels: joints 0–3 on the first, 4–5 on the second.
const JOINTS: [[Option<usize>; MAX_AXES_PER_CHANNEL]; 2] =
    [[Some(0), Some(1), Some(2), Some(3)], [Some(4), Some(5), None, None]];

#[test]
fn a_channel_stopped_before_the_others_run_still_gets_telemetry_with_its_fault_bits() {
    let chain = ttkin::robots::gantry6();
    let planner = HitPlanner::new(&chain, HitOptions::default()).unwrap();
    let reply = UdpSocket::bind("127.0.0.1:0").unwrap();
    let t0_ns = rt::now_ns() + 20 * PERIOD_NS;
    let ends = Endpoints {
        mode: Mode::Hit,
        listen: "127.0.0.1:0".parse().unwrap(),
        reply: reply.local_addr().unwrap(),
    };
    let cfg = OnlineConfig {
        priority: 0,
        telemetry_decimation: 5,
        ..OnlineConfig::default()
    };
    let (sess, mut followers) = session::start(ends, planner, &JOINTS, PERIOD_NS, t0_ns, &cfg).unwrap();
    // The first channel's bus holds drives 1 and 2 only; its master expects 1–4: 3 and 4 never
    // boot, the channel stops (no boot-up) without ever running. The second channel never starts.
    let vch = VirtualChannel {
        axes: (1..=2).map(|n| (n, Units::default())).collect(),
    };
    let mut port = VirtualBus::new(&vch, 1e-3, 500).unwrap();
    let links: Vec<LinkConfig> = (1..=4)
        .map(|n| LinkConfig {
            node: n,
            units: Units::default(),
            following_error_limit: 1.0,
            max_current: 100.0,
        })
        .collect();
    let wd = WatchdogConfig {
        enable_cycles: 100,
        feedback_cycles: 500,
        heartbeat_cycles: 5000,
        ..WatchdogConfig::default()
    };
    let master = ChannelMaster::new(&links, OpMode::Csp, wd).unwrap();
    let plan = ChannelPlan {
        joints: JOINTS[0],
        approach_s: 0.0,
        period_ns: PERIOD_NS,
        t0_ns,
        max_cycles: 3000,
        telemetry_rows: 16,
    };
    let shared = Shared::new(1, Arc::new(AtomicBool::new(false)));
    let report = run_channel_with("mem0", &mut port, master, &mut followers[0], &plan, &shared);
    assert!(
        matches!(report.stop_reason, Some(StopReason::NoBootUp(3 | 4))),
        "{:?}",
        report.stop_reason
    );
    assert!(!sess.timeline.all_enabled());
    // Telemetry keeps coming after the stop, every datagram with joints 0–3 faulted.
    let mut got: Vec<TelemetryMsg> = Vec::new();
    let mut buf = [0u8; 2048];
    reply.set_read_timeout(Some(Duration::from_millis(20))).unwrap();
    let until = controller_time() + 0.3;
    while controller_time() < until {
        if let Ok((n, _)) = reply.recv_from(&mut buf) {
            if let Ok(Message::Telemetry(t)) = wire::decode(&buf[..n]).map(|d| d.message) {
                got.push(t);
            }
        }
    }
    let k = sess.stop();
    assert!(got.len() >= 10, "{} telemetry datagrams in 0.3 s: {k:?}", got.len());
    assert!(k.telemetry_sent >= got.len() as u64, "{k:?}");
    for t in &got {
        assert_eq!(t.faults & 0b1111, 0b1111, "{t:?}");
        assert_eq!(t.faults >> 4, 0, "joints 4 and 5 never faulted: {t:?}");
        assert_eq!(t.joints, 6);
    }
}
