//! One controller thread per channel: a SYNC-driven cycle at absolute deadlines t0 + k·T (read
//! every waiting event → update the channel controller with this cycle's setpoints → write the
//! RPDOs and the SYNC), statistics and telemetry recorded into storage allocated before the loop.
//! Channels share a [`Shared`] block: the motion starts when every channel runs, and a stop on
//! one channel stops all. A thread woken more than a period late skips the missed deadlines
//! (counted) rather than sending a burst of SYNCs; the motion time counts executed cycles, so a
//! stall pauses the motion instead of making the target jump. What the axes follow is a
//! [`SetpointSource`]: a trajectory file or the demo ([`TrajectorySource`]), or the strokes the
//! online planner hands over ([`crate::online::handoff::StrokeFollower`]).

use super::master::{AxisSetpoint, ChannelCounters, ChannelMaster, Phase, StopReason, MAX_AXES_PER_CHANNEL};
use super::rt::{now_ns, sleep_until};
use super::stats::CycleStats;
use super::trajectory::{approach, Trajectory};
use crate::bus::{BusError, CanBus};
use crate::canopen::Frames;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};

/// State shared by the channel threads of one controller.
#[derive(Debug)]
pub struct Shared {
    /// Set by the first channel that stops for a fault; every other channel then stops.
    pub stop: AtomicBool,
    /// Set by the signal handler (SIGINT/SIGTERM): controlled stop of everything.
    pub interrupt: std::sync::Arc<AtomicBool>,
    running: AtomicUsize,
    channels: usize,
    go_cycle: AtomicU64,
}

impl Shared {
    /// Shared state for `channels` threads; `interrupt` is the signal flag.
    pub fn new(channels: usize, interrupt: std::sync::Arc<AtomicBool>) -> Self {
        Shared {
            stop: AtomicBool::new(false),
            interrupt,
            running: AtomicUsize::new(0),
            channels,
            go_cycle: AtomicU64::new(u64::MAX),
        }
    }
}

/// What a channel thread does.
#[derive(Debug, Clone, Copy)]
pub struct ChannelPlan {
    /// Trajectory joint of each axis (`None`: hold).
    pub joints: [Option<usize>; MAX_AXES_PER_CHANNEL],
    /// Approach duration from the held position to the trajectory start, s.
    pub approach_s: f64,
    /// Cycle period, ns.
    pub period_ns: u64,
    /// Common start time of all channels (monotonic ns).
    pub t0_ns: u64,
    /// Cycles after which the channel stops whatever happens (a safety net).
    pub max_cycles: u64,
    /// Telemetry rows kept for the report at most (0: none). Their storage is allocated before
    /// the loop and, with the process's memory locked (`mlockall`), every page of it is touched
    /// then: about 350 bytes a row, so a long run's rows delay the first cycle (measured: 115 ms
    /// for 430 s of three channels at 1 kHz); keep none when nothing writes them.
    pub telemetry_rows: u64,
}

/// What the channel thread knows about the present cycle when it asks for setpoints.
#[derive(Debug, Clone, Copy)]
pub struct CycleInfo {
    /// Deadline index (cycles since the common start `t0`, skipped deadlines included).
    pub k: u64,
    /// Motion time, s: executed cycles since every channel runs (negative before).
    pub t: f64,
    /// Phase of the channel before this cycle's update.
    pub phase: Phase,
    /// Cycle period, s.
    pub period: f64,
}

/// What the axes of one channel follow: called once per cycle on the cycle thread, so an
/// implementation must not lock, allocate or make a system call.
pub trait SetpointSource {
    /// Writes this cycle's setpoint of every axis into `out` (position, velocity, torque) and the
    /// commanded acceleration into `qdd` (telemetry only); `master` gives the held positions
    /// and the feedback. Returns true when the motion is complete (the channel then stops).
    fn fill(&mut self, c: &CycleInfo, master: &ChannelMaster, out: &mut [AxisSetpoint], qdd: &mut [f64]) -> bool;
    /// True while a plan is being made elsewhere (the statistics are split by it).
    fn planning(&self) -> bool {
        false
    }
    /// Called after the cycle's frames were sent (feedback of this cycle in `master`).
    fn after_cycle(&mut self, _c: &CycleInfo, _master: &ChannelMaster) {}
    /// The cycle of the source's own clock that the last [`SetpointSource::fill`] sampled (online
    /// strokes: the executed cycle, which skipped deadlines and held cycles do not advance);
    /// `None`: the channel's executed cycles are the source's clock.
    fn clock(&self) -> Option<u64> {
        None
    }
}

