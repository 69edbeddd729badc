//! One online session: the receiver, planning and telemetry threads started around the channel
//! threads, and their settings ([`OnlineConfig`], the `[online]` table of the controller's TOML).
//! The channel threads themselves are the caller's (`ttctl`, or a test): they follow the
//! [`StrokeFollower`]s returned by [`start`].

use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::sync_channel;
use std::sync::Arc;
use std::thread::JoinHandle;

use ttkin::hit::HitPlanner;

use super::ball::{BallBrain, BallBrainConfig};
use super::brain::Brain;
use super::counters::{Counters, CountersSnapshot};
use super::handoff::{self, StrokeFollower, Timeline, MAX_CHANNELS};
use super::planner::{run_planner, PlannerConfig, Splicer};
use super::receiver::{controller_time, run_receiver, Mode};
use super::wire::{self, Message, TelemetryMsg, MAX_JOINTS};
use crate::runtime::master::MAX_AXES_PER_CHANNEL;

/// The `[online]` table of the controller configuration: timeouts and budgets of the online
/// modes (s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OnlineConfig {
    /// Silence of the upper computer or camera (no valid datagram) after which the robot goes back
    /// to the ready pose and holds it, s.
    #[serde(default = "silence")]
    pub silence_s: f64,
    /// Latency budget, s: a hit whose send time (controller clock) is further than this from its
    /// arrival is stale and dropped.
    #[serde(default = "budget")]
    pub latency_budget_s: f64,
    /// Time from the present cycle to the splice cycle, s (longer than planning takes).
    #[serde(default = "lead")]
    pub splice_lead_s: f64,
    /// One telemetry datagram every this many cycles.
    #[serde(default = "decimation")]
    pub telemetry_decimation: u32,
    /// Commands waiting for the planning thread at most (more are refused, hits answered).
    #[serde(default = "queue")]
    pub queue: usize,
    /// SCHED_FIFO priority (1–98) of the receiver, planning and telemetry threads, below the
    /// channel threads' (so that other processes of the machine do not delay a decision); 0
    /// keeps them on normal scheduling. Refused by the system: normal scheduling, counted
    /// (`realtime_refused`).
    #[serde(default = "thread_priority")]
    pub priority: u8,
    /// Ball mode: observations ahead of each decision at which its search is made, on a worker
    /// thread of its own (at `priority` − 1), so that the deciding observation only plans the hit
    /// found again (`ttcan::online::ball::BallBrainConfig::speculate_frames`); 0: every decision
    /// searches when its observation comes (0..=20).
    #[serde(default = "speculate_frames")]
    pub speculate_frames: usize,
    /// Ball mode, with `speculate_frames` ≥ 2: each search ahead made again on the worker one
    /// frame before its decision (`ttcan::online::ball::BallBrainConfig::refresh_ahead`).
    #[serde(default = "refresh_ahead")]
    pub refresh_ahead: bool,
}

fn silence() -> f64 {
    2.0
}
fn budget() -> f64 {
    0.05
}
fn lead() -> f64 {
    0.02
}
fn decimation() -> u32 {
    1
}
fn queue() -> usize {
    64
}
fn thread_priority() -> u8 {
    40
}
fn speculate_frames() -> usize {
    3
}
fn refresh_ahead() -> bool {
    true
}

impl Default for OnlineConfig {
    fn default() -> Self {
        OnlineConfig {
            silence_s: silence(),
            latency_budget_s: budget(),
            splice_lead_s: lead(),
            telemetry_decimation: decimation(),
            queue: queue(),
            priority: thread_priority(),
            speculate_frames: speculate_frames(),
            refresh_ahead: refresh_ahead(),
        }
    }
}

