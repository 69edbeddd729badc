//! The online hit mode end to end, in process: gantry6 on three channels of two virtual drives
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
use ttcan::runtime::vdrives::{VirtualBus, VirtualChannel};
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

const JOINTS: [[Option<usize>; MAX_AXES_PER_CHANNEL]; 3] = [
    [Some(0), Some(1), None, None],
    [Some(2), Some(3), None, None],
    [Some(4), Some(5), None, None],
];

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
    let vch: Vec<VirtualChannel> = (0..3)
        .map(|_| VirtualChannel {
            axes: (1..=2).map(|n| (n, Units::default())).collect(),
        })
        .collect();
    let ports: Vec<VirtualBus> = vch.iter().map(|c| VirtualBus::new(c, 1e-3, 500).unwrap()).collect();
    let interrupt = Arc::new(AtomicBool::new(false));
    let shared = Shared::new(3, interrupt.clone());
    // the machine is shared: generous watchdogs; the timing is not what is tested here
    let wd = WatchdogConfig {
        feedback_cycles: 500,
        heartbeat_cycles: 5000,
        ..WatchdogConfig::default()
    };
    let links: Vec<LinkConfig> = (1..=2)
        .map(|n| LinkConfig {
            node: n,
            units: Units::default(),
            following_error_limit: 1.0,
            max_current: 100.0,
        })
        .collect();
    let (reports, (statuses, telemetry)) = std::thread::scope(|s| {
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
                    telemetry_rows: 120_000 + 16,
                };
                let shared = &shared;
                s.spawn(move || {
                    let r = run_channel_with(&format!("mem{c}"), &mut port, master, &mut follower, &plan, shared);
                    if std::env::var("ONLINE_DEBUG").is_ok() {
                        for d in port.drives() {
                            eprintln!(
                                "mem{c}: drive fault {:?} state {:?}",
                                d.axis().fault(),
                                d.node().cia402.state()
                            );
                        }
                    }
                    r
                })
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
        (reports, got)
    });
    let counters = sess.stop();
    let reasons: Vec<_> = reports
        .iter()
        .map(|r| (r.name.clone(), r.stop_reason, r.skipped, r.stats.summary().max_us))
        .collect();
    if std::env::var("ONLINE_DEBUG").is_ok() {
        for r in &reports {
            let stop = r.telemetry.iter().position(|x| x.phase >= 3).unwrap_or(0);
            let first_run = r.telemetry.iter().position(|x| x.phase == 2).unwrap_or(0);
            eprintln!("{} run from {first_run} stop at {stop}", r.name);
            for x in &r.telemetry[stop.saturating_sub(5)..(stop + 2).min(r.telemetry.len())] {
                eprintln!("{} {} {:?} {:?} {:?}", x.cycle, x.phase, x.q_ref, x.q, x.qd_ref);
            }
        }
    }
    for r in &reports {
        assert_eq!(r.stop_reason, Some(StopReason::Requested), "{reasons:?}");
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
    /// The commanded joint stream (q, qd, qdd per joint) by deadline (the channels keep one
    /// stroke clock: a channel that skipped deadlines has no row there, and the others hold
    /// their stroke as long, repeating a row), every channel in the Run phase.
    fn commanded(&self) -> Vec<(u64, [[f64; 3]; 6])> {
        self.commanded_clocked().into_iter().map(|(k, s, _)| (k, s)).collect()
    }

    /// [`Run::commanded`] with each channel's stroke clock at that deadline (the executed cycle
    /// its stroke follower sampled, as the controller recorded it: `TelemetryRow::source_cycle`).
    fn commanded_clocked(&self) -> Vec<(u64, [[f64; 3]; 6], [u64; 3])> {
        let by_deadline: Vec<std::collections::HashMap<u64, usize>> = self
            .reports
            .iter()
            .map(|r| r.telemetry.iter().enumerate().map(|(i, x)| (x.cycle, i)).collect())
            .collect();
        let last = self.reports[0].telemetry.last().map_or(0, |x| x.cycle);
        let mut out = Vec::new();
        for k in 0..=last {
            let Some(rows) = self
                .reports
                .iter()
                .zip(&by_deadline)
                .map(|(r, m)| m.get(&k).map(|&i| r.telemetry[i]))
                .collect::<Option<Vec<_>>>()
            else {
                continue;
            };
            if rows.iter().any(|r| r.phase != 2) {
                continue;
            }
            let mut s = [[0.0; 3]; 6];
            let mut clock = [0u64; 3];
            for (ch, r) in rows.iter().enumerate() {
                clock[ch] = r.source_cycle;
                for k in 0..2 {
                    s[2 * ch + k] = [r.q_ref[k], r.qd_ref[k], r.qdd_ref[k]];
                }
            }
            out.push((k, s, clock));
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
                if a == b {
                    continue; // held (a pause to keep the stroke clock), or at rest
                }
                dq = dq.max((b[0] - a[0] - t * 0.5 * (a[1] + b[1])).abs());
                let v = (b[1] - a[1] - t * 0.5 * (a[2] + b[2])).abs();
                if v > 1e-3 && std::env::var("STALL_DEBUG").is_ok() {
                    eprintln!("dv {v:.2e} at deadline {} joint {j}: {a:?} -> {b:?}", w[0].0);
                }
                dv = dv.max(v);
                jerk = jerk.max((b[2] - a[2]).abs() / t);
            }
        }
        (dq, dv, jerk)
    }

    /// The largest step of the commanded acceleration against its neighbours: over every joint
    /// and three consecutive cycle pairs, |Δq̈ₖ| − 2·max(|Δq̈ₖ₋₁|, |Δq̈ₖ₊₁|) (m/s² or rad/s²).
    /// A continuous q̈ (finite jerk, also where the jerk itself jumps at a splice) changes by
    /// about the same from one cycle to the next: this stays near or below 0; a step shows.
    fn acceleration_step(&self) -> f64 {
        let c = self.commanded();
        let mut worst = f64::NEG_INFINITY;
        for w in c.windows(4) {
            if w[3].0 != w[0].0 + 3 {
                continue;
            }
            for j in 0..6 {
                if (0..3).any(|k| w[k + 1].1[j] == w[k].1[j]) {
                    continue; // held or at rest
                }
                let d = |k: usize| (w[k + 1].1[j][2] - w[k].1[j][2]).abs();
                worst = worst.max(d(1) - 2.0 * d(0).max(d(2)));
            }
        }
        worst
    }

    /// Racket centre error (m) of the commanded joints at the hit `h` planned for controller time
    /// `t` at controller time `planned` or later ([`Run::closest`]). Each chord runs from the
    /// joints commanded at a deadline to each channel's next executed cycle (its next sample of
    /// the stroke, wherever a stall of that channel put it): a stall just after an in-step hit
    /// that falls between two cycles removes the row after it, and the error would then be the
    /// distance from the row before, up to half a cycle of racket motion (the 0.1–0.85 mm "in
    /// step" errors of earlier runs; the measured racket was within 3e-5 m there).
    fn commanded_error_at(&self, t: f64, h: &HitMsg, planned: f64) -> f64 {
        let rows: Vec<Row> = self
            .commanded_clocked()
            .into_iter()
            .map(|(k, s, c)| (k, (0..6).map(|j| s[j][0]).collect(), c))
            .collect();
        // each channel's commanded joints by its executed cycle (Run phase)
        let by_exec: Vec<std::collections::HashMap<u64, [f64; 2]>> = self
            .reports
            .iter()
            .map(|r| {
                r.telemetry
                    .iter()
                    .filter(|x| x.phase == 2)
                    .map(|x| (x.source_cycle, [x.q_ref[0], x.q_ref[1]]))
                    .collect()
            })
            .collect();
        let next = |r: &Row| -> Option<Vec<f64>> {
            let mut q = Vec::with_capacity(6);
            for (c, m) in by_exec.iter().enumerate() {
                q.extend_from_slice(m.get(&(r.2[c] + 1))?);
            }
            Some(q)
        };
        self.closest_with(&rows, t, h, planned, Some(&next))
    }

    /// The closest approach (m) of the racket centre of `rows` (joints by deadline, with each
    /// channel's stroke clock) to the hit `h` planned for controller time `t` at controller time
    /// `planned` or later.
    ///
    /// Every row carries the executed cycle its channel's stroke follower sampled, as the
    /// controller recorded it (`TelemetryRow::source_cycle`), so deadline − that is the deadlines
    /// the channel had skipped. The planner puts the hit at the deadline `x` of `t` with the skips
    /// it sees (a re-plan that brings the channels back in step keeps it there, or moves it to
    /// when the channel furthest behind reaches it); deadlines a channel skips after that delay
    /// it. So the hit is within `x − 5` .. `x + 5 + S`, `S` the most deadlines any channel skipped
    /// since `planned` up to that end. Over the rows there, linear between rows of consecutive
    /// deadlines (every channel commanding; the racket moves ~3 mm per cycle). A stall that
    /// leaves the channels apart at the hit shows as a large error here; the controller counts
    /// such hits (`hits_out_of_step`).
    fn closest(&self, rows: &[Row], t: f64, h: &HitMsg, planned: f64) -> f64 {
        self.closest_with(rows, t, h, planned, None)
    }

    /// [`Run::closest`] with chords from each row to `next` of it (else to the row of the next
    /// deadline).
    #[allow(clippy::type_complexity)]
    fn closest_with(
        &self,
        rows: &[Row],
        t: f64,
        h: &HitMsg,
        planned: f64,
        next: Option<&dyn Fn(&Row) -> Option<Vec<f64>>>,
    ) -> f64 {
        let deadline = |t: f64| (t * 1e9 - self.t0_ns as f64) / PERIOD_NS as f64;
        let x = deadline(t);
        // each channel's skipped deadlines as of deadline d: from the last row at or before it
        let lag = |d: f64| -> [f64; 3] {
            let i = rows.partition_point(|r| (r.0 as f64) <= d);
            rows[..i].last().map_or([0.0; 3], |r| r.2.map(|c| (r.0 - c) as f64))
        };
        let before = lag(deadline(planned));
        let mut hi = x + 5.0;
        loop {
            let now = lag(hi);
            let s = (0..3).map(|c| now[c] - before[c]).fold(0.0, f64::max);
            if x + 5.0 + s <= hi {
                break;
            }
            hi = x + 5.0 + s;
        }
        let lo = x - 5.0;
        let centre = |q: &[f64]| {
            let tool = self.planner.chain().fk(q).unwrap();
            self.planner.mount().racket_pose(&tool).translation.vector
        };
        let p = Vector3::from(h.centre);
        let mut best = f64::INFINITY;
        for (i, r) in rows.iter().enumerate() {
            let k = r.0 as f64;
            if k < lo || k > hi {
                continue;
            }
            let end = match next {
                Some(f) => f(r),
                None => rows.get(i + 1).filter(|n| n.0 == r.0 + 1).map(|n| n.1.clone()),
            };
            let Some(end) = end else { continue };
            let (a, b) = (centre(&r.1), centre(&end));
            let d = b - a;
            let s = if d.norm_squared() > 0.0 {
                ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            best = best.min((a + s * d - p).norm());
        }
        if std::env::var("STALL_DEBUG").is_ok() {
            eprintln!("  x {x:.0} deadlines {lo:.0}..{hi:.0}");
        }
        best
    }
}

