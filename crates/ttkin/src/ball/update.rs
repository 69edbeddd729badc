//! An estimate updated with the observations delivered after it, through the bounce.
//!
//! Why. Spin about the flight direction makes no Magnus force, so the window fit of
//! [`super::estimate`](mod@super::estimate) cannot see it (its ridge prior keeps it near zero), yet the bounce turns it
//! into sideways speed (the contact point slips across the flight): the prediction after the
//! bounce is off across the table by r·ω∥/κ ≈ 0.3 m/s for ω∥ = 40 rad/s in the rolling regime.
//! The observations after the bounce show that sideways speed, and through the bounce model the
//! spin that made it.
//!
//! Method. The prior's state θ₀ = (p, v, ω) at its time t₀ and its covariance C (9 × 9,
//! [`Estimate::full_covariance`], the spin prior included) stand for the observations it was fitted
//! to. The new observations y_i at t_i > t₀ are predicted by the flight model from θ through every
//! bounce on the way, P_i(θ), and θ minimises
//! (θ − θ₀)ᵀC⁻¹(θ − θ₀) + Σ w_i·|y_i − P_i(θ)|²/σ² (σ the prior's noise scale), by Gauss–Newton with
//! the Jacobian of P by forward differences (steps of 1 % of the prior's standard deviation of each
//! parameter), recomputed every iteration (the bounce's friction makes P non-linear in the spin).
//! Weights are Huber's (3 s) with rejection beyond 6 s, s = max(σ, the median residual's σ): the
//! larger scale while the prediction is still off. It stops when a step moves θ by less than 2 %
//! of its standard deviation.
//!
//! The ball's own bounce ([`update_kick`]): a real ball's table friction, restitution and Magnus
//! constant depart from the model's (the calibration's groups of flights differ by ±45 % in k_m,
//! whose error shows as a spin error at the bounce, docs/ball.md), so the velocity leaving the
//! bounce departs from the model's prediction. With a bounce spread σ_b (m/s per axis) the
//! update's parameters gain a velocity kick Δv added at the first table bounce (prior mean 0,
//! standard deviation σ_b); the observations after the bounce decide it.

use super::estimate::{huber, robust_sigma, Estimate, EstimateError, EstimateOptions, Segment, SPIN_PRIOR};
use super::flight::{hermite, BallState, EventKind, Flight};
use nalgebra::{SMatrix, SVector, Vector3};

/// An estimate updated with later observations ([`update`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Update {
    /// Ball state at the last new observation's time (after a bounce on the way, after it).
    pub state: BallState,
    /// The updated state at the prior's time.
    pub at_prior: BallState,
    /// Covariance of [p; v; ω] (m, m/s, rad/s) at the prior's time, 9 × 9.
    pub covariance: [[f64; 9]; 9],
    /// New observations used (weight > 0).
    pub used: usize,
    /// New observations rejected as outliers (or predicted after the flight's end).
    pub outliers: usize,
    /// Whether the updated flight bounces on the table between the prior's time and `state`.
    pub bounced: bool,
    /// Gauss–Newton iterations made.
    pub iterations: usize,
}

/// Smallest step (in prior standard deviations) that ends the iterations.
const CONVERGED: f64 = 0.02;

/// Forward-difference step of each parameter, as a fraction of its prior standard deviation.
const DIFF_STEP: f64 = 0.01;