impl OnlineConfig {
    /// Checks the values; the message names the key and what is allowed.
    pub fn check(&self) -> Result<(), String> {
        let pos = |name: &str, v: f64, max: f64| {
            if v.is_finite() && v > 0.0 && v <= max {
                Ok(())
            } else {
                Err(format!("online.{name} = {v}: must be finite, > 0 and ≤ {max} s"))
            }
        };
        pos("silence_s", self.silence_s, 3600.0)?;
        pos("latency_budget_s", self.latency_budget_s, 10.0)?;
        pos("splice_lead_s", self.splice_lead_s, 1.0)?;
        if self.telemetry_decimation == 0 {
            return Err("online.telemetry_decimation = 0: must be ≥ 1".into());
        }
        if !(1..=100_000).contains(&self.queue) {
            return Err(format!("online.queue = {}: must be in 1..=100000", self.queue));
        }
        if self.speculate_frames > 20 {
            return Err(format!(
                "online.speculate_frames = {}: must be in 0..=20 (0: no search ahead)",
                self.speculate_frames
            ));
        }
        if self.priority > 98 {
            return Err(format!(
                "online.priority = {}: must be in 0..=98 (0: normal scheduling)",
                self.priority
            ));
        }
        Ok(())
    }
}

/// The running threads of an online session.
pub struct Session {
    /// The atomics shared with the channel threads.
    pub timeline: Arc<Timeline>,
    /// The counters.
    pub counters: Arc<Counters>,
    /// The address the receiver listens on.
    pub local: SocketAddr,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

impl Session {
    /// Stops the threads and returns the final counters.
    pub fn stop(self) -> CountersSnapshot {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads {
            let _ = t.join();
        }
        let mut c = self.counters.snapshot();
        c.splices_late += self.timeline.late_applied();
        c
    }
}

/// Where an online session listens and answers, and in which mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Endpoints {
    /// Hit mode or ball mode.
    pub mode: Mode,
    /// Address the receiver binds (port 0: any free port, see [`Session::local`]).
    pub listen: SocketAddr,
    /// Address statuses and telemetry go to.
    pub reply: SocketAddr,
}

/// Starts an online session at `ends` (hit mode, or ball mode with a [`BallBrain`]),
/// planning with `planner`, for channel threads with the joint of each axis `joints` (one entry
/// per channel), at `period_ns` from deadline 0 at `t0_ns` (monotonic). Returns the session and
/// one [`StrokeFollower`] per channel.
pub fn start(
    ends: Endpoints,
    planner: HitPlanner,
    joints: &[[Option<usize>; MAX_AXES_PER_CHANNEL]],
    period_ns: u64,
    t0_ns: u64,
    cfg: &OnlineConfig,
) -> io::Result<(Session, Vec<StrokeFollower>)> {
    cfg.check()
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))?;
    let Endpoints { mode, listen, reply } = ends;
    // Ball mode: the ball brain of this robot (its base placed at the table by the core's rally
    // placement), the receiver's latency budget for the observations.
    // Its searches ahead on a worker thread just below the planning thread's priority.
    let brain = match mode {
        Mode::Hit => None,
        Mode::Ball => {
            let mut b = BallBrain::new(
                planner.chain().clone(),
                BallBrainConfig {
                    latency_budget: cfg.latency_budget_s,
                    speculate_frames: cfg.speculate_frames,
                    refresh_ahead: cfg.refresh_ahead,
                    ..BallBrainConfig::default()
                },
            )
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, format!("ball mode: {e}")))?;
            b.spawn_worker(cfg.priority.saturating_sub(1))?;
            Some(b)
        }
    };
    let dof = planner.chain().dof();
    if joints.is_empty() || joints.len() > MAX_CHANNELS || dof > MAX_JOINTS {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "online mode takes 1..={MAX_CHANNELS} channels and ≤ {MAX_JOINTS} joints, got {} and {dof}",
                joints.len()
            ),
        ));
    }
    for j in 0..dof {
        if !joints.iter().flatten().any(|x| *x == Some(j)) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("joint {j} of the robot has no axis: give it one in the configuration (joint = {j})"),
            ));
        }
    }
    let socket = UdpSocket::bind(listen)?;
    let local = socket.local_addr()?;
    let timeline = Arc::new(Timeline::new(joints.len(), dof, period_ns, t0_ns));
    let counters = Arc::new(Counters::default());
    let stop = Arc::new(AtomicBool::new(false));
    let mut senders = Vec::new();
    let mut followers = Vec::new();
    for (c, j) in joints.iter().enumerate() {
        let (s, f) = handoff::channel(c, *j, timeline.clone());
        senders.push(s);
        followers.push(f);
    }
    let mut splicer = Splicer::new(
        planner,
        timeline.clone(),
        senders,
        PlannerConfig {
            splice_lead: cfg.splice_lead_s,
            silence: cfg.silence_s,
        },
    );
    // Ball mode: the robot waits at the ball planner's ready pose, where its strokes start.
    if let Some(b) = &brain {
        splicer.set_ready(&b.planner().ready);
    }
    let (tx, rx) = sync_channel(cfg.queue);
    let prio = cfg.priority;
    let mut threads = Vec::new();
    {
        let (socket, counters, stop) = (socket.try_clone()?, counters.clone(), stop.clone());
        let budget = cfg.latency_budget_s;
        threads.push(
            std::thread::Builder::new()
                .name("ttctl-receiver".into())
                .spawn(move || {
                    realtime(prio, &counters);
                    run_receiver(&socket, mode, budget, reply, &tx, &counters, &stop)
                })?,
        );
    }
    {
        let (socket, counters, stop) = (socket.try_clone()?, counters.clone(), stop.clone());
        threads.push(
            std::thread::Builder::new()
                .name("ttctl-planner".into())
                .spawn(move || {
                    realtime(prio, &counters);
                    let mut brain = brain;
                    let b = brain.as_mut().map(|b| b as &mut dyn Brain);
                    run_planner(splicer, &rx, b, &socket, reply, &counters, &stop)
                })?,
        );
    }
    {
        let (counters, stop, tl) = (counters.clone(), stop.clone(), timeline.clone());
        let every = cfg.telemetry_decimation as u64 * period_ns;
        threads.push(
            std::thread::Builder::new()
                .name("ttctl-telemetry".into())
                .spawn(move || {
                    realtime(prio, &counters);
                    run_telemetry(&socket, reply, &tl, every, &counters, &stop)
                })?,
        );
    }
    Ok((
        Session {
            timeline,
            counters,
            local,
            stop,
            threads,
        },
        followers,
    ))
}

