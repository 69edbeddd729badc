use std::hint::black_box;
use ttkin::clik::*;
use ttkin::redundancy::*;
use ttkin::task::Task;
use ttkin::wholebody::WholeBody;
fn main() {
    let which = std::env::args().nth(1).unwrap();
    let model = WholeBody::fixed(ttkin::robots::mobile8());
    let q = ttkin::robots::mobile8_start();
    let task = Task::Racket { offset: 0.15 };
    if which == "wls" {
        let mut step = WlsStep::new(&model, task, Weighting::ChanDubey, Damping::default()).unwrap();
        let xdot = [0.1, 0.05, -0.08, 0.3, -0.2];
        let prev = [0.01; 8];
        let mut acc = 0.0;
        for _ in 0..2_000_000 {
            let (qd, _) = step.solve(black_box(&q), black_box(&xdot), &prev);
            acc += qd[0];
        }
        println!("{acc}");
    } else if which == "jac" {
        let mut data = model.data();
        let mut j = nalgebra::Matrix6xX::zeros(8);
        let mut acc = 0.0;
        for _ in 0..2_000_000 {
            let t = model.jacobian_into(black_box(&q), &mut data, &mut j);
            acc += t.translation.x + j[(0, 0)];
        }
        println!("{acc}");
    } else {
        let mut x0 = [0.0; 5];
        task.coordinates(&model.tool_pose(&q).unwrap(), &mut x0);
        let x4 = [0.5501, 1.0647, 0.3998, 0.4699, 1.0528];
        let x1: Vec<f64> = (0..5).map(|i| x0[i] + 0.15 * (x4[i] - x0[i])).collect();
        let mut acc = 0;
        for _ in 0..200 {
            let traj = TaskTrajectory::line(task, &x0, &x1, 4.0, 1000.0).unwrap();
            let r = track(&model, black_box(&q), &traj, ClikOptions::default()).unwrap();
            acc += r.len();
        }
        println!("{acc}");
    }
}
