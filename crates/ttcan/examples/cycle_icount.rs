//! Fixed-count loop of the controller cycle (four channels of two axes in Run: each reads its
//! drives' TPDOs, updates and writes RPDOs and SYNC), for instruction counts under valgrind:
//! `cycle_icount N`. Public API of main 40fcfd8 only, so the same source builds on both sides of
//! a before/after comparison.
use std::hint::black_box;
use ttcan::canopen::Frames;
use ttcan::runtime::master::AxisSetpoint;

#[path = "../tests/support/channel.rs"]
mod channel;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .expect("usage: cycle_icount N");
    let mut channels: Vec<_> = (0..4).map(|_| channel::running_channel()).collect();
    let sp = [AxisSetpoint::default(); 2];
    let mut out = Frames::new();
    for _ in 0..n {
        for (m, tpdos) in channels.iter_mut() {
            for ev in tpdos.iter() {
                m.on_event(black_box(ev));
            }
            out.clear();
            m.cycle(black_box(&sp), &mut out);
            black_box(out.len());
        }
    }
    for (m, _) in &channels {
        assert_eq!(m.stop_reason(), None, "the channels stayed in Run");
    }
}
