//! The rally's incoming balls ([`serve`]: the opponent's shots described in the module doc of
//! [`super`]) and the world each ball flies in ([`WorldSpread`]), with the random draws they use.

use crate::ball::flight::{BallState, EventKind, Flight};
use crate::ball::hitplan::shoot;
use crate::ball::model::BallModel;
use nalgebra::Vector3;

/// How the simulated world departs from the planner's model, drawn anew for every ball (from its
/// own random stream, so the incoming balls are the same with and without it): the true ball's
/// drag and Magnus constants scaled by (1 + σ·N(0, 1)), its table restitution and friction moved
/// by σ·N(0, 1) (clamped to their physical ranges), and the camera's time stamps off by a constant
/// uniform in ±`latency_jitter` for the ball (the delivery latency differs from the one the
/// planner assumes).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct WorldSpread {
    /// Relative standard deviation of k_d.
    pub k_drag: f64,
    /// Relative standard deviation of k_m.
    pub k_magnus: f64,
    /// Standard deviation of the table restitution.
    pub restitution: f64,
    /// Standard deviation of the table friction.
    pub friction: f64,
    /// Largest time-stamp error (s) of the observations.
    pub latency_jitter: f64,
}

impl WorldSpread {
    /// The spreads between the calibrations of the four ball-gun groups of the PAM flights
    /// (docs/ball.md, "The world the planner does not know"): k_d 4 %, k_m 45 % (0.00064–0.00235),
    /// restitution 0.008; friction 0.05 and ±3 ms of latency jitter are assumed, not measured (the
    /// flights do not identify μ and carry no time stamps).
    pub fn measured() -> Self {
        WorldSpread {
            k_drag: 0.04,
            k_magnus: 0.45,
            restitution: 0.008,
            friction: 0.05,
            latency_jitter: 0.003,
        }
    }

    /// The ball model of one ball's world: `model` with its constants drawn with `rng`.
    pub fn draw(&self, model: &BallModel, rng: &mut fastrand::Rng) -> BallModel {
        BallModel {
            k_drag: (model.k_drag * (1.0 + self.k_drag * gauss(rng))).max(0.0),
            k_magnus: (model.k_magnus * (1.0 + self.k_magnus * gauss(rng))).max(0.0),
            table_restitution: (model.table_restitution + self.restitution * gauss(rng)).clamp(0.0, 1.0),
            table_friction: (model.table_friction + self.friction * gauss(rng)).max(0.0),
            ..*model
        }
    }
}

pub(super) fn gauss(rng: &mut fastrand::Rng) -> f64 {
    let u = rng.f64().max(1e-300);
    let v = rng.f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

pub(super) fn uniform(rng: &mut fastrand::Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.f64()
}

/// An incoming ball from the opponent (see the module doc), drawn with `rng`.
pub fn serve(flight: &Flight, rng: &mut fastrand::Rng, max_spin_rps: f64, corkscrew: f64) -> BallState {
    let r = flight.model.radius;
    loop {
        let p = Vector3::new(
            uniform(rng, 1.45, 1.9),
            uniform(rng, -0.5, 0.5),
            uniform(rng, 0.10, 0.35),
        );
        let land = Vector3::new(uniform(rng, -1.15, -0.35), uniform(rng, -0.55, 0.55), r);
        let tf = uniform(rng, 0.35, 0.6);
        // Spin axis: top/back spin (horizontal, across the flight) to side spin (vertical), tilted
        // toward the flight direction (corkscrew spin) by at most `corkscrew` (tan of the tilt).
        let d = Vector3::new(land.x - p.x, land.y - p.y, 0.0).normalize();
        let phi = uniform(rng, 0.0, std::f64::consts::TAU);
        let axis =
            phi.cos() * Vector3::z().cross(&d) + phi.sin() * Vector3::z() + uniform(rng, -corkscrew, corkscrew) * d;
        let w = axis.normalize() * uniform(rng, 0.0, max_spin_rps) * std::f64::consts::TAU;
        let Some(v) = shoot(flight, &p, &land, tf, |_| Some(w)) else {
            continue;
        };
        let s = BallState { t: 0.0, p, v, w };
        let (_, ev) = flight.run(&s, tf + 0.1, None);
        if ev
            .first()
            .is_some_and(|e| e.kind == EventKind::Table && e.before.p.x < 0.0)
        {
            return s;
        }
    }
}
