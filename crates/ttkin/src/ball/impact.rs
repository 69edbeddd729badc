//! Racket impact: the ball's velocity and spin after it meets the racket face, and the inverse,
//! the racket normal and velocity that send the ball off with a wanted velocity.
//!
//! The same rigid-ball impulse model as the table bounce ([`super::contact::impulse`]), applied to
//! the ball's velocity relative to the racket face: normal restitution e and Coulomb friction μ with
//! the rolling cap (the rigid-ball part of Nakashima et al., "Modeling of rebound phenomenon of a
//! rigid ball with friction and elastic effects", ACC 2010).
//!
//! Rubber constants, parameters of [`Racket`] (set `HitPlanner::racket` to change them):
//! - **restitution e = 0.85**. Reference points: the ITTF ball rule (Technical Leaflet T3: dropped
//!   from 305 mm on a steel block it bounces 240–260 mm, e = √(h₁/h₀) = 0.89–0.92) and the table
//!   (ITTF Laws 2.1.3: about 23 cm from 30 cm, e ≈ 0.88) bound it from above, since rubber on a
//!   wooden blade dissipates more than steel; measured rubber restitution falls with the impact
//!   speed (JSME Symposium on Sports Engineering 2017, rubber sheets at 20–70 km/h; Rinaldi et al.,
//!   "Table tennis ball impacting racket polymeric coatings", Appl. Sci. 9(1):158, 2019,
//!   doi:10.3390/app9010158). 0.85 is our choice for the 5–10 m/s of these strokes, not a value
//!   read from those papers.
//! - **friction μ = 0.9**: inverted (pimples-in) rubber grips: the tangential impulse then almost
//!   always reaches the rolling cap, so the result depends little on μ above ≈ 0.5 (Rinaldi et al.
//!   2019 identify the friction coefficient of the outer layer as the key parameter of oblique
//!   impacts). A choice of the order of tacky rubber, to be identified on a real racket.
//! - Table, for comparison ([`super::model::BallModel`]): e = 0.93, μ = 0.25 (Nakashima et al. 2010).
//!
//! Inverse: the racket moves along its normal at the hit (velocity s·n, no brushing). Unknowns are
//! the normal (two angles) and s; the frictionless solution n ∥ v_out − v_in,
//! s = (v_out·n + e·v_in·n)/(1 + e) starts a Newton iteration (finite-difference Jacobian, 3×3) on
//! the full model until the outgoing velocity matches to 1e-9 m/s.

use super::contact::impulse;
use super::model::BallModel;
use crate::error::{Error, Result};
use nalgebra::{Matrix3, Vector3};

/// Rubber contact parameters of the racket face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Racket {
    /// Normal restitution ball–rubber (0.85).
    pub restitution: f64,
    /// Coulomb friction coefficient ball–rubber (0.9).
    pub friction: f64,
    /// Radius (m) of the face region counted as a hit around the racket centre (0.075 m).
    pub radius: f64,
}

impl Default for Racket {
    fn default() -> Self {
        Racket {
            restitution: 0.85,
            friction: 0.9,
            radius: 0.075,
        }
    }
}

/// A racket state at the impact that sends the ball off as wanted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacketHit {
    /// Unit face normal (world), pointing toward the outgoing ball.
    pub normal: Vector3<f64>,
    /// Racket-centre velocity (m/s, world) at the impact: speed·normal.
    pub velocity: Vector3<f64>,
    /// Ball spin after the impact (rad/s, world).
    pub spin_out: Vector3<f64>,
}

impl Racket {
    /// Ball velocity and spin (m/s, rad/s, world) after the impact of a ball with velocity `v`
    /// and spin `w` on a face with unit normal `n` whose contact point moves at `racket_v`.
    pub fn hit(
        &self,
        model: &BallModel,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
        n: &Vector3<f64>,
        racket_v: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let rel = v - racket_v;
        let (dv, dw) = impulse(model, &rel, w, n, self.restitution, self.friction);
        (v + dv, w + dw)
    }

    /// The racket normal and velocity (along the normal) that turn an incoming ball (`v_in`, `w_in`)
    /// into one leaving with `v_out` (m/s, rad/s, world).
    pub fn solve(
        &self,
        model: &BallModel,
        v_in: &Vector3<f64>,
        w_in: &Vector3<f64>,
        v_out: &Vector3<f64>,
    ) -> Result<RacketHit> {
        self.solve_from(model, v_in, w_in, v_out, None)
    }

    /// [`Racket::solve`] started from a nearby solution `guess` (e.g. that of a slightly different
    /// `v_out`) instead of the frictionless one.
    pub fn solve_from(
        &self,
        model: &BallModel,
        v_in: &Vector3<f64>,
        w_in: &Vector3<f64>,
        v_out: &Vector3<f64>,
        guess: Option<&RacketHit>,
    ) -> Result<RacketHit> {
        let e = self.restitution;
        let dv = v_out - v_in;
        if !(dv.norm() > 1e-6) {
            return Err(Error::invalid(
                "v_out",
                "equals the incoming velocity: no impact needed",
            ));
        }
        let n0 = dv.normalize();
        let s0 = (v_out.dot(&n0) + e * v_in.dot(&n0)) / (1.0 + e);
        // Parameters: azimuth, elevation of n, speed s.
        let to_n = |x: &Vector3<f64>| Vector3::new(x[1].cos() * x[0].cos(), x[1].cos() * x[0].sin(), x[1].sin());
        let (n0, s0) = match guess {
            Some(g) => (g.normal, g.velocity.dot(&g.normal)),
            None => (n0, s0),
        };
        let mut x = Vector3::new(n0.y.atan2(n0.x), n0.z.clamp(-1.0, 1.0).asin(), s0);
        let f = |x: &Vector3<f64>| {
            let n = to_n(x);
            self.hit(model, v_in, w_in, &n, &(x[2] * n)).0 - v_out
        };
        let mut r = f(&x);
        for _ in 0..30 {
            if r.norm() < 1e-9 {
                break;
            }
            let mut jac = Matrix3::zeros();
            for c in 0..3 {
                let mut xp = x;
                xp[c] += 1e-7;
                jac.set_column(c, &((f(&xp) - r) / 1e-7));
            }
            let step = jac
                .lu()
                .solve(&(-r))
                .ok_or_else(|| Error::Singular("racket impact Jacobian".into()))?;
            // Damped step: halve until the residual falls.
            let mut lambda = 1.0;
            loop {
                let xn = x + lambda * step;
                let rn = f(&xn);
                if rn.norm() < r.norm() || lambda < 1e-3 {
                    x = xn;
                    r = rn;
                    break;
                }
                lambda *= 0.5;
            }
        }
        if !(r.norm() < 1e-6) {
            return Err(Error::Unreachable(format!(
                "no racket normal and speed give the outgoing velocity (residual {:.2e} m/s)",
                r.norm()
            )));
        }
        let n = to_n(&x);
        let velocity = x[2] * n;
        let (_, spin_out) = self.hit(model, v_in, w_in, &n, &velocity);
        Ok(RacketHit {
            normal: n,
            velocity,
            spin_out,
        })
    }
}
