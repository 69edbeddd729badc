//! Kinematic limits of joint trajectories: exact peak values, limit checks, and the minimal
//! duration of a polynomial segment.
//!
//! Peaks are exact up to rounding: on each polynomial piece the extrema of a derivative lie at the
//! piece's ends or at roots of the next derivative, which [`poly::roots_in`] isolates (closed form up to degree 2, safeguarded Newton above).
//! Nothing is sampled, so a violation between two control ticks is still found.
//!
//! Length (about 600 lines): one concept, the exact checks of one trajectory type, read top to
//! bottom (peaks, violations, minimal durations share the per-piece root isolation); its tests
//! live in `crates/ttkin/tests`.

use super::{poly, JointState, JointTrajectory};
use crate::chain::Chain;
use crate::error::{check_vector, Error, Result};

/// Relative tolerance of a limit check: a peak up to `limit·(1 + 1e-9)` passes, so a trajectory
/// planned exactly at a limit is not reported for rounding.
pub const LIMIT_TOLERANCE: f64 = 1e-9;

/// Per-joint kinematic limits; +∞ (or −∞ for `lower`) where a joint has none.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicLimits {
    /// Lower position limits (rad or m).
    pub lower: Vec<f64>,
    /// Upper position limits (rad or m).
    pub upper: Vec<f64>,
    /// Speed limits (rad/s or m/s), > 0.
    pub velocity: Vec<f64>,
    /// Acceleration limits (rad/s² or m/s²), > 0.
    pub acceleration: Vec<f64>,
    /// Jerk limits (rad/s³ or m/s³), > 0.
    pub jerk: Vec<f64>,
}

impl KinematicLimits {
    /// Velocity, acceleration and jerk limits (dof long each; +∞ allowed), no position limits.
    pub fn new(velocity: &[f64], acceleration: &[f64], jerk: &[f64]) -> Result<Self> {
        let n = velocity.len();
        let l = KinematicLimits {
            lower: vec![f64::NEG_INFINITY; n],
            upper: vec![f64::INFINITY; n],
            velocity: velocity.to_vec(),
            acceleration: acceleration.to_vec(),
            jerk: jerk.to_vec(),
        };
        l.validate()?;
        Ok(l)
    }

    /// The limits of a chain's joints (absent velocity or acceleration limits are +∞) with the
    /// given jerk limits (+∞ when `None`; robot files carry none).
    pub fn from_chain(chain: &Chain, jerk: Option<&[f64]>) -> Result<Self> {
        let lim = chain.limits();
        let n = lim.len();
        let jerk = match jerk {
            Some(j) => j.to_vec(),
            None => vec![f64::INFINITY; n],
        };
        let l = KinematicLimits {
            lower: lim.iter().map(|l| l.lower).collect(),
            upper: lim.iter().map(|l| l.upper).collect(),
            velocity: lim.iter().map(|l| l.velocity.unwrap_or(f64::INFINITY)).collect(),
            acceleration: lim.iter().map(|l| l.acceleration.unwrap_or(f64::INFINITY)).collect(),
            jerk,
        };
        l.validate()?;
        Ok(l)
    }

    /// The same limits with position limits `lower`, `upper` (rad or m).
    pub fn with_position(mut self, lower: &[f64], upper: &[f64]) -> Result<Self> {
        self.lower = lower.to_vec();
        self.upper = upper.to_vec();
        self.validate()?;
        Ok(self)
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.velocity.len()
    }

    fn validate(&self) -> Result<()> {
        let n = self.velocity.len();
        if n == 0 {
            return Err(Error::shape("velocity limits", "at least one joint", "0 values"));
        }
        for (what, v) in [
            ("lower", &self.lower),
            ("upper", &self.upper),
            ("acceleration limits", &self.acceleration),
            ("jerk limits", &self.jerk),
        ] {
            if v.len() != n {
                return Err(Error::shape(what, format!("{n} values"), format!("{} values", v.len())));
            }
        }
        for (what, v) in [
            ("velocity limits", &self.velocity),
            ("acceleration limits", &self.acceleration),
            ("jerk limits", &self.jerk),
        ] {
            if let Some(j) = v.iter().position(|x| !(*x > 0.0)) {
                return Err(Error::invalid(
                    what,
                    format!("joint {j}: limit must be > 0, got {}", v[j]),
                ));
            }
        }
        for j in 0..n {
            if self.lower[j].is_nan() || self.upper[j].is_nan() || self.lower[j] > self.upper[j] {
                return Err(Error::invalid(
                    "position limits",
                    format!(
                        "joint {j}: need lower ≤ upper, got [{}, {}]",
                        self.lower[j], self.upper[j]
                    ),
                ));
            }
        }
        Ok(())
    }

    fn check_dof(&self, n: usize) -> Result<()> {
        if self.dof() != n {
            return Err(Error::shape(
                "limits",
                format!("{n} joints"),
                format!("{} joints", self.dof()),
            ));
        }
        Ok(())
    }
}

