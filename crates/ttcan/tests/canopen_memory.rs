//! The controller and two virtual drives on the in-memory bus, in lock step (one cycle = master
//! read/update/write, then the drives): tracking of a motion, and every injected fault bringing
//! both axes to a controlled stop with the right reason, without panics and without motion on
//! stale data.

#[path = "support/channel.rs"]
mod channel;
use ttcan::bus::memory::{Faults, MemoryBus, MemoryPort};
use ttcan::bus::CanBus;
use ttcan::canopen::cia402::OpMode;
use ttcan::canopen::{DriveState, Frames, Units};
use ttcan::runtime::master::{AxisSetpoint, ChannelMaster, Phase, StopReason, WatchdogConfig};
use ttcan::vdrive::{Failure, VirtualDrive};
use ttcan::{AxisConfig, MotorModel};

/// A fault injected at a cycle of the motion.
type Injection<'a> = Option<(u64, &'a dyn Fn(&mut Rig))>;

struct Rig {
    bus: MemoryBus,
    master_port: MemoryPort,
    master: ChannelMaster,
    drives: Vec<(MemoryPort, VirtualDrive)>,
    cycle: u64,
}

fn rig() -> Rig {
    rig_with(AxisConfig::new(MotorModel::maxon_re25_gp26()))
}

fn rig_with(cfg: AxisConfig) -> Rig {
    let bus = MemoryBus::new();
    let master_port = bus.port();
    let links = channel::two_links();
    let master = ChannelMaster::new(&links, OpMode::Csp, WatchdogConfig::default()).unwrap();
    let model = MotorModel::maxon_re25_gp26();
    let drives = (1..=2)
        .map(|n| {
            let mut port = bus.port();
            let mut out = Frames::new();
            let d = VirtualDrive::new(n, &model, &cfg, Units::default(), 1e-3, &mut out).unwrap();
            for f in out.as_slice() {
                port.send(f).unwrap();
            }
            (port, d)
        })
        .collect();
    Rig {
        bus,
        master_port,
        master,
        drives,
        cycle: 0,
    }
}

impl Rig {
    /// Injects `failure` into drive `k` (0-based); the frames it answers with are sent on the bus
    /// when `send` is true, dropped otherwise.
    fn inject(&mut self, k: usize, failure: Failure, send: bool) {
        let mut out = Frames::new();
        self.drives[k].1.inject(failure, &mut out);
        if send {
            for f in out.as_slice() {
                self.drives[k].0.send(f).unwrap();
            }
        }
    }

    /// One lock-step cycle: the controller reads, updates and writes, then the drives answer.
    fn step(&mut self, q: f64) {
        self.master_read();
        self.master_write(q);
        self.serve_drives();
        self.cycle += 1;
    }

    /// The controller's read phase: every waiting event.
    fn master_read(&mut self) {
        while let Ok(Some(ev)) = self.master_port.poll() {
            self.master.on_event(&ev);
        }
    }

    /// The controller's update and write phases: axis 1 to `q`, axis 2 to −`q`.
    fn master_write(&mut self, q: f64) {
        let mut out = Frames::new();
        let sp = [
            AxisSetpoint { q, qd: 0.0, tau: 0.0 },
            AxisSetpoint {
                q: -q,
                qd: 0.0,
                tau: 0.0,
            },
        ];
        self.master.cycle(&sp, &mut out);
        for f in out.as_slice() {
            let _ = self.master_port.send(f);
        }
    }

    /// The drives handle every frame waiting for them, tick their 1 ms time base and answer.
    fn serve_drives(&mut self) {
        for (port, d) in self.drives.iter_mut() {
            let mut out = Frames::new();
            while let Ok(Some(ev)) = port.poll() {
                if let ttcan::bus::BusEvent::Frame { frame, .. } = ev {
                    d.on_frame(&frame, &mut out);
                }
            }
            d.tick_ms(&mut out);
            for f in out.as_slice() {
                let _ = port.send(f);
            }
        }
    }

    /// From now on the bus drops every frame whose COB-ID is in `ids` (no other fault).
    fn drop_frames(&mut self, ids: &[u16]) {
        self.bus.set_faults(Faults {
            drop_ids: ids.to_vec(),
            ..Faults::default()
        });
    }