/// One row of a record: deadline, joint positions, each channel's stroke clock.
type Row = (u64, Vec<f64>, [u64; 3]);

/// A long silence timeout, and a splice lead for a debug build of the planner on a loaded
/// machine (a release build plans the demo hit in a few ms).
fn fast() -> OnlineConfig {
    OnlineConfig {
        // a debug build plans for tens of ms: normal scheduling on the shared machine
        priority: 0,
        silence_s: 30.0,
        splice_lead_s: 0.05,
        telemetry_decimation: 10,
        ..OnlineConfig::default()
    }
}

#[test]
fn a_hit_is_planned_spliced_and_executed_end_to_end() {
    let mut sent = None;
    let mut sent_at = 0.0;
    let r = run(fast(), |c, _| {
        let h = demo_hit(1, 1, controller_time() + 0.8, 0.0);
        sent = Some(h);
        sent_at = controller_time();
        c.hit(h);
        c.drain(2.5)
    });
    let h = sent.unwrap();
    // its status; a second one, `out_of_step`, when a stall left the channels apart too close to
    // the hit to re-plan (a loaded machine)
    let (own, late): (Vec<StatusMsg>, Vec<StatusMsg>) =
        r.statuses.iter().partition(|s| s.status != PlanStatus::OutOfStep);
    assert_eq!(own.len(), 1, "{:?}", r.statuses);
    assert!(late.iter().all(|s| s.id == 1) && late.len() <= 1, "{:?}", r.statuses);
    let st = own[0];
    assert_eq!((st.id, st.status), (1, PlanStatus::Accepted), "{st:?}");
    assert!((st.t_hit - h.t_hit).abs() < 1e-6, "{st:?}");
    assert!(st.planning_time > 0.0 && st.planning_time < 0.5, "{st:?}");
    let e = r.commanded_error_at(st.t_hit, &h, sent_at);
    let k = r.counters;
    assert_eq!(k.hits_in_step + k.hits_out_of_step, 1, "{k:?}");
    assert!(
        e < 1e-3 || k.hits_out_of_step == 1,
        "commanded racket error at the hit {e} m: {k:?}"
    );
    let (dq, dv, jerk) = r.discontinuities();
    assert!(dq < 1e-4 && dv < 5e-3, "{dq} {dv} {jerk}");
    assert!(!r.telemetry.is_empty());
    assert_eq!(r.counters.splices, 2, "approach and the hit: {:?}", r.counters);
    assert_eq!(r.counters.status_accepted, 1);
    eprintln!("{:?} jerk {jerk}", r.counters);
}