/// The quantity a limit bounds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Joint position (rad or m).
    Position,
    /// Joint velocity (per s).
    Velocity,
    /// Joint acceleration (per s²).
    Acceleration,
    /// Joint jerk (per s³).
    Jerk,
}

impl Quantity {
    /// Lower-case name: "position", "velocity", "acceleration", "jerk".
    pub fn name(&self) -> &'static str {
        match self {
            Quantity::Position => "position",
            Quantity::Velocity => "velocity",
            Quantity::Acceleration => "acceleration",
            Quantity::Jerk => "jerk",
        }
    }
}

/// The worst excess of one quantity of one joint over its limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Violation {
    /// Joint index.
    pub joint: usize,
    /// Which quantity.
    pub quantity: Quantity,
    /// Time of the worst value (s).
    pub time: f64,
    /// The worst value (signed; rad or m per s^k).
    pub value: f64,
    /// The limit it exceeds (the crossed bound for positions, the magnitude bound otherwise).
    pub limit: f64,
}

/// Peak of one quantity of one joint: time (s) and signed value of the largest magnitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    /// Time of the peak (s).
    pub time: f64,
    /// Signed value at the peak.
    pub value: f64,
}

impl JointTrajectory {
    /// Exact peak magnitude of velocity (`order` 1), acceleration (2) or jerk (3) of every joint
    /// over the whole trajectory.
    pub fn peaks(&self, order: usize) -> Result<Vec<Peak>> {
        if !(1..=3).contains(&order) {
            return Err(Error::invalid("order", format!("1, 2 or 3 expected, got {order}")));
        }
        let n = self.dof();
        let mut out = vec![Peak { time: 0.0, value: 0.0 }; n];
        for k in 0..self.segments() {
            let (t0, h) = (self.knots()[k], self.knots()[k + 1] - self.knots()[k]);
            for (j, best) in out.iter_mut().enumerate() {
                let mut c = self.coefficients(k, j).expect("segment and joint in range");
                for _ in 0..order {
                    c = poly::derivative(&c);
                }
                let (tau, v) = poly::max_abs(&c, h);
                if v.abs() > best.value.abs() {
                    *best = Peak {
                        time: t0 + tau,
                        value: v,
                    };
                }
            }
        }
        Ok(out)
    }

    /// Exact lowest and highest position of every joint: (time s, value) pairs.
    pub fn position_range(&self) -> Vec<(Peak, Peak)> {
        (0..self.dof()).map(|j| self.joint_position_range(j)).collect()
    }

