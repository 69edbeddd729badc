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
//!
//! Each channel follows its strokes on its own stroke clock (its executed cycles: a stall of its
//! thread pauses them, the target never jumps), and each stroke is handed to each channel with
//! its own start cycle on that clock: the planner puts every channel's start at the same
//! deadline (its start = the deadline less the deadlines it skipped), so the channels start each
//! stroke in step wherever their clocks are, and a channel that stalled during a stroke is
//! brought back in step by the next stroke (the planning thread re-plans a pending hit from the
//! state each channel commands when their skips drift apart). Each channel records the deadline
//! at which it commanded a stroke's hit ([`Timeline::hit_deadlines`]): the hit was in step when
//! every channel commanded it at the same deadline.

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
/// Hit records kept per channel (by stroke sequence number modulo this).
pub const HIT_SLOTS: usize = 32;
/// No hit in the stroke.
pub const NO_HIT: u64 = u64::MAX;
/// Bits of a packed clock word (and of a hit record) that hold the cycle or deadline.
const LOW: u32 = 40;
const LOW_MASK: u64 = (1 << LOW) - 1;

const PENDING: u64 = 0;
const TAKEN: u64 = 1;
const LATE: u64 = 2;

/// A complete stroke for the cycle threads: from `start_cycle` on, the axes follow `traj`
/// (time 0 at that cycle; its end state held after its end).
#[derive(Debug, Clone, Default)]
pub struct Stroke {
    /// Handoff sequence number (strictly increasing).
    pub seq: u64,
    /// This channel's executed cycle (its stroke clock) that commands the stroke's time 0.
    pub start_cycle: u64,
    /// This channel's executed cycle of the stroke's hit ([`NO_HIT`]: none); the deadline at
    /// which the channel commands it is recorded ([`Timeline::hit_deadlines`]).
    pub hit_cycle: u64,
    /// The joint trajectory (all joints of the robot).
    pub traj: Option<JointTrajectory>,
    /// Every channel's start cycle of the stroke, each on its own stroke clock (`u64::MAX`: no
    /// constraint): the channel that decides takes the stroke only while no channel has
    /// commanded its start cycle yet, so that no channel follows it late.
    pub starts: [u64; MAX_CHANNELS],
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
    /// Per channel: deadlines skipped (high bits) and the executed cycle sampled (low bits),
    /// one word so that they are read together.
    clock: [AtomicU64; MAX_CHANNELS],
    /// Per channel and slot: stroke seq (high bits) and the deadline its hit was commanded at.
    hits: [[AtomicU64; HIT_SLOTS]; MAX_CHANNELS],
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
            clock: std::array::from_fn(|_| AtomicU64::new(0)),
            hits: std::array::from_fn(|_| std::array::from_fn(|_| AtomicU64::new(u64::MAX))),
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

    /// Channel `ch`'s (deadlines skipped, executed cycle sampled) as of its last cycle.
    pub fn clock_of(&self, ch: usize) -> (u64, u64) {
        let w = self.clock[ch.min(MAX_CHANNELS - 1)].load(Ordering::Acquire);
        (w >> LOW, w & LOW_MASK)
    }

    /// Deadlines each channel skipped so far (one entry per channel).
    pub fn skips(&self) -> Vec<u64> {
        (0..self.channels).map(|c| self.clock_of(c).0).collect()
    }

    /// Deadlines skipped so far by the channel that skipped the most.
    pub fn skipped(&self) -> u64 {
        (0..self.channels).map(|c| self.clock_of(c).0).max().unwrap_or(0)
    }

    /// Controller time (s, monotonic clock) of deadline `d`.
    pub fn time_of(&self, d: u64) -> f64 {
        (self.t0_ns as f64 + d as f64 * self.period_ns as f64) * 1e-9
    }

    /// The first deadline at or after controller time `t` (s).
    pub fn deadline_at(&self, t: f64) -> u64 {
        ((t * 1e9 - self.t0_ns as f64) / self.period_ns as f64).ceil().max(0.0) as u64
    }

    /// Period, s.
    pub fn period(&self) -> f64 {
        self.period_ns as f64 * 1e-9
    }