impl Run {
    /// The commanded rows from cycle `from` on.
    fn commanded_from(&self, from: u64) -> Vec<(u64, [[f64; 3]; 6])> {
        self.commanded().into_iter().filter(|r| r.0 >= from).collect()
    }

    /// Racket centre error (m) of the measured joints at the hit `h` (as
    /// [`Run::commanded_error_at`], the feedback a few cycles behind the command).
    fn measured_error_at(&self, t: f64, h: &HitMsg, planned: f64) -> f64 {
        let by_deadline: Vec<std::collections::HashMap<u64, usize>> = self
            .reports
            .iter()
            .map(|r| r.telemetry.iter().enumerate().map(|(i, x)| (x.cycle, i)).collect())
            .collect();
        let last = self.reports[0].telemetry.last().map_or(0, |x| x.cycle);
        let rows: Vec<Row> = (0..=last)
            .filter_map(|k| {
                let idx: Vec<usize> = by_deadline.iter().map(|m| m.get(&k).copied()).collect::<Option<_>>()?;
                let tel = |c: usize| self.reports[c].telemetry[idx[c]];
                (0..3).all(|c| tel(c).phase == 2).then(|| {
                    (
                        k,
                        (0..6).map(|j| tel(j / 2).q[j % 2]).collect(),
                        [0, 1, 2].map(|c| tel(c).source_cycle),
                    )
                })
            })
            .collect();
        self.closest(&rows, t + 0.004, h, planned)
    }
}

