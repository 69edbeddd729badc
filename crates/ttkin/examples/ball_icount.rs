//! Fixed work of the ball estimator and flight for instruction counts under valgrind:
//! `ball_icount estimate N` fits N windows of 41 noisy observations (0.2 s at 200 Hz, σ = 2 mm,
//! the data of the `ball` bench, estimator step 5 ms), `ball_icount crossing N` predicts N
//! crossings of the hitting plane x = −1.6 m with the default 2 ms flight, `ball_icount check`
//! prints each fit's velocity error against the truth (m/s) for comparing estimator versions.
use nalgebra::Vector3;
use std::hint::black_box;
use ttkin::ball::estimate::estimate;
use ttkin::ball::flight::{Flight, Plane};
use ttkin::ball::predict::crossing;
#[path = "../tests/support/ball_windows.rs"]
mod ball_windows;
use ball_windows::{estimate_options, observations};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(2).map_or(1000, |a| a.parse().unwrap());
    let obs = observations(64);
    let opts = estimate_options();
    match args[1].as_str() {
        "estimate" => {
            for i in 0..n {
                let o = &obs[i % obs.len()];
                black_box(estimate(black_box(&o.0), black_box(&o.1), &opts).unwrap());
            }
        }
        "crossing" => {
            let plane = Plane {
                point: Vector3::new(-1.6, 0.0, 0.0),
                normal: Vector3::x(),
            };
            let flight = Flight::default();
            for i in 0..n {
                black_box(crossing(&flight, black_box(&obs[i % obs.len()].2), &plane, 2.0).unwrap());
            }
        }
        "check" => {
            let mut worst: f64 = 0.0;
            for o in &obs {
                let e = estimate(&o.0, &o.1, &opts).unwrap();
                let err = (e.state.v - o.2.v).norm();
                worst = worst.max(err);
                println!("{err:.5} used {} outliers {}", e.used, e.outliers);
            }
            println!("worst {worst:.5}");
        }
        other => panic!("unknown mode {other:?}; expected estimate, crossing or check"),
    }
}
