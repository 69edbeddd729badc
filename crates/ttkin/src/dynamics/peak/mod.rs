//! The certified effort peak of a planned motion: the largest |τ_j(t)|/limit_j(q̇_j(t)) over the
//! whole trajectory, not at check points, found by branch and bound on time intervals.
//!
//! τ(t) = RNEA(q(t), q̇(t), q̈(t)) + friction is not a polynomial, so its peak has no closed form.
//! On a time interval [a, b] the trajectory's q, q̇, q̈ and jerk lie in boxes (Bernstein bounds of
//! the polynomial pieces, [`poly::bounds`]). The Newton–Euler recursion run once on interval
//! values with interval time derivatives ([`IvDual`]) encloses both τ_s (rigid body, armature,
//! viscous friction) and dτ_s/dt over the box. The enclosure of τ_s on [a, b] is the intersection
//! of that direct enclosure with the mean-value form τ_s(m) + [dτ_s/dt]·[−h/2, h/2] (m the
//! midpoint, h = b − a; τ_s is continuous and piecewise C¹, so the mean-value inequality holds
//! across the pieces' knots). Its width shrinks like h² near a smooth peak, so a few bisections
//! settle it. The Coulomb term f_c·sign(q̇) is added as an interval of signs over the q̇ box (it
//! jumps where q̇ crosses zero, and the supremum there is a one-sided limit the midpoints
//! approach). The limit over the interval is the effective limit at the largest |q̇| in the box
//! ([`crate::effort`]: it only falls with speed).
//!
//! Every interval gets a lower value (the ratio at its midpoint, an instant of the trajectory)
//! and an upper bound per joint; the interval with the largest gap is bisected until the gap is
//! below the tolerance everywhere ([`PeakStop::refine`]), or until the peak is known to be above
//! or below a threshold, or too close to it to matter ([`PeakStop::decide`]). Intervals shorter than [`MIN_WIDTH`] of the
//! duration are not split further (their bound stays in the result): then `bound` is still an
//! upper bound, only a looser one.

// The recursions index several per-joint arrays at once: index loops read like the textbook.
#![allow(clippy::needless_range_loop)]

mod recursion;
#[cfg(test)]
mod tests;

use nalgebra::Vector3;

use super::interval::{Iv, IvDual, Real};
use super::model::{Dynamics, DynamicsData};
use crate::effort::EffortLimits;
use crate::joint::COULOMB_DEADBAND;
use crate::traj::{poly, JointTrajectory};
use recursion::Work;

/// Intervals at the start of a search (evenly spaced over the trajectory).
const START_INTERVALS: usize = 4;

/// Shortest interval the search splits, as a fraction of the trajectory's duration.
pub const MIN_WIDTH: f64 = 1e-7;

/// Most interval evaluations per search; beyond, the bound found so far is returned.
const MAX_EVALUATIONS: usize = 4000;

/// Relative widening of every upper bound for the rounding of the enclosures
/// ([`super::interval`]).
const ROUNDING: f64 = 1e-12;

/// When the search may stop (ratios |τ|/limit, dimensionless): when every interval's bound is
/// within `tolerance` of the larger of the best value found and `floor`, when a value above
/// `above` is found, or when the bound is at most `below`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakStop {
    /// Width of the bracket that ends the search.
    pub tolerance: f64,
    /// Values up to it need no refinement (another part of a motion already reaches it).
    pub floor: f64,
    /// A value found above it ends the search (+∞: never).
    pub above: f64,
    /// A bound at most it ends the search (−∞: never).
    pub below: f64,
}

impl PeakStop {
    /// Refine the peak to `tolerance`: the bound is then within it of the ratio found.
    pub fn refine(tolerance: f64) -> Self {
        PeakStop {
            tolerance,
            floor: 0.0,
            above: f64::INFINITY,
            below: f64::NEG_INFINITY,
        }
    }

    /// Refine to `tolerance` unless a value above `threshold` turns up (then a decision only).
    pub fn refine_below(tolerance: f64, threshold: f64) -> Self {
        PeakStop {
            above: threshold,
            ..PeakStop::refine(tolerance)
        }
    }

    /// Decide whether the peak is above `threshold` (a value above it found) or at most it (the
    /// bound at most it); a peak bracketed within `tolerance` with the bound above `threshold`
    /// is left undecided, and a caller deciding feasibility by `bound ≤ threshold` rejects it,
    /// which errs on the safe side.
    pub fn decide(threshold: f64, tolerance: f64) -> Self {
        PeakStop {
            tolerance,
            floor: 0.0,
            above: threshold,
            below: threshold,
        }
    }
}