/// A trajectory (file or demo) preceded by a quintic approach from the held positions.
#[derive(Debug, Clone, Copy)]
pub struct TrajectorySource<'a> {
    /// The trajectory.
    pub traj: &'a Trajectory,
    /// Trajectory joint of each axis (`None`: hold).
    pub joints: [Option<usize>; MAX_AXES_PER_CHANNEL],
    /// Approach duration, s.
    pub approach_s: f64,
}

impl SetpointSource for TrajectorySource<'_> {
    fn fill(&mut self, c: &CycleInfo, master: &ChannelMaster, out: &mut [AxisSetpoint], qdd: &mut [f64]) -> bool {
        let (traj, t) = (self.traj, c.t);
        for (a, setpoint) in out.iter_mut().enumerate() {
            let hold = master.hold_position(a);
            qdd[a] = 0.0;
            *setpoint = match (self.joints[a], t >= 0.0) {
                (Some(j), true) if j < traj.joints() => {
                    if t < self.approach_s {
                        let (q, qd) = approach(hold, traj.sample(j, 0.0).q, self.approach_s, t);
                        AxisSetpoint { q, qd, tau: 0.0 }
                    } else {
                        let s = traj.sample(j, t - self.approach_s);
                        qdd[a] = s.qdd;
                        AxisSetpoint {
                            q: s.q,
                            qd: s.qd,
                            tau: s.tau,
                        }
                    }
                }
                _ => AxisSetpoint {
                    q: hold,
                    qd: 0.0,
                    tau: 0.0,
                },
            };
        }
        t >= 0.0 && t > self.approach_s + traj.duration() + 0.2 && c.phase == Phase::Run
    }
}

/// One telemetry row (one cycle of one channel).
#[derive(Debug, Clone, Copy, Default)]
pub struct TelemetryRow {
    /// Cycle index.
    pub cycle: u64,
    /// Motion time, s (negative before the motion starts).
    pub t: f64,
    /// Phase code: 0 configure, 1 enable, 2 run, 3 stopping, 4 stopped.
    pub phase: u8,
    /// Position reference sent, per axis.
    pub q_ref: [f64; MAX_AXES_PER_CHANNEL],
    /// Velocity reference sent, per axis.
    pub qd_ref: [f64; MAX_AXES_PER_CHANNEL],
    /// Commanded acceleration, per axis.
    pub qdd_ref: [f64; MAX_AXES_PER_CHANNEL],
    /// Position feedback, per axis.
    pub q: [f64; MAX_AXES_PER_CHANNEL],
    /// Current feedback, A, per axis.
    pub current: [f64; MAX_AXES_PER_CHANNEL],
    /// Wake-up latency, µs.
    pub latency_us: f32,
    /// The setpoint source's clock at this cycle ([`SetpointSource::clock`]; else executed cycles
    /// of this channel): channels whose rows of one deadline differ in it were commanded from
    /// different instants of the strokes (a stall of one channel thread, measured).
    pub source_cycle: u64,
}

