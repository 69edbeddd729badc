//! Scalar polynomials of degree ≤ 5 in local time τ (s): the boundary-value formulas of cubic and
//! quintic segments, their evaluation, and the exact extrema of their derivatives.
//!
//! Coefficients are stored in ascending powers, `c[k]` multiplying τᵏ.
//!
//! Cubic with boundary positions and velocities (seed 001, eqs. (17)–(25), corrected; see
//! `shared/seeds/README.md`): with h = θf − θ0,
//! a0 = θ0, a1 = θ̇0, a2 = 3h/tf² − (2θ̇0 + θ̇f)/tf, a3 = −2h/tf³ + (θ̇0 + θ̇f)/tf².
//! The seed's (24)–(25) are wrong whenever a boundary velocity is nonzero, and its (2) lacks the
//! cube; the rest-to-rest case (13)–(16) is the special case θ̇0 = θ̇f = 0, with (15) read as
//! A1 + 2A2·tf + 3A3·tf² = 0.
//!
//! Quintic with boundary (θ0, v0, α0) → (θ1, v1, α1) over tf (the patent's step S104, as
//! reconstructed in the seeds' README): f = θ0, e = v0, d = α0/2,
//! c = [20h − (8v1 + 12v0)tf − (3α0 − α1)tf²]/(2tf³),
//! b = [−30h + (14v1 + 16v0)tf + (3α0 − 2α1)tf²]/(2tf⁴),
//! a = [12h − 6(v0 + v1)tf + (α1 − α0)tf²]/(2tf⁵).

/// Coefficients (ascending powers of τ in s) of one joint's polynomial segment; degree ≤ 5.
pub type Coeffs = [f64; 6];

/// Cubic through (q0, v0) at τ = 0 and (q1, v1) at τ = tf (rad or m, per s).
pub fn cubic(q0: f64, q1: f64, v0: f64, v1: f64, tf: f64) -> Coeffs {
    let h = q1 - q0;
    let a2 = 3.0 * h / (tf * tf) - (2.0 * v0 + v1) / tf;
    let a3 = -2.0 * h / (tf * tf * tf) + (v0 + v1) / (tf * tf);
    [q0, v0, a2, a3, 0.0, 0.0]
}

/// Quintic through (q0, v0, a0) at τ = 0 and (q1, v1, a1) at τ = tf.
pub fn quintic(q0: f64, v0: f64, a0: f64, q1: f64, v1: f64, a1: f64, tf: f64) -> Coeffs {
    let h = q1 - q0;
    let (t2, t3) = (tf * tf, tf * tf * tf);
    let (t4, t5) = (t3 * tf, t3 * t2);
    let c = (20.0 * h - (8.0 * v1 + 12.0 * v0) * tf - (3.0 * a0 - a1) * t2) / (2.0 * t3);
    let b = (-30.0 * h + (14.0 * v1 + 16.0 * v0) * tf + (3.0 * a0 - 2.0 * a1) * t2) / (2.0 * t4);
    let a = (12.0 * h - 6.0 * (v0 + v1) * tf + (a1 - a0) * t2) / (2.0 * t5);
    [q0, v0, 0.5 * a0, c, b, a]
}

/// Position, velocity and acceleration of `c` at τ (Horner).
#[inline]
pub fn eval3(c: &Coeffs, tau: f64) -> [f64; 3] {
    let q = ((((c[5] * tau + c[4]) * tau + c[3]) * tau + c[2]) * tau + c[1]) * tau + c[0];
    let qd = (((5.0 * c[5] * tau + 4.0 * c[4]) * tau + 3.0 * c[3]) * tau + 2.0 * c[2]) * tau + c[1];
    let qdd = ((20.0 * c[5] * tau + 12.0 * c[4]) * tau + 6.0 * c[3]) * tau + 2.0 * c[2];
    [q, qd, qdd]
}

/// Position, velocity, acceleration and jerk of `c` at τ (Horner).
#[inline]
pub fn eval(c: &Coeffs, tau: f64) -> [f64; 4] {
    let q = ((((c[5] * tau + c[4]) * tau + c[3]) * tau + c[2]) * tau + c[1]) * tau + c[0];
    let qd = (((5.0 * c[5] * tau + 4.0 * c[4]) * tau + 3.0 * c[3]) * tau + 2.0 * c[2]) * tau + c[1];
    let qdd = ((20.0 * c[5] * tau + 12.0 * c[4]) * tau + 6.0 * c[3]) * tau + 2.0 * c[2];
    let jerk = (60.0 * c[5] * tau + 24.0 * c[4]) * tau + 6.0 * c[3];
    [q, qd, qdd, jerk]
}

