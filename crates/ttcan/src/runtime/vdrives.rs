//! In-process virtual drives for a controller without CAN hardware: each channel's bus is a
//! [`VirtualBus`] holding the channel's drives ([`crate::vdrive::VirtualDrive`], the maxon RE 25 +
//! GP 26 A model as `ttdrive-sim` has). A frame the controller sends reaches every drive at once
//! and their answers wait for the controller's next poll, as on a bus; the drives advance one
//! period per SYNC and run their 1 ms time base (heartbeat, SYNC watchdog) from the monotonic
//! clock. The controller runs its ordinary channel threads on these buses: the same controller
//! code, only the bus differs. The drives work inside the channel thread's send (test and laptop
//! infrastructure: it allocates a little; on a real bus that work is the drives').

use std::collections::VecDeque;

use crate::bus::{BusError, BusEvent, CanBus};
use crate::canopen::{Frame, Frames, Units};
use crate::vdrive::VirtualDrive;
use crate::{AxisConfig, MotorModel};

/// The drives of one channel: node id and scaling of each axis.
#[derive(Debug, Clone)]
pub struct VirtualChannel {
    /// (node id, units) of each axis.
    pub axes: Vec<(u8, Units)>,
}

/// One channel's bus with its virtual drives on it.
#[derive(Debug)]
pub struct VirtualBus {
    drives: Vec<VirtualDrive>,
    rx: VecDeque<BusEvent>,
    out: Frames,
    last_tick_ns: u64,
}

impl VirtualBus {
    /// The drives of `channel` for a SYNC period of `period` s, their SYNC watchdog
    /// `sync_timeout_ms`; their boot-up messages wait on the bus.
    pub fn new(channel: &VirtualChannel, period: f64, sync_timeout_ms: u32) -> crate::Result<Self> {
        let model = MotorModel::maxon_re25_gp26();
        let cfg = AxisConfig::new(model);
        let mut out = Frames::new();
        let mut drives = Vec::new();
        for &(node, units) in &channel.axes {
            let mut d = VirtualDrive::new(node, &model, &cfg, units, period, &mut out)?;
            d.sync_timeout_ms = sync_timeout_ms;
            drives.push(d);
        }
        let mut bus = VirtualBus {
            drives,
            rx: VecDeque::with_capacity(256),
            out: Frames::new(),
            last_tick_ns: crate::runtime::rt::now_ns(),
        };
        bus.queue(&out);
        Ok(bus)
    }

    /// The drives.
    pub fn drives(&self) -> &[VirtualDrive] {
        &self.drives
    }

    fn queue(&mut self, frames: &Frames) {
        let now = crate::runtime::rt::now_ns();
        for f in frames.as_slice() {
            self.rx.push_back(BusEvent::Frame {
                frame: *f,
                timestamp_ns: now,
            });
        }
    }

    fn tick(&mut self) {
        let now = crate::runtime::rt::now_ns();
        let ms = (now.saturating_sub(self.last_tick_ns) / 1_000_000).min(1000);
        self.last_tick_ns += ms * 1_000_000;
        for _ in 0..ms {
            for d in &mut self.drives {
                d.tick_ms(&mut self.out);
            }
        }
    }
}

impl CanBus for VirtualBus {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        self.out.clear();
        self.tick();
        for d in &mut self.drives {
            d.on_frame(frame, &mut self.out);
        }
        let out = std::mem::take(&mut self.out);
        self.queue(&out);
        self.out = out;
        Ok(())
    }

    fn poll(&mut self) -> Result<Option<BusEvent>, BusError> {
        Ok(self.rx.pop_front())
    }
}
