//! Interval arithmetic for certified bounds of the dynamics over a time interval: [`Iv`], a closed
//! interval of reals, and [`IvDual`], an interval value with an interval time derivative (forward
//! mode), the number type [`super::peak`] runs the Newton–Euler recursion on.
//!
//! Every operation returns an interval that contains all results of the operation on members of
//! its operands (the inclusion property, Moore, Kearfott and Cloud, "Introduction to Interval
//! Analysis", 2009, ch. 4–5). Rounding is to nearest, not outward: the enclosures may miss a true
//! value by a few units in the last place of the operands' magnitudes (relative 1e-15 per
//! operation, 1e-13 through a six-joint recursion), far below the relative tolerance of a limit
//! check ([`crate::traj::limits::LIMIT_TOLERANCE`], 1e-9), which callers widen by.

use std::f64::consts::{FRAC_PI_2, PI};
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A closed interval [lo, hi] of reals (lo ≤ hi).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iv {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl Iv {
    /// The interval [lo, hi] (the caller keeps lo ≤ hi).
    #[inline(always)]
    pub fn new(lo: f64, hi: f64) -> Iv {
        Iv { lo, hi }
    }

    /// The single point x.
    #[inline(always)]
    pub fn point(x: f64) -> Iv {
        Iv { lo: x, hi: x }
    }

    /// Largest magnitude of a member.
    #[inline(always)]
    pub fn mag(&self) -> f64 {
        self.hi.max(-self.lo)
    }

    /// The intersection with `o` (the hull of both ends when they do not overlap, which only
    /// rounding can cause for two enclosures of the same value).
    #[inline(always)]
    pub fn meet(&self, o: &Iv) -> Iv {
        let (lo, hi) = (self.lo.max(o.lo), self.hi.min(o.hi));
        if lo <= hi {
            Iv { lo, hi }
        } else {
            Iv { lo: hi, hi: lo }
        }
    }

    /// The interval times the scalar `k`.
    #[inline(always)]
    pub fn scale(self, k: f64) -> Iv {
        if k >= 0.0 {
            Iv::new(self.lo * k, self.hi * k)
        } else {
            Iv::new(self.hi * k, self.lo * k)
        }
    }

    /// sin over the interval: the end values, and ±1 where the interval holds π/2 + 2kπ or
    /// −π/2 + 2kπ.
    pub fn sin(self) -> Iv {
        if !(self.hi - self.lo < 2.0 * PI) {
            return Iv::new(-1.0, 1.0);
        }
        let (a, b) = (self.lo.sin(), self.hi.sin());
        let (mut lo, mut hi) = (a.min(b), a.max(b));
        let holds = |x0: f64| {
            // Smallest x0 + 2kπ ≥ lo.
            let k = ((self.lo - x0) / (2.0 * PI)).ceil();
            x0 + 2.0 * PI * k <= self.hi
        };
        if holds(FRAC_PI_2) {
            hi = 1.0;
        }
        if holds(-FRAC_PI_2) {
            lo = -1.0;
        }
        Iv::new(lo, hi)
    }

    /// cos over the interval: sin(x + π/2).
    pub fn cos(self) -> Iv {
        Iv::new(self.lo + FRAC_PI_2, self.hi + FRAC_PI_2).sin()
    }
}

impl Add for Iv {
    type Output = Iv;
    #[inline(always)]
    fn add(self, o: Iv) -> Iv {
        Iv::new(self.lo + o.lo, self.hi + o.hi)
    }
}

impl Sub for Iv {
    type Output = Iv;
    #[inline(always)]
    fn sub(self, o: Iv) -> Iv {
        Iv::new(self.lo - o.hi, self.hi - o.lo)
    }
}

impl Neg for Iv {
    type Output = Iv;
    #[inline(always)]
    fn neg(self) -> Iv {
        Iv::new(-self.hi, -self.lo)
    }
}

/// The smaller of two numbers (one `minsd`; the enclosures hold no NaN unless an input did,
/// and a NaN input makes the caller's bound NaN, which it treats as unbounded).
#[inline(always)]
fn lesser(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

/// The larger of two numbers (one `maxsd`).
#[inline(always)]
fn greater(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

impl Mul for Iv {
    type Output = Iv;
    #[inline(always)]
    fn mul(self, o: Iv) -> Iv {
        let (a, b, c, d) = (self.lo * o.lo, self.lo * o.hi, self.hi * o.lo, self.hi * o.hi);
        Iv::new(
            lesser(lesser(a, b), lesser(c, d)),
            greater(greater(a, b), greater(c, d)),
        )
    }
}

/// A value known to lie in `v` whose time derivative lies in `d`, both intervals: forward-mode
/// differentiation on intervals, so that one pass of an algorithm encloses a function of time
/// and its rate over a time interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IvDual {
    /// Enclosure of the value.
    pub v: Iv,
    /// Enclosure of its time derivative.
    pub d: Iv,
}

impl IvDual {
    /// A value in `v` with a derivative in `d`.
    #[inline(always)]
    pub fn new(v: Iv, d: Iv) -> IvDual {
        IvDual { v, d }
    }
}

/// The number type of a generic algorithm: f64, or [`IvDual`] for enclosures.
pub trait Real:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self> + AddAssign
{
    /// The constant `x` (derivative 0).
    fn cst(x: f64) -> Self;
    /// The value times the constant `k`.
    fn scale(self, k: f64) -> Self;
    /// (sin, cos) of the value.
    fn sin_cos(self) -> (Self, Self);
}

impl Real for f64 {
    #[inline(always)]
    fn cst(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn scale(self, k: f64) -> f64 {
        self * k
    }
    #[inline(always)]
    fn sin_cos(self) -> (f64, f64) {
        crate::trig::sin_cos(self)
    }
}

impl Add for IvDual {
    type Output = IvDual;
    #[inline(always)]
    fn add(self, o: IvDual) -> IvDual {
        IvDual::new(self.v + o.v, self.d + o.d)
    }
}

impl AddAssign for IvDual {
    #[inline(always)]
    fn add_assign(&mut self, o: IvDual) {
        *self = *self + o;
    }
}

impl Sub for IvDual {
    type Output = IvDual;
    #[inline(always)]
    fn sub(self, o: IvDual) -> IvDual {
        IvDual::new(self.v - o.v, self.d - o.d)
    }
}

impl Neg for IvDual {
    type Output = IvDual;
    #[inline(always)]
    fn neg(self) -> IvDual {
        IvDual::new(-self.v, -self.d)
    }
}

impl Mul for IvDual {
    type Output = IvDual;
    #[inline(always)]
    fn mul(self, o: IvDual) -> IvDual {
        IvDual::new(self.v * o.v, self.d * o.v + self.v * o.d)
    }
}

impl Real for IvDual {
    #[inline(always)]
    fn cst(x: f64) -> IvDual {
        IvDual::new(Iv::point(x), Iv::point(0.0))
    }
    #[inline(always)]
    fn scale(self, k: f64) -> IvDual {
        IvDual::new(self.v.scale(k), self.d.scale(k))
    }
    fn sin_cos(self) -> (IvDual, IvDual) {
        let (s, c) = (self.v.sin(), self.v.cos());
        (IvDual::new(s, c * self.d), IvDual::new(c, -(s * self.d)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contains(i: Iv, x: f64) -> bool {
        let slack = 1e-14 * (1.0 + x.abs());
        i.lo - slack <= x && x <= i.hi + slack
    }

    #[test]
    fn operations_contain_every_result_of_their_members() {
        let mut rng = fastrand::Rng::with_seed(11);
        let draw = |rng: &mut fastrand::Rng| {
            let (a, b) = (8.0 * rng.f64() - 4.0, 8.0 * rng.f64() - 4.0);
            Iv::new(a.min(b), a.max(b))
        };
        for _ in 0..5000 {
            let (x, y) = (draw(&mut rng), draw(&mut rng));
            let k = 6.0 * rng.f64() - 3.0;
            for _ in 0..8 {
                let a = x.lo + (x.hi - x.lo) * rng.f64();
                let b = y.lo + (y.hi - y.lo) * rng.f64();
                assert!(contains(x + y, a + b) && contains(x - y, a - b) && contains(x * y, a * b));
                assert!(contains(-x, -a) && contains(x.scale(k), a * k));
                assert!(contains(x.sin(), a.sin()) && contains(x.cos(), a.cos()), "{x:?} {a}");
            }
        }
        // Tight where it can be: the extrema of sin are reached.
        let s = Iv::new(1.0, 2.0).sin();
        assert_eq!(s.hi, 1.0);
        assert!((s.lo - 1f64.sin()).abs() < 1e-15);
        assert_eq!(Iv::new(-0.1, 7.0).cos(), Iv::new(-1.0, 1.0));
    }

    #[test]
    fn dual_derivative_encloses_the_derivative_of_a_composite() {
        // f(t) = sin(q(t))·q̇(t) with q = 0.3 + 2t + t², q̇ = 2 + 2t on [0.1, 0.2].
        let (a, b) = (0.1f64, 0.2f64);
        let q = |t: f64| 0.3 + 2.0 * t + t * t;
        let qd = |t: f64| 2.0 + 2.0 * t;
        let qi = IvDual::new(Iv::new(q(a), q(b)), Iv::new(qd(a), qd(b)));
        let qdi = IvDual::new(Iv::new(qd(a), qd(b)), Iv::point(2.0));
        let f = qi.sin_cos().0 * qdi;
        for k in 0..=100 {
            let t = a + (b - a) * k as f64 / 100.0;
            let value = q(t).sin() * qd(t);
            let rate = q(t).cos() * qd(t) * qd(t) + q(t).sin() * 2.0;
            assert!(contains(f.v, value) && contains(f.d, rate));
        }
    }
}