/// Switches the calling thread to SCHED_FIFO at `prio` (nothing for 0); a refusal is counted.
fn realtime(prio: u8, counters: &Counters) {
    if prio > 0 && crate::runtime::rt::make_thread_realtime(prio).is_err() {
        Counters::bump(&counters.realtime_refused);
    }
}

/// Sends the measured joint state and the fault bits to `reply` every `every_ns` until `stop`,
/// from the first cycle at which [`Timeline::telemetry_due`] (the channels run, or one stopped).
fn run_telemetry(
    socket: &UdpSocket,
    reply: SocketAddr,
    tl: &Timeline,
    every_ns: u64,
    counters: &Counters,
    stop: &AtomicBool,
) {
    let mut next = crate::runtime::rt::now_ns();
    let mut seq = 0u64;
    let mut buf = [0u8; wire::MAX_LEN];
    let mut live = false;
    while !stop.load(Ordering::Relaxed) {
        next += every_ns;
        crate::runtime::rt::sleep_until(next);
        let now = crate::runtime::rt::now_ns();
        if now > next + 100 * every_ns {
            next = now; // far behind (a stall): no burst
        }
        // Once due, always sent (a faulted channel's fault bits included), so that the upper
        // computer hears a fault instead of silence.
        if !live {
            live = tl.telemetry_due();
            if !live {
                continue;
            }
        }
        let m = tl.measured();
        seq += 1;
        let t = controller_time();
        let msg = Message::Telemetry(TelemetryMsg {
            time: t,
            cycle: m.cycle,
            faults: m.faults,
            joints: tl.dof() as u16,
            q: m.q,
            qd: m.qd,
        });
        let n = wire::encode(&msg, seq, t, &mut buf);
        match socket.send_to(&buf[..n], reply) {
            Ok(_) => Counters::bump(&counters.telemetry_sent),
            Err(_) => Counters::bump(&counters.send_errors),
        }
    }
}
