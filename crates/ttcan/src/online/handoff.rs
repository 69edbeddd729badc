//! The wait-free handoff between the planning thread and the cycle threads.
//!
//! A [`Stroke`] (a complete joint trajectory and the cycle it starts at) is built on the planning
//! thread, boxed, and pushed into one single-producer single-consumer ring per channel
//! (`rtrb`: a bounded lock-free ring whose push and pop are wait-free and never allocate; chosen
//! over `triple_buffer`, which keeps only the newest value and would lose a pending stroke, and
//! over `arc-swap`, whose last `Arc` can be dropped, i.e. freed, on the reader's side). The cycle
//! thread never frees a stroke either: every box it is done with goes back through a second ring
//! to the planning thread, which reuses it, so the cycle thread does no allocation, no
//! deallocation, no lock and no system call.
//!
//! The rest of the exchange is atomics in a [`Timeline`]: the cycle each channel is at, the
//! positions held at enable, the measured joint state (a sequence lock made of atomics), and the
//! decision on each stroke. Several channels take the same stroke: the first channel thread that
//! sees it decides for all (compare-and-swap): taken when it arrives before its start cycle is
//! commanded (at the latest in the cycle that commands it), refused (late) otherwise, so the
//! channels never split on a stroke.

use std::sync::atomic::{fence, AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;

use ttkin::traj::JointTrajectory;

use crate::runtime::channel::{CycleInfo, SetpointSource};
use crate::runtime::master::{AxisSetpoint, ChannelMaster, Phase, MAX_AXES_PER_CHANNEL};

use super::wire::MAX_JOINTS;

/// Most channels of an online controller.
pub const MAX_CHANNELS: usize = 8;
/// Strokes a channel holds waiting for their start cycle.
pub const MAX_PENDING: usize = 4;
/// Boxes in circulation per channel (the return ring holds them all, so it never overflows).
pub const POOL: usize = 2 * MAX_PENDING + 4;

const PENDING: u64 = 0;
const TAKEN: u64 = 1;
const LATE: u64 = 2;

/// A complete stroke for the cycle threads: from `start_cycle` on, the axes follow `traj`
/// (time 0 at that cycle; its end state held after its end).
#[derive(Debug, Clone, Default)]
pub struct Stroke {
    /// Handoff sequence number (strictly increasing).
    pub seq: u64,
    /// Deadline index of the cycle that commands the stroke's time 0.
    pub start_cycle: u64,
    /// The joint trajectory (all joints of the robot).
    pub traj: Option<JointTrajectory>,
}

/// How a cycle thread decided on a stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// Not yet seen by any cycle thread.
    Pending,
    /// Taken: the channels follow it from its start cycle.
    Taken,
    /// Refused: it reached the channels after its start cycle (or they had no room).
    Late,
}

/// The atomics shared by the planning thread, the telemetry thread and the cycle threads.
#[derive(Debug)]
pub struct Timeline {
    /// Cycle period, ns.
    pub period_ns: u64,
    /// Monotonic time of deadline 0, ns.
    pub t0_ns: u64,
    channels: usize,
    dof: usize,
    cycle: [AtomicU64; MAX_CHANNELS],
    skipped: [AtomicU64; MAX_CHANNELS],
    enabled: AtomicUsize,
    hold: [AtomicU64; MAX_JOINTS],
    decision: AtomicU64,
    seen: [AtomicU64; MAX_CHANNELS],
    /// Set by the planning thread while it plans (the cycle statistics are split by it).
    pub planning: AtomicBool,
    /// Set when a channel left the Run phase (stopping): no more strokes are taken.
    pub stopped: AtomicBool,
    measured_seq: [AtomicU64; MAX_CHANNELS],
    measured_q: [AtomicU64; MAX_JOINTS],
    measured_qd: [AtomicU64; MAX_JOINTS],
    faults: AtomicU32,
    late: AtomicU64,
    paused: AtomicU64,
}