/// Bad input of every class, then a flood at 10 000 datagrams/s: counted and dropped, every hit
/// that got through the screen answered, and the commanded state unchanged (the ready pose).
#[test]
fn bad_input_of_every_class_and_a_flood_change_nothing_but_the_counters() {
    let mut from_cycle = 0;
    let flood_s = 1.0;
    let r = run(fast(), |c, sess| {
        from_cycle = sess.timeline.present_cycle();
        let now = controller_time();
        // a hit in the past: through the screen, answered `rejected`
        let past = demo_hit(7, 7, now - 0.1, 0.0);
        let good = c.encode(&Message::Hit(past), now);
        c.send_raw(&good);
        c.send_raw(&good); // duplicate
        let older = {
            let mut b = good.clone();
            b[8..16].copy_from_slice(&(c.seq - 1).to_le_bytes());
            b
        };
        c.send_raw(&older); // out of order
        let stale = c.encode(&Message::Hit(demo_hit(8, 8, now + 0.5, 0.0)), now - 1.0);
        c.send_raw(&stale);
        let mut nan = demo_hit(9, 9, now + 0.5, 0.0);
        nan.centre[1] = f64::NAN;
        let nan = c.encode(&Message::Hit(nan), now);
        c.send_raw(&nan);
        let mut inf = demo_hit(10, 10, now + 0.5, 0.0);
        inf.twist[0] = f64::INFINITY;
        let inf = c.encode(&Message::Hit(inf), now);
        c.send_raw(&inf);
        let valid = c.encode(&Message::Hit(demo_hit(11, 11, now + 5.0, 0.0)), now);
        c.send_raw(&valid[..60]); // truncated
        let mut long = valid.clone();
        long.extend_from_slice(&[0; 8]);
        c.send_raw(&long); // oversized
        let mut v2 = valid.clone();
        v2[4] = 2;
        c.send_raw(&v2); // unknown version
        let mut magic = valid.clone();
        magic[..4].copy_from_slice(b"XXXX");
        c.send_raw(&magic); // malformed
        c.send_raw(&[0u8; 1]);
        let mut got = c.drain(0.2);
        // the flood: 10 000 datagrams/s of every bad class in turn
        let bad: [Vec<u8>; 5] = [
            valid[..60].to_vec(),
            long.clone(),
            v2.clone(),
            magic.clone(),
            nan.clone(),
        ];
        let n = (10_000.0 * flood_s) as usize;
        let t_start = rt::now_ns();
        for k in 0..n {
            rt::sleep_until(t_start + k as u64 * 100_000);
            c.send_raw(&bad[k % 5]);
        }
        let (s, t) = c.drain(0.5);
        got.0.extend(s);
        got.1.extend(t);
        got
    });
    let k = r.counters;
    let n = (10_000.0 * flood_s) as u64;
    assert_eq!(k.duplicate, 1, "{k:?}");
    assert_eq!(k.out_of_order, 1, "{k:?}");
    assert_eq!(k.stale, 1, "{k:?}");
    assert_eq!(k.truncated, 2 + n / 5, "{k:?}");
    assert_eq!(k.oversized, 1 + n / 5, "{k:?}");
    assert_eq!(k.unknown_version, 1 + n / 5, "{k:?}");
    assert_eq!(k.malformed, 1 + n / 5, "{k:?}");
    assert_eq!(k.non_finite, 2 + n / 5, "{k:?}");
    // every datagram the socket kept was counted (loopback may drop under a flood, never here
    // silently: received = accepted + refused)
    assert_eq!(k.received, k.accepted + k.refused(), "{k:?}");
    assert_eq!((k.accepted, k.hits, k.status_rejected), (1, 1, 1), "{k:?}");
    assert_eq!(r.statuses.len(), 1);
    assert_eq!((r.statuses[0].id, r.statuses[0].status), (7, PlanStatus::Rejected));
    assert_eq!(k.splices, 1, "only the approach to ready: {k:?}");
    let ready = r.planner.default_ready().to_vec();
    let rows = r.commanded_from(from_cycle);
    assert!(rows.len() as f64 > 1000.0 * flood_s, "{} rows", rows.len());
    let first = rows[0].1;
    for j in 0..6 {
        assert!((first[j][0] - ready[j]).abs() < 1e-12, "{first:?}");
    }
    for (cycle, s) in rows {
        assert_eq!(s, first, "cycle {cycle}: the commanded state changed");
    }
}

