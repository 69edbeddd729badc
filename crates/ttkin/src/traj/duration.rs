//! Shortest durations of polynomial segments under kinematic limits: rest-to-rest in closed form
//! ([`minimal_duration_rest`]), and the earliest feasible quintic between arbitrary states
//! ([`earliest_quintic_duration`], [`minimal_quintic_duration`]) by root bracketing on the
//! duration, each step weighing the quintic's exact peaks against the limits
//! ([`quintic_limit_ratio`], with the cheaper bound-first [`quintic_limit_ratio_above`]).

use super::limits::KinematicLimits;
use super::{poly, JointState};
use crate::error::{check_vector, Error, Result};

/// Polynomial family of a single segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SegmentKind {
    /// Cubic (boundary positions and velocities).
    Cubic,
    /// Quintic (boundary positions, velocities and accelerations).
    Quintic,
}

impl std::str::FromStr for SegmentKind {
    type Err = Error;

    /// Parses `"cubic"` or `"quintic"`.
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "cubic" => Ok(SegmentKind::Cubic),
            "quintic" => Ok(SegmentKind::Quintic),
            other => Err(Error::invalid(
                "kind",
                format!("expected cubic or quintic, got '{other}'"),
            )),
        }
    }
}

/// Minimal duration (s) of a rest-to-rest segment from `q0` to `q1` under velocity, acceleration
/// and jerk limits, in closed form. Per joint with h = |q1 − q0|, the peaks are
/// cubic: 3h/(2T), 6h/T², 12h/T³; quintic: 15h/(8T), 10h/(√3·T²), 60h/T³; the duration is the
/// largest T that puts one of them exactly at its limit. Zero when q0 = q1.
pub fn minimal_duration_rest(q0: &[f64], q1: &[f64], limits: &KinematicLimits, kind: SegmentKind) -> Result<f64> {
    let n = q0.len();
    limits.check_dof(n)?;
    check_vector("q0", q0, n)?;
    check_vector("q1", q1, n)?;
    let mut t: f64 = 0.0;
    for j in 0..n {
        let h = (q1[j] - q0[j]).abs();
        let (v, a, jk) = (limits.velocity[j], limits.acceleration[j], limits.jerk[j]);
        t = t.max(match kind {
            SegmentKind::Cubic => (1.5 * h / v).max((6.0 * h / a).sqrt()).max((12.0 * h / jk).cbrt()),
            SegmentKind::Quintic => quintic_rest_bound(h, v, a, jk),
        });
    }
    Ok(t)
}

/// The shortest rest-to-rest quintic over a distance `h` (m or rad) under the speed, acceleration
/// and jerk limits `v`, `a`, `j` (s): the largest of 15h/(8v), √(10h/(√3·a)), ∛(60h/j), the
/// durations that put each exact peak at its limit. The one home of this bound.
pub fn quintic_rest_bound(h: f64, v: f64, a: f64, j: f64) -> f64 {
    (15.0 * h / (8.0 * v))
        .max((10.0 * h / (3f64.sqrt() * a)).sqrt())
        .max((60.0 * h / j).cbrt())
}

/// A duration (s) from which a search for a feasible quintic from `from` to `to` starts: per joint
/// the rest-to-rest bound [`quintic_rest_bound`] and the times to change the velocity at full
/// acceleration and the acceleration at full jerk (at least 1 ms). Not a lower bound of the
/// minimal quintic (the rest-to-rest bound ignores the end velocities).
pub fn quintic_start_duration(from: &JointState, to: &JointState, lim: &KinematicLimits) -> f64 {
    let mut t: f64 = 1e-3;
    for j in 0..from.q.len() {
        let h = (to.q[j] - from.q[j]).abs();
        t = t
            .max(quintic_rest_bound(h, lim.velocity[j], lim.acceleration[j], lim.jerk[j]))
            .max((to.qd[j] - from.qd[j]).abs() / lim.acceleration[j])
            .max((to.qdd[j] - from.qdd[j]).abs() / lim.jerk[j]);
    }
    t
}

/// Longest duration (s) [`earliest_quintic_duration`] tries before giving up.
pub const MAX_DURATION: f64 = 1e4;

/// Factor by which [`earliest_quintic_duration`] grows an infeasible duration while bracketing.
pub const GROWTH: f64 = 1.5;

/// Factor between consecutive durations of the fine scan that [`earliest_quintic_duration`] runs
/// when the coarse bracketing finds no feasible duration (about 12,000 evaluations at most).
pub const FINE_GROWTH: f64 = 1.001;

/// First feasible duration of a log-spaced scan from `from` (infeasible: g(from) > 0) up to
/// [`MAX_DURATION`]: returns (g(a), a, b, g(b)) with g(a) > 0 ≥ g(b) and b = a·[`FINE_GROWTH`].
fn fine_scan(g: &impl Fn(f64) -> f64, from: f64) -> Option<(f64, f64, f64, f64)> {
    let (mut a, mut fa) = (from, g(from));
    while a < MAX_DURATION {
        let b = a * FINE_GROWTH;
        let fb = g(b);
        if fb <= 0.0 {
            return Some((fa, a, b, fb));
        }
        (a, fa) = (b, fb);
    }
    None
}

