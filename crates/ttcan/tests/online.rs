//! The online hit mode end to end, in process: gantry6 on two channels of three virtual drives
//! (in-memory buses, 1 kHz), the receiver, planning and telemetry threads of
//! `ttcan::online::session`, and a client on loopback UDP sending hits and bad datagrams. The
//! tests check what the controller commands (the recorded setpoint stream of every channel),
//! what it answers, and its counters.

use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use nalgebra::Vector3;
use ttcan::canopen::cia402::OpMode;
use ttcan::canopen::Units;
use ttcan::online::counters::CountersSnapshot;
use ttcan::online::receiver::{controller_time, Mode};
use ttcan::online::session::{self, Endpoints, OnlineConfig};
use ttcan::online::wire::{self, HitMsg, Message, PlanStatus, StatusMsg, TelemetryMsg};
use ttcan::runtime::channel::{run_channel_with, ChannelPlan, ChannelReport, Shared};
use ttcan::runtime::master::{ChannelMaster, LinkConfig, StopReason, WatchdogConfig, MAX_AXES_PER_CHANNEL};
use ttcan::runtime::rt;
use ttcan::runtime::vdrives::{VirtualChannel, VirtualDrives};
use ttkin::hit::{Hit, HitOptions, HitPlanner};

/// One online run at a time: each runs five threads at 1 kHz on a shared machine.
static SERIAL: Mutex<()> = Mutex::new(());

const PERIOD_NS: u64 = 1_000_000;

/// The pipeline demo's hit (centre (0.35, −0.55, 0.05) m, 3 m/s along the normal) at controller
/// time `t_hit`, moved by `dx` along x.
fn demo_hit(id: u32, stroke: u32, t_hit: f64, dx: f64) -> HitMsg {
    let n = Vector3::new(0.3, -1.0, -0.2).normalize() * 3.0;
    let h = Hit::from_normal(
        [0.35 + dx, -0.55, 0.05],
        [0.3, -1.0, -0.2],
        [n.x, n.y, n.z],
        1.0,
        None,
        None,
    )
    .unwrap();
    let r = h.pose.rotation.matrix();
    let mut rotation = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            rotation[3 * i + j] = r[(i, j)];
        }
    }
    let c = h.pose.translation.vector;
    HitMsg {
        id,
        stroke,
        t_hit,
        rotation,
        centre: [c.x, c.y, c.z],
        twist: h.twist,
    }
}

/// The client side: sends datagrams to the controller, collects statuses and telemetry.
struct Client {
    socket: UdpSocket,
    to: SocketAddr,
    seq: u64,
}

impl Client {
    fn send_raw(&self, bytes: &[u8]) {
        self.socket.send_to(bytes, self.to).unwrap();
    }

    fn encode(&mut self, m: &Message, sent: f64) -> Vec<u8> {
        self.seq += 1;
        let mut buf = [0u8; wire::MAX_LEN];
        let n = wire::encode(m, self.seq, sent, &mut buf);
        buf[..n].to_vec()
    }

    fn hit(&mut self, h: HitMsg) {
        let b = self.encode(&Message::Hit(h), controller_time());
        self.send_raw(&b);
    }

    /// Every datagram received within `timeout` s (statuses, telemetry).
    fn drain(&self, timeout: f64) -> (Vec<StatusMsg>, Vec<TelemetryMsg>) {
        let (mut s, mut t) = (Vec::new(), Vec::new());
        let until = controller_time() + timeout;
        let mut buf = [0u8; 2048];
        self.socket.set_read_timeout(Some(Duration::from_millis(5))).unwrap();
        while controller_time() < until {
            if let Ok((n, _)) = self.socket.recv_from(&mut buf) {
                match wire::decode(&buf[..n]).map(|d| d.message) {
                    Ok(Message::Status(x)) => s.push(x),
                    Ok(Message::Telemetry(x)) => t.push(x),
                    _ => panic!("the controller sent something else"),
                }
            }
        }
        (s, t)
    }
}