/// Coefficients of the derivative of `c`.
pub fn derivative(c: &Coeffs) -> Coeffs {
    [c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4], 5.0 * c[5], 0.0]
}

/// Value of `c` at τ.
#[inline]
pub fn value(c: &Coeffs, tau: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * tau + k)
}

fn degree(c: &Coeffs) -> usize {
    c.iter().rposition(|&k| k != 0.0).unwrap_or(0)
}

/// Appends to `out` the roots of `c` in the open interval (lo, hi), in increasing order.
///
/// Exact up to rounding: the critical points of `c` (roots of its derivative, found recursively)
/// split (lo, hi) into intervals where `c` is monotone; each interval with a sign change holds one
/// root, found by Newton steps safeguarded by bisection down to a few ulps (degree ≤ 2: closed form). A root where `c` only touches
/// zero (even multiplicity) is reported when `c` is exactly zero at a critical point.
pub fn roots_in(c: &Coeffs, lo: f64, hi: f64, out: &mut Vec<f64>) {
    roots_into(c, lo, hi, out);
}

/// Where [`roots_into`] appends roots: a `Vec` for callers, a stack buffer inside this module.
trait RootSink {
    fn push_root(&mut self, r: f64);
    fn last_root(&self) -> Option<f64>;
}

impl RootSink for Vec<f64> {
    fn push_root(&mut self, r: f64) {
        self.push(r);
    }
    fn last_root(&self) -> Option<f64> {
        self.last().copied()
    }
}

/// At most five roots (degree ≤ 5) on the stack: the critical points of the peak searches,
/// which run for every stroke the planners try, without a heap allocation.
#[derive(Default)]
struct Roots {
    v: [f64; 5],
    n: usize,
}

impl Roots {
    fn as_slice(&self) -> &[f64] {
        &self.v[..self.n]
    }
}

impl RootSink for Roots {
    fn push_root(&mut self, r: f64) {
        // A polynomial of degree d has at most d roots and `roots_into` reports each once, so
        // five never overflow; `min` keeps an impossible sixth from indexing out of bounds.
        self.v[self.n.min(4)] = r;
        self.n = (self.n + 1).min(5);
    }
    fn last_root(&self) -> Option<f64> {
        self.n.checked_sub(1).map(|k| self.v[k])
    }
}

/// [`roots_in`] into any [`RootSink`].
fn roots_into<S: RootSink>(c: &Coeffs, lo: f64, hi: f64, out: &mut S) {
    match degree(c) {
        0 => {}
        1 => {
            let r = -c[0] / c[1];
            if r > lo && r < hi {
                out.push_root(r);
            }
        }
        2 => {
            // Stable quadratic formula: q = −(c1 + sign(c1)·√disc)/2, roots q/c2 and c0/q.
            let disc = c[1] * c[1] - 4.0 * c[2] * c[0];
            if disc < 0.0 {
                return;
            }
            let q = -0.5 * (c[1] + c[1].signum() * disc.sqrt());
            let (mut r1, mut r2) = (q / c[2], if q != 0.0 { c[0] / q } else { q / c[2] });
            if r1 > r2 {
                std::mem::swap(&mut r1, &mut r2);
            }
            for r in [r1, r2] {
                if r > lo && r < hi && out.last_root() != Some(r) {
                    out.push_root(r);
                }
            }
        }
        _ => {
            let mut crit = Roots::default();
            roots_into(&derivative(c), lo, hi, &mut crit);
            let mut a = lo;
            for b in crit.as_slice().iter().copied().chain(std::iter::once(hi)) {
                let (fa, fb) = (value(c, a), value(c, b));
                if fb == 0.0 && b < hi {
                    out.push_root(b);
                } else if fa != 0.0 && (fa < 0.0) != (fb < 0.0) {
                    out.push_root(bisect(c, a, b, fa));
                }
                a = b;
            }
        }
    }
}