/// Velocity, acceleration and jerk polynomials of joint `j`'s quintic from `start` to `end` in
/// `duration` s, each with its limit, finite limits only.
fn limited_derivatives(
    start: &JointState,
    end: &JointState,
    j: usize,
    duration: f64,
    limits: &KinematicLimits,
) -> impl Iterator<Item = (poly::Coeffs, f64)> {
    let mut d = start.quintic_to(end, j, duration);
    [limits.velocity[j], limits.acceleration[j], limits.jerk[j]]
        .into_iter()
        .filter_map(move |bound| {
            d = poly::derivative(&d);
            bound.is_finite().then_some((d, bound))
        })
}

/// Largest ratio peak/limit of velocity, acceleration and jerk over the joints of the quintic from
/// `start` to `end` in `duration` s (exact peaks); the quintic respects the limits iff it is ≤ 1.
pub fn quintic_limit_ratio(start: &JointState, end: &JointState, duration: f64, limits: &KinematicLimits) -> f64 {
    let mut worst: f64 = 0.0;
    for j in 0..start.q.len() {
        for (d, bound) in limited_derivatives(start, end, j, duration, limits) {
            worst = worst.max(poly::max_abs(&d, duration).1.abs() / bound);
        }
    }
    worst
}

/// [`quintic_limit_ratio`] when it exceeds `floor` (≥ 0), exactly the same number; otherwise some
/// value ≤ `floor`. Cheaper: each peak is first bounded ([`poly::bound_abs`]) and computed exactly
/// only when its bound exceeds both `floor` and the largest exact ratio found so far (largest
/// bounds first).
pub fn quintic_limit_ratio_above(
    start: &JointState,
    end: &JointState,
    duration: f64,
    limits: &KinematicLimits,
    floor: f64,
) -> f64 {
    if start.q.len() > MAX_QUICK_DOF {
        let r = quintic_limit_ratio(start, end, duration, limits);
        return if r > floor { r } else { 0.0 };
    }
    bounded_limit_ratio(start, end, duration, limits, floor, f64::INFINITY)
}

/// [`quintic_limit_ratio`] when it is below `ceiling`, exactly the same number; otherwise some
/// value ≥ `ceiling` (a peak found so far). Cheaper when most trials fail: peaks are computed
/// exactly in the order of their bounds ([`poly::bound_abs`], largest first), skipping those whose
/// bound is below the largest exact ratio found, and the search stops at the first ≥ `ceiling`.
pub fn quintic_limit_ratio_below(
    start: &JointState,
    end: &JointState,
    duration: f64,
    limits: &KinematicLimits,
    ceiling: f64,
) -> f64 {
    if start.q.len() > MAX_QUICK_DOF {
        return quintic_limit_ratio(start, end, duration, limits);
    }
    bounded_limit_ratio(start, end, duration, limits, f64::NEG_INFINITY, ceiling)
}

/// The search of [`quintic_limit_ratio_above`] and [`quintic_limit_ratio_below`] (at most
/// `MAX_QUICK_DOF` joints): the peaks whose bound exceeds `floor`, computed exactly largest bound
/// first while the bound exceeds the largest exact ratio found, stopping at the first ≥ `ceiling`.
fn bounded_limit_ratio(
    start: &JointState,
    end: &JointState,
    duration: f64,
    limits: &KinematicLimits,
    floor: f64,
    ceiling: f64,
) -> f64 {
    // (bound of the ratio, derivative polynomial, limit) of every finite limit above `floor`.
    let mut items = [(0.0, [0.0; 6], 1.0); 3 * MAX_QUICK_DOF];
    let mut count = 0;
    for j in 0..start.q.len() {
        for (d, bound) in limited_derivatives(start, end, j, duration, limits) {
            let ub = poly::bound_abs(&d, duration) / bound;
            if ub > floor {
                items[count] = (ub, d, bound);
                count += 1;
            }
        }
    }
    // Largest bound first, picked one at a time (the search usually stops after a few peaks, so
    // no full sort); a picked item's bound is set to −∞.
    let items = &mut items[..count];
    let mut worst: f64 = 0.0;
    while let Some((k, ub)) = items
        .iter()
        .enumerate()
        .map(|(k, it)| (k, it.0))
        .reduce(|a, b| if b.1 > a.1 { b } else { a })
    {
        if ub <= worst {
            break;
        }
        let (_, d, bound) = items[k];
        items[k].0 = f64::NEG_INFINITY;
        worst = worst.max(poly::max_abs(&d, duration).1.abs() / bound);
        if worst >= ceiling {
            break;
        }
    }
    worst
}

/// Most joints [`quintic_limit_ratio_above`] handles on the stack.
const MAX_QUICK_DOF: usize = 8;