/// What a channel thread reports when it ends.
#[derive(Debug, Clone)]
pub struct ChannelReport {
    /// Interface name.
    pub name: String,
    /// Number of axes.
    pub axes: usize,
    /// Why it stopped.
    pub stop_reason: Option<StopReason>,
    /// Cycles from the stop decision to all axes stopped.
    pub stopped_after: Option<u32>,
    /// Protocol counters.
    pub counters: ChannelCounters,
    /// Latency statistics.
    pub stats: CycleStats,
    /// Latency statistics of the cycles while no plan was being made.
    pub stats_quiet: CycleStats,
    /// Latency statistics of the cycles while a plan was being made ([`SetpointSource::planning`]).
    pub stats_planning: CycleStats,
    /// Telemetry rows.
    pub telemetry: Vec<TelemetryRow>,
    /// Largest |feedback − the target sent two cycles earlier| during the motion, per axis
    /// (feedback in step with the SYNCs only, [`ChannelMaster::feedback_in_step`]).
    pub max_tracking_error: [f64; MAX_AXES_PER_CHANNEL],
    /// Frames that could not be sent (queue full).
    pub tx_full: u64,
    /// Deadlines skipped after late wake-ups.
    pub skipped: u64,
    /// True when the trajectory ran to its end.
    pub completed: bool,
    /// The device name (0x1008) of each axis' drive, as read at boot-up.
    pub device_names: Vec<Option<String>>,
    /// Page faults and involuntary context switches of the channel thread during its cycle loop.
    pub usage: super::rt::Usage,
}

fn phase_code(p: Phase) -> u8 {
    match p {
        Phase::Configure => 0,
        Phase::Enable => 1,
        Phase::Run => 2,
        Phase::Stopping => 3,
        Phase::Stopped => 4,
    }
}

/// Runs one channel following `traj` (after the approach) until its axes are stopped.
pub fn run_channel<B: CanBus>(
    name: &str,
    bus: &mut B,
    master: ChannelMaster,
    traj: &Trajectory,
    plan: &ChannelPlan,
    shared: &Shared,
) -> ChannelReport {
    let mut source = TrajectorySource {
        traj,
        joints: plan.joints,
        approach_s: plan.approach_s,
    };
    run_channel_with(name, bus, master, &mut source, plan, shared)
}

