//! Racket impact: the ball's velocity and spin after it meets the racket face, and the inverse,
//! the racket normal and velocity that send the ball off with a wanted velocity.
//!
//! The same rigid-ball impulse model as the table bounce ([`super::contact::impulse`]), applied to
//! the ball's velocity relative to the racket face: normal restitution e and Coulomb friction μ with
//! the rolling cap (the rigid-ball part of Nakashima et al., "Modeling of rebound phenomenon of a
//! rigid ball with friction and elastic effects", ACC 2010).
//!
//! Rubber constants, parameters of [`RacketImpact`] (set `ReturnPlanner::impact` to change them):
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
//! s = (v_out·n + e·v_in·n)/(1 + e) starts a Newton iteration (analytic 3×3 Jacobian, `RacketImpact::jacobian`, private) on
//! the full model until the outgoing velocity matches to 1e-9 m/s.

use super::contact::impulse;
use super::flight::BallState;
use super::model::BallModel;
use crate::error::{Error, Result};
use nalgebra::{Matrix3, Vector3};

/// The racket's impact model: rubber contact parameters of the racket face (the robot side of
/// the racket is [`crate::hit::RacketMount`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacketImpact {
    /// Normal restitution ball–rubber (0.85).
    pub restitution: f64,
    /// Coulomb friction coefficient ball–rubber (0.9).
    pub friction: f64,
    /// Radius (m) of the face region counted as a hit around the racket centre (0.075 m).
    pub radius: f64,
}

impl Default for RacketImpact {
    fn default() -> Self {
        RacketImpact {
            restitution: 0.85,
            friction: 0.9,
            radius: 0.075,
        }
    }
}

/// The racket at the impact that sends the ball off as wanted (the inverse impact model's solution).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacketAtImpact {
    /// Unit face normal (world), pointing toward the outgoing ball.
    pub normal: Vector3<f64>,
    /// Racket-centre velocity (m/s, world) at the impact: speed·normal.
    pub velocity: Vector3<f64>,
    /// Ball spin after the impact (rad/s, world).
    pub spin_out: Vector3<f64>,
}

/// Deprecated name of [`RacketImpact`] (`Racket` named the impact model and the robot's racket
/// mount, `ttkin::hit::RacketMount`).
#[deprecated(note = "one name per concept: use `RacketImpact` (the mount is `ttkin::hit::RacketMount`)")]
pub type Racket = RacketImpact;

/// Deprecated name of [`RacketAtImpact`].
#[deprecated(note = "one name per concept: use `RacketAtImpact`")]
pub type RacketHit = RacketAtImpact;

impl RacketImpact {
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

    /// The ball `state` just after the impact on a face with unit normal `n` whose contact point
    /// moves at `racket_v` (m/s, world), with the checks a caller's input needs: a physical
    /// state, a unit normal (within 1e-6) and a finite velocity.
    pub fn hit_state(
        &self,
        model: &BallModel,
        state: &BallState,
        n: &Vector3<f64>,
        racket_v: &Vector3<f64>,
    ) -> Result<BallState> {
        state.validate("state")?;
        let unit = (n.norm() - 1.0).abs() < 1e-6;
        if !unit || !racket_v.iter().all(|x| x.is_finite()) {
            return Err(Error::invalid(
                "normal, velocity",
                format!(
                    "the normal must be a unit vector (norm {}) and the velocity finite",
                    n.norm()
                ),
            ));
        }
        let (v, w) = self.hit(model, &state.v, &state.w, n, racket_v);
        Ok(BallState { v, w, ..*state })
    }

    /// The racket normal and velocity (along the normal) that turn an incoming ball (`v_in`, `w_in`)
    /// into one leaving with `v_out` (m/s, rad/s, world).
    pub fn solve(
        &self,
        model: &BallModel,
        v_in: &Vector3<f64>,
        w_in: &Vector3<f64>,
        v_out: &Vector3<f64>,
    ) -> Result<RacketAtImpact> {
        self.solve_from(model, v_in, w_in, v_out, None)
    }

