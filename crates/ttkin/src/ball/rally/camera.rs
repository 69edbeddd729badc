//! The rally's camera: its model ([`Camera`]) and what it delivers of one ball's true flight
//! (positions with Gaussian noise and outliers at the frame times, stamped as the planner sees
//! them); [`observe_ball`], ball `i` of a rally as its camera sees it.

use super::serve::{gauss, serve, uniform};
use super::RallyConfig;
use crate::ball::flight::{BallState, Flight};

/// Camera model.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Camera {
    /// Frame rate (Hz).
    pub rate_hz: f64,
    /// Delay from exposure to delivery (s).
    pub latency: f64,
    /// Position noise σ per axis (m).
    pub noise: f64,
    /// Probability of an outlier observation.
    pub outlier_rate: f64,
    /// Largest outlier displacement per axis (m).
    pub outlier_size: f64,
    /// First observation after the opponent's hit (s).
    pub start: f64,
    /// Observation window (s).
    pub window: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            rate_hz: 200.0,
            latency: 0.010,
            noise: 0.002,
            outlier_rate: 0.02,
            outlier_size: 0.10,
            start: 0.02,
            window: 0.20,
        }
    }
}

/// What the camera delivered of one ball's flight: frames over the whole incoming flight, each
/// plan seeing those delivered by its time; with the ball and the world it flew in.
#[derive(Debug, Clone, PartialEq)]
pub struct Observations {
    /// Incoming state at the opponent's hit (t = 0).
    pub incoming: BallState,
    /// The ball's world (the flight it was observed in; a rally's: its truth with the constants
    /// drawn by [`RallyConfig::world`]).
    pub world: Flight,
    /// True exposure times (s from the opponent's hit).
    pub exposures: Vec<f64>,
    /// The time stamps the planner sees (s): the exposures, off by the ball's latency error.
    pub times: Vec<f64>,
    /// Observed positions (m, world), one per frame.
    pub positions: Vec<[f64; 3]>,
    /// Frames in the first observation window (the first plan uses `positions[..first]`).
    pub first: usize,
}

impl Camera {
    /// The frames of the true flight from `s0` over 1.2 s, noise and outliers drawn with `rng`,
    /// time stamps off by `stamp_error` (s).
    pub fn observe(&self, truth: &Flight, s0: &BallState, stamp_error: f64, rng: &mut fastrand::Rng) -> Observations {
        let cam = self;
        // The camera runs for the whole incoming flight; each plan sees what was delivered by then.
        let count = (1.2 * cam.rate_hz) as usize;
        let exposures: Vec<f64> = (0..count).map(|k| cam.start + k as f64 / cam.rate_hz).collect();
        let truth_path = crate::ball::predict::predict(truth, s0, &exposures).expect("valid times");
        // The time stamps the planner sees: the exposures, off by the ball's latency error.
        let times: Vec<f64> = exposures.iter().map(|t| t + stamp_error).collect();
        let positions: Vec<[f64; 3]> = truth_path
            .positions
            .iter()
            .map(|p| {
                let mut o = *p;
                let outlier = rng.f64() < cam.outlier_rate;
                for x in o.iter_mut() {
                    *x += cam.noise * gauss(rng);
                    if outlier {
                        *x += uniform(rng, -cam.outlier_size, cam.outlier_size);
                    }
                }
                o
            })
            .collect();
        let first = (cam.window * cam.rate_hz).round() as usize + 1;
        Observations {
            incoming: *s0,
            world: *truth,
            exposures,
            times,
            positions,
            first,
        }
    }
}

/// Ball `index` of the rally `cfg` as its camera sees it: served (or `incoming` when given, e.g. a
/// recorded shot, re-based to t = 0), flying in its own world when [`RallyConfig::world`] is set
/// (constants drawn around `truth`'s, time stamps off by the drawn latency error), observed by
/// [`RallyConfig::camera`]. The rally's random streams of that ball: [`super::play_with`] sees the
/// same ball and observations.
pub fn observe_ball(truth: &Flight, cfg: &RallyConfig, index: u64, incoming: Option<&BallState>) -> Observations {
    let mut rng = fastrand::Rng::with_seed(
        cfg.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03),
    );
    let s0 = match incoming {
        Some(s) => BallState { t: 0.0, ..*s },
        None => serve(truth, &mut rng, cfg.max_spin_rps, cfg.corkscrew),
    };
    // The ball's own world, from a stream of its own (the serve and the camera noise unchanged).
    let mut world_rng = fastrand::Rng::with_seed(
        cfg.seed.wrapping_mul(0xA076_1D64_78BD_642F) ^ index.wrapping_mul(0xE703_7ED1_A0B4_28DB) ^ 0x5EED,
    );
    let (world, stamp_error) = match &cfg.world {
        Some(w) => (
            Flight {
                model: w.draw(&truth.model, &mut world_rng),
                ..*truth
            },
            w.latency_jitter * (2.0 * world_rng.f64() - 1.0),
        ),
        None => (*truth, 0.0),
    };
    cfg.camera.observe(&world, &s0, stamp_error, &mut rng)
}