/// The effort peak of a trajectory: ratios |τ|/limit (dimensionless), torques N·m or N, times s.
#[derive(Debug, Clone, PartialEq)]
pub struct EffortPeak {
    /// Largest ratio found at an instant of the trajectory (a value it takes).
    pub ratio: f64,
    /// Certified upper bound of the ratio over the whole trajectory (≥ `ratio`).
    pub bound: f64,
    /// Time of `ratio` (s from the trajectory's start).
    pub time: f64,
    /// Joint of `ratio`.
    pub joint: usize,
    /// Largest |τ| per joint at the instants evaluated (the search's lower values).
    pub peak: Vec<f64>,
    /// Interval enclosures computed (cost; about 20 single inverse dynamics each).
    pub evaluations: usize,
}

impl Dynamics {
    /// The certified effort peak of `traj` against `limits` under `gravity` (m/s², base frame),
    /// stopping as `stop` says (module doc). `data` is scratch for the point evaluations; `traj`
    /// and `limits` must have this model's dof (callers check).
    pub fn effort_peak(
        &self,
        data: &mut DynamicsData,
        traj: &JointTrajectory,
        limits: &EffortLimits,
        gravity: &Vector3<f64>,
        stop: PeakStop,
    ) -> EffortPeak {
        Search::new(self, traj, limits, gravity).run(data, stop)
    }
}

/// One interval of the search with its per-joint upper bounds of the ratio, and, when its own
/// enclosure was computed, that enclosure (valid on every sub-interval too).
struct Interval {
    a: f64,
    b: f64,
    upper: Vec<f64>,
    hull: Option<Vec<Hull>>,
}

/// What one joint's enclosure over an interval says about every instant of it: the smooth part
/// τ_s (N·m or N), the largest |dτ_s/dt| (N·m/s or N/s), the Coulomb term and the smallest
/// effective limit over the q̇ box (N·m or N).
#[derive(Clone, Copy)]
struct Hull {
    smooth: Iv,
    rate: f64,
    coulomb: Iv,
    limit: f64,
}

impl Interval {
    fn key(&self) -> f64 {
        self.upper.iter().fold(f64::NEG_INFINITY, |k, u| k.max(*u))
    }
}

/// The state of one branch-and-bound search.
struct Search<'a> {
    model: &'a Dynamics,
    traj: &'a JointTrajectory,
    limits: &'a EffortLimits,
    gravity: Vector3<f64>,
    n: usize,
    coulomb: Vec<f64>,
    work: Work<IvDual>,
    boxes: [Vec<IvDual>; 3],
    tau: Vec<IvDual>,
    q: [Vec<f64>; 3],
    smooth: Vec<f64>,
    peak: Vec<f64>,
    best: (f64, f64, usize),
    evaluations: usize,
}

impl<'a> Search<'a> {
    fn new(model: &'a Dynamics, traj: &'a JointTrajectory, limits: &'a EffortLimits, gravity: &Vector3<f64>) -> Self {
        let n = model.dof();
        let zero = IvDual::cst(0.0);
        Search {
            model,
            traj,
            limits,
            gravity: *gravity,
            n,
            coulomb: model.drives.iter().map(|d| d.map_or(0.0, |d| d.coulomb)).collect(),
            work: Work::new(n),
            boxes: std::array::from_fn(|_| vec![zero; n]),
            tau: vec![zero; n],
            q: std::array::from_fn(|_| vec![0.0; n]),
            smooth: vec![0.0; n],
            peak: vec![0.0; n],
            best: (0.0, 0.0, 0),
            evaluations: 0,
        }
    }

    /// τ at time `t` (inverse dynamics with friction, the numbers `Robot.torques` gives): updates
    /// the largest values found and leaves the smooth part (without the Coulomb term) in `smooth`.
    fn point(&mut self, data: &mut DynamicsData, t: f64) {
        let [q, qd, qdd] = &mut self.q;
        self.traj.sample_unchecked(t.min(self.traj.duration()), q, qd, qdd);
        if !q.iter().chain(qd.iter()).chain(qdd.iter()).all(|v| v.is_finite()) {
            self.smooth.fill(f64::INFINITY);
            self.best = (f64::INFINITY, t, 0);
            return;
        }
        // Six joints: the fixed-size recursion on the stack (the same numbers, faster).
        let fixed = <&[f64; 6]>::try_from(&q[..])
            .ok()
            .zip(<&[f64; 6]>::try_from(&qd[..]).ok())
            .zip(<&[f64; 6]>::try_from(&qdd[..]).ok())
            .and_then(|((q, qd), qdd)| self.model.inverse_dynamics_fixed::<6>(data, q, qd, qdd, &self.gravity));
        let tau: &[f64] = match &fixed {
            Some(t) => t,
            None => self
                .model
                .inverse_dynamics_unchecked(data, q, qd, qdd, &self.gravity)
                .as_slice(),
        };
        for j in 0..self.n {
            let (tj, v) = (tau[j], qd[j]);
            self.smooth[j] = tj - self.coulomb[j] * sign(v);
            self.peak[j] = self.peak[j].max(tj.abs());
            let r = ratio(tj.abs(), self.limits.at(j, v));
            if r > self.best.0 {
                self.best = (r, t, j);
            }
        }
    }