    /// The newest executed cycle any channel has started (its stroke clock).
    pub fn present_cycle(&self) -> u64 {
        (0..self.channels).map(|c| self.clock_of(c).1).max().unwrap_or(0)
    }

    /// The newest deadline any channel has executed.
    pub fn present_deadline(&self) -> u64 {
        (0..self.channels)
            .map(|c| {
                let (s, k) = self.clock_of(c);
                s + k
            })
            .max()
            .unwrap_or(0)
    }

    /// The deadline at which each channel commanded the hit of stroke `seq`, once every channel
    /// has (`None` before, or when the record was overwritten by later strokes).
    pub fn hit_deadlines(&self, seq: u64) -> Option<Vec<u64>> {
        self.hit_records(seq).into_iter().collect()
    }

    /// The deadline at which each channel commanded the hit of stroke `seq` (`None`: not yet, or
    /// the record was overwritten by later strokes).
    pub fn hit_records(&self, seq: u64) -> Vec<Option<u64>> {
        (0..self.channels)
            .map(|c| {
                let w = self.hits[c][seq as usize % HIT_SLOTS].load(Ordering::Acquire);
                (w != u64::MAX && w >> LOW == seq & (u64::MAX >> LOW)).then_some(w & LOW_MASK)
            })
            .collect()
    }

    /// True when every channel runs and has published its held positions.
    pub fn all_enabled(&self) -> bool {
        self.enabled.load(Ordering::Acquire) >= self.channels
    }