    /// Runs until Run phase; returns the cycle count.
    fn enable(&mut self) -> u64 {
        for _ in 0..200 {
            self.step(0.0);
            if self.master.phase() == Phase::Run {
                return self.cycle;
            }
        }
        panic!("not enabled: {:?} {:?}", self.master.phase(), self.master.stop_reason());
    }

    fn motion(t: f64) -> f64 {
        0.5 * (1.0 - (2.0 * std::f64::consts::PI * t).cos())
    }

    /// Runs `cycles` of motion from the start of Run; returns the largest tracking error seen.
    fn run(&mut self, cycles: u64, fault_at: Injection<'_>) -> f64 {
        let t0 = self.cycle;
        let mut worst: f64 = 0.0;
        for k in 0..cycles {
            if let Some((at, f)) = fault_at {
                if k == at {
                    f(self);
                }
            }
            let q = Rig::motion((self.cycle - t0) as f64 * 1e-3);
            self.step(q);
            if self.master.phase() == Phase::Run {
                if let Some(fb) = self.master.feedback(0) {
                    worst = worst.max((fb.q - Rig::motion((self.cycle - t0) as f64 * 1e-3 - 2e-3)).abs());
                }
            }
        }
        worst
    }
}

#[test]
fn two_drives_boot_enable_and_track_a_motion() {
    let mut r = rig();
    let c = r.enable();
    assert!(c < 50, "enabled after {c} cycles");
    let worst = r.run(1000, None);
    assert_eq!(r.master.stop_reason(), None);
    assert!(worst < 0.02, "tracking error {worst} rad");
    assert_eq!(r.master.counters().missed_feedback, 0);
    for (_, d) in &r.drives {
        assert_eq!(
            d.node().counters().missed_rpdo,
            0,
            "every SYNC in Operational has its RPDO"
        );
    }
    let err = (r.drives[1].1.position() - (-Rig::motion(1.0))).abs();
    assert!(err < 0.02, "final error {err}");
}

/// Drives that answer late (their thread stalled, then catching up between the controller's read
/// and write, as a loaded host schedules it): the newest answer the controller then reads is one
/// SYNC older than its last SYNC, although it arrived in the last cycle. Such feedback is not in
/// step; every feedback that is in step is exactly what a lock-step run reads at that cycle.
#[test]
fn late_answers_are_not_taken_for_feedback_in_step() {
    let (mut a, mut b) = (rig(), rig());
    assert_eq!(a.enable(), b.enable());
    let (mut in_step, mut late_but_fresh) = (0, 0);
    for k in 0..400u64 {
        let q = Rig::motion(k as f64 * 1e-3);
        a.step(q);
        b.master_read();
        if k == 102 {
            // the stalled drives catch up before this cycle's SYNC
            b.serve_drives();
        }
        b.master_write(q);
        if !(100..=102).contains(&k) {
            b.serve_drives();
        }
        b.cycle += 1;
        for ax in 0..2 {
            let (fa, fb) = (a.master.feedback(ax).unwrap(), b.master.feedback(ax).unwrap());
            if b.master.feedback_in_step(ax) {
                in_step += 1;
                assert_eq!(
                    fb.q, fa.q,
                    "cycle {k} axis {ax}: in step but not the lock-step feedback"
                );
            } else if fb.received_cycle + 1 == b.master.counters().cycles && fb.q != fa.q {
                late_but_fresh += 1;
            }
        }
        if k >= 5 {
            assert!(
                a.master.feedback_in_step(0) && a.master.feedback_in_step(1),
                "lock step, cycle {k}"
            );
        }
    }
    assert_eq!(b.master.stop_reason(), None);
    assert!(
        late_but_fresh > 0,
        "the stall made no late answer: the case is not exercised"
    );
    assert!(in_step > 2 * 380, "{in_step} in-step samples");
}

fn fault_case(inject: &dyn Fn(&mut Rig), expected: fn(StopReason) -> bool, within: u32) {
    fault_case_except(inject, expected, within, None)
}

/// `unplugged`: a drive cut off the bus (its own state is not observable).
fn fault_case_except(
    inject: &dyn Fn(&mut Rig),
    expected: fn(StopReason) -> bool,
    within: u32,
    unplugged: Option<usize>,
) {
    fault_case_coasting(inject, expected, within, unplugged, None)
}