    /// The interval [a, b] with its per-joint upper bounds (the midpoint evaluated first).
    fn interval(&mut self, data: &mut DynamicsData, a: f64, b: f64) -> Interval {
        let m = 0.5 * (a + b);
        self.point(data, m);
        self.boxes_over(a, b);
        self.evaluations += 1;
        let [q, qd, qdd] = &self.boxes;
        self.model
            .rnea_smooth(&mut self.work, q, qd, qdd, &self.gravity, &mut self.tau);
        let half = 0.5 * (b - a);
        let mut upper = vec![0.0; self.n];
        let mut hull = Vec::with_capacity(self.n);
        for j in 0..self.n {
            let t = self.tau[j];
            let spread = t.d.mag() * half;
            let smooth = t.v.meet(&Iv::new(self.smooth[j] - spread, self.smooth[j] + spread));
            let speed = self.boxes[1][j].v;
            let fc = self.coulomb[j];
            let coulomb = Iv::new(
                if speed.lo > COULOMB_DEADBAND {
                    fc
                } else if speed.lo >= -COULOMB_DEADBAND {
                    0.0
                } else {
                    -fc
                },
                if speed.hi < -COULOMB_DEADBAND {
                    -fc
                } else if speed.hi <= COULOMB_DEADBAND {
                    0.0
                } else {
                    fc
                },
            );
            let limit = self.limits.at(j, speed.mag());
            upper[j] = bound(smooth + coulomb, limit);
            hull.push(Hull {
                smooth,
                rate: t.d.mag(),
                coulomb,
                limit,
            });
        }
        Interval {
            a,
            b,
            upper,
            hull: Some(hull),
        }
    }

    /// The sub-interval [a, b] of an interval with enclosure `hull`, bounded without an enclosure
    /// of its own: its midpoint evaluated, then per joint the mean-value form τ_s(m) ±
    /// max|dτ_s/dt|·(b − a)/2 with the parent's rate, met with the parent's τ_s, plus the parent's
    /// Coulomb term, against the parent's limit (all valid on a sub-interval). Costs one point
    /// evaluation; looser than an enclosure of its own (the rate does not shrink with the
    /// interval), enough away from the peak.
    fn cheap(&mut self, data: &mut DynamicsData, a: f64, b: f64, hull: &[Hull]) -> Interval {
        self.point(data, 0.5 * (a + b));
        let half = 0.5 * (b - a);
        let upper = (0..self.n)
            .map(|j| {
                let h = &hull[j];
                let spread = h.rate * half;
                let smooth = h
                    .smooth
                    .meet(&Iv::new(self.smooth[j] - spread, self.smooth[j] + spread));
                bound(smooth + h.coulomb, h.limit)
            })
            .collect();
        Interval {
            a,
            b,
            upper,
            hull: None,
        }
    }

    /// Boxes of (q, q̇), (q̇, q̈), (q̈, jerk) over [a, b] from the pieces that overlap it.
    fn boxes_over(&mut self, a: f64, b: f64) {
        let knots = self.traj.knots();
        let segments = self.traj.segments();
        let first = knots.partition_point(|&t| t <= a).saturating_sub(1).min(segments - 1);
        let empty = Iv::new(f64::INFINITY, f64::NEG_INFINITY);
        for j in 0..self.n {
            let mut r = [empty; 4];
            let mut k = first;
            loop {
                let (t0, t1) = (knots[k], knots[k + 1]);
                let (u0, u1) = ((a.max(t0) - t0).max(0.0), (b.min(t1) - t0).max(0.0));
                let mut c = shift(&self.traj.coefficients(k, j).expect("segment and joint in range"), u0);
                for slot in r.iter_mut() {
                    let (lo, hi) = poly::bounds(&c, (u1 - u0).max(0.0));
                    *slot = Iv::new(slot.lo.min(lo), slot.hi.max(hi));
                    c = poly::derivative(&c);
                }
                k += 1;
                if k >= segments || knots[k] >= b {
                    break;
                }
            }
            self.boxes[0][j] = IvDual::new(r[0], r[1]);
            self.boxes[1][j] = IvDual::new(r[1], r[2]);
            self.boxes[2][j] = IvDual::new(r[2], r[3]);
        }
    }

