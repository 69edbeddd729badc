//! The outgoing ball of a hit: shooting for the velocity that lands on the target, the racket that
//! produces it, and the check that the return clears the net and lands there.

use super::super::flight::{BallState, EventKind, Flight};
use super::super::impact::RacketAtImpact;
use super::ReturnPlanner;
use nalgebra::{Matrix3, Vector3};
use std::cell::Cell;

impl ReturnPlanner {
    /// Outgoing velocity, racket and landing point returning the ball at `s` to `target` in a
    /// return flight of `tf` s.
    pub(super) fn outgoing(
        &self,
        s: &BallState,
        target: [f64; 2],
        tf: f64,
    ) -> Option<(Vector3<f64>, RacketAtImpact, Vector3<f64>)> {
        let f = &self.flight;
        let goal = Vector3::new(target[0], target[1], f.model.radius);
        // Each solve starts from the previous one (the shooting iterates move v₀ a little); the
        // last solved racket is kept with its v₀.
        let last: Cell<Option<(Vector3<f64>, RacketAtImpact)>> = Cell::new(None);
        let racket = |v: &Vector3<f64>| {
            let guess = last.get().map(|(_, h)| h);
            let hit = self
                .impact
                .solve_from(&f.model, &s.v, &s.w, v, guess.as_ref())
                .or_else(|_| self.impact.solve(&f.model, &s.v, &s.w, v))
                .ok();
            if let Some(h) = hit {
                last.set(Some((*v, h)));
            }
            hit
        };
        // The outgoing spin follows the racket, which follows v₀: solved together.
        let v_out = shoot_coarse(f, &s.p, &goal, tf, |v| racket(v).map(|r| r.spin_out))?;
        // The shooting's last evaluation was at v_out (Broyden returns the point it evaluated last).
        let hit = match last.get() {
            Some((v, h)) if v == v_out => h,
            _ => racket(&v_out)?,
        };
        let out = BallState {
            v: v_out,
            w: hit.spin_out,
            ..*s
        };
        // The first event only (what `run` reports first, without the flight after it), on the
        // shooting's own integration (RK4 at `COARSE_FACTOR` × the flight's step, within 1.3e-5 m
        // of the flight's) with the guards sampled `COARSE_FACTOR` times per step on its cubic
        // Hermite interpolant: the guard spacing of the flight's own step.
        let check = Flight {
            step: COARSE_FACTOR * f.step,
            ..*f
        };
        let (_, first) = check.advance_sampled(&out, s.t + tf + 0.5, None, COARSE_FACTOR as usize);
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
    let end = |v: &Vector3<f64>| end_point(f, f.step, p, v, tf, &spin) - goal;
    let start = drag_free(f, p, goal, tf);
    let (v, r, _) = broyden(&end, start, end(&start), Matrix3::identity() / tf, FINE_TOLERANCE)?;
    (r.norm() < 1e-4).then_some(v)
}

/// [`shoot`] on the flight integrated at `COARSE_FACTOR` × its step (that many times fewer RK4
/// steps), to the same tolerance, from the inverse of [`initial_jacobian`] instead of T⁻¹·I (5.2
/// instead of 6.4 flights per solve on 300 random shots). On the hit planner's shots the coarse
/// and the flight's own integration of the same v₀ end at most 1.3e-5 m apart at 80 ms against 10
/// ms (7e-7 m at 40 ms; 300 random shots, spins to 150 rad/s, flights of 0.55–1.05 s; tested
/// below), far inside the 1 mm landing check of [`ReturnPlanner::outgoing`] (the same integration,
/// its guards sampled at the flight's own step).
fn shoot_coarse<S>(f: &Flight, p: &Vector3<f64>, goal: &Vector3<f64>, tf: f64, spin: S) -> Option<Vector3<f64>>
where
    S: Fn(&Vector3<f64>) -> Option<Vector3<f64>>,
{
    let step = COARSE_FACTOR * f.step;
    let coarse = |v: &Vector3<f64>| end_point(f, step, p, v, tf, &spin) - goal;
    let start = drag_free(f, p, goal, tf);
    let w = spin(&start)?;
    let jinv = initial_jacobian(f, &start, &w, tf)
        .try_inverse()
        .unwrap_or_else(|| Matrix3::identity() / tf);
    let r = fly(f, step, p, &start, &w, tf) - goal;
    let (v, r, _) = broyden(&coarse, start, r, jinv, FINE_TOLERANCE)?;
    (r.norm() < 1e-4).then_some(v)
}

/// An estimate of ∂p(T)/∂v₀ for a flight of `tf` s from velocity `v` (m/s) with spin `w` (rad/s):
/// T·I + (T²/3)·∂a/∂v, the acceleration's Jacobian (drag −k_d·(|v|·I + v·vᵀ/|v|), Magnus
/// k_m·[ω]×) taken at v₀. The drag-free flight's T·I with the first-order term of the linearised
/// flight, whose T²/2 is shrunk to T²/3 because the speed, and with it the drag's Jacobian, falls
/// along the flight (T²/2: 6.3 flights per solve, T²/3: 5.2, T²/4: 5.2, on the shots of
/// `shoot_coarse`'s doc). Only Broyden's start: the root it converges to is the same.
fn initial_jacobian(f: &Flight, v: &Vector3<f64>, w: &Vector3<f64>, tf: f64) -> Matrix3<f64> {
    let m = &f.model;
    let speed = v.norm();
    let drag = if speed > 0.0 {
        -m.k_drag * (speed * Matrix3::identity() + v * v.transpose() / speed)
    } else {
        Matrix3::zeros()
    };
    let dadv = drag + m.k_magnus * w.cross_matrix();
    tf * Matrix3::identity() + (tf * tf / 3.0) * dadv
}

/// Landing tolerance (m) of the shooting solves.
const FINE_TOLERANCE: f64 = 1e-5;
/// Step of [`shoot_coarse`], in flight steps.
const COARSE_FACTOR: f64 = 8.0;

/// The drag-free velocity from `p` to `goal` in `tf` s.
fn drag_free(f: &Flight, p: &Vector3<f64>, goal: &Vector3<f64>, tf: f64) -> Vector3<f64> {
    let g = Vector3::new(0.0, 0.0, -f.model.gravity);
    (goal - p - 0.5 * g * tf * tf) / tf
}

/// Position after `tf` s of flight from `p` with velocity `v` and spin `spin(v)`, RK4 steps of at
/// most `step` s (the last one shortened); NaN when `spin` has no answer.
fn end_point<S>(f: &Flight, step: f64, p: &Vector3<f64>, v: &Vector3<f64>, tf: f64, spin: &S) -> Vector3<f64>
where
    S: Fn(&Vector3<f64>) -> Option<Vector3<f64>>,
{
    match spin(v) {
        Some(w) => fly(f, step, p, v, &w, tf),
        None => Vector3::repeat(f64::NAN),
    }
}

/// Position after `tf` s of flight from `p` with velocity `v` and spin `w`, RK4 steps of at most
/// `step` s (the last one shortened).
fn fly(f: &Flight, step: f64, p: &Vector3<f64>, v: &Vector3<f64>, w: &Vector3<f64>, tf: f64) -> Vector3<f64> {
    let mut s = BallState {
        t: 0.0,
        p: *p,
        v: *v,
        w: *w,
    };
    while s.t < tf - 1e-12 {
        let h = step.min(tf - s.t);
        s = f.rk4(&s, h);
    }
    s.p
}

/// Broyden's method ("good" update on the inverse Jacobian `jinv`) on the residual `end` from
/// `v` (its residual `r` = `end(v)` given), at most 20 steps, until |r| < `tol`: the last velocity, its residual and the inverse
/// Jacobian; `None` when a residual is not finite.
fn broyden<E>(
    end: &E,
    v: Vector3<f64>,
    r: Vector3<f64>,
    jinv: Matrix3<f64>,
    tol: f64,
) -> Option<(Vector3<f64>, Vector3<f64>, Matrix3<f64>)>
where
    E: Fn(&Vector3<f64>) -> Vector3<f64>,
{
    let (mut v, mut r, mut jinv) = (v, r, jinv);
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
    fn coarse_solve_lands_where_the_one_stage_solve_does() {
        let f = Flight {
            step: 0.01,
            ..Flight::default()
        };
        let mut rng = fastrand::Rng::with_seed(9);
        let (mut worst, mut worst_miss): (f64, f64) = (0.0, 0.0);
        for _ in 0..200 {
            let p = Vector3::new(-1.6 - 0.4 * rng.f64(), 0.8 * (rng.f64() - 0.5), 0.05 + 0.3 * rng.f64());
            let goal = Vector3::new(0.4 + 0.8 * rng.f64(), 0.9 * (rng.f64() - 0.5), f.model.radius);
            let w = Vector3::new(0.0, 150.0 * (rng.f64() - 0.5), 60.0 * (rng.f64() - 0.5));
            // The spin follows v₀ as a racket's does (a smooth function of it).
            let spin = |v: &Vector3<f64>| Some(w + Vector3::new(0.0, 2.0 * v.x, 0.0));
            let tf = [0.65, 0.8, 0.95][rng.usize(0..3)];
            let one = shoot(&f, &p, &goal, tf, spin).unwrap();
            let two = shoot_coarse(&f, &p, &goal, tf, spin).unwrap();
            // The coarse solve lands within its tolerance plus the two integrations' difference
            // (≤ 1.3e-5 m on such shots) at the flight's own step.
            let miss = (end_point(&f, f.step, &p, &two, tf, &spin) - goal).norm();
            assert!(miss < FINE_TOLERANCE + 2e-5, "miss {miss}");
            worst_miss = worst_miss.max(miss);
            worst = worst.max((one - two).norm());
        }
        // 1e-5 m on a ~1 m flight of ~0.8 s: velocities agree to a few 1e-5 m/s.
        assert!(worst < 1e-4, "velocities differ by {worst} m/s");
        // The coarse step is coarse: a solve at the flight's step would land within 1e-5 m.
        assert!(
            worst_miss > FINE_TOLERANCE / 10.0,
            "coarse misses by at most {worst_miss} m"
        );
    }

    #[test]
    fn the_linearised_start_saves_flights_and_finds_the_same_root() {
        let f = Flight {
            step: 0.01,
            ..Flight::default()
        };
        let mut rng = fastrand::Rng::with_seed(11);
        let (mut plain, mut linear) = (0, 0);
        for _ in 0..100 {
            let p = Vector3::new(-1.6 - 0.4 * rng.f64(), 0.8 * (rng.f64() - 0.5), 0.05 + 0.3 * rng.f64());
            let goal = Vector3::new(0.4 + 0.8 * rng.f64(), 0.9 * (rng.f64() - 0.5), f.model.radius);
            let w = Vector3::new(0.0, 300.0 * (rng.f64() - 0.5), 100.0 * (rng.f64() - 0.5));
            let tf = [0.55, 0.8, 1.05][rng.usize(0..3)];
            let step = COARSE_FACTOR * f.step;
            let end = |v: &Vector3<f64>| fly(&f, step, &p, v, &w, tf) - goal;
            let start = drag_free(&f, &p, &goal, tf);
            let mut roots = Vec::new();
            for (jinv, count) in [
                (Matrix3::identity() / tf, &mut plain),
                (initial_jacobian(&f, &start, &w, tf).try_inverse().unwrap(), &mut linear),
            ] {
                let calls = std::cell::Cell::new(0);
                let counted = |v: &Vector3<f64>| {
                    calls.set(calls.get() + 1);
                    end(v)
                };
                let (v, r, _) = broyden(&counted, start, end(&start), jinv, FINE_TOLERANCE).unwrap();
                assert!(r.norm() < FINE_TOLERANCE);
                *count += calls.get();
                roots.push(v);
            }
            assert!((roots[0] - roots[1]).norm() < 1e-4, "{roots:?}");
        }
        assert!(linear * 10 < plain * 9, "{linear} flights against {plain} from T⁻¹·I");
    }
}
