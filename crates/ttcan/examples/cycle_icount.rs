//! Fixed-count loop of the controller cycle (four channels of two axes in Run: each reads its
//! drives' TPDOs, updates and writes RPDOs and SYNC), for instruction counts under valgrind:
//! `cycle_icount N`. Public API of main 40fcfd8 only, so the same source builds on both sides of
//! a before/after comparison.
use ttcan::canopen::Frames;
use ttcan::runtime::master::AxisSetpoint;

#[path = "../tests/support/channel.rs"]
mod channel;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .expect("usage: cycle_icount N");
    let mut channels = channel::running_channels_8_axes();
    let sp = [AxisSetpoint::default(); 2];
    let mut out = Frames::new();
    for _ in 0..n {
        channel::cycle_all(&mut channels, &sp, &mut out);
    }
    channel::assert_all_in_run(&channels);
}
