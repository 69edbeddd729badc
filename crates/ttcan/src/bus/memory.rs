//! An in-process CAN bus: every port receives what the other ports send (as on a real bus), in
//! order, with a monotonic timestamp. Fault injection for tests: drop, corrupt (truncate to 3
//! bytes) or delay frames of chosen identifiers, and bus-off. Test infrastructure: it locks a
//! mutex and allocates; the controller cycle code that runs on it does neither.

use super::{BusError, BusEvent, BusFault, CanBus};
use crate::canopen::Frame;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

/// Faults applied to frames as they are sent.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Faults {
    /// Identifiers whose frames are lost.
    pub drop_ids: Vec<u16>,
    /// Identifiers whose frames arrive truncated to 3 bytes (a malformed frame).
    pub corrupt_ids: Vec<u16>,
    /// Identifiers whose frames arrive only after `delay_frames` later frames.
    pub delay_ids: Vec<u16>,
    /// Delay in frames for `delay_ids`.
    pub delay_frames: u32,
    /// Bus-off: sends fail with [`BusError::Down`], every port sees [`BusFault::BusOff`] once.
    pub bus_off: bool,
}

#[derive(Debug)]
struct Inner {
    queues: Vec<VecDeque<(usize, BusEvent)>>,
    delayed: Vec<(u32, usize, Frame)>,
    faults: Faults,
    bus_off_reported: Vec<bool>,
    start: Instant,
    frames: u64,
}

/// The shared bus; create ports with [`MemoryBus::port`].
#[derive(Debug, Clone)]
pub struct MemoryBus {
    inner: Arc<Mutex<Inner>>,
}

impl Default for MemoryBus {
    fn default() -> Self {
        Self::new()
    }
}

fn lock(m: &Mutex<Inner>) -> MutexGuard<'_, Inner> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

impl MemoryBus {
    /// An empty bus without faults.
    pub fn new() -> Self {
        MemoryBus {
            inner: Arc::new(Mutex::new(Inner {
                queues: Vec::new(),
                delayed: Vec::new(),
                faults: Faults::default(),
                bus_off_reported: Vec::new(),
                start: Instant::now(),
                frames: 0,
            })),
        }
    }

    /// A new port (a node's connection to the bus).
    pub fn port(&self) -> MemoryPort {
        let mut g = lock(&self.inner);
        g.queues.push(VecDeque::with_capacity(256));
        g.bus_off_reported.push(false);
        MemoryPort {
            inner: self.inner.clone(),
            index: g.queues.len() - 1,
        }
    }

    /// Replaces the fault configuration.
    pub fn set_faults(&self, faults: Faults) {
        let mut g = lock(&self.inner);
        if !faults.bus_off {
            g.bus_off_reported.iter_mut().for_each(|r| *r = false);
        }
        g.faults = faults;
    }

    /// Frames delivered so far.
    pub fn frames(&self) -> u64 {
        lock(&self.inner).frames
    }
}

/// One port of a [`MemoryBus`].
#[derive(Debug)]
pub struct MemoryPort {
    inner: Arc<Mutex<Inner>>,
    index: usize,
}

fn deliver(g: &mut Inner, from: usize, frame: Frame) {
    let t = g.start.elapsed().as_nanos() as u64;
    g.frames += 1;
    for (k, q) in g.queues.iter_mut().enumerate() {
        if k != from {
            q.push_back((from, BusEvent::Frame { frame, timestamp_ns: t }));
        }
    }
}

impl CanBus for MemoryPort {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        let mut g = lock(&self.inner);
        if g.faults.bus_off {
            return Err(BusError::Down);
        }
        // release delayed frames whose delay has run out
        let mut k = 0;
        while k < g.delayed.len() {
            if g.delayed[k].0 == 0 {
                let (_, from, f) = g.delayed.remove(k);
                deliver(&mut g, from, f);
            } else {
                g.delayed[k].0 -= 1;
                k += 1;
            }
        }
        let id = frame.id();
        if g.faults.drop_ids.contains(&id) {
            return Ok(());
        }
        let mut f = *frame;
        if g.faults.corrupt_ids.contains(&id) {
            f = Frame::new(id, &frame.data()[..frame.len().min(3)]).unwrap_or(f);
        }
        if g.faults.delay_ids.contains(&id) {
            let d = g.faults.delay_frames;
            g.delayed.push((d, self.index, f));
            return Ok(());
        }
        deliver(&mut g, self.index, f);
        Ok(())
    }

    fn poll(&mut self) -> Result<Option<BusEvent>, BusError> {
        let mut g = lock(&self.inner);
        if g.faults.bus_off && !g.bus_off_reported[self.index] {
            g.bus_off_reported[self.index] = true;
            return Ok(Some(BusEvent::Fault(BusFault::BusOff)));
        }
        Ok(g.queues[self.index].pop_front().map(|(_, e)| e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ports_see_each_other_but_not_themselves_and_faults_apply() {
        let bus = MemoryBus::new();
        let (mut a, mut b) = (bus.port(), bus.port());
        let f = Frame::new(0x181, &[1, 2, 3, 4, 5, 6, 7, 8]).unwrap();
        a.send(&f).unwrap();
        assert!(a.poll().unwrap().is_none());
        assert!(matches!(b.poll().unwrap(), Some(BusEvent::Frame { frame, .. }) if frame == f));
        bus.set_faults(Faults {
            corrupt_ids: vec![0x181],
            ..Faults::default()
        });
        a.send(&f).unwrap();
        assert!(matches!(b.poll().unwrap(), Some(BusEvent::Frame { frame, .. }) if frame.len() == 3));
        bus.set_faults(Faults {
            drop_ids: vec![0x181],
            ..Faults::default()
        });
        a.send(&f).unwrap();
        assert!(b.poll().unwrap().is_none());
        bus.set_faults(Faults {
            delay_ids: vec![0x181],
            delay_frames: 1,
            ..Faults::default()
        });
        a.send(&f).unwrap();
        let g = Frame::new(0x80, &[]).unwrap();
        a.send(&g).unwrap();
        assert!(matches!(b.poll().unwrap(), Some(BusEvent::Frame { frame, .. }) if frame == g));
        a.send(&g).unwrap();
        assert!(matches!(b.poll().unwrap(), Some(BusEvent::Frame { frame, .. }) if frame == f));
        bus.set_faults(Faults {
            bus_off: true,
            ..Faults::default()
        });
        assert_eq!(a.send(&f), Err(BusError::Down));
        assert_eq!(b.poll().unwrap(), Some(BusEvent::Fault(BusFault::BusOff)));
    }
}