/// Silence longer than the timeout in the middle of a stroke: back to ready (the hit abandoned)
/// and held there, the setpoints continuous.
#[test]
fn silence_brings_the_robot_back_to_ready_and_holds_it() {
    let cfg = OnlineConfig {
        priority: 0,
        silence_s: 0.4,
        splice_lead_s: 0.1,
        ..OnlineConfig::default()
    };
    let r = run(cfg, |c, _| {
        c.hit(demo_hit(1, 1, controller_time() + 1.2, 0.0));
        c.drain(2.0)
    });
    let k = r.counters;
    assert_eq!((k.status_accepted, k.silence_timeouts, k.splices), (1, 1, 3), "{k:?}");
    let ready = r.planner.default_ready().to_vec();
    let last = r.commanded().last().unwrap().1;
    for j in 0..6 {
        assert!(
            (last[j][0] - ready[j]).abs() < 1e-9 && last[j][1].abs() < 1e-9,
            "{last:?}"
        );
    }
    let (dq, dv, _) = r.discontinuities();
    assert!(dq < 1e-4 && dv < 5e-3, "{dq} {dv}");
}

/// 100 hits at random times while strokes run (some replacing the pending hit of their stroke):
/// every hit answered, every executed one met by the commanded racket within 1 mm at its hit time
/// (the offline simulation's bound, docs/simulate.md) unless the controller counted it out of
/// step (its channels commanded it at different deadlines: a channel thread stalled too close to
/// the hit to re-plan; `hits_out_of_step`), every executed hit counted in step or out of step,
/// the commanded position, velocity and acceleration continuous (q̈ changing by at most the jerk
/// limit × T per cycle), and the measured racket error reported.
#[test]
fn hits_at_random_times_are_all_answered_and_executed_continuously() {
    let n = 100;
    let mut sent = Vec::new();
    let r = run(fast(), |c, _| {
        let mut rng = 0x2545F4914F6CDD1Du64;
        let mut u = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut stroke = 1;
        let mut got = (Vec::new(), Vec::new());
        for id in 1..=n {
            if u() > 0.3 {
                stroke += 1;
            }
            let h = demo_hit(id, stroke, controller_time() + 0.7 + 0.5 * u(), 0.1 * (u() - 0.5));
            sent.push((h, controller_time()));
            c.hit(h);
            // every 10th hit, time to come to rest at ready
            let wait = 0.15 + 0.35 * u();
            let (s, t) = c.drain(if id % 10 == 0 { 2.0 } else { wait });
            got.0.extend(s);
            got.1.extend(t);
        }
        let (s, t) = c.drain(1.5);
        got.0.extend(s);
        got.1.extend(t);
        got
    });
    let k = r.counters;
    eprintln!("{k:?}");
    // a hit's own status; `replaced` and `out_of_step` come as second statuses of accepted hits
    let own: Vec<&StatusMsg> = r
        .statuses
        .iter()
        .filter(|s| !matches!(s.status, PlanStatus::Replaced | PlanStatus::OutOfStep))
        .collect();
    assert_eq!(own.len(), n as usize, "one status per hit: {:?}", r.statuses);
    for id in 1..=n {
        assert!(own.iter().any(|s| s.id == id), "hit {id} unanswered");
    }
    let replaced: Vec<u32> = r
        .statuses
        .iter()
        .filter(|s| s.status == PlanStatus::Replaced)
        .map(|s| s.id)
        .collect();
    let executed: Vec<(&StatusMsg, &(HitMsg, f64))> = own
        .iter()
        .filter(|s| s.status == PlanStatus::Accepted && !replaced.contains(&s.id))
        .map(|s| (*s, sent.iter().find(|h| h.0.id == s.id).unwrap()))
        .collect();
    // (how many are accepted depends on the load: a debug planner of 0.1–0.5 s against hits 0.7–1.2 s ahead)
    assert!(executed.len() >= 10, "{} executed of {n}: {k:?}", executed.len());
    let mut worst = (0.0f64, 0.0f64);
    let mut outside = Vec::new();
    for (s, h) in &executed {
        let (h, at) = (&h.0, h.1);
        let e = r.commanded_error_at(s.t_hit, h, at);
        let m = r.measured_error_at(s.t_hit, h, at);
        if std::env::var("STALL_DEBUG").is_ok() {
            eprintln!(
                "hit {}: commanded racket error {e:.2e} m, measured {m:.2e} m, t {:.4}",
                h.id, s.t_hit
            );
        }
        if e < 1e-3 {
            worst = (worst.0.max(e), worst.1.max(m));
        } else {
            outside.push((h.id, e));
        }
    }
    // Each executed hit is counted once by the controller, in step or not (before, in two loaded
    // runs one was counted by neither: docs/online.md); those outside the bound are at most the
    // ones it counted out of step (a stall within a few cycles of the hit, too close to re-plan:
    // the controller says so, the test does not exclude them itself). A hit answered
    // `out_of_step` before its time was accepted, and is counted out of step or (brought back
    // in step by a later re-plan) in step.
    let counted = k.hits_in_step + k.hits_out_of_step;
    assert_eq!(counted, executed.len() as u64, "hits counted in or out of step: {k:?}");
    let announced: Vec<u32> = r
        .statuses
        .iter()
        .filter(|s| s.status == PlanStatus::OutOfStep)
        .map(|s| s.id)
        .collect();
    for id in &announced {
        let known = executed.iter().any(|(s, _)| s.id == *id) || replaced.contains(id);
        assert!(known, "hit {id} answered out_of_step was not accepted");
    }
    eprintln!("answered out_of_step before the hit: {announced:?}");
    // A hit in step is exact: the re-plans keep its joint state and the commanded racket meets
    // the centre to 1e-5 m (a cycle of skew is 0.3–0.9 mm): the hits off by more are at most
    // those counted out of step.
    let off = executed
        .iter()
        .filter(|(s, h)| r.commanded_error_at(s.t_hit, &h.0, h.1) > 1e-5)
        .count() as u64;
    assert!(off <= k.hits_out_of_step, "{off} hits off by more than 1e-5 m: {k:?}");
    assert!(
        outside.len() as u64 <= k.hits_out_of_step,
        "hits outside the 1 mm bound {outside:?} but {} counted out of step: {k:?}",
        k.hits_out_of_step
    );
    let (dq, dv, jerk) = r.discontinuities();
    let step = r.acceleration_step();
    eprintln!(
        "{} executed, {} within the 1 mm racket bound, {} outside {outside:?} ({} counted out of step, \
         skew up to {} cycles; {} re-plans in step, {} failed), {} replaced; \
         worst racket error within the bound commanded {:.2e} m, measured {:.2e} m; \
         discontinuity q {dq:.1e} qd {dv:.1e}, jerk {jerk:.0}, q̈ step {step:.2e}",
        executed.len(),
        executed.len() - outside.len(),
        outside.len(),
        k.hits_out_of_step,
        k.hit_skew_max_cycles,
        k.resyncs,
        k.resyncs_failed,
        replaced.len(),
        worst.0,
        worst.1
    );
    assert_eq!(k.splices_late, 0, "{k:?}");
    // Continuity with the jerk the strokes may have: every joint's q̈ changes by at most its jerk
    // limit × T from one cycle to the next (a step of q̈ at a splice would exceed it: tens of
    // m/s² against J·T), and q̇ follows q̈ to the trapezoid rule's error for a jerk within the
    // limit, J·T²/4. (The re-plans that bring the channels in step start from moving states and
    // are more often jerk-limited legs, whose jerk switches within a cycle: the relative
    // acceleration-step measure, `step`, fits the quintic legs only and is printed.)
    let t = PERIOD_NS as f64 * 1e-9;
    let jmax = r.planner.limits().jerk.clone();
    let over = r.jerk_ratio(&jmax);
    let j_top = jmax.iter().cloned().fold(0.0, f64::max);
    eprintln!("largest q̈ change per cycle / (jerk limit × T): {over:.4}");
    assert!(dq < 1e-4 && dv <= 0.25 * j_top * t * t * 1.01, "{dq} {dv}");
    assert!(
        over <= 1.0 + 1e-3,
        "the commanded acceleration changes by {over} × the jerk limit in a cycle"
    );
}

impl Run {
    /// The largest change of a joint's commanded q̈ between consecutive cycles over its jerk
    /// limit × T (`jerk`: per joint, m/s³ or rad/s³).
    fn jerk_ratio(&self, jerk: &[f64]) -> f64 {
        let c = self.commanded();
        let t = PERIOD_NS as f64 * 1e-9;
        let mut worst = 0.0f64;
        for w in c.windows(2) {
            if w[1].0 != w[0].0 + 1 {
                continue;
            }
            for (j, limit) in jerk.iter().enumerate().take(6) {
                worst = worst.max((w[1].1[j][2] - w[0].1[j][2]).abs() / (limit * t));
            }
        }
        worst
    }
}