/// Runs one channel following `source` until its axes are stopped. No allocation inside the loop.
pub fn run_channel_with<B: CanBus, S: SetpointSource + ?Sized>(
    name: &str,
    bus: &mut B,
    mut master: ChannelMaster,
    source: &mut S,
    plan: &ChannelPlan,
    shared: &Shared,
) -> ChannelReport {
    let n = master.len();
    let mut stats = CycleStats::new();
    let mut stats_quiet = CycleStats::new();
    let mut stats_planning = CycleStats::new();
    let mut qdd = [0.0f64; MAX_AXES_PER_CHANNEL];
    let mut telemetry = Vec::with_capacity(plan.telemetry_rows.min(plan.max_cycles.saturating_add(16)) as usize);
    let mut out = Frames::new();
    let mut setpoints = [AxisSetpoint::default(); MAX_AXES_PER_CHANNEL];
    // setpoints of the last two cycles: feedback sampled at SYNC k−1 is compared with the target
    // in force before it, sent at cycle k−2
    let mut refs = [[0.0f64; MAX_AXES_PER_CHANNEL]; 2];
    let mut max_err = [0.0f64; MAX_AXES_PER_CHANNEL];
    let (mut tx_full, mut skipped) = (0u64, 0u64);
    let mut counted = false;
    let mut completed = false;
    let period = plan.period_ns as f64 * 1e-9;
    let mut k: u64 = 0;
    let mut executed: u64 = 0;
    let mut go_executed: Option<u64> = None;
    let usage_before = super::rt::Usage::thread();
    loop {
        let deadline = plan.t0_ns + k * plan.period_ns;
        sleep_until(deadline);
        let wake = now_ns();
        let latency = wake.saturating_sub(deadline);
        // read
        loop {
            match bus.poll() {
                Ok(Some(ev)) => master.on_event(&ev),
                Ok(None) => break,
                Err(BusError::Down) => {
                    master.request_stop(StopReason::BusOff);
                    break;
                }
                Err(_) => break,
            }
        }
        if shared.interrupt.load(Ordering::Relaxed) {
            master.request_stop(StopReason::Requested);
        }
        if shared.stop.load(Ordering::Relaxed) {
            master.request_stop(StopReason::OtherChannel);
        }
        // update
        let phase = master.phase();
        if phase == Phase::Run && !counted {
            counted = true;
            if shared.running.fetch_add(1, Ordering::SeqCst) + 1 == shared.channels {
                shared.go_cycle.store(k + 2, Ordering::SeqCst);
            }
        }
        // motion time counts executed cycles, not deadlines: after a stall the motion resumes
        // where it was (the drives' physics advance per SYNC too), the target never jumps
        let go = shared.go_cycle.load(Ordering::SeqCst);
        if go != u64::MAX && k >= go && go_executed.is_none() {
            go_executed = Some(executed);
        }
        let t = match go_executed {
            Some(g) => (executed - g) as f64 * period,
            None => -1.0,
        };
        let planning = source.planning();
        let info = CycleInfo { k, t, phase, period };
        if source.fill(&info, &master, &mut setpoints[..n], &mut qdd[..n]) {
            completed = true;
            master.request_stop(StopReason::Requested);
        }
        if k >= plan.max_cycles {
            master.request_stop(StopReason::Requested);
        }
        out.clear();
        master.cycle(&setpoints[..n], &mut out);
        // write
        for f in out.as_slice() {
            match bus.send(f) {
                Ok(()) => {}
                Err(BusError::Full) => tx_full += 1,
                Err(_) => master.request_stop(StopReason::BusOff),
            }
        }
        if let Some(r) = master.stop_reason() {
            if !matches!(r, StopReason::Requested | StopReason::OtherChannel) {
                shared.stop.store(true, Ordering::Relaxed);
            }
        }
        source.after_cycle(&info, &master);
        // record
        let mut row = TelemetryRow {
            cycle: k,
            t,
            phase: phase_code(master.phase()),
            latency_us: (latency as f64 / 1000.0) as f32,
            source_cycle: source.clock().unwrap_or(executed),
            ..Default::default()
        };
        for a in 0..n {
            row.q_ref[a] = setpoints[a].q;
            row.qd_ref[a] = setpoints[a].qd;
            row.qdd_ref[a] = qdd[a];
            if let Some(fb) = master.feedback(a) {
                row.q[a] = fb.q;
                row.current[a] = fb.current;
                // only feedback known to answer the last SYNC: after a stall of the drives the
                // newest answer can be older, and pairing it with refs[1] would count the motion
                // of the missed cycles as tracking error
                if master.feedback_in_step(a)
                    && phase == Phase::Run
                    && t >= 2.0 * period
                    && master.stop_reason().is_none()
                {
                    max_err[a] = max_err[a].max((fb.q - refs[1][a]).abs());
                }
            }
        }
        refs[1] = refs[0];
        for a in 0..n {
            refs[0][a] = setpoints[a].q;
        }
        if telemetry.len() < telemetry.capacity() {
            telemetry.push(row);
        }
        let work = now_ns().saturating_sub(wake);
        stats.record(latency, work, plan.period_ns);
        if planning || source.planning() {
            stats_planning.record(latency, work, plan.period_ns);
        } else {
            stats_quiet.record(latency, work, plan.period_ns);
        }
        if master.phase() == Phase::Stopped {
            break;
        }
        k += 1;
        executed += 1;
        let late = now_ns().saturating_sub(plan.t0_ns + k * plan.period_ns);
        if late > plan.period_ns {
            let skip = late / plan.period_ns;
            skipped += skip;
            k += skip;
            master.hold_off_following_check((2 * skip + 2).min(u32::MAX as u64) as u32);
        }
    }
    let usage = super::rt::Usage::thread().since(&usage_before);
    // drain what is still in flight (late TPDOs of the last SYNCs), so that the loss count is exact
    let drain_until = now_ns() + 100 * plan.period_ns.max(1_000_000);
    while now_ns() < drain_until {
        while let Ok(Some(ev)) = bus.poll() {
            master.on_event(&ev);
        }
        sleep_until(now_ns() + plan.period_ns);
    }
    ChannelReport {
        name: name.to_string(),
        axes: n,
        stop_reason: master.stop_reason(),
        stopped_after: master.stopped_after(),
        counters: master.counters(),
        stats,
        stats_quiet,
        stats_planning,
        telemetry,
        max_tracking_error: max_err,
        tx_full,
        skipped,
        completed,
        device_names: (0..n).map(|k| master.device_name(k)).collect(),
        usage,
    }
}
