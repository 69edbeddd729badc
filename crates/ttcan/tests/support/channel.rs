//! One channel of two axes (nodes 1 and 2) for the CANopen tests, the bench and the
//! instruction-count example: the axes as the controller sees them, and a controller brought to
//! Run by protocol-only drive nodes, and the controller cycle the bench and the example measure.
#![allow(dead_code)]

use std::hint::black_box;
use ttcan::bus::BusEvent;
use ttcan::canopen::cia402::OpMode;
use ttcan::canopen::node::{DriveNode, NodeEvent};
use ttcan::canopen::{Frames, Units};
use ttcan::runtime::master::{AxisSetpoint, ChannelMaster, LinkConfig, Phase, WatchdogConfig};

/// Nodes 1 and 2 with the default units, a 0.05 rad following-error limit and a 10 A current limit.
pub fn two_links() -> Vec<LinkConfig> {
    (1..=2)
        .map(|n| LinkConfig {
            node: n,
            units: Units::default(),
            following_error_limit: 0.05,
            max_current: 10.0,
        })
        .collect()
}

/// A channel master brought to Run by two protocol-only drive nodes; returns it and the TPDOs the
/// drives answer a steady-state SYNC with.
pub fn running_channel() -> (ChannelMaster, Vec<BusEvent>) {
    let links = two_links();
    let mut m = ChannelMaster::new(&links, OpMode::Csp, WatchdogConfig::default()).unwrap();
    let mut boot = Frames::new();
    let mut nodes: Vec<DriveNode> = (1..=2).map(|n| DriveNode::new(n, &mut boot).unwrap()).collect();
    let mut last = Vec::new();
    for _ in 0..100 {
        let mut out = Frames::new();
        m.cycle(&[AxisSetpoint::default(); 2], &mut out);
        last.clear();
        for f in out.as_slice() {
            for n in nodes.iter_mut() {
                let mut back = Frames::new();
                if n.on_frame(f, &mut back) == NodeEvent::Sync {
                    n.on_sync(0, 0, 0, 1000, &mut back);
                }
                for g in back.as_slice() {
                    let ev = BusEvent::Frame {
                        frame: *g,
                        timestamp_ns: 0,
                    };
                    m.on_event(&ev);
                    last.push(ev);
                }
            }
        }
        if m.phase() == Phase::Run {
            break;
        }
    }
    assert_eq!(m.phase(), Phase::Run);
    (m, last)
}

/// Four channels of two axes (8 axes), each brought to Run with its steady-state TPDOs.
pub fn running_channels_8_axes() -> Vec<(ChannelMaster, Vec<BusEvent>)> {
    (0..4).map(|_| running_channel()).collect()
}

/// One controller cycle of every channel at the setpoints `sp`: read its drives' TPDOs,
/// watchdog, update, write RPDOs and SYNC into `out` (cleared per channel).
pub fn cycle_all(channels: &mut [(ChannelMaster, Vec<BusEvent>)], sp: &[AxisSetpoint], out: &mut Frames) {
    for (m, tpdos) in channels.iter_mut() {
        for ev in tpdos.iter() {
            m.on_event(black_box(ev));
        }
        out.clear();
        m.cycle(black_box(sp), out);
        black_box(out.len());
    }
}

/// Panics unless every channel is still in Run (no stop reason).
pub fn assert_all_in_run(channels: &[(ChannelMaster, Vec<BusEvent>)]) {
    for (m, _) in channels {
        assert_eq!(m.stop_reason(), None, "the measured channels stayed in Run");
    }
}
