//! The outgoing ball of a hit: shooting for the velocity that lands on the target, the racket that
//! produces it, and the check that the return clears the net and lands there.

use super::super::flight::{BallState, EventKind, Flight};
use super::super::impact::RacketHit;
use super::HitPlanner;
use nalgebra::{Matrix3, Vector3};

impl HitPlanner {
    /// Outgoing velocity, racket and landing point returning the ball at `s` to `target` in a
    /// return flight of `tf` s.
    pub(super) fn outgoing(
        &self,
        s: &BallState,
        target: [f64; 2],
        tf: f64,
    ) -> Option<(Vector3<f64>, RacketHit, Vector3<f64>)> {
        let f = &self.flight;
        let goal = Vector3::new(target[0], target[1], f.model.radius);
        // Each solve starts from the previous one (the shooting iterates move v₀ a little).
        let last: std::cell::Cell<Option<RacketHit>> = std::cell::Cell::new(None);
        let racket = |v: &Vector3<f64>| {
            let guess = last.get();
            let hit = self
                .racket
                .solve_from(&f.model, &s.v, &s.w, v, guess.as_ref())
                .or_else(|_| self.racket.solve(&f.model, &s.v, &s.w, v))
                .ok();
            if hit.is_some() {
                last.set(hit);
            }
            hit
        };
        // The outgoing spin follows the racket, which follows v₀: solved together.
        let v_out = shoot(f, &s.p, &goal, tf, |v| racket(v).map(|r| r.spin_out))?;
        let hit = racket(&v_out)?;
        let out = BallState {
            v: v_out,
            w: hit.spin_out,
            ..*s
        };
        // The first event only (what `run` reports first, without the flight after it).
        let (_, first) = f.advance(&out, s.t + tf + 0.5, None);
        let e = first.as_ref()?;
        let landing = e.before.p;
        let ok = e.kind == EventKind::Table
            && f.table.on_opponent_half(landing.x, landing.y)
            && (landing - goal).xy().norm() < 1e-3;
        ok.then_some((v_out, hit, landing))
    }
}

/// Velocity v₀ (m/s) with which a ball at `p`, spinning with `spin(v₀)` (rad/s; a constant or the
/// spin a racket gives it), is at `goal` after `tf` s of free flight (no contacts): Broyden's method
/// from the drag-free solution, to 1e-5 m. `None` when `spin` has no answer or it does not converge.
pub fn shoot<S>(f: &Flight, p: &Vector3<f64>, goal: &Vector3<f64>, tf: f64, spin: S) -> Option<Vector3<f64>>
where
    S: Fn(&Vector3<f64>) -> Option<Vector3<f64>>,
{
    let g = Vector3::new(0.0, 0.0, -f.model.gravity);
    let mut v = (goal - p - 0.5 * g * tf * tf) / tf;
    let end = |v: &Vector3<f64>| {
        let Some(w) = spin(v) else {
            return Vector3::repeat(f64::NAN);
        };
        let mut s = BallState {
            t: 0.0,
            p: *p,
            v: *v,
            w,
        };
        while s.t < tf - 1e-12 {
            s = f.rk4(&s, f.step.min(tf - s.t));
        }
        s.p - goal
    };
    let mut jinv = Matrix3::identity() / tf; // inverse Jacobian (Broyden, "good" update on the inverse)
    let mut r = end(&v);
    if !r.norm().is_finite() {
        return None;
    }
    for _ in 0..20 {
        if r.norm() < 1e-5 {
            return Some(v);
        }
        let dv = -(jinv * r);
        let vn = v + dv;
        let rn = end(&vn);
        let dr = rn - r;
        let denom = dv.dot(&(jinv * dr));
        if denom.abs() > 1e-30 {
            jinv += (dv - jinv * dr) * (dv.transpose() * jinv) / denom;
        }
        v = vn;
        r = rn;
        if !r.norm().is_finite() {
            return None;
        }
    }
    (r.norm() < 1e-4).then_some(v)
}