    /// Cheap bounds (lo, hi) of the position of joint `j` (< dof) over the whole trajectory,
    /// containing its exact range ([`poly::bounds`] per segment).
    pub fn joint_position_bounds(&self, j: usize) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..self.segments() {
            let h = self.knots()[k + 1] - self.knots()[k];
            let c = self.coefficients(k, j).expect("segment and joint in range");
            let (l, u) = poly::bounds(&c, h);
            lo = lo.min(l);
            hi = hi.max(u);
        }
        (lo, hi)
    }

    /// Exact lowest and highest position of joint `j` (< dof): (time s, value) pairs.
    pub fn joint_position_range(&self, j: usize) -> (Peak, Peak) {
        let mut lo = Peak {
            time: 0.0,
            value: f64::INFINITY,
        };
        let mut hi = Peak {
            time: 0.0,
            value: f64::NEG_INFINITY,
        };
        for k in 0..self.segments() {
            let (t0, h) = (self.knots()[k], self.knots()[k + 1] - self.knots()[k]);
            let c = self.coefficients(k, j).expect("segment and joint in range");
            let ((tl, vl), (th, vh)) = poly::min_max(&c, h);
            if vl < lo.value {
                lo = Peak {
                    time: t0 + tl,
                    value: vl,
                };
            }
            if vh > hi.value {
                hi = Peak {
                    time: t0 + th,
                    value: vh,
                };
            }
        }
        (lo, hi)
    }

    /// Every joint's lowest and highest position that leaves the position limits of `limits`
    /// (to [`LIMIT_TOLERANCE`]), exactly, with times shifted by `t0` s; `limits` must have
    /// `self.dof()` joints. Cheap bounds first: the exact extrema only for joints they cannot clear.
    pub fn position_violations(&self, limits: &KinematicLimits, t0: f64) -> Vec<Violation> {
        let slack = |b: f64| LIMIT_TOLERANCE * b.abs().max(1.0);
        let mut out = Vec::new();
        for j in 0..self.dof() {
            let (lower, upper) = (limits.lower[j], limits.upper[j]);
            let (lo_bound, hi_bound) = self.joint_position_bounds(j);
            if lo_bound >= lower - slack(lower) && hi_bound <= upper + slack(upper) {
                continue;
            }
            let (lo, hi) = self.joint_position_range(j);
            for (peak, limit, bad) in [
                (lo, lower, lo.value < lower - slack(lower)),
                (hi, upper, hi.value > upper + slack(upper)),
            ] {
                if bad {
                    out.push(Violation {
                        joint: j,
                        quantity: Quantity::Position,
                        time: t0 + peak.time,
                        value: peak.value,
                        limit,
                    });
                }
            }
        }
        out
    }

    /// Every joint's worst violation of each limit (position, velocity, acceleration, jerk), found
    /// exactly; empty when the trajectory respects all limits (to [`LIMIT_TOLERANCE`]).
    pub fn check_limits(&self, limits: &KinematicLimits) -> Result<Vec<Violation>> {
        limits.check_dof(self.dof())?;
        let mut out = self.position_violations(limits, 0.0);
        for (order, quantity, bound) in [
            (1, Quantity::Velocity, &limits.velocity),
            (2, Quantity::Acceleration, &limits.acceleration),
            (3, Quantity::Jerk, &limits.jerk),
        ] {
            for (j, p) in self.peaks(order)?.into_iter().enumerate() {
                if p.value.abs() > bound[j] * (1.0 + LIMIT_TOLERANCE) {
                    out.push(Violation {
                        joint: j,
                        quantity,
                        time: p.time,
                        value: p.value,
                        limit: bound[j],
                    });
                }
            }
        }
        Ok(out)
    }
}

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
    let (kv, ka, kj) = match kind {
        SegmentKind::Cubic => (1.5, 6.0, 12.0),
        SegmentKind::Quintic => (15.0 / 8.0, 10.0 / 3f64.sqrt(), 60.0),
    };
    let mut t: f64 = 0.0;
    for j in 0..n {
        let h = (q1[j] - q0[j]).abs();
        t = t
            .max(kv * h / limits.velocity[j])
            .max((ka * h / limits.acceleration[j]).sqrt())
            .max((kj * h / limits.jerk[j]).cbrt());
    }
    Ok(t)
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
    // (bound of the ratio, derivative polynomial, limit) of every finite limit above `floor`.
    let mut items = [(0.0, [0.0; 6], 1.0); 3 * MAX_QUICK_DOF];
    let n = start.q.len();
    if n > MAX_QUICK_DOF {
        let r = quintic_limit_ratio(start, end, duration, limits);
        return if r > floor { r } else { 0.0 };
    }
    let mut count = 0;
    for j in 0..n {
        for (d, bound) in limited_derivatives(start, end, j, duration, limits) {
            let ub = poly::bound_abs(&d, duration) / bound;
            if ub > floor {
                items[count] = (ub, d, bound);
                count += 1;
            }
        }
    }
    let items = &mut items[..count];
    items.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    let mut worst: f64 = 0.0;
    for (ub, d, bound) in items.iter() {
        if *ub <= worst {
            break;
        }
        worst = worst.max(poly::max_abs(d, duration).1.abs() / bound);
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
    let n = start.check("start")?;
    if end.check("end")? != n {
        return Err(Error::shape(
            "end.q",
            format!("{n} values"),
            format!("{} values", end.q.len()),
        ));
    }
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
    let n = start.check("start")?;
    if end.check("end")? != n {
        return Err(Error::shape(
            "end.q",
            format!("{n} values"),
            format!("{} values", end.q.len()),
        ));
    }
    limits.check_dof(n)?;
    earliest_quintic_duration(start, end, limits, necessary_duration(start, end, limits).max(1e-3))
}

impl super::Samples {
    /// Worst violation per joint of the position, velocity and acceleration limits over the
    /// samples (sampled, unlike [`JointTrajectory::check_limits`]; jerk is not sampled).
    pub fn check_limits(&self, limits: &KinematicLimits) -> Result<Vec<Violation>> {
        limits.check_dof(self.dof)?;
        let n = self.dof;
        let mut out = Vec::new();
        let neg = |v: &[f64]| v.iter().map(|x| -x).collect::<Vec<f64>>();
        let checks = [
            (Quantity::Position, &self.q, limits.lower.clone(), limits.upper.clone()),
            (
                Quantity::Velocity,
                &self.qd,
                neg(&limits.velocity),
                limits.velocity.clone(),
            ),
            (
                Quantity::Acceleration,
                &self.qdd,
                neg(&limits.acceleration),
                limits.acceleration.clone(),
            ),
        ];
        for (quantity, x, lo, hi) in checks {
            for j in 0..n {
                let mut worst: Option<(f64, usize, f64)> = None;
                for (i, row) in x.chunks_exact(n).enumerate() {
                    let v = row[j];
                    let excess = (lo[j] - v).max(v - hi[j]);
                    let slack = LIMIT_TOLERANCE * hi[j].abs().min(lo[j].abs()).max(1.0);
                    if excess > slack && worst.is_none_or(|(e, _, _)| excess > e) {
                        worst = Some((excess, i, v));
                    }
                }
                if let Some((_, i, v)) = worst {
                    out.push(Violation {
                        joint: j,
                        quantity,
                        time: self.t[i],
                        value: v,
                        limit: if v < lo[j] { lo[j] } else { hi[j] },
                    });
                }
            }
        }
        Ok(out)
    }
}
