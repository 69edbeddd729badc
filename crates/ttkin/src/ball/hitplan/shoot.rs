//! The outgoing ball of a hit: shooting for the velocity that lands on the target, the racket that
//! produces it, and the check that the return clears the net and lands there.

use super::super::flight::{BallState, EventKind, Flight};
use super::super::impact::RacketHit;
use super::HitPlanner;
use nalgebra::{Matrix3, Vector3};
use std::cell::RefCell;

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
        // The outgoing spin follows the racket, which follows v₀: solved together. The fine
        // stage's last flight (the one at v_out) is kept for the return check.
        let path = RefCell::new(FinePath {
            steps: Vec::with_capacity((tf / f.step) as usize + 2),
            ..FinePath::default()
        });
        let v_out = shoot_coarse_first(f, &s.p, &goal, tf, |v| racket(v).map(|r| r.spin_out), Some(&path))?;
        let path = path.into_inner();
        // The racket of the last evaluation is the one at v_out (`racket` ran last for it).
        let kept = last.get().filter(|h| path.v == v_out && path.w == h.spin_out);
        let hit = match kept {
            Some(h) => h,
            None => racket(&v_out)?,
        };
        let out = BallState {
            v: v_out,
            w: hit.spin_out,
            ..*s
        };
        // The first event only (what `run` reports first, without the flight after it), along the
        // steps the shooting already integrated when they are those of this flight.
        let done: &[_] = if kept.is_some() { &path.steps } else { &[] };
        let (_, first) = f.advance_along(&out, done, s.t + tf + 0.5, None);
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
    let end = |v: &Vector3<f64>| end_point(f, f.step, p, v, tf, &spin, None) - goal;
    let (v, r, _) = broyden(
        &end,
        drag_free(f, p, goal, tf),
        Matrix3::identity() / tf,
        FINE_TOLERANCE,
    )?;
    (r.norm() < 1e-4).then_some(v)
}

/// The last fine flight of a shooting solve: its initial velocity (m/s) and spin (rad/s), and
/// the positions and velocities after each of its full steps (world), as
/// [`Flight::advance_along`] takes them.
#[derive(Debug, Default)]
struct FinePath {
    v: Vector3<f64>,
    w: Vector3<f64>,
    steps: Vec<(Vector3<f64>, Vector3<f64>)>,
}

/// [`shoot`] in two stages, the result to the same tolerance at the flight's own step: Broyden's
/// method first on the flight integrated at 4 × its step (4 times fewer RK4
/// steps, to 0.1 mm), then continued from that velocity and inverse Jacobian at the
/// flight's step (usually one or two evaluations, as the two integrations differ by far less than
/// the coarse tolerance). With `path`, the last fine flight is kept there.
fn shoot_coarse_first<S>(
    f: &Flight,
    p: &Vector3<f64>,
    goal: &Vector3<f64>,
    tf: f64,
    spin: S,
    path: Option<&RefCell<FinePath>>,
) -> Option<Vector3<f64>>
where
    S: Fn(&Vector3<f64>) -> Option<Vector3<f64>>,
{
    let coarse = |v: &Vector3<f64>| end_point(f, COARSE_FACTOR * f.step, p, v, tf, &spin, None) - goal;
    let start = drag_free(f, p, goal, tf);
    let (v0, jinv) = match broyden(&coarse, start, Matrix3::identity() / tf, COARSE_TOLERANCE) {
        Some((v, r, jinv)) if r.norm() < COARSE_TOLERANCE => (v, jinv),
        _ => (start, Matrix3::identity() / tf),
    };
    let fine = |v: &Vector3<f64>| end_point(f, f.step, p, v, tf, &spin, path) - goal;
    let (v, r, _) = broyden(&fine, v0, jinv, FINE_TOLERANCE)?;
    (r.norm() < 1e-4).then_some(v)
}

/// Landing tolerance (m) of the shooting solves.
const FINE_TOLERANCE: f64 = 1e-5;
/// Tolerance (m) of [`shoot_coarse_first`]'s coarse stage.
const COARSE_TOLERANCE: f64 = 1e-4;
/// Step of [`shoot_coarse_first`]'s coarse stage, in flight steps.
const COARSE_FACTOR: f64 = 4.0;