    fn run(mut self, data: &mut DynamicsData, stop: PeakStop) -> EffortPeak {
        let d = self.traj.duration();
        // The instants first (cheap): a leg above the threshold there needs no enclosure.
        for k in 0..=2 * START_INTERVALS {
            self.point(data, d * k as f64 / (2 * START_INTERVALS) as f64);
        }
        if self.best.0 > stop.above {
            let best = self.best.0;
            return self.result(best);
        }
        let mut active: Vec<Interval> = (0..START_INTERVALS)
            .map(|k| {
                let (a, b) = (
                    d * k as f64 / START_INTERVALS as f64,
                    d * (k + 1) as f64 / START_INTERVALS as f64,
                );
                self.interval(data, a, b)
            })
            .collect();
        let mut settled: f64 = 0.0;
        loop {
            let mut bound = settled;
            let mut pick: Option<(usize, f64)> = None;
            for (idx, iv) in active.iter().enumerate() {
                let mut key = f64::NEG_INFINITY;
                for j in 0..self.n {
                    bound = bound.max(iv.upper[j]);
                    key = key.max(iv.upper[j]);
                }
                if pick.is_none_or(|(_, k)| key > k) {
                    pick = Some((idx, key));
                }
            }
            let reached = self.best.0.max(stop.floor);
            let done = match pick {
                None => true,
                Some((_, key)) => key - reached <= stop.tolerance,
            } || self.best.0 > stop.above
                || bound <= stop.below;
            if done || self.evaluations >= MAX_EVALUATIONS || !self.best.0.is_finite() {
                return self.result(bound);
            }
            let (idx, _) = pick.expect("not done");
            let iv = active.swap_remove(idx);
            if iv.b - iv.a <= MIN_WIDTH * d {
                settled = iv.upper.iter().fold(settled, |s, u| s.max(*u));
                continue;
            }
            let Some(hull) = iv.hull else {
                // Bounded cheaply and still in the way: its own enclosure first.
                let mut full = self.interval(data, iv.a, iv.b);
                for (f, u) in full.upper.iter_mut().zip(&iv.upper) {
                    *f = f.min(*u);
                }
                active.push(full);
                continue;
            };
            let m = 0.5 * (iv.a + iv.b);
            for (a, b) in [(iv.a, m), (m, iv.b)] {
                // The cheap bound from the parent's enclosure first; the child's own enclosure
                // only when that cannot settle it (a bound the search would refine further).
                let child = self.cheap(data, a, b, &hull);
                let enough = (self.best.0.max(stop.floor) + stop.tolerance).max(stop.below);
                if child.key() <= enough {
                    active.push(child);
                } else {
                    let mut full = self.interval(data, a, b);
                    for (f, u) in full.upper.iter_mut().zip(&child.upper) {
                        *f = f.min(*u);
                    }
                    active.push(full);
                }
            }
        }
    }

    fn result(self, bound: f64) -> EffortPeak {
        let (ratio, time, joint) = self.best;
        EffortPeak {
            ratio,
            bound: bound.max(ratio),
            time,
            joint,
            peak: self.peak,
            evaluations: self.evaluations,
        }
    }
}

/// sign(v) with the Coulomb dead band of [`crate::joint::Drive::friction`].
fn sign(v: f64) -> f64 {
    if v > COULOMB_DEADBAND {
        1.0
    } else if v < -COULOMB_DEADBAND {
        -1.0
    } else {
        0.0
    }
}

/// The ratio bound of a torque enclosure against `limit`, widened for rounding; +∞ for NaN.
fn bound(tau: Iv, limit: f64) -> f64 {
    let mag = tau.mag() * (1.0 + ROUNDING);
    if mag.is_nan() {
        f64::INFINITY
    } else {
        ratio(mag, limit)
    }
}

/// |τ|/limit, 0 for no torque, +∞ for a torque against a zero limit.
fn ratio(mag: f64, limit: f64) -> f64 {
    if mag == 0.0 {
        0.0
    } else if limit > 0.0 {
        mag / limit
    } else {
        f64::INFINITY
    }
}

/// The coefficients of c(u + τ) in τ (Taylor shift by `u`, Horner's scheme).
fn shift(c: &poly::Coeffs, u: f64) -> poly::Coeffs {
    let mut c = *c;
    if u != 0.0 {
        for i in 0..5 {
            for k in (i..5).rev() {
                c[k] += u * c[k + 1];
            }
        }
    }
    c
}