/// Earliest duration T ≥ `not_before` (s) for which the quintic from `start` to `end` respects the
/// velocity, acceleration and jerk limits.
///
/// Method: root bracketing on T, each step evaluating the quintic's exact extrema
/// ([`quintic_limit_ratio`], roots of the derivative polynomials). If `not_before` is infeasible,
/// T grows by factors of [`GROWTH`] until a feasible duration is found (at most [`MAX_DURATION`]; beyond it, an error gives the closest
/// peak/limit ratio seen); the crossing of
/// the ratio through 1 between the last infeasible and the first feasible duration is then located
/// by the Illinois variant of regula falsi (a bisection step when three steps shrink the bracket
/// by less than 4) to a relative width of
/// 1e-13, returning the feasible end. A feasible window narrower than one growth step would be
/// missed (feasibility in T is not monotone in general when boundary velocities are nonzero).
pub fn earliest_quintic_duration(
    start: &JointState,
    end: &JointState,
    limits: &KinematicLimits,
    not_before: f64,
) -> Result<f64> {
    let n = start.check_pair("start", end, "end")?;
    limits.check_dof(n)?;
    super::check_duration("not_before", not_before)?;
    for (what, s) in [("start", start), ("end", end)] {
        for j in 0..n {
            if s.qd[j].abs() > limits.velocity[j] || s.qdd[j].abs() > limits.acceleration[j] {
                return Err(Error::invalid(
                    what,
                    format!(
                        "joint {j}: boundary velocity {} or acceleration {} exceeds the limits {} / {}; no duration \
                         can help",
                        s.qd[j], s.qdd[j], limits.velocity[j], limits.acceleration[j]
                    ),
                ));
            }
        }
    }
    let g = |t: f64| quintic_limit_ratio(start, end, t, limits) - 1.0;
    let mut fb = g(not_before);
    if fb <= 0.0 {
        return Ok(not_before);
    }
    // Nothing shorter than the necessary bound can be feasible: start bracketing there.
    let from = not_before.max(necessary_duration(start, end, limits));
    let (mut a, mut fa, mut b) = (not_before, fb, from * GROWTH);
    if from > not_before {
        let f = g(from);
        if f <= 0.0 {
            return Ok(from);
        }
        (a, fa) = (from, f);
    }
    let mut best = (a, fa);
    loop {
        fb = g(b);
        if fb <= 0.0 {
            break;
        }
        if fb < best.1 {
            best = (b, fb);
        }
        (a, fa) = (b, fb);
        b *= GROWTH;
        if b > MAX_DURATION {
            // The feasible durations need not form one interval: a window narrower than the coarse
            // growth factor can lie between two infeasible samples. Scan finely before giving up.
            if let Some((fa2, fine_a, fine_b, fine_fb)) = fine_scan(&g, from) {
                (a, fa, b, fb) = (fine_a, fa2, fine_b, fine_fb);
                break;
            }
            return Err(Error::invalid(
                "limits",
                format!(
                    "no quintic of up to {MAX_DURATION} s respects the velocity, acceleration and jerk limits \
                     (closest: peak/limit = {:.4} at {:.4} s); the boundary states ask for more than one \
                     quintic can give",
                    best.1 + 1.0,
                    best.0
                ),
            ));
        }
    }
    // Invariant: g(a) > 0 ≥ g(b).
    let (mut side, mut checkpoint) = (0i8, b - a);
    for iteration in 1..=300 {
        if b - a <= 1e-13 * b {
            break;
        }
        let mut x = (a * fb - b * fa) / (fb - fa);
        if !(x > a && x < b) {
            x = 0.5 * (a + b);
        }
        let fx = g(x);
        if fx <= 0.0 {
            (b, fb) = (x, fx);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            (a, fa) = (x, fx);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
        if iteration % 3 == 0 && b - a > 0.25 * std::mem::replace(&mut checkpoint, b - a) {
            // Three steps shrank the bracket by less than 4: one bisection step.
            let m = 0.5 * (a + b);
            let fm = g(m);
            if fm <= 0.0 {
                (b, fb) = (m, fm);
            } else {
                (a, fa) = (m, fm);
            }
            side = 0;
        }
    }
    Ok(b)
}

/// A duration below which no motion from `start` to `end` can respect the limits (s):
/// max_j(|Δq_j|/v_max, |Δv_j|/a_max), since the mean velocity and the mean acceleration are bounded
/// by the limits.
fn necessary_duration(start: &JointState, end: &JointState, limits: &KinematicLimits) -> f64 {
    let mut lower: f64 = 0.0;
    for j in 0..start.q.len() {
        lower = lower
            .max((end.q[j] - start.q[j]).abs() / limits.velocity[j])
            .max((end.qd[j] - start.qd[j]).abs() / limits.acceleration[j]);
    }
    lower
}

/// Minimal duration (s) of the quintic from `start` to `end` under the velocity, acceleration and
/// jerk limits: [`earliest_quintic_duration`] from the necessary lower bound
/// max_j(|Δq_j|/v_max, |Δv_j|/a_max) (or 1 ms when that is smaller).
pub fn minimal_quintic_duration(start: &JointState, end: &JointState, limits: &KinematicLimits) -> Result<f64> {
    let n = start.check_pair("start", end, "end")?;
    limits.check_dof(n)?;
    earliest_quintic_duration(start, end, limits, necessary_duration(start, end, limits).max(1e-3))
}