/// Root of `c` in (a, b), where `c` is monotone and changes sign (`fa` = c(a)): Newton steps
/// safeguarded by bisection (a Newton step leaving the bracket is replaced by its midpoint), down
/// to a bracket of a few ulps or a step below 1e-16 of the root.
fn bisect(c: &Coeffs, mut a: f64, mut b: f64, fa: f64) -> f64 {
    let neg = fa < 0.0;
    let d = derivative(c);
    let mut x = 0.5 * (a + b);
    for _ in 0..200 {
        let fx = value(c, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == neg {
            a = x;
        } else {
            b = x;
        }
        let dx = value(&d, x);
        let newton = x - fx / dx;
        let next = if newton > a && newton < b {
            newton
        } else {
            0.5 * (a + b)
        };
        if (next - x).abs() <= 1e-16 * x.abs().max(1e-300) || b - a <= 4.0 * f64::EPSILON * a.abs().max(b.abs()) {
            return next;
        }
        x = next;
    }
    x
}

/// Bounds (lo, hi) with lo ≤ c(τ) ≤ hi for every τ in [0, tf], cheap and not exact: the extreme
/// coefficients of `c` in the degree-5 Bernstein basis of [0, tf] (its values lie in their convex
/// hull), widened by 1e-12 of Σ|c_k|·tf^k so that they also bound `c` evaluated with rounding.
pub fn bounds(c: &Coeffs, tf: f64) -> (f64, f64) {
    // b_k = Σ_{i ≤ k} C(k, i)/C(5, i) · c_i·tf^i.
    const W: [[f64; 6]; 6] = [
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 0.2, 0.0, 0.0, 0.0, 0.0],
        [1.0, 0.4, 0.1, 0.0, 0.0, 0.0],
        [1.0, 0.6, 0.3, 0.1, 0.0, 0.0],
        [1.0, 0.8, 0.6, 0.4, 0.2, 0.0],
        [1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    ];
    let mut a = [0.0; 6];
    let mut scale = 1.0;
    let mut size = 0.0;
    for k in 0..6 {
        a[k] = c[k] * scale;
        size += a[k].abs();
        scale *= tf;
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for w in &W {
        let b: f64 = w.iter().zip(&a).map(|(w, a)| w * a).sum();
        lo = lo.min(b);
        hi = hi.max(b);
    }
    let slack = 1e-12 * size;
    (lo - slack, hi + slack)
}

/// An upper bound of |c(τ)| over [0, tf] from [`bounds`].
pub fn bound_abs(c: &Coeffs, tf: f64) -> f64 {
    let (lo, hi) = bounds(c, tf);
    hi.max(-lo)
}

/// True when evaluating `c` and its first two derivatives by Horner's rule anywhere in
/// τ ∈ [0, h] cannot overflow: every intermediate is at most 2·20·Σ|c_k|·max(1, h)⁵ in magnitude
/// (the derivatives' coefficients are k·c_k and k(k−1)·c_k ≤ 20|c_k|), and that bound is
/// required below 1e300. False only means the bound cannot tell (NaN or infinite coefficients
/// included).
pub fn cannot_overflow(c: &Coeffs, h: f64) -> bool {
    let sum: f64 = c.iter().map(|x| x.abs()).sum();
    40.0 * sum * h.max(1.0).powi(5) < 1e300
}

impl super::JointTrajectory {
    /// True when no sample of this trajectory can overflow ([`cannot_overflow`] on every segment
    /// and joint): callers may then skip checking sampled values for infinities. False only means
    /// the bound cannot tell (e.g. a duration so short that 1/T⁵ overflows).
    pub fn samples_cannot_overflow(&self) -> bool {
        let knots = self.knots();
        (0..self.segments()).all(|k| {
            let h = knots[k + 1] - knots[k];
            (0..self.dof()).all(|j| self.coefficients(k, j).is_some_and(|c| cannot_overflow(&c, h)))
        })
    }
}

/// The τ in [0, tf] and value of the largest |c(τ)|, exact up to rounding (endpoints and the
/// roots of the derivative are the only candidates).
pub fn max_abs(c: &Coeffs, tf: f64) -> (f64, f64) {
    let mut crit = Roots::default();
    roots_into(&derivative(c), 0.0, tf, &mut crit);
    let mut best = (0.0, value(c, 0.0));
    for tau in crit.as_slice().iter().copied().chain(std::iter::once(tf)) {
        let v = value(c, tau);
        if v.abs() > best.1.abs() {
            best = (tau, v);
        }
    }
    best
}

/// The τ in [0, tf] and value of the smallest and of the largest c(τ), exact up to rounding.
pub fn min_max(c: &Coeffs, tf: f64) -> ((f64, f64), (f64, f64)) {
    let mut crit = Roots::default();
    roots_into(&derivative(c), 0.0, tf, &mut crit);
    let v0 = value(c, 0.0);
    let (mut lo, mut hi) = ((0.0, v0), (0.0, v0));
    for tau in crit.as_slice().iter().copied().chain(std::iter::once(tf)) {
        let v = value(c, tau);
        if v < lo.1 {
            lo = (tau, v);
        }
        if v > hi.1 {
            hi = (tau, v);
        }
    }
    (lo, hi)
}