    /// [`RacketImpact::solve`] started from a nearby solution `guess` (e.g. that of a slightly different
    /// `v_out`) instead of the frictionless one.
    pub fn solve_from(
        &self,
        model: &BallModel,
        v_in: &Vector3<f64>,
        w_in: &Vector3<f64>,
        v_out: &Vector3<f64>,
        guess: Option<&RacketAtImpact>,
    ) -> Result<RacketAtImpact> {
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
        let (n0, s0) = match guess {
            Some(g) => (g.normal.normalize(), g.velocity.dot(&g.normal)),
            None => (n0, s0),
        };
        // Unknowns: the normal, moved in its tangent plane and renormalised (no angles, no
        // sin/cos), and the speed s.
        let f = |fr: &NormalFrame, s: f64| self.hit(model, v_in, w_in, &fr.n, &(s * fr.n)).0 - v_out;
        let mut fr = NormalFrame::at(&n0);
        let mut speed = s0;
        let mut r = f(&fr, speed);
        for _ in 0..30 {
            if r.norm() < 1e-9 {
                break;
            }
            let jac = self.jacobian(model, v_in, w_in, &fr, speed);
            let step = jac
                .lu()
                .solve(&(-r))
                .ok_or_else(|| Error::Singular("racket impact Jacobian".into()))?;
            // Damped step: halve until the residual falls.
            let mut lambda = 1.0;
            loop {
                let frn = fr.moved(lambda * step[0], lambda * step[1]);
                let sn = speed + lambda * step[2];
                let rn = f(&frn, sn);
                if rn.norm() < r.norm() || lambda < 1e-3 {
                    fr = frn;
                    speed = sn;
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
        let n = fr.n;
        let velocity = speed * n;
        let (_, spin_out) = self.hit(model, v_in, w_in, &n, &velocity);
        Ok(RacketAtImpact {
            normal: n,
            velocity,
            spin_out,
        })
    }

    /// Jacobian (m/s per rad, per rad, per m/s) of the outgoing ball velocity of [`RacketImpact::hit`]
    /// with respect to (a, b, s) of a racket moving at s·n, n = (n₀ + a·t₁ + b·t₂)/|·| in the
    /// tangent basis of `fr` (n₀ = `fr.n`), at a = b = 0 and speed `s`: the impulse model of [`super::contact::impulse`] differentiated by
    /// hand. With rel = v − s·n: N = (1+e)(s − v·n), slip u = v − (v·n)n − r·ω×n (independent
    /// of s), v' = v + N·n + j with j = −u/κ (rolling) or −μN·u/|u| (sliding).
    fn jacobian(
        &self,
        model: &BallModel,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
        fr: &NormalFrame,
        s: f64,
    ) -> Matrix3<f64> {
        let (e, mu, r) = (self.restitution, self.friction, model.radius);
        let n = &fr.n;
        let vn_ball = v.dot(n);
        if vn_ball - s >= 0.0 {
            // No impact: the outgoing velocity is v, independent of the racket.
            return Matrix3::zeros();
        }
        let big_n = (1.0 + e) * (s - vn_ball);
        let slip = v - vn_ball * n - r * w.cross(n);
        let kappa = 1.0 + model.mass * r * r / model.inertia();
        let rolling = (slip / kappa).norm() <= mu * big_n;
        let slip_norm = slip.norm();
        let u = if slip_norm > 0.0 {
            slip / slip_norm
        } else {
            Vector3::zeros()
        };
        let mut jac = Matrix3::zeros();
        for (c, d) in [fr.t1, fr.t2].iter().enumerate() {
            let dvn = v.dot(d);
            let d_big_n = -(1.0 + e) * dvn;
            let d_slip = -dvn * n - vn_ball * d - r * w.cross(d);
            let dj = if rolling {
                -d_slip / kappa
            } else {
                -mu * (d_big_n * u + big_n * (d_slip - u * u.dot(&d_slip)) / slip_norm)
            };
            jac.set_column(c, &(d_big_n * n + big_n * d + dj));
        }
        let dj_ds = if rolling { Vector3::zeros() } else { -mu * (1.0 + e) * u };
        jac.set_column(2, &((1.0 + e) * n + dj_ds));
        jac
    }
}

/// A unit normal and an orthonormal basis of its tangent plane (the derivatives of the normal in
/// the solve's two direction unknowns).
struct NormalFrame {
    /// Unit normal.
    n: Vector3<f64>,
    /// First tangent, ⟂ n.
    t1: Vector3<f64>,
    /// Second tangent, n × t₁.
    t2: Vector3<f64>,
}

impl NormalFrame {
    /// The frame at the unit normal `n`.
    fn at(n: &Vector3<f64>) -> Self {
        // Cross with the axis least aligned with n: |n × axis| ≥ √(2/3).
        let (ax, ay, az) = (n.x.abs(), n.y.abs(), n.z.abs());
        let axis = if ax <= ay && ax <= az {
            Vector3::x()
        } else if ay <= az {
            Vector3::y()
        } else {
            Vector3::z()
        };
        let t1 = n.cross(&axis).normalize();
        NormalFrame {
            n: *n,
            t1,
            t2: n.cross(&t1),
        }
    }

    /// The frame at the normal n + a·t₁ + b·t₂, renormalised.
    fn moved(&self, a: f64, b: f64) -> Self {
        NormalFrame::at(&(self.n + a * self.t1 + b * self.t2).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Incoming states and wanted outgoing velocities of rally-like returns, with spin.
    fn cases() -> Vec<(Vector3<f64>, Vector3<f64>, Vector3<f64>)> {
        let mut out = Vec::new();
        for (i, &(vx, vz, w)) in [
            (-5.0, -1.0, 0.0),
            (-7.0, 1.5, 120.0),
            (-3.0, -2.5, -200.0),
            (-9.0, 0.2, 60.0),
        ]
        .iter()
        .enumerate()
        {
            let v_in = Vector3::new(vx, 0.3 * i as f64 - 0.4, vz);
            let w_in = Vector3::new(10.0 * i as f64, w, -0.5 * w);
            let v_out = Vector3::new(4.0 + i as f64, 0.5 - 0.3 * i as f64, 1.0 + 0.5 * i as f64);
            out.push((v_in, w_in, v_out));
        }
        out
    }

    #[test]
    fn analytic_jacobian_matches_central_differences() {
        let m = BallModel::default();
        let mut checked = 0;
        let (mut rolling, mut sliding) = (0, 0);
        // The default rubber grips (the ball leaves rolling); a slippery one makes it slide.
        for racket in [
            RacketImpact::default(),
            RacketImpact {
                friction: 0.1,
                ..RacketImpact::default()
            },
        ] {
            for (v_in, w_in, v_out) in cases() {
                let sol = racket.solve(&m, &v_in, &w_in, &v_out).unwrap();
                let n = sol.normal;
                let s = sol.velocity.dot(&n);
                // At the solution and at perturbed points (other regimes of the friction law).
                for (dn, ds) in [
                    (Vector3::zeros(), 0.0),
                    (Vector3::new(0.2, -0.1, 0.15), 1.0),
                    (Vector3::new(-0.3, 0.25, -0.1), -0.8),
                ] {
                    let fr = NormalFrame::at(&(n + dn).normalize());
                    let speed = s + ds;
                    let jac = racket.jacobian(&m, &v_in, &w_in, &fr, speed);
                    let h = 1e-6;
                    let g = |x: &Vector3<f64>| {
                        let f2 = fr.moved(x[0], x[1]);
                        racket.hit(&m, &v_in, &w_in, &f2.n, &(x[2] * f2.n)).0
                    };
                    let x = Vector3::new(0.0, 0.0, speed);
                    let mut fd = Matrix3::zeros();
                    for c in 0..3 {
                        let (mut xp, mut xm) = (x, x);
                        xp[c] += h;
                        xm[c] -= h;
                        fd.set_column(c, &((g(&xp) - g(&xm)) / (2.0 * h)));
                    }
                    assert!(jac.norm() > 1.0, "a zero Jacobian checks nothing");
                    assert!(
                        (jac - fd).norm() < 1e-6 * (1.0 + fd.norm()),
                        "analytic {jac} central differences {fd}"
                    );
                    // ∂v'/∂s = (1+e)·n exactly when the ball leaves rolling.
                    if (jac.column(2) - (1.0 + racket.restitution) * fr.n).norm() < 1e-12 {
                        rolling += 1;
                    } else {
                        sliding += 1;
                    }
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 24);
        assert!(
            rolling > 0 && sliding > 0,
            "both friction regimes: {rolling} rolling, {sliding} sliding"
        );
    }

    #[test]
    fn solve_reproduces_the_outgoing_velocity_through_the_forward_model() {
        let m = BallModel::default();
        let racket = RacketImpact::default();
        for (v_in, w_in, v_out) in cases() {
            let sol = racket.solve(&m, &v_in, &w_in, &v_out).unwrap();
            assert!((sol.normal.norm() - 1.0).abs() < 1e-12);
            assert!((sol.velocity - sol.velocity.dot(&sol.normal) * sol.normal).norm() < 1e-12);
            let (v, spin) = racket.hit(&m, &v_in, &w_in, &sol.normal, &sol.velocity);
            assert!((v - v_out).norm() < 1e-9, "{v} vs {v_out}");
            assert!((spin - sol.spin_out).norm() < 1e-12);
            // A warm start from a neighbour's solution reaches the same hit.
            let near = v_out + Vector3::new(0.05, -0.02, 0.03);
            let warm = racket.solve_from(&m, &v_in, &w_in, &near, Some(&sol)).unwrap();
            let (v2, _) = racket.hit(&m, &v_in, &w_in, &warm.normal, &warm.velocity);
            assert!((v2 - near).norm() < 1e-9);
        }
    }
}