/// `coasting`: a drive whose fault reaction switches the bridge off at once (open winding): its
/// joint coasts down under friction, as the hardware's does, so it is checked for its power stage
/// being off, not for standing still.
fn fault_case_coasting(
    inject: &dyn Fn(&mut Rig),
    expected: fn(StopReason) -> bool,
    within: u32,
    unplugged: Option<usize>,
    coasting: Option<usize>,
) {
    let mut r = rig();
    r.enable();
    r.run(300, Some((200, inject)));
    let reason = r.master.stop_reason().expect("a stop");
    assert!(expected(reason), "reason {reason:?}");
    assert_eq!(r.master.phase(), Phase::Stopped, "stopped, reason {reason:?}");
    let after = r.master.stopped_after().unwrap();
    assert!(
        after <= within,
        "stopped after {after} cycles (> {within}) for {reason:?}"
    );
    // every answering drive has its power stage off; nothing moves afterwards
    let p: Vec<f64> = r.drives.iter().map(|d| d.1.position()).collect();
    for _ in 0..100 {
        r.step(0.0);
    }
    for (k, d) in r.drives.iter().enumerate().filter(|(k, _)| Some(*k) != unplugged) {
        assert!(
            !d.1.node().cia402.state().torque_on(),
            "drive {k} state {:?}",
            d.1.node().cia402.state()
        );
        if Some(k) == coasting {
            assert_eq!(d.1.node().cia402.state(), DriveState::Fault, "drive {k}");
            continue;
        }
        assert!((d.1.position() - p[k]).abs() < 1e-3, "drive {k} moved after the stop");
    }
}

#[test]
fn silent_drive_stops_every_axis() {
    fault_case_except(
        &|r| r.inject(0, Failure::Silent, false),
        |s| matches!(s, StopReason::MissingFeedback(1)),
        400,
        Some(0),
    );
}

/// The over-current is raised by the drive layer itself (its current sensing); its reaction is
/// bridge off at once, so drive 2's joint coasts (open winding: correct hardware behaviour, a
/// controlled stop with an uncontrollable current is impossible) while drive 1 makes the
/// controlled stop and stands still.
#[test]
fn emcy_stops_every_axis() {
    fault_case_coasting(
        &|r| r.inject(1, Failure::Emcy, true),
        |s| matches!(s, StopReason::Emcy(2, 0x2310)),
        400,
        None,
        Some(1),
    );
}

#[test]
fn drive_leaving_operation_enabled_stops_every_axis() {
    fault_case(
        &|r| r.inject(0, Failure::LeaveEnabled, false),
        |s| matches!(s, StopReason::LeftOperationEnabled(1)),
        400,
    );
}

#[test]
fn malformed_and_out_of_range_feedback_stop_every_axis() {
    for f in [Failure::Malformed, Failure::OutOfRange] {
        fault_case(
            &move |r| r.inject(1, f, false),
            |s| matches!(s, StopReason::BadFrame(2)),
            400,
        );
    }
}

#[test]
fn corrupted_frames_on_the_bus_stop_every_axis() {
    fault_case(
        &|r| {
            r.bus.set_faults(Faults {
                corrupt_ids: vec![0x181],
                ..Faults::default()
            })
        },
        |s| matches!(s, StopReason::BadFrame(1)),
        400,
    );
}

#[test]
fn stuck_sync_stops_the_drives_and_the_controller() {
    let mut r = rig();
    r.enable();
    r.run(100, None);
    r.drop_frames(&[0x080]);
    for _ in 0..100 {
        r.step(r.master.hold_position(0));
    }
    assert!(
        matches!(r.master.stop_reason(), Some(StopReason::MissingFeedback(_))),
        "{:?}",
        r.master.stop_reason()
    );
    for _ in 0..500 {
        r.step(0.0);
    }
    for (port, d) in &r.drives {
        let _ = port;
        let s = d.node().cia402.state();
        assert!(
            matches!(s, DriveState::Fault | DriveState::SwitchOnDisabled),
            "drive-side SYNC watchdog: {s:?}"
        );
    }
}

