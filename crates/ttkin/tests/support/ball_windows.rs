//! The noisy ball observations shared by the `ball` bench and the `ball_icount` example: incoming
//! balls served by `rally::serve` (40 rev/s spin at most), 41 positions at 200 Hz from 0.02 s to
//! 0.22 s after the hit, σ = 2 mm per axis (world frame, m), from a 1 ms reference flight.
#![allow(dead_code)]

use ttkin::ball::estimate::EstimateOptions;
use ttkin::ball::flight::{BallState, Flight};
use ttkin::ball::predict::predict;
use ttkin::ball::rally;

/// Noisy observations of `count` incoming balls and the true state at the last observation.
pub fn observations(count: usize) -> Vec<(Vec<f64>, Vec<[f64; 3]>, BallState)> {
    let truth = Flight {
        step: 0.001,
        ..Flight::default()
    };
    let mut rng = fastrand::Rng::with_seed(1);
    (0..count)
        .map(|_| {
            let s = rally::serve(&truth, &mut rng, 40.0, 0.2);
            let t: Vec<f64> = (0..41).map(|k| 0.02 + k as f64 * 0.005).collect();
            let p = predict(&truth, &s, &t).unwrap().positions;
            let p = p
                .iter()
                .map(|x| {
                    let mut o = *x;
                    for v in o.iter_mut() {
                        *v += 0.002 * (rng.f64() + rng.f64() + rng.f64() - 1.5) * 2.0;
                    }
                    o
                })
                .collect();
            let (last, _) = truth.run(&s, t[40], None);
            (t, p, last)
        })
        .collect()
}

/// The estimator options both measure: the defaults with a 5 ms RK4 step (the observation spacing).
pub fn estimate_options() -> EstimateOptions {
    EstimateOptions {
        flight: Flight {
            step: 0.005,
            ..Flight::default()
        },
        ..EstimateOptions::default()
    }
}
