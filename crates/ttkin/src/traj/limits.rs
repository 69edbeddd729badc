//! Kinematic limits of joint trajectories: the limit set, exact peak values and the limit checks.
//!
//! Peaks are exact up to rounding: on each polynomial piece the extrema of a derivative lie at the
//! piece's ends or at roots of the next derivative, which [`poly::roots_in`] isolates (closed form
//! up to degree 2, safeguarded Newton above). Nothing is sampled, so a violation between two
//! control ticks is still found. The shortest durations under these limits are
//! [`super::duration`]'s.

use super::{poly, JointTrajectory};
use crate::chain::Chain;
use crate::error::{Error, Result};

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
    /// given jerk limits (+∞ when `None`; robot files carry none). The velocity limits are the
    /// effective ones ([`crate::speed::effective_velocity_limits`]): the robot file's or the
    /// drive's largest speed, the smaller.
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
            velocity: crate::speed::effective_velocity_limits(chain),
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

    /// An error naming `limits` unless the set has `n` joints.
    pub(crate) fn check_dof(&self, n: usize) -> Result<()> {
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
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
    /// Lower-case name: "position", "velocity", "acceleration", "jerk" (also its serde form).
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
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
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

    /// Every joint's worst excess of its velocity, acceleration and jerk limits (to
    /// [`LIMIT_TOLERANCE`]), exactly, with times shifted by `t0` s; `limits` must have
    /// `self.dof()` joints. Cheap bounds first ([`poly::bound_abs`] per segment): the exact peaks
    /// only for the joints and orders they cannot clear.
    pub fn rate_violations(&self, limits: &KinematicLimits, t0: f64) -> Vec<Violation> {
        let mut out = Vec::new();
        for (order, quantity, bound) in [
            (1, Quantity::Velocity, &limits.velocity),
            (2, Quantity::Acceleration, &limits.acceleration),
            (3, Quantity::Jerk, &limits.jerk),
        ] {
            for (j, &bound) in bound.iter().enumerate() {
                let limit = bound * (1.0 + LIMIT_TOLERANCE);
                let mut worst = Peak { time: 0.0, value: 0.0 };
                let mut clear = true;
                for k in 0..self.segments() {
                    let (start, h) = (self.knots()[k], self.knots()[k + 1] - self.knots()[k]);
                    let mut c = self.coefficients(k, j).expect("segment and joint in range");
                    for _ in 0..order {
                        c = poly::derivative(&c);
                    }
                    if poly::bound_abs(&c, h) <= limit {
                        continue;
                    }
                    let (tau, v) = poly::max_abs(&c, h);
                    if v.abs() > limit {
                        clear = false;
                        if v.abs() > worst.value.abs() {
                            worst = Peak {
                                time: start + tau,
                                value: v,
                            };
                        }
                    }
                }
                if !clear {
                    out.push(Violation {
                        joint: j,
                        quantity,
                        time: t0 + worst.time,
                        value: worst.value,
                        limit: bound,
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