/// What a run produced.
struct Run {
    reports: Vec<ChannelReport>,
    counters: CountersSnapshot,
    statuses: Vec<StatusMsg>,
    telemetry: Vec<TelemetryMsg>,
    t0_ns: u64,
    planner: HitPlanner,
}

const JOINTS: [[Option<usize>; MAX_AXES_PER_CHANNEL]; 2] =
    [[Some(0), Some(1), Some(2), None], [Some(3), Some(4), Some(5), None]];

/// Runs gantry6 online with `cfg`; `client` is called once the robot holds the ready pose (with
/// the client and the timeline's deadline-0 time), then the axes are stopped.
fn run(
    cfg: OnlineConfig,
    drive: impl FnOnce(&mut Client, &session::Session) -> (Vec<StatusMsg>, Vec<TelemetryMsg>),
) -> Run {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let chain = ttkin::robots::gantry6();
    let planner = HitPlanner::new(&chain, HitOptions::default()).unwrap();
    let reply = UdpSocket::bind("127.0.0.1:0").unwrap();
    let t0_ns = rt::now_ns() + 50 * PERIOD_NS;
    let ends = Endpoints {
        mode: Mode::Hit,
        listen: "127.0.0.1:0".parse().unwrap(),
        reply: reply.local_addr().unwrap(),
    };
    let (sess, followers) = session::start(ends, planner.clone(), &JOINTS, PERIOD_NS, t0_ns, &cfg).unwrap();
    let mut client = Client {
        socket: reply,
        to: sess.local,
        seq: 0,
    };
    let vch: Vec<VirtualChannel> = (0..2)
        .map(|_| VirtualChannel {
            axes: (1..=3).map(|n| (n, Units::default())).collect(),
        })
        .collect();
    let (mut drives, ports) = VirtualDrives::new(&vch, 1e-3, 500).unwrap();
    let interrupt = Arc::new(AtomicBool::new(false));
    let shared = Shared::new(2, interrupt.clone());
    let done = AtomicBool::new(false);
    // the machine is shared: generous watchdogs; the timing is not what is tested here
    let wd = WatchdogConfig {
        feedback_cycles: 500,
        ..WatchdogConfig::default()
    };
    let links: Vec<LinkConfig> = (1..=3)
        .map(|n| LinkConfig {
            node: n,
            units: Units::default(),
            following_error_limit: 1.0,
            max_current: 100.0,
        })
        .collect();
    let (reports, (statuses, telemetry)) = std::thread::scope(|s| {
        s.spawn(|| drives.serve(&done));
        let handles: Vec<_> = ports
            .into_iter()
            .zip(followers)
            .enumerate()
            .map(|(c, (mut port, mut follower))| {
                let master = ChannelMaster::new(&links, OpMode::Csp, wd).unwrap();
                let plan = ChannelPlan {
                    joints: JOINTS[c],
                    approach_s: 0.0,
                    period_ns: PERIOD_NS,
                    t0_ns,
                    max_cycles: 120_000,
                };
                let shared = &shared;
                s.spawn(move || run_channel_with(&format!("mem{c}"), &mut port, master, &mut follower, &plan, shared))
            })
            .collect();
        // enabled, then the approach to ready
        let until = controller_time() + 20.0;
        while !sess.timeline.all_enabled() && controller_time() < until {
            std::thread::sleep(Duration::from_millis(10));
        }
        assert!(sess.timeline.all_enabled(), "the drives were not enabled");
        std::thread::sleep(Duration::from_millis(1500));
        let got = drive(&mut client, &sess);
        interrupt.store(true, Ordering::Relaxed);
        let reports: Vec<ChannelReport> = handles.into_iter().map(|h| h.join().unwrap()).collect();
        done.store(true, Ordering::Relaxed);
        (reports, got)
    });
    let counters = sess.stop();
    for r in &reports {
        assert_eq!(
            r.stop_reason,
            Some(StopReason::Requested),
            "{}: {:?}",
            r.name,
            r.stop_reason
        );
    }
    Run {
        reports,
        counters,
        statuses,
        telemetry,
        t0_ns,
        planner,
    }
}