/// The measured joint state as the telemetry thread reads it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measured {
    /// Cycle (deadline index) of the newest channel.
    pub cycle: u64,
    /// Positions (rad or m).
    pub q: [f64; MAX_JOINTS],
    /// Velocities by differencing successive feedback (rad/s or m/s).
    pub qd: [f64; MAX_JOINTS],
    /// Fault bits (bit j: joint j's channel is stopping or stopped).
    pub faults: u32,
}

fn bits(x: f64) -> u64 {
    x.to_bits()
}

fn val(a: &AtomicU64) -> f64 {
    f64::from_bits(a.load(Ordering::Relaxed))
}

impl Timeline {
    /// A timeline for `channels` channel threads of a `dof`-joint robot at `period_ns` from
    /// deadline 0 at `t0_ns` (monotonic).
    pub fn new(channels: usize, dof: usize, period_ns: u64, t0_ns: u64) -> Self {
        Timeline {
            period_ns,
            t0_ns,
            channels: channels.min(MAX_CHANNELS),
            dof: dof.min(MAX_JOINTS),
            cycle: std::array::from_fn(|_| AtomicU64::new(0)),
            skipped: std::array::from_fn(|_| AtomicU64::new(0)),
            enabled: AtomicUsize::new(0),
            hold: std::array::from_fn(|_| AtomicU64::new(0)),
            decision: AtomicU64::new(0),
            seen: std::array::from_fn(|_| AtomicU64::new(0)),
            planning: AtomicBool::new(false),
            stopped: AtomicBool::new(false),
            measured_seq: std::array::from_fn(|_| AtomicU64::new(0)),
            measured_q: std::array::from_fn(|_| AtomicU64::new(0)),
            measured_qd: std::array::from_fn(|_| AtomicU64::new(0)),
            faults: AtomicU32::new(0),
            late: AtomicU64::new(0),
            paused: AtomicU64::new(0),
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Deadlines skipped so far (the most of any channel): a stall pauses the strokes.
    pub fn skipped(&self) -> u64 {
        self.skipped[..self.channels]
            .iter()
            .map(|c| c.load(Ordering::Acquire))
            .max()
            .unwrap_or(0)
    }

    /// Controller time (s, monotonic clock) of executed cycle `k` (deadline k + skipped).
    pub fn time_of(&self, k: u64) -> f64 {
        (self.t0_ns as f64 + (k + self.skipped()) as f64 * self.period_ns as f64) * 1e-9
    }

    /// The first executed cycle at or after controller time `t` (s), skips so far counted.
    pub fn cycle_at(&self, t: f64) -> u64 {
        let d = ((t * 1e9 - self.t0_ns as f64) / self.period_ns as f64).ceil().max(0.0) as u64;
        d.saturating_sub(self.skipped())
    }

    /// Period, s.
    pub fn period(&self) -> f64 {
        self.period_ns as f64 * 1e-9
    }

    /// The newest cycle (executed cycles since deadline 0) any channel has started.
    pub fn present_cycle(&self) -> u64 {
        self.cycle[..self.channels]
            .iter()
            .map(|c| c.load(Ordering::Acquire))
            .max()
            .unwrap_or(0)
    }

    /// True when every channel runs and has published its held positions.
    pub fn all_enabled(&self) -> bool {
        self.enabled.load(Ordering::Acquire) >= self.channels
    }

    /// The positions held at enable (valid once [`Timeline::all_enabled`]).
    pub fn hold(&self) -> Vec<f64> {
        self.hold[..self.dof].iter().map(val).collect()
    }

    /// Strokes that a channel followed although it saw them after their start cycle (another
    /// channel had taken them): a discontinuity, counted.
    pub fn late_applied(&self) -> u64 {
        self.late.load(Ordering::Relaxed)
    }

    /// Cycles a channel held its stroke still to stay with a channel that had skipped more
    /// deadlines (summed over the channels).
    pub fn paused(&self) -> u64 {
        self.paused.load(Ordering::Relaxed)
    }

    /// Opens the decision on stroke `seq` (planning thread, before pushing it).
    pub fn open(&self, seq: u64) {
        self.decision.store(seq << 2 | PENDING, Ordering::Release);
    }

    /// The decision on stroke `seq`.
    pub fn decision(&self, seq: u64) -> Decision {
        let d = self.decision.load(Ordering::Acquire);
        match (d >> 2 == seq, d & 3) {
            (true, TAKEN) => Decision::Taken,
            (true, LATE) => Decision::Late,
            _ => Decision::Pending,
        }
    }

    /// True when every channel has seen stroke `seq` (or a later one).
    pub fn seen_by_all(&self, seq: u64) -> bool {
        self.seen[..self.channels]
            .iter()
            .all(|s| s.load(Ordering::Acquire) >= seq)
    }

    fn decide(&self, seq: u64, on_time: bool) -> bool {
        let want = seq << 2 | if on_time { TAKEN } else { LATE };
        match self
            .decision
            .compare_exchange(seq << 2 | PENDING, want, Ordering::AcqRel, Ordering::Acquire)
        {
            Ok(_) => on_time,
            Err(d) => d == seq << 2 | TAKEN,
        }
    }

    /// The measured state (consistent per channel: a sequence lock of atomics).
    pub fn measured(&self) -> Measured {
        let mut m = Measured {
            cycle: self.present_cycle(),
            faults: self.faults.load(Ordering::Relaxed),
            ..Default::default()
        };
        for _ in 0..100 {
            let before: [u64; MAX_CHANNELS] = std::array::from_fn(|c| self.measured_seq[c].load(Ordering::Acquire));
            if before.iter().any(|s| s % 2 == 1) {
                std::hint::spin_loop();
                continue;
            }
            for j in 0..self.dof {
                m.q[j] = val(&self.measured_q[j]);
                m.qd[j] = val(&self.measured_qd[j]);
            }
            fence(Ordering::Acquire);
            if (0..MAX_CHANNELS).all(|c| self.measured_seq[c].load(Ordering::Relaxed) == before[c]) {
                break;
            }
        }
        m
    }
}

/// The planning thread's side of one channel's handoff: the stroke ring and the return ring.
#[derive(Debug)]
pub struct Sender {
    to_cycle: rtrb::Producer<Box<Stroke>>,
    back: rtrb::Consumer<Box<Stroke>>,
    boxes: usize,
}

impl Sender {
    /// Hands `stroke` (a copy of it) to the channel: a returned box is reused, a new one made only
    /// while fewer than [`POOL`] are in circulation. `false` when the ring is full.
    pub fn push(&mut self, seq: u64, start_cycle: u64, traj: &JointTrajectory) -> bool {
        let mut b = match self.back.pop() {
            Ok(b) => b,
            Err(_) if self.boxes < POOL => {
                self.boxes += 1;
                Box::default()
            }
            Err(_) => return false,
        };
        b.seq = seq;
        b.start_cycle = start_cycle;
        b.traj = Some(traj.clone());
        match self.to_cycle.push(b) {
            Ok(()) => true,
            Err(rtrb::PushError::Full(b)) => {
                // freed here, on the planning thread
                drop(b);
                self.boxes -= 1;
                false
            }
        }
    }
}

/// The cycle thread's side: follows the strokes it is handed, holds the enable positions before
/// the first one. Implements [`SetpointSource`] without locking, allocating or freeing.
#[derive(Debug)]
pub struct StrokeFollower {
    ch: usize,
    timeline: Arc<Timeline>,
    from_planner: rtrb::Consumer<Box<Stroke>>,
    back: rtrb::Producer<Box<Stroke>>,
    joints: [Option<usize>; MAX_AXES_PER_CHANNEL],
    active: Option<Box<Stroke>>,
    pending: [Option<Box<Stroke>>; MAX_PENDING],
    published: bool,
    hold: [f64; MAX_AXES_PER_CHANNEL],
    prev_q: [f64; MAX_AXES_PER_CHANNEL],
    q: [f64; MAX_JOINTS],
    qd: [f64; MAX_JOINTS],
    qdd: [f64; MAX_JOINTS],
    /// The next executed cycle (deadline index less the skipped deadlines): the strokes' clock.
    executed: u64,
    /// A cycle was executed already.
    started: bool,
}

/// The two ends of channel `ch`'s handoff (`joints`: the robot joint of each axis).
pub fn channel(
    ch: usize,
    joints: [Option<usize>; MAX_AXES_PER_CHANNEL],
    timeline: Arc<Timeline>,
) -> (Sender, StrokeFollower) {
    let (to_cycle, from_planner) = rtrb::RingBuffer::new(POOL);
    let (back_tx, back_rx) = rtrb::RingBuffer::new(POOL);
    (
        Sender {
            to_cycle,
            back: back_rx,
            boxes: 0,
        },
        StrokeFollower {
            ch,
            timeline,
            from_planner,
            back: back_tx,
            joints,
            active: None,
            pending: Default::default(),
            published: false,
            hold: [0.0; MAX_AXES_PER_CHANNEL],
            prev_q: [f64::NAN; MAX_AXES_PER_CHANNEL],
            q: [0.0; MAX_JOINTS],
            qd: [0.0; MAX_JOINTS],
            qdd: [0.0; MAX_JOINTS],
            executed: 0,
            started: false,
        },
    )
}

impl StrokeFollower {
    fn give_back(&mut self, b: Box<Stroke>) {
        // the ring holds every box in circulation: this push cannot fail; if it ever did, the box
        // is kept in `active`'s place rather than freed here
        if let Err(rtrb::PushError::Full(b)) = self.back.push(b) {
            std::mem::forget(b);
        }
    }

    fn receive(&mut self, k: u64) {
        while let Ok(s) = self.from_planner.pop() {
            let free = self.pending.iter().position(|p| p.is_none());
            let stopped = self.timeline.stopped.load(Ordering::Relaxed);
            let taken = self
                .timeline
                .decide(s.seq, k <= s.start_cycle && free.is_some() && !stopped);
            self.timeline.seen[self.ch].store(s.seq, Ordering::Release);
            if !taken {
                self.give_back(s);
                continue;
            }
            // Seen one cycle after its start (another channel took it at its start cycle): this
            // channel commanded the running stroke there, which is the new stroke's start state,
            // so it follows on without a jump. Later than that is a discontinuity.
            if k > s.start_cycle + 1 {
                self.timeline.late.fetch_add(1, Ordering::Relaxed);
            }
            // a stroke supersedes every pending one that would start at or after it
            for p in 0..MAX_PENDING {
                if self.pending[p].as_ref().is_some_and(|x| x.start_cycle >= s.start_cycle) {
                    if let Some(b) = self.pending[p].take() {
                        self.give_back(b);
                    }
                }
            }
            match self.pending.iter().position(|p| p.is_none()) {
                Some(p) => self.pending[p] = Some(s),
                None => self.give_back(s),
            }
        }
        // the latest pending stroke whose start has come becomes the active one
        loop {
            let due = (0..MAX_PENDING)
                .filter(|&p| self.pending[p].as_ref().is_some_and(|x| x.start_cycle <= k))
                .min_by_key(|&p| self.pending[p].as_ref().map_or(u64::MAX, |x| x.start_cycle));
            let Some(p) = due else { break };
            let next = self.pending[p].take();
            if let Some(old) = std::mem::replace(&mut self.active, next) {
                self.give_back(old);
            }
        }
    }
}

impl SetpointSource for StrokeFollower {
    fn fill(&mut self, c: &CycleInfo, master: &ChannelMaster, out: &mut [AxisSetpoint], qdd: &mut [f64]) -> bool {
        let n = out.len();
        // The strokes run on executed cycles: a stall of this thread pauses them (the drives'
        // physics advance per SYNC too), the target never jumps. The channels keep one stroke
        // clock: a channel whose thread skipped fewer deadlines than another's holds its stroke
        // (repeats its setpoint) until their counts agree, but only while its joints are at
        // rest (a held target of drives in motion stops them abruptly: their tracking error
        // jumps and a drive may refuse the next target, EMCY 0xFF01). So the joints of
        // different channels are apart by the stalls of one stroke at most and agree again at
        // the next rest (the ready pose between balls). The skipped deadlines are published
        // so that the planner maps the controller clock onto this count.
        let next = self.executed;
        let own = c.k.saturating_sub(next);
        let lag = &self.timeline.skipped[self.ch];
        lag.fetch_max(own, Ordering::AcqRel);
        let most = self.timeline.skipped();
        let dof = self.timeline.dof;
        let resting = self.qd[..dof].iter().chain(&self.qdd[..dof]).all(|v| v.abs() < 1e-9);
        let k = if self.started && resting {
            next.min(c.k.saturating_sub(most)).max(next - 1)
        } else {
            next
        };
        let paused = self.started && k < next;
        self.started = true;
        self.executed = k + 1;
        lag.store(c.k.saturating_sub(k), Ordering::Release);
        if paused {
            self.timeline.paused.fetch_add(1, Ordering::Relaxed);
        }
        self.timeline.cycle[self.ch].store(k, Ordering::Release);
        if c.phase != Phase::Run {
            if matches!(c.phase, Phase::Stopping | Phase::Stopped) {
                self.timeline.stopped.store(true, Ordering::Relaxed);
            }
            for a in 0..n {
                self.hold[a] = master.hold_position(a);
                out[a] = AxisSetpoint {
                    q: self.hold[a],
                    qd: 0.0,
                    tau: 0.0,
                };
                qdd[a] = 0.0;
            }
            return false;
        }
        if !self.published {
            for a in 0..n {
                self.hold[a] = master.hold_position(a);
                if let Some(j) = self.joints[a].filter(|&j| j < MAX_JOINTS) {
                    self.timeline.hold[j].store(bits(self.hold[a]), Ordering::Relaxed);
                }
            }
            self.published = true;
            self.timeline.enabled.fetch_add(1, Ordering::AcqRel);
        }
        self.receive(k);
        let dof = self.timeline.dof;
        let sampled = match self
            .active
            .as_ref()
            .and_then(|s| s.traj.as_ref().map(|t| (s.start_cycle, t)))
        {
            Some((start, traj)) if traj.dof() == dof => {
                let t = ((k - start.min(k)) as f64 * c.period).min(traj.duration());
                let ok = traj
                    .sample(t, &mut self.q[..dof], &mut self.qd[..dof], &mut self.qdd[..dof])
                    .is_ok();
                // paused: the same sample as the cycle before (the target held)
                ok
            }
            _ => false,
        };
        for a in 0..n {
            out[a] = match self.joints[a].filter(|&j| sampled && j < dof) {
                Some(j) => {
                    qdd[a] = self.qdd[j];
                    AxisSetpoint {
                        q: self.q[j],
                        qd: self.qd[j],
                        tau: 0.0,
                    }
                }
                None => {
                    qdd[a] = 0.0;
                    AxisSetpoint {
                        q: self.hold[a],
                        qd: 0.0,
                        tau: 0.0,
                    }
                }
            };
        }
        false
    }

    fn planning(&self) -> bool {
        self.timeline.planning.load(Ordering::Relaxed)
    }

    fn clock(&self) -> Option<u64> {
        // the executed cycle the last fill sampled (the strokes' clock)
        self.started.then(|| self.executed - 1)
    }

    fn after_cycle(&mut self, c: &CycleInfo, master: &ChannelMaster) {
        let tl = &self.timeline;
        let seq = &tl.measured_seq[self.ch];
        let s = seq.load(Ordering::Relaxed);
        seq.store(s + 1, Ordering::Relaxed);
        fence(Ordering::Release);
        let stopped = master.stop_reason().is_some();
        for a in 0..master.len() {
            let Some(j) = self.joints[a].filter(|&j| j < MAX_JOINTS) else {
                continue;
            };
            if let Some(fb) = master.feedback(a) {
                let qd = if self.prev_q[a].is_finite() {
                    (fb.q - self.prev_q[a]) / c.period
                } else {
                    0.0
                };
                self.prev_q[a] = fb.q;
                tl.measured_q[j].store(bits(fb.q), Ordering::Relaxed);
                tl.measured_qd[j].store(bits(qd), Ordering::Relaxed);
            }
            if stopped {
                tl.faults.fetch_or(1 << j, Ordering::Relaxed);
            }
        }
        seq.store(s + 2, Ordering::Release);
    }
}
