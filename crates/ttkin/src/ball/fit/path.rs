//! The fit's flight model: positions at the camera's frames through bounces on the table plane,
//! and the globals (k_d, k_m, e, μ, surface, period) as one vector.

use super::{Bounce, FitModel};
use crate::ball::contact::impulse;
use crate::ball::flight::{BallState, Flight};
use crate::ball::model::BallModel;
use nalgebra::Vector3;

/// Slowest rebound (m/s) a bounce of [`FitModel::path`] keeps: √(2 g · 0.1 mm); a slower one
/// leaves the ball on the plane, rolling.
pub const MIN_REBOUND_SPEED: f64 = 0.044;
impl FitModel {
    /// Positions (m) at frames `0..frames` (t = k·period) of the flight from `s0` (at t = 0),
    /// through bounces on the plane z = surface (at the centre height surface + r).
    pub fn path(&self, s0: &BallState, frames: usize, step: f64) -> Vec<Vector3<f64>> {
        self.path_with(s0, frames, step, &mut |_| {})
    }

    /// [`FitModel::path`], calling `on_bounce` with the state just before each bounce.
    pub fn path_with(
        &self,
        s0: &BallState,
        frames: usize,
        step: f64,
        on_bounce: &mut dyn FnMut(&BallState),
    ) -> Vec<Vector3<f64>> {
        let flight = Flight {
            model: self.model,
            ..Flight::default()
        };
        let zc = self.surface + self.model.radius;
        let mut cur = *s0;
        let mut out = Vec::with_capacity(frames);
        for k in 0..frames {
            let t = k as f64 * self.period;
            let mut guard = 0;
            while cur.t < t - 1e-12 && guard < 100_000 {
                guard += 1;
                let h = step.min(t - cur.t);
                let next = flight.rk4(&cur, h);
                if cur.p.z <= zc && cur.v.z == 0.0 && next.p.z < zc {
                    // Rolling on the plane (after a rebound below MIN_REBOUND_SPEED): the plane
                    // holds the ball up, no bounce to look for.
                    cur = next;
                    cur.p.z = zc;
                    cur.v.z = 0.0;
                } else if cur.p.z >= zc && next.p.z < zc {
                    // Bisection on the RK4 step from `cur` for the contact time.
                    let (mut lo, mut hi) = (0.0, h);
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if flight.rk4(&cur, mid).p.z >= zc {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    let b = flight.rk4(&cur, lo);
                    on_bounce(&b);
                    cur = self.bounce(&b);
                    if cur.v.z <= MIN_REBOUND_SPEED {
                        // No rebound (e = 0), or one below 0.1 mm: the ball stays on the plane's
                        // level. Without the floor a ball bouncing ever lower (e < 1) bounced
                        // without end in finite time, each bounce a bisection: a frame period far
                        // from the data's ran the fit for hours (issue 29).
                        cur.v.z = 0.0;
                        cur = flight.rk4(&cur, (h - lo).max(0.0));
                        if cur.p.z <= zc {
                            cur.p.z = zc;
                            cur.v.z = cur.v.z.max(0.0);
                        }
                    }
                } else {
                    cur = next;
                }
            }
            out.push(cur.p);
        }
        out
    }

    fn bounce(&self, b: &BallState) -> BallState {
        match self.bounce {
            Bounce::Impulse => {
                let m = &self.model;
                let (dv, dw) = impulse(m, &b.v, &b.w, &Vector3::z(), m.table_restitution, m.table_friction);
                BallState {
                    v: b.v + dv,
                    w: b.w + dw,
                    ..*b
                }
            }
            Bounce::Linear(c) => BallState {
                v: Vector3::new(c[0] * b.v.x, c[1] * b.v.y, -c[2] * b.v.z),
                ..*b
            },
        }
    }

    /// The globals (k_d, k_m, e, μ, surface, period), as in [`super::GLOBAL_NAMES`].
    pub(super) fn globals(&self) -> [f64; 6] {
        [
            self.model.k_drag,
            self.model.k_magnus,
            self.model.table_restitution,
            self.model.table_friction,
            self.surface,
            self.period,
        ]
    }

    /// This model with the globals `g`, clamped to their physical ranges.
    pub(super) fn with_globals(&self, g: &[f64; 6]) -> FitModel {
        FitModel {
            model: BallModel {
                k_drag: g[0].max(0.0),
                k_magnus: g[1].max(0.0),
                table_restitution: g[2].clamp(0.0, 1.0),
                table_friction: g[3].max(0.0),
                ..self.model
            },
            surface: g[4],
            period: g[5].max(1e-6),
            ..*self
        }
    }
}