#[test]
fn bus_off_stops_the_channel() {
    let mut r = rig();
    r.enable();
    r.run(50, None);
    r.bus.set_faults(Faults {
        bus_off: true,
        ..Faults::default()
    });
    r.step(0.0);
    r.step(0.0);
    assert_eq!(r.master.stop_reason(), Some(StopReason::BusOff));
}

#[test]
fn delayed_feedback_is_not_used_as_fresh() {
    let mut r = rig();
    r.enable();
    r.bus.set_faults(Faults {
        delay_ids: vec![0x182],
        delay_frames: 40,
        ..Faults::default()
    });
    r.run(20, None);
    assert!(
        matches!(r.master.stop_reason(), Some(StopReason::MissingFeedback(2))),
        "{:?}",
        r.master.stop_reason()
    );
}

/// The threaded runtime: `run_channel` at 1 kHz with absolute deadlines against two virtual drives
/// served by a second thread, on the in-memory bus; the motion completes, or an interrupt (what
/// SIGINT sets) brings both axes to a controlled stop.
fn threaded(interrupt_after_ms: Option<u64>) -> ttcan::runtime::channel::ChannelReport {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    use ttcan::runtime::channel::{run_channel, ChannelPlan, Shared};
    use ttcan::runtime::rt;
    use ttcan::runtime::trajectory::Trajectory;
    let bus = MemoryBus::new();
    let mut master_port = bus.port();
    let mut drive_port = bus.port();
    let links = channel::two_links();
    // the test machine is shared: generous feedback watchdog, the timing is not what is tested here
    let wd = WatchdogConfig {
        feedback_cycles: 200,
        ..WatchdogConfig::default()
    };
    let master = ChannelMaster::new(&links, OpMode::Csp, wd).unwrap();
    let traj = Trajectory::demo(2, 0.2, 0.5);
    let interrupt = Arc::new(AtomicBool::new(false));
    let shared = Shared::new(1, interrupt.clone());
    let done = AtomicBool::new(false);
    let period_ns = 1_000_000;
    let plan = ChannelPlan {
        joints: [Some(0), Some(1), None, None],
        approach_s: 0.1,
        period_ns,
        t0_ns: rt::now_ns() + 5 * period_ns,
        max_cycles: 20_000,
        telemetry_rows: 20_000 + 16,
    };
    std::thread::scope(|s| {
        s.spawn(|| {
            let model = MotorModel::maxon_re25_gp26();
            let cfg = AxisConfig::new(model);
            let mut out = Frames::new();
            let mut drives: Vec<VirtualDrive> = (1..=2)
                .map(|n| {
                    let mut d = VirtualDrive::new(n, &model, &cfg, Units::default(), 1e-3, &mut out).unwrap();
                    // as generous as the feedback watchdog: a controller thread descheduled for
                    // 20 ms on a loaded host is not what is tested here (the drive-side SYNC
                    // watchdog is: `stuck_sync_stops_the_drives_and_the_controller`)
                    d.sync_timeout_ms = 200;
                    d
                })
                .collect();
            let mut next = rt::now_ns();
            while !done.load(Ordering::Relaxed) {
                while let Ok(Some(ttcan::bus::BusEvent::Frame { frame, .. })) = drive_port.poll() {
                    for d in drives.iter_mut() {
                        d.on_frame(&frame, &mut out);
                    }
                }
                if rt::now_ns() >= next {
                    drives.iter_mut().for_each(|d| d.tick_ms(&mut out));
                    next += 1_000_000;
                }
                for f in out.as_slice() {
                    let _ = drive_port.send(f);
                }
                out.clear();
                rt::sleep_until(rt::now_ns() + 50_000);
            }
        });
        if let Some(ms) = interrupt_after_ms {
            let i = interrupt.clone();
            s.spawn(move || {
                std::thread::sleep(std::time::Duration::from_millis(ms));
                i.store(true, Ordering::Relaxed);
            });
        }
        let r = run_channel("mem0", &mut master_port, master, &traj, &plan, &shared);
        done.store(true, Ordering::Relaxed);
        r
    })
}