impl Run {
    /// The commanded joint stream (q, qd, qdd per joint) by deadline index, Run phase only.
    fn commanded(&self) -> Vec<(u64, [[f64; 3]; 6])> {
        let a = &self.reports[0].telemetry;
        let b = &self.reports[1].telemetry;
        let mut out = Vec::new();
        for ra in a.iter().filter(|r| r.phase == 2) {
            if let Some(rb) = b.iter().find(|r| r.cycle == ra.cycle && r.phase == 2) {
                let mut s = [[0.0; 3]; 6];
                for k in 0..3 {
                    s[k] = [ra.q_ref[k], ra.qd_ref[k], ra.qdd_ref[k]];
                    s[3 + k] = [rb.q_ref[k], rb.qd_ref[k], rb.qdd_ref[k]];
                }
                out.push((ra.cycle, s));
            }
        }
        out
    }

    /// Largest jumps of the commanded stream between consecutive cycles: |Δq − T·(qd+qd')/2|,
    /// |Δqd − T·(qdd+qdd')/2| and |Δqdd|/T (jerk) over joints.
    fn discontinuities(&self) -> (f64, f64, f64) {
        let c = self.commanded();
        let t = PERIOD_NS as f64 * 1e-9;
        let (mut dq, mut dv, mut jerk) = (0.0f64, 0.0f64, 0.0f64);
        for w in c.windows(2) {
            if w[1].0 != w[0].0 + 1 {
                continue;
            }
            for j in 0..6 {
                let (a, b) = (w[0].1[j], w[1].1[j]);
                dq = dq.max((b[0] - a[0] - t * 0.5 * (a[1] + b[1])).abs());
                dv = dv.max((b[1] - a[1] - t * 0.5 * (a[2] + b[2])).abs());
                jerk = jerk.max((b[2] - a[2]).abs() / t);
            }
        }
        (dq, dv, jerk)
    }

    /// Racket centre error (m) of the commanded joints at controller time `t`, against `h`.
    fn commanded_error_at(&self, t: f64, h: &HitMsg) -> f64 {
        let c = self.commanded();
        let x = (t * 1e9 - self.t0_ns as f64) / PERIOD_NS as f64;
        let k = x.floor() as u64;
        let f = x - k as f64;
        let a = c.iter().find(|r| r.0 == k).expect("cycle recorded").1;
        let b = c.iter().find(|r| r.0 == k + 1).expect("cycle recorded").1;
        let q: Vec<f64> = (0..6).map(|j| a[j][0] + f * (b[j][0] - a[j][0])).collect();
        let tool = self.planner.chain().fk(&q).unwrap();
        let racket = self.planner.racket().racket_pose(&tool);
        (racket.translation.vector - Vector3::from(h.centre)).norm()
    }
}

fn fast() -> OnlineConfig {
    OnlineConfig {
        silence_s: 30.0,
        ..OnlineConfig::default()
    }
}

#[test]
fn a_hit_is_planned_spliced_and_executed_end_to_end() {
    let mut sent = None;
    let r = run(fast(), |c, _| {
        let h = demo_hit(1, 1, controller_time() + 0.6, 0.0);
        sent = Some(h);
        c.hit(h);
        c.drain(2.5)
    });
    let h = sent.unwrap();
    assert_eq!(r.statuses.len(), 1, "{:?}", r.statuses);
    let st = r.statuses[0];
    assert_eq!((st.id, st.status), (1, PlanStatus::Accepted), "{st:?}");
    assert!((st.t_hit - h.t_hit).abs() < 1e-6, "{st:?}");
    assert!(st.planning_time > 0.0 && st.planning_time < 0.5, "{st:?}");
    let e = r.commanded_error_at(st.t_hit, &h);
    assert!(e < 1e-3, "commanded racket error at the hit {e} m");
    let (dq, dv, jerk) = r.discontinuities();
    assert!(dq < 1e-4 && dv < 5e-3, "{dq} {dv} {jerk}");
    assert!(!r.telemetry.is_empty());
    assert_eq!(r.counters.splices, 2, "approach and the hit: {:?}", r.counters);
    assert_eq!(r.counters.status_accepted, 1);
    eprintln!("{:?} jerk {jerk}", r.counters);
}
