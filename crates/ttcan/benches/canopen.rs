//! CANopen benches: encode + decode of one cycle's frames for 8 axes (8 RPDOs, a SYNC, 8 TPDOs),
//! and the controller's per-cycle work for 8 axes (4 channels × 2: read the TPDOs, watchdog,
//! update, write RPDOs + SYNC). Budget: each ≤ 2 µs.

#[path = "../tests/support/channel.rs"]
mod channel;
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use ttcan::canopen::nmt::{decode_sync, encode_sync};
use ttcan::canopen::{Frame, Frames, Rpdo, Tpdo};
use ttcan::runtime::master::AxisSetpoint;

fn encode_decode(c: &mut Criterion) {
    c.bench_function("canopen_encode_decode_cycle_8_axes", |b| {
        let mut k = 0i32;
        b.iter(|| {
            k = k.wrapping_add(1);
            let mut sum = 0i64;
            let mut frames = [Frame::default(); 17];
            for n in 0..8u8 {
                frames[n as usize] = Rpdo {
                    target: k + n as i32,
                    torque_offset: 12,
                    controlword: 0x0F,
                }
                .encode(n + 1)
                .unwrap();
                frames[8 + n as usize] = Tpdo {
                    position: k - n as i32,
                    current: -40,
                    statusword: 0x1637,
                }
                .encode(n + 1)
                .unwrap();
            }
            frames[16] = encode_sync();
            for f in &frames[..8] {
                let (n, r) = Rpdo::decode(black_box(f)).unwrap();
                sum += r.target as i64 + n as i64;
            }
            for f in &frames[8..16] {
                let (n, t) = Tpdo::decode(black_box(f)).unwrap();
                sum += t.position as i64 + t.statusword as i64 + n as i64;
            }
            sum += decode_sync(&frames[16]).unwrap().unwrap_or(0) as i64;
            black_box(sum)
        })
    });
}

fn controller_cycle(c: &mut Criterion) {
    let mut channels = channel::running_channels_8_axes();
    let sp = [AxisSetpoint::default(); 2];
    c.bench_function("controller_cycle_8_axes", |b| {
        let mut out = Frames::new();
        b.iter(|| channel::cycle_all(&mut channels, &sp, &mut out))
    });
    channel::assert_all_in_run(&channels);
}

criterion_group!(benches, encode_decode, controller_cycle);
criterion_main!(benches);