#[test]
fn threaded_runtime_completes_the_motion() {
    let r = threaded(None);
    assert!(r.completed, "stop: {:?}", r.stop_reason);
    assert_eq!(r.stop_reason, Some(StopReason::Requested));
    assert!(r.stats.summary().cycles > 600);
    assert!(
        r.max_tracking_error[0] < 0.02 && r.max_tracking_error[1] < 0.02,
        "{:?}",
        r.max_tracking_error
    );
    assert!(r.telemetry.len() as u64 >= r.stats.summary().cycles);
}

#[test]
fn interrupt_brings_the_axes_to_a_controlled_stop() {
    let r = threaded(Some(400));
    assert!(!r.completed);
    assert_eq!(r.stop_reason, Some(StopReason::Requested));
    assert!(r.stopped_after.is_some());
    let last = r.telemetry.last().unwrap();
    assert_eq!(last.phase, 4, "stopped");
}

#[test]
fn lost_sdo_response_is_retried_and_configuration_completes() {
    let mut r = rig();
    // drop node 2's SDO responses for a while: one timeout, then the retry goes through
    r.drop_frames(&[0x582]);
    for _ in 0..60 {
        r.step(0.0);
    }
    r.bus.set_faults(Faults::default());
    r.enable();
    assert!(r.master.counters().sdo_failures >= 1);
    assert_eq!(r.master.stop_reason(), None);
}

#[test]
fn drive_that_never_answers_sdo_fails_configuration() {
    let mut r = rig();
    r.drop_frames(&[0x582]);
    for _ in 0..400 {
        r.step(0.0);
    }
    assert_eq!(r.master.stop_reason(), Some(StopReason::ConfigurationFailed(2)));
}

/// The controller's setpoints to drive 1 stop arriving mid-motion: nothing moves on the stale
/// target (the drive's interpolator holds the last one at zero speed), the drive layer's
/// setpoint watchdog quick-stops the axis and the drive reports it (EMCY 0x8250, RPDO timeout).
#[test]
fn lost_setpoints_stop_the_drive_on_its_last_target() {
    let mut r = rig();
    r.enable();
    r.run(200, None);
    let last_target = Rig::motion(199e-3);
    r.drop_frames(&[0x201]);
    for k in 200..300 {
        r.step(Rig::motion(k as f64 * 1e-3));
    }
    assert!(
        matches!(r.master.stop_reason(), Some(StopReason::Emcy(1, 0x8250))),
        "{:?}",
        r.master.stop_reason()
    );
    let d = &r.drives[0].1;
    assert_eq!(d.node().cia402.state(), DriveState::Fault);
    let overrun = (d.position() - last_target).abs();
    // at 3 rad/s one period is 3 mrad; the motion, had it continued, would be 0.3 rad further
    assert!(overrun < 0.01, "drive 1 ended {overrun} rad from its last target");
}

/// With a holding brake the controlled stop ends with the brake holding before the bridge goes
/// off: the drive that left Operation Enabled and the one the controller stopped both stand still.
#[test]
fn controlled_stop_engages_the_holding_brake_before_bridge_off() {
    let mut cfg = AxisConfig::new(MotorModel::maxon_re25_gp26());
    cfg.holding_brake = Some(ttcan::HoldingBrake {
        release_delay: 0.01,
        engage_delay: 0.02,
    });
    let mut r = rig_with(cfg);
    r.enable();
    r.run(
        300,
        Some((200, &|r: &mut Rig| r.inject(0, Failure::LeaveEnabled, false))),
    );
    assert_eq!(r.master.stop_reason(), Some(StopReason::LeftOperationEnabled(1)));
    let p: Vec<f64> = r.drives.iter().map(|d| d.1.position()).collect();
    for _ in 0..100 {
        r.step(0.0);
    }
    for (k, (_, d)) in r.drives.iter().enumerate() {
        assert!(
            d.axis().brake_holding() && !d.axis().bridge_on(),
            "drive {k}: {:?}",
            d.axis().state()
        );
        assert!(!d.node().cia402.state().torque_on(), "drive {k}");
        assert!((d.position() - p[k]).abs() < 1e-3, "drive {k} moved after the stop");
    }
}