/// Positions (m, world) at `times` (s, increasing, > `s.t`) of the flight from `s` through its
/// bounces, written to `out` (`None` after a net or floor contact): RK4 steps of the flight's
/// step, cubic Hermite positions between them (from p and v at both ends, as the flight's event
/// location); whether a table bounce happened.
fn positions(
    flight: &Flight,
    s: &BallState,
    times: &[f64],
    out: &mut [Option<Vector3<f64>>],
    kick: &Vector3<f64>,
) -> bool {
    let mut cur = *s;
    let mut bounced = false;
    let mut k = 0;
    let t_end = times.last().copied().unwrap_or(s.t);
    while k < times.len() {
        let (next, ev) = flight.advance(&cur, (cur.t + flight.step).min(t_end), None);
        // The arc from `cur` to `end` is free flight: before the contact's impulse at an event.
        let end = ev.as_ref().map_or(next, |e| e.before);
        while k < times.len() && times[k] <= end.t {
            out[k] = Some(if end.t > cur.t {
                hermite(&cur, &end, times[k] - cur.t)
            } else {
                end.p
            });
            k += 1;
        }
        let mut next = next;
        if let Some(e) = ev {
            if e.kind == EventKind::Table && !bounced {
                next.v += kick;
            }
            bounced |= e.kind == EventKind::Table;
            if e.kind.terminal() {
                out[k..].fill(None);
                break;
            }
        }
        cur = next;
    }
    bounced
}

/// The flight from `s` to `t_end` (s) with `kick` (m/s) added to the velocity at its first table
/// bounce: the state at `t_end` (or at a terminal contact) and whether it bounced on the table.
fn run_kicked(flight: &Flight, s: &BallState, t_end: f64, kick: &Vector3<f64>) -> (BallState, bool) {
    let mut cur = *s;
    let mut bounced = false;
    // At most 64 events, as `Flight::run`.
    let mut events = 0;
    while cur.t < t_end && events < 64 {
        let (mut next, ev) = flight.advance(&cur, t_end, None);
        if let Some(e) = ev {
            events += 1;
            if e.kind == EventKind::Table && !bounced {
                next.v += kick;
            }
            bounced |= e.kind == EventKind::Table;
            if e.kind.terminal() {
                return (next, bounced);
            }
        }
        cur = next;
    }
    (cur, bounced)
}

/// Parameters of the update: p, v, ω (9) and the bounce's velocity kick (3).
const N: usize = 12;

fn kick_of(x: &SVector<f64, N>) -> Vector3<f64> {
    Vector3::new(x[9], x[10], x[11])
}

fn state_of(t: f64, x: &SVector<f64, N>) -> BallState {
    BallState {
        t,
        p: Vector3::new(x[0], x[1], x[2]),
        v: Vector3::new(x[3], x[4], x[5]),
        w: Vector3::new(x[6], x[7], x[8]),
    }
}

/// Updates `prior` with the observations `p` (m, world) at `t` (s) later than its state's time
/// (earlier ones and rows with a non-finite value are ignored), through the bounce (module doc).
/// Errors: `t` and `p` of different lengths, times not increasing, a prior predicted through a
/// bounce (its covariance is not at its state's time), a degenerate covariance.
pub fn update(prior: &Estimate, t: &[f64], p: &[[f64; 3]], opts: &EstimateOptions) -> Result<Update, EstimateError> {
    update_kick(prior, t, p, opts, None)
}

/// [`update`] with the ball's own bounce (module doc) when `bounce_spread` (m/s, world axes, the
/// prior standard deviation of the bounce's velocity kick along x, y, z, each > 0; e.g.
/// [`BOUNCE_SPREAD`]) is given: the update is made with the kick fixed at 0 and with it fitted,
/// and the fitted one is kept only when it lowers the fit's cost by more than the 99 % point of
/// χ² with 3 degrees of freedom (so a ball that bounces as the model says keeps the plain
/// update). Errors as [`update`], and a spread that is not positive and finite.
pub fn update_kick(
    prior: &Estimate,
    t: &[f64],
    p: &[[f64; 3]],
    opts: &EstimateOptions,
    bounce_spread: Option<[f64; 3]>,
) -> Result<Update, EstimateError> {
    let Some(sd) = bounce_spread else {
        return fit(prior, t, p, opts, None, false).map(|(u, _)| u);
    };
    if !sd.iter().all(|x| *x > 0.0 && x.is_finite()) {
        return Err(EstimateError::Option {
            what: "bounce_spread",
            message: format!("must be positive and finite, got {sd:?}"),
        });
    }
    let fixed = fit(prior, t, p, opts, None, true);
    let free = fit(prior, t, p, opts, Some(sd), true);
    match (fixed, free) {
        (Ok((a, ca)), Ok((b, cb))) => Ok(if ca - cb > KICK_GATE { b } else { a }),
        (Ok((a, _)), Err(_)) => Ok(a),
        (Err(_), Ok((b, _))) => Ok(b),
        (Err(e), Err(_)) => Err(e),
    }
}