/// The drag-free velocity from `p` to `goal` in `tf` s.
fn drag_free(f: &Flight, p: &Vector3<f64>, goal: &Vector3<f64>, tf: f64) -> Vector3<f64> {
    let g = Vector3::new(0.0, 0.0, -f.model.gravity);
    (goal - p - 0.5 * g * tf * tf) / tf
}

/// Position after `tf` s of flight from `p` with velocity `v` and spin `spin(v)`, RK4 steps of at
/// most `step` s (the last one shortened); NaN when `spin` has no answer. With `path`, the flight
/// is kept there (its full steps only).
fn end_point<S>(
    f: &Flight,
    step: f64,
    p: &Vector3<f64>,
    v: &Vector3<f64>,
    tf: f64,
    spin: &S,
    path: Option<&RefCell<FinePath>>,
) -> Vector3<f64>
where
    S: Fn(&Vector3<f64>) -> Option<Vector3<f64>>,
{
    let Some(w) = spin(v) else {
        return Vector3::repeat(f64::NAN);
    };
    let mut s = BallState {
        t: 0.0,
        p: *p,
        v: *v,
        w,
    };
    let mut path = path.map(|c| c.borrow_mut());
    if let Some(path) = path.as_mut() {
        path.v = *v;
        path.w = w;
        path.steps.clear();
    }
    while s.t < tf - 1e-12 {
        let h = step.min(tf - s.t);
        s = f.rk4(&s, h);
        if let (Some(path), true) = (path.as_mut(), h == step) {
            path.steps.push((s.p, s.v));
        }
    }
    s.p
}

/// Broyden's method ("good" update on the inverse Jacobian `jinv`) on the residual `end` from
/// `v`, at most 20 steps, until |r| < `tol`: the last velocity, its residual and the inverse
/// Jacobian; `None` when a residual is not finite.
fn broyden<E>(
    end: &E,
    v: Vector3<f64>,
    jinv: Matrix3<f64>,
    tol: f64,
) -> Option<(Vector3<f64>, Vector3<f64>, Matrix3<f64>)>
where
    E: Fn(&Vector3<f64>) -> Vector3<f64>,
{
    let (mut v, mut jinv) = (v, jinv);
    let mut r = end(&v);
    if !r.norm().is_finite() {
        return None;
    }
    for _ in 0..20 {
        if r.norm() < tol {
            return Some((v, r, jinv));
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
    Some((v, r, jinv))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ball::flight::Flight;

    #[test]
    fn coarse_first_lands_where_the_one_stage_solve_does() {
        let f = Flight {
            step: 0.01,
            ..Flight::default()
        };
        let mut rng = fastrand::Rng::with_seed(9);
        let mut worst: f64 = 0.0;
        for _ in 0..200 {
            let p = Vector3::new(-1.6 - 0.4 * rng.f64(), 0.8 * (rng.f64() - 0.5), 0.05 + 0.3 * rng.f64());
            let goal = Vector3::new(0.4 + 0.8 * rng.f64(), 0.9 * (rng.f64() - 0.5), f.model.radius);
            let w = Vector3::new(0.0, 150.0 * (rng.f64() - 0.5), 60.0 * (rng.f64() - 0.5));
            // The spin follows v₀ as a racket's does (a smooth function of it).
            let spin = |v: &Vector3<f64>| Some(w + Vector3::new(0.0, 2.0 * v.x, 0.0));
            let tf = [0.65, 0.8, 0.95][rng.usize(0..3)];
            let one = shoot(&f, &p, &goal, tf, spin).unwrap();
            let two = shoot_coarse_first(&f, &p, &goal, tf, spin, None).unwrap();
            // Both land within the tolerance at the flight's own step.
            let miss = (end_point(&f, f.step, &p, &two, tf, &spin, None) - goal).norm();
            assert!(miss < FINE_TOLERANCE, "miss {miss}");
            worst = worst.max((one - two).norm());
        }
        // 1e-5 m on a ~1 m flight of ~0.8 s: velocities agree to a few 1e-5 m/s.
        assert!(worst < 1e-4, "velocities differ by {worst} m/s");
    }
}
