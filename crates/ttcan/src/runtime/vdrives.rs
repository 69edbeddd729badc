//! In-process virtual drives for a controller without CAN hardware: one in-memory bus
//! ([`crate::bus::memory`]) per channel, the channel's drives ([`crate::vdrive::VirtualDrive`],
//! the maxon RE 25 + GP 26 A model as `ttdrive-sim` has) served by one thread for all channels.
//! The controller runs its ordinary channel threads on the other port of each bus: the same
//! controller code, only the bus differs.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::bus::memory::{MemoryBus, MemoryPort};
use crate::bus::{BusEvent, CanBus};
use crate::canopen::{Frames, Units};
use crate::vdrive::VirtualDrive;
use crate::{AxisConfig, MotorModel};

/// The drives of one channel: node ids and scaling of each axis.
#[derive(Debug, Clone)]
pub struct VirtualChannel {
    /// (node id, units) of each axis.
    pub axes: Vec<(u8, Units)>,
}

/// The drives of every channel on their buses, ready to be served.
pub struct VirtualDrives {
    channels: Vec<(MemoryPort, Vec<VirtualDrive>)>,
}

impl VirtualDrives {
    /// Builds the drives of `channels` for a SYNC period of `period` s; returns them and the
    /// controller's port of each channel's bus. `sync_timeout_ms`: the drives' SYNC watchdog.
    pub fn new(
        channels: &[VirtualChannel],
        period: f64,
        sync_timeout_ms: u32,
    ) -> crate::Result<(VirtualDrives, Vec<MemoryPort>)> {
        let model = MotorModel::maxon_re25_gp26();
        let cfg = AxisConfig::new(model);
        let mut ports = Vec::new();
        let mut served = Vec::new();
        for ch in channels {
            let bus = MemoryBus::new();
            ports.push(bus.port());
            let mut port = bus.port();
            let mut out = Frames::new();
            let mut drives = Vec::new();
            for &(node, units) in &ch.axes {
                let mut d = VirtualDrive::new(node, &model, &cfg, units, period, &mut out)?;
                d.sync_timeout_ms = sync_timeout_ms;
                drives.push(d);
            }
            for f in out.as_slice() {
                let _ = port.send(f);
            }
            served.push((port, drives));
        }
        Ok((VirtualDrives { channels: served }, ports))
    }

    /// Serves the drives until `done`: every frame to every drive of its bus, the drives' 1 ms
    /// tick, their answers on the bus; polls every 100 µs.
    pub fn serve(&mut self, done: &AtomicBool) {
        let mut out = Frames::new();
        let mut next = crate::runtime::rt::now_ns();
        while !done.load(Ordering::Relaxed) {
            let now = crate::runtime::rt::now_ns();
            let tick = now >= next;
            if tick {
                next += 1_000_000;
                if now > next + 100_000_000 {
                    next = now;
                }
            }
            for (port, drives) in &mut self.channels {
                while let Ok(Some(BusEvent::Frame { frame, .. })) = port.poll() {
                    for d in drives.iter_mut() {
                        d.on_frame(&frame, &mut out);
                    }
                }
                if tick {
                    drives.iter_mut().for_each(|d| d.tick_ms(&mut out));
                }
                for f in out.as_slice() {
                    let _ = port.send(f);
                }
                out.clear();
            }
            crate::runtime::rt::sleep_until(crate::runtime::rt::now_ns() + 100_000);
        }
    }
}