/// The kick is kept only when it lowers the fit's cost by more than this: the 99 % point of χ²
/// with 3 degrees of freedom (a kick of zero, the model's bounce, explains the observations).
const KICK_GATE: f64 = 11.34;

/// Prior standard deviation (m/s, world x, y, z) of the bounce's velocity kick the rally's
/// correction fits ([`update_kick`]): horizontally the calibration's friction spread at a typical
/// incoming vertical speed, 0.05·(1 + e)·3 m/s ≈ 0.3 m/s; vertically 0.05 m/s, twice the
/// restitution spread's 0.008·3 m/s (docs/ball.md: chosen among 0.15–0.5 m/s on seed 0's rally).
pub const BOUNCE_SPREAD: [f64; 3] = [0.3, 0.3, 0.05];

/// The update with the kick fitted (`Some(spread)`) or fixed at 0, and, with `want_cost`, its
/// final cost (else 0): the prior term plus Σ min(|r_i|/σ, 6)² over the new observations (a
/// robust cost shared by both fits).
fn fit(
    prior: &Estimate,
    t: &[f64],
    p: &[[f64; 3]],
    opts: &EstimateOptions,
    bounce_spread: Option<[f64; 3]>,
    want_cost: bool,
) -> Result<(Update, f64), EstimateError> {
    if t.len() != p.len() {
        return Err(EstimateError::Shape {
            expected: t.len(),
            got: p.len(),
        });
    }
    if prior.segment == Segment::BeforeBounce {
        return Err(EstimateError::Option {
            what: "prior",
            message: "an estimate predicted through a bounce has no covariance at its state's time".into(),
        });
    }
    let t0 = prior.state.t;
    let mut times: Vec<f64> = Vec::with_capacity(t.len());
    let mut ys: Vec<Vector3<f64>> = Vec::with_capacity(t.len());
    for (i, (&ti, pi)) in t.iter().zip(p).enumerate() {
        if !(ti > t0) || !pi.iter().all(|x| x.is_finite()) {
            continue;
        }
        if times.last().is_some_and(|&last| !(ti > last)) {
            return Err(EstimateError::Times { index: i, value: ti });
        }
        times.push(ti);
        ys.push(Vector3::from(*pi));
    }
    let mut cov = SMatrix::<f64, 9, 9>::from_fn(|r, c| prior.full_covariance[r][c]);
    if !prior.spin_fitted {
        for k in 6..9 {
            cov[(k, k)] = SPIN_PRIOR * SPIN_PRIOR;
        }
    }
    let info9 = cov
        .cholesky()
        .ok_or_else(|| EstimateError::Degenerate("the prior's covariance is not positive definite".into()))?
        .inverse();
    // The kick's prior is independent of the state's; without a spread the kick is fixed at 0
    // (no Jacobian column, unit information, a zero step: the 9-parameter update exactly).
    let fitted = bounce_spread.is_some();
    let sd_kick = bounce_spread.unwrap_or([1.0; 3]);
    let mut info = SMatrix::<f64, N, N>::zeros();
    info.fixed_view_mut::<9, 9>(0, 0).copy_from(&info9);
    for (k, sd) in sd_kick.iter().enumerate() {
        info[(9 + k, 9 + k)] = 1.0 / (sd * sd);
    }
    let st = &prior.state;
    let x0 = SVector::<f64, N>::from_iterator(
        st.p.iter()
            .chain(st.v.iter())
            .chain(st.w.iter())
            .copied()
            .chain([0.0; 3]),
    );
    let steps: [f64; N] = std::array::from_fn(|k| {
        let sd = if k >= 9 { sd_kick[k - 9] } else { cov[(k, k)].sqrt() };
        DIFF_STEP * sd.max(1e-6)
    });
    let sigma = prior.sigma.max(opts.sigma_floor);
    let flight = &Flight {
        step: opts.step,
        ..opts.flight
    };
    let n = times.len();
    let mut x = x0;
    let mut base = vec![None; n];
    let mut shifted = vec![None; n];
    let mut jac = vec![SMatrix::<f64, 3, N>::zeros(); n];
    let mut weights = vec![0.0; n];
    let mut scratch: Vec<f64> = Vec::with_capacity(n);
    let mut normal = info;
    let mut iterations = 0;
    for iter in 0..opts.iterations.max(1) {
        iterations = iter + 1;
        positions(flight, &state_of(t0, &x), &times, &mut base, &kick_of(&x));
        // The Jacobian of the first iteration only (a chord method, as the window fit).
        for k in (0..if fitted { N } else { 9 }).filter(|_| iter == 0) {
            let mut xk = x;
            xk[k] += steps[k];
            positions(flight, &state_of(t0, &xk), &times, &mut shifted, &kick_of(&xk));
            for i in 0..n {
                if let (Some(a), Some(b)) = (base[i], shifted[i]) {
                    jac[i].set_column(k, &((b - a) / steps[k]));
                }
            }
        }
        scratch.clear();
        scratch.extend((0..n).filter_map(|i| base[i].map(|b| (ys[i] - b).norm())));
        let scale = if scratch.is_empty() {
            sigma
        } else {
            robust_sigma(&mut scratch, sigma)
        };
        normal = info;
        let mut rhs = -(info * (x - x0));
        for i in 0..n {
            weights[i] = 0.0;
            let (Some(b), true) = (base[i], shifted[i].is_some()) else {
                continue;
            };
            let r = ys[i] - b;
            let w = huber(r.norm(), scale);
            weights[i] = w;
            if w > 0.0 {
                let jw = jac[i].transpose() * (w / (sigma * sigma));
                normal += jw * jac[i];
                rhs += jw * r;
            }
        }
        let chol = normal
            .cholesky()
            .ok_or_else(|| EstimateError::Degenerate("the update's normal matrix is singular".into()))?;
        let d = chol.solve(&rhs);
        x += d;
        if d.dot(&rhs).max(0.0).sqrt() < CONVERGED {
            break;
        }
    }
    let post = normal
        .cholesky()
        .ok_or_else(|| EstimateError::Degenerate("the update's normal matrix is singular".into()))?
        .inverse();
    let at_prior = state_of(t0, &x);
    if at_prior.validate("state").is_err() {
        return Err(EstimateError::Degenerate("non-finite state".into()));
    }
    let t_last = times.last().copied().unwrap_or(t0);
    let (state, bounced) = if fitted {
        run_kicked(flight, &at_prior, t_last, &kick_of(&x))
    } else {
        let (state, events) = flight.run(&at_prior, t_last, None);
        (state, events.iter().any(|e| e.kind == EventKind::Table))
    };
    let used = weights.iter().filter(|w| **w > 0.0).count();
    let mut cost = 0.0;
    if want_cost {
        positions(flight, &at_prior, &times, &mut base, &kick_of(&x));
        let dx = x - x0;
        cost = dx.dot(&(info * dx));
        for i in 0..n {
            if let Some(b) = base[i] {
                cost += ((ys[i] - b).norm() / sigma).min(6.0).powi(2);
            }
        }
    }
    Ok((
        Update {
            state,
            at_prior,
            covariance: std::array::from_fn(|r| std::array::from_fn(|c| post[(r, c)])),
            used,
            outliers: n - used,
            bounced,
            iterations,
        },
        cost,
    ))
}