    /// True once telemetry is to be sent: every channel runs, or a channel has stopped or set a
    /// fault bit (a drive that never enabled, or left Operation Enabled): from then on the
    /// telemetry carries the fault bits and is never silent.
    pub fn telemetry_due(&self) -> bool {
        self.all_enabled() || self.faults.load(Ordering::Relaxed) != 0 || self.stopped.load(Ordering::Relaxed)
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

    /// Opens the decision on stroke `seq` (planning thread, once it is pushed to every channel:
    /// a channel leaves a stroke whose decision is not open in its ring).
    pub fn open(&self, seq: u64) {
        self.decision.store(seq << 2 | PENDING, Ordering::Release);
    }

    /// Refuses stroke `seq` unless a channel has decided on it already (planning thread: it could
    /// not be pushed to every channel, or no channel saw it in time); the channels that hold it
    /// then discard it. The decision that stands.
    pub fn refuse(&self, seq: u64) -> Decision {
        if self.decision.load(Ordering::Acquire) >> 2 < seq {
            // not opened: no channel decides on it before this
            self.decision.store(seq << 2 | LATE, Ordering::Release);
        } else {
            let _ = self.decision.compare_exchange(
                seq << 2 | PENDING,
                seq << 2 | LATE,
                Ordering::AcqRel,
                Ordering::Acquire,
            );
        }
        self.decision(seq)
    }

    /// True when the decision on stroke `seq` is open or made (or a later stroke's is).
    fn opened(&self, seq: u64) -> bool {
        self.decision.load(Ordering::Acquire) >> 2 >= seq
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
    ch: usize,
    to_cycle: rtrb::Producer<Box<Stroke>>,
    back: rtrb::Consumer<Box<Stroke>>,
    boxes: usize,
    joints: [Option<usize>; MAX_AXES_PER_CHANNEL],
}

impl Sender {
    /// Hands `stroke` (a copy of it) to the channel: a returned box is reused, a new one made only
    /// while fewer than [`POOL`] are in circulation. `false` when the ring is full.
    pub fn push(&mut self, seq: u64, start_cycle: u64, traj: &JointTrajectory) -> bool {
        self.push_hit(seq, start_cycle, NO_HIT, traj)
    }

    /// [`Sender::push`] of a stroke whose hit comes at this channel's executed cycle `hit_cycle`.
    pub fn push_hit(&mut self, seq: u64, start_cycle: u64, hit_cycle: u64, traj: &JointTrajectory) -> bool {
        let mut starts = [u64::MAX; MAX_CHANNELS];
        starts[self.ch] = start_cycle;
        self.push_joint(seq, &starts, hit_cycle, traj)
    }

    /// [`Sender::push_hit`] of a stroke every channel starts at one deadline: `starts` holds each
    /// channel's start cycle on its own stroke clock (this channel's among them); the stroke is
    /// taken only while no channel has commanded its start cycle yet.
    pub fn push_joint(&mut self, seq: u64, starts: &[u64], hit_cycle: u64, traj: &JointTrajectory) -> bool {
        let start_cycle = starts.get(self.ch).copied().unwrap_or(u64::MAX);
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
        b.hit_cycle = hit_cycle;
        b.starts = [u64::MAX; MAX_CHANNELS];
        for (d, s) in b.starts.iter_mut().zip(starts) {
            *d = *s;
        }
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

    /// This channel's entry of `starts` (one start cycle per channel).
    pub fn own(&self, starts: &[u64]) -> u64 {
        starts.get(self.ch).copied().unwrap_or(u64::MAX)
    }

    /// The robot joint of each axis of this channel.
    pub fn joints(&self) -> &[Option<usize>; MAX_AXES_PER_CHANNEL] {
        &self.joints
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
    /// The stroke whose hit this channel recorded last.
    hit_recorded: u64,
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
            ch: ch.min(MAX_CHANNELS - 1),
            to_cycle,
            back: back_rx,
            boxes: 0,
            joints,
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
            hit_recorded: 0,
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

    /// True when no other channel has commanded its start cycle of `s` yet (its clock word holds
    /// the executed cycle of its last fill; it takes the stroke at its next fill at the latest).
    fn others_before_start(&self, s: &Stroke) -> bool {
        (0..self.timeline.channels)
            .filter(|&c| c != self.ch)
            .all(|c| self.timeline.clock_of(c).1 < s.starts[c])
    }

    fn receive(&mut self, k: u64) {
        // a stroke whose decision is not open yet is not yet in every channel's ring: left
        // there until it is (the planning thread opens it after the last push)
        while let Ok(seq) = self.from_planner.peek().map(|s| s.seq) {
            if !self.timeline.opened(seq) {
                break;
            }
            let Ok(s) = self.from_planner.pop() else { break };
            let free = self.pending.iter().position(|p| p.is_none());
            let stopped = self.timeline.stopped.load(Ordering::Relaxed);
            let on_time = k <= s.start_cycle && free.is_some() && !stopped && self.others_before_start(&s);
            let taken = self.timeline.decide(s.seq, on_time);
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
                None => {
                    // taken by another channel, no room here: this channel does not follow it
                    // (counted with the late ones: the channels split on it)
                    self.timeline.late.fetch_add(1, Ordering::Relaxed);
                    self.give_back(s);
                }
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
        // physics advance per SYNC too), the target never jumps. Each channel keeps its own
        // stroke clock; the planner gives each channel its own start cycle so that every stroke
        // starts at the same deadline on all channels, and re-plans a pending hit when a stall
        // during a stroke put them apart (nothing is held: a held target of drives in motion
        // stops them abruptly, EMCY 0xFF01). The skips are published with the executed cycle.
        let k = self.executed;
        let own = c.k.saturating_sub(k).min(LOW_MASK >> 16);
        self.started = true;
        self.executed = k + 1;
        self.timeline.clock[self.ch].store(own << LOW | (k & LOW_MASK), Ordering::Release);
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
                traj.sample(t, &mut self.q[..dof], &mut self.qd[..dof], &mut self.qdd[..dof])
                    .is_ok()
            }
            _ => false,
        };
        // the deadline at which this channel commands the stroke's hit
        if let Some(st) = self
            .active
            .as_ref()
            .filter(|s| s.hit_cycle != NO_HIT && s.hit_cycle <= k)
        {
            if st.seq != self.hit_recorded {
                self.hit_recorded = st.seq;
                let slot = &self.timeline.hits[self.ch][st.seq as usize % HIT_SLOTS];
                slot.store(st.seq << LOW | (c.k & LOW_MASK), Ordering::Release);
            }
        }
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
