//! Seed 000's racket motion on mobile8, shared by the mobile test and the redundancy bench: from
//! the start configuration's racket coordinates toward the seed's x(4).
#![allow(dead_code)]

use ttkin::task::Task;
use ttkin::wholebody::WholeBody;

/// Seed 000's x(4): racket centre (m) and two face angles (rad), base frame (Table 1).
pub const X4: [f64; 5] = [0.5501, 1.0647, 0.3998, 0.4699, 1.0528];

/// mobile8 on a fixed base, its start configuration, the racket task (0.15 m along tool z), and
/// the racket coordinates x(0) at the start and `fraction` of the way from x(0) to [`X4`] (beyond
/// about 0.18 the literal Table 1 arm is stretched out and singular).
pub fn seed000_line(fraction: f64) -> (WholeBody, [f64; 8], Task, [f64; 5], [f64; 5]) {
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q0 = ttkin::robots::mobile8_start();
    let task = Task::Racket { offset: 0.15 };
    let mut x0 = [0.0; 5];
    task.coordinates(&model.tool_pose(&q0).expect("mobile8_start is valid"), &mut x0);
    let x1 = std::array::from_fn(|i| x0[i] + fraction * (X4[i] - x0[i]));
    (model, q0, task, x0, x1)
}