/// The boot-up plans of both axes for `setup` (node set per axis) on `device`.
fn plans(
    device: &ttcan::canopen::eds::DeviceFile,
    setup: &ttcan::runtime::boot::NodeSetup,
) -> Vec<ttcan::runtime::boot::BootPlan> {
    (1..=2)
        .map(|n| {
            let s = ttcan::runtime::boot::NodeSetup {
                node: n,
                ..setup.clone()
            };
            ttcan::runtime::boot::BootPlan::build(&s, device).unwrap()
        })
        .collect()
}

fn setup() -> ttcan::runtime::boot::NodeSetup {
    ttcan::runtime::boot::NodeSetup {
        node: 1,
        mode: OpMode::Csp,
        rpdo: None,
        tpdo: None,
        sdo: vec![],
        heartbeat_ms: 100,
        following_window: 5000,
        cycle_s: 1e-3,
    }
}

/// Issue 27: the controller remaps both PDOs of the drives over SDO (6-byte RPDO controlword +
/// target, 6-byte TPDO statusword + position, no current) and runs the motion on them.
#[test]
fn remapped_pdos_boot_enable_and_track() {
    let mut r = rig();
    let s = ttcan::runtime::boot::NodeSetup {
        rpdo: Some(vec![(0x6040, 0), (0x607A, 0)]),
        tpdo: Some(vec![(0x6041, 0), (0x6064, 0)]),
        sdo: vec![ttcan::runtime::boot::SdoInit {
            index: 0x2000,
            sub: 0,
            value: ttcan::runtime::boot::SdoValue::Text("shoulder pitch, left arm".into()),
        }],
        ..setup()
    };
    let p = plans(&ttcan::runtime::boot::default_device(), &s);
    r.master = ChannelMaster::with_plans(&channel::two_links(), &p, WatchdogConfig::default()).unwrap();
    let c = r.enable();
    assert!(c < 60, "enabled after {c} cycles");
    for (_, d) in &r.drives {
        assert_eq!(d.node().rpdo_mapping(), p[0].rpdo);
        assert_eq!(d.node().tpdo_mapping().len(), 6);
        assert_eq!(
            d.node().od.text(0x2000, 0),
            Some(&b"shoulder pitch, left arm"[..]),
            "segmented download"
        );
        assert_eq!(d.node().od.get(0x60C2, 1), Some(1));
    }
    let worst = r.run(1000, None);
    assert_eq!(r.master.stop_reason(), None);
    assert!(worst < 0.02, "tracking error {worst} rad");
    assert_eq!(r.master.counters().malformed, 0);
}

/// Issue 27: a device file whose identity is not the drive's is refused at boot-up, before NMT
/// Start: the drives stay in Pre-operational, nothing moves.
#[test]
fn wrong_identity_is_refused_before_nmt_start() {
    let mut r = rig();
    let vendor = ttcan::canopen::eds::DeviceFile::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/vendor-402.eds"
    )))
    .unwrap();
    r.master = ChannelMaster::with_plans(
        &channel::two_links(),
        &plans(&vendor, &setup()),
        WatchdogConfig::default(),
    )
    .unwrap();
    for _ in 0..50 {
        r.step(0.0);
    }
    let reason = r.master.stop_reason().unwrap();
    assert!(
        matches!(
            reason,
            StopReason::Mismatch {
                index: 0x1018,
                sub: 1,
                got: 0,
                expected: 0x1234_5678,
                ..
            }
        ),
        "{reason:?}"
    );
    assert!(
        reason.to_string().contains("0x1018:1 reads 0x0, expected 0x12345678"),
        "{reason}"
    );
    for (_, d) in &r.drives {
        assert_eq!(d.node().nmt_state(), ttcan::canopen::nmt::NmtState::PreOperational);
    }
}

/// Issue 27: a boot-up message lost on the way: the controller resets the drive again after an
/// SDO timeout and the boot-up completes.
#[test]
fn lost_boot_up_message_is_answered_by_a_second_reset() {
    let mut r = rig();
    r.drop_frames(&[0x702]);
    for _ in 0..10 {
        r.step(0.0);
    }
    r.bus.set_faults(Faults::default());
    let c = r.enable();
    assert!(
        c > WatchdogConfig::default().sdo_cycles as u64,
        "enabled after {c} cycles"
    );
    assert_eq!(r.master.stop_reason(), None);
}
