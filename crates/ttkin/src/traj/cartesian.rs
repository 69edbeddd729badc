//! Task-space trajectories: the tool pose moves along a straight line or a circular arc while its
//! orientation turns on SO(3) by slerp, both driven by one time law s(t) from 0 to 1.
//!
//! Seed 000 §4 (task-space linear and arc interpolation). Poses map the tool frame into the base
//! frame (m); velocities are the tool-origin velocity and the angular velocity, both in base-frame
//! axes. Joint trajectories come from a caller's inverse kinematics at every sample
//! ([`CartesianTrajectory::to_joint`]).

use nalgebra::{IsometryMatrix3, Rotation3, Translation3, Vector3};

use super::{check_duration, rate_times, Samples};
use crate::error::{check_finite, Error, Result};

/// Default blend of the trapezoidal time law (`TimeLaw::Trapezoid`), the one "trapezoid" gives.
pub const TRAPEZOID_BLEND: f64 = 0.25;

/// Time law s(t): the path parameter from 0 at t = 0 to 1 at the duration, at rest at both ends.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum TimeLaw {
    /// s = 3τ² − 2τ³ with τ = t/T (rest-to-rest cubic).
    Cubic,
    /// s = 10τ³ − 15τ⁴ + 6τ⁵ (rest-to-rest quintic, zero acceleration at the ends).
    Quintic,
    /// Trapezoidal speed: constant acceleration for `blend`·T, cruise, constant deceleration for
    /// `blend`·T; `blend` in (0, 0.5] (0.5: triangular speed).
    Trapezoid {
        /// Fraction of the duration spent accelerating (and as much decelerating).
        blend: f64,
    },
}

impl TimeLaw {
    /// Parses "cubic", "quintic" or "trapezoid" (blend 0.25).
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "cubic" => Ok(TimeLaw::Cubic),
            "quintic" => Ok(TimeLaw::Quintic),
            "trapezoid" | "trapezoidal" => Ok(TimeLaw::Trapezoid { blend: TRAPEZOID_BLEND }),
            _ => Err(Error::invalid(
                "law",
                format!("expected cubic, quintic or trapezoid, got '{name}'"),
            )),
        }
    }

    fn validate(&self) -> Result<()> {
        if let TimeLaw::Trapezoid { blend } = *self {
            if !(blend > 0.0 && blend <= 0.5) {
                return Err(Error::invalid("blend", format!("must lie in (0, 0.5], got {blend}")));
            }
        }
        Ok(())
    }

    /// s, ds/dt (1/s), d²s/dt² (1/s²) and d³s/dt³ (1/s³) at `t` ∈ [0, `duration`] s. The trapezoid's
    /// jerk is reported as 0 (it is a Dirac at the switching times).
    pub fn eval(&self, t: f64, duration: f64) -> [f64; 4] {
        let tau = (t / duration).clamp(0.0, 1.0);
        let (d1, d2, d3) = (
            1.0 / duration,
            1.0 / (duration * duration),
            1.0 / (duration * duration * duration),
        );
        match *self {
            TimeLaw::Cubic => [
                tau * tau * (3.0 - 2.0 * tau),
                6.0 * tau * (1.0 - tau) * d1,
                (6.0 - 12.0 * tau) * d2,
                -12.0 * d3,
            ],
            TimeLaw::Quintic => {
                let t2 = tau * tau;
                [
                    t2 * tau * (10.0 + tau * (-15.0 + 6.0 * tau)),
                    30.0 * t2 * (1.0 - tau) * (1.0 - tau) * d1,
                    60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) * d2,
                    60.0 * (1.0 - 6.0 * tau + 6.0 * t2) * d3,
                ]
            }
            TimeLaw::Trapezoid { blend: b } => {
                // Peak speed v = 1/(1 − b) (per unit τ), acceleration a = v/b.
                let v = 1.0 / (1.0 - b);
                let a = v / b;
                if tau < b {
                    [0.5 * a * tau * tau, a * tau * d1, a * d2, 0.0]
                } else if tau <= 1.0 - b {
                    [0.5 * a * b * b + v * (tau - b), v * d1, 0.0, 0.0]
                } else {
                    let r = 1.0 - tau;
                    [1.0 - 0.5 * a * r * r, a * r * d1, -a * d2, 0.0]
                }
            }
        }
    }
}

/// Geometric path of the tool origin, parameterised by s ∈ [0, 1]; base frame, m.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Path {
    /// Straight segment from `start` to `end`.
    Line {
        /// Start point (m).
        start: Vector3<f64>,
        /// End point (m).
        end: Vector3<f64>,
    },
    /// Circular arc p(s) = centre + radius·(cos φ·u + sin φ·w), φ = s·angle, w = axis × u.
    Arc {
        /// Centre of the circle (m).
        centre: Vector3<f64>,
        /// Radius (m).
        radius: f64,
        /// Unit vector from the centre to the start point.
        u: Vector3<f64>,
        /// Unit vector axis × u (direction of motion at the start).
        w: Vector3<f64>,
        /// Unit axis of the circle (right-handed with the motion).
        axis: Vector3<f64>,
        /// Swept angle (rad), positive.
        angle: f64,
    },
}

impl Path {
    /// Point, first and second derivative with respect to s (m, m, m) at `s`.
    pub fn eval(&self, s: f64) -> [Vector3<f64>; 3] {
        match self {
            Path::Line { start, end } => {
                let d = end - start;
                [start + d * s, d, Vector3::zeros()]
            }
            Path::Arc {
                centre,
                radius,
                u,
                w,
                angle,
                ..
            } => {
                let (sn, cs) = (s * angle).sin_cos();
                let radial = u * cs + w * sn;
                let tangent = w * cs - u * sn;
                [
                    centre + radial * *radius,
                    tangent * (radius * angle),
                    -radial * (radius * angle * angle),
                ]
            }
        }
    }

    /// Length of the path (m).
    pub fn length(&self) -> f64 {
        match self {
            Path::Line { start, end } => (end - start).norm(),
            Path::Arc { radius, angle, .. } => radius * angle,
        }
    }
}

/// Pose and its derivatives at one instant; base frame, m and rad.
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianState {
    /// Time (s).
    pub t: f64,
    /// Tool pose in the base frame.
    pub pose: IsometryMatrix3<f64>,
    /// Velocity of the tool origin (m/s), base axes.
    pub velocity: Vector3<f64>,
    /// Angular velocity of the tool (rad/s), base axes.
    pub angular_velocity: Vector3<f64>,
    /// Acceleration of the tool origin (m/s²), base axes.
    pub acceleration: Vector3<f64>,
    /// Angular acceleration of the tool (rad/s²), base axes.
    pub angular_acceleration: Vector3<f64>,
}

impl CartesianState {
    /// Twist [v; ω] (m/s, rad/s), base axes.
    pub fn twist(&self) -> [f64; 6] {
        let (v, w) = (self.velocity, self.angular_velocity);
        [v.x, v.y, v.z, w.x, w.y, w.z]
    }

    /// Twist derivative [a; α] (m/s², rad/s²), base axes.
    pub fn twist_derivative(&self) -> [f64; 6] {
        let (a, b) = (self.acceleration, self.angular_acceleration);
        [a.x, a.y, a.z, b.x, b.y, b.z]
    }
}

/// Tool pose over time: a [`Path`] for the origin, slerp from the start to the end orientation,
/// one [`TimeLaw`] for both.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CartesianTrajectory {
    path: Path,
    law: TimeLaw,
    duration: f64,
    start_rotation: Rotation3<f64>,
    /// Rotation from start to end orientation as a rotation vector in base axes (rad):
    /// R(s) = Exp(s·rotation)·R0.
    rotation: Vector3<f64>,
}

/// Slerp from `r0` to `r1` as a rotation vector in base axes (rad): with R0ᵀR1 = Exp(ω_b) (the
/// shorter way round), R(s) = R0·Exp(s·ω_b) = Exp(s·R0·ω_b)·R0, so the base-axis vector is R0·ω_b.
fn slerp_vector(r0: &Rotation3<f64>, r1: &Rotation3<f64>) -> Vector3<f64> {
    r0 * (r0.inverse() * r1).scaled_axis()
}

fn check_pose(what: &str, t: &IsometryMatrix3<f64>) -> Result<()> {
    let v = t.translation.vector;
    check_finite(what, &[v.x, v.y, v.z])?;
    check_finite(what, t.rotation.matrix().as_slice())
}

fn check_point(what: &str, p: &Vector3<f64>) -> Result<()> {
    check_finite(what, p.as_slice())
}

impl CartesianTrajectory {
    /// `rotation`: rotation vector (rad, base axes) taking the start to the end orientation.
    fn build(path: Path, r0: Rotation3<f64>, rotation: Vector3<f64>, duration: f64, law: TimeLaw) -> Result<Self> {
        check_duration("duration", duration)?;
        law.validate()?;
        Ok(CartesianTrajectory {
            path,
            law,
            duration,
            start_rotation: r0,
            rotation,
        })
    }

    /// `path` in `duration` s with the orientation turning by slerp from `start`'s to `end`'s
    /// (about a fixed axis).
    fn slerped(
        path: Path,
        start: &IsometryMatrix3<f64>,
        end: &IsometryMatrix3<f64>,
        duration: f64,
        law: TimeLaw,
    ) -> Result<Self> {
        Self::build(
            path,
            start.rotation,
            slerp_vector(&start.rotation, &end.rotation),
            duration,
            law,
        )
    }

    /// Straight line from pose `start` to pose `end` (tool in base frame) in `duration` s; the
    /// orientation turns by slerp about a fixed axis.
    pub fn line(start: &IsometryMatrix3<f64>, end: &IsometryMatrix3<f64>, duration: f64, law: TimeLaw) -> Result<Self> {
        check_pose("start", start)?;
        check_pose("end", end)?;
        let path = Path::Line {
            start: start.translation.vector,
            end: end.translation.vector,
        };
        Self::slerped(path, start, end, duration, law)
    }

    /// Circular arc from pose `start` through the point `via` (m, base frame) to pose `end`, in
    /// `duration` s; the orientation turns by slerp from start to end. Errors when the three
    /// points are (nearly) collinear or coincide.
    pub fn arc_through(
        start: &IsometryMatrix3<f64>,
        via: &Vector3<f64>,
        end: &IsometryMatrix3<f64>,
        duration: f64,
        law: TimeLaw,
    ) -> Result<Self> {
        check_pose("start", start)?;
        check_pose("end", end)?;
        check_point("via", via)?;
        let (p0, p2) = (start.translation.vector, end.translation.vector);
        let (a, b) = (via - p0, p2 - p0);
        let n = a.cross(&b);
        let n2 = n.norm_squared();
        if !(n2 > 1e-18 * a.norm_squared() * b.norm_squared()) || n2 == 0.0 {
            return Err(Error::invalid(
                "via",
                "the start, via and end points are collinear or coincide: no unique circle",
            ));
        }
        // Circumcentre of the triangle (p0, via, p2).
        let centre = p0 + (b * a.norm_squared() - a * b.norm_squared()).cross(&n) / (2.0 * n2);
        let axis = n / n2.sqrt();
        let radius = (p0 - centre).norm();
        let u = (p0 - centre) / radius;
        let w = axis.cross(&u);
        let e = p2 - centre;
        let mut angle = e.dot(&w).atan2(e.dot(&u));
        if angle <= 0.0 {
            angle += 2.0 * std::f64::consts::PI;
        }
        let path = Path::Arc {
            centre,
            radius,
            u,
            w,
            axis,
            angle,
        };
        Self::slerped(path, start, end, duration, law)
    }

    /// Circular arc from pose `start` about the line through `centre` (m) along `axis` (base frame)
    /// by `angle` rad (right-handed about `axis`, may be negative), in `duration` s. The tool
    /// turns with the arc: the end orientation is Rot(axis, angle)·R_start.
    pub fn arc_about(
        start: &IsometryMatrix3<f64>,
        centre: &Vector3<f64>,
        axis: &Vector3<f64>,
        angle: f64,
        duration: f64,
        law: TimeLaw,
    ) -> Result<Self> {
        check_pose("start", start)?;
        check_point("centre", centre)?;
        check_point("axis", axis)?;
        check_finite("angle", &[angle])?;
        let norm = axis.norm();
        if !(norm > 0.0) || angle == 0.0 {
            return Err(Error::invalid("axis", "need a nonzero axis and a nonzero angle"));
        }
        let k = axis / norm * angle.signum();
        let p0 = start.translation.vector;
        // The circle's centre is the foot of p0 on the axis line.
        let c = centre + k * (p0 - centre).dot(&k);
        let radius = (p0 - c).norm();
        if !(radius > 1e-12 * (1.0 + p0.norm())) {
            return Err(Error::invalid(
                "centre",
                "the start point lies on the axis: the arc has zero radius",
            ));
        }
        let u = (p0 - c) / radius;
        let path = Path::Arc {
            centre: c,
            radius,
            u,
            w: k.cross(&u),
            axis: k,
            angle: angle.abs(),
        };
        Self::build(path, start.rotation, k * angle.abs(), duration, law)
    }

    /// Duration (s).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The geometric path of the tool origin.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The time law.
    pub fn law(&self) -> TimeLaw {
        self.law
    }

    /// Pose, twist and twist derivative at time `t` (s, in [0, duration]).
    pub fn sample(&self, t: f64) -> Result<CartesianState> {
        if t.is_nan() {
            return Err(Error::NonFinite {
                what: "t".into(),
                index: 0,
                value: t,
            });
        }
        let d = self.duration;
        if t < -1e-9 * d || t > d * (1.0 + 1e-9) {
            return Err(Error::invalid("t", format!("time {t} s is outside [0, {d}] s")));
        }
        let t = t.clamp(0.0, d);
        let [s, sd, sdd, _] = self.law.eval(t, d);
        let [p, dp, ddp] = self.path.eval(s);
        let rot = Rotation3::new(self.rotation * s) * self.start_rotation;
        Ok(CartesianState {
            t,
            pose: IsometryMatrix3::from_parts(Translation3::from(p), rot),
            velocity: dp * sd,
            angular_velocity: self.rotation * sd,
            acceleration: ddp * (sd * sd) + dp * sdd,
            angular_acceleration: self.rotation * sdd,
        })
    }

    /// States at a control rate of `hz` (times as in [`rate_times`]).
    pub fn sample_rate(&self, hz: f64) -> Result<Vec<CartesianState>> {
        if hz > 0.0 {
            crate::budget::check_bytes("hz", self.duration * hz + 2.0, std::mem::size_of::<CartesianState>())?;
        }
        rate_times(self.duration, hz)?
            .into_iter()
            .map(|t| self.sample(t))
            .collect()
    }

    /// Joint samples at `hz` by inverse kinematics at every sample.
    ///
    /// `ik(pose, seed)` returns the joint vector reaching `pose` (tool in base frame), starting
    /// from `seed`: `q_start` for the first sample, then the previous solution. Velocities and
    /// accelerations are finite differences of the solutions on the sample grid (second-order
    /// central inside, second-order one-sided at the ends; exact for quadratic motion). The first
    /// sample the IK cannot solve ends the call with its error, prefixed by its index and time;
    /// `Unreachable` and `Singular` keep their variant.
    pub fn to_joint<F>(&self, hz: f64, q_start: &[f64], mut ik: F) -> Result<Samples>
    where
        F: FnMut(&IsometryMatrix3<f64>, &[f64]) -> Result<Vec<f64>>,
    {
        let dof = q_start.len();
        if dof == 0 {
            return Err(Error::shape("q_start", "at least one joint", "0 values"));
        }
        check_finite("q_start", q_start)?;
        let times = rate_times(self.duration, hz)?;
        let m = times.len();
        let mut q = Vec::with_capacity(m * dof);
        let mut seed = q_start.to_vec();
        for (i, &t) in times.iter().enumerate() {
            let pose = self.sample(t)?.pose;
            let at = |e: String| format!("sample {i} at t = {t} s: {e}");
            let sol = ik(&pose, &seed).map_err(|e| match e {
                Error::Unreachable(m) => Error::Unreachable(at(m)),
                Error::Singular(m) => Error::Singular(at(m)),
                other => Error::invalid("ik", at(other.to_string())),
            })?;
            if sol.len() != dof {
                return Err(Error::shape(
                    at("IK solution".into()),
                    format!("{dof} values"),
                    sol.len(),
                ));
            }
            check_finite(&at("IK solution".into()), &sol)?;
            q.extend_from_slice(&sol);
            seed = sol;
        }
        let (qd, qdd) = differentiate(&times, &q, dof);
        Ok(Samples {
            dof,
            t: times,
            q,
            qd,
            qdd,
        })
    }
}

/// First and second time derivatives of row-major samples `x` (m × dof) on the (possibly
/// non-uniform) grid `t`, by the three-point Lagrange formulas.
fn differentiate(t: &[f64], x: &[f64], dof: usize) -> (Vec<f64>, Vec<f64>) {
    let m = t.len();
    let (mut d1, mut d2) = (vec![0.0; m * dof], vec![0.0; m * dof]);
    if m < 3 {
        if m == 2 {
            let h = t[1] - t[0];
            for j in 0..dof {
                let v = (x[dof + j] - x[j]) / h;
                d1[j] = v;
                d1[dof + j] = v;
            }
        }
        return (d1, d2);
    }
    for i in 0..m {
        // Three-point stencil around i (shifted inwards at the ends).
        let c = i.clamp(1, m - 2);
        let (t0, t1, t2) = (t[c - 1], t[c], t[c + 1]);
        let ti = t[i];
        // Derivatives of the Lagrange basis polynomials at ti.
        let l0 = ((ti - t1) + (ti - t2)) / ((t0 - t1) * (t0 - t2));
        let l1 = ((ti - t0) + (ti - t2)) / ((t1 - t0) * (t1 - t2));
        let l2 = ((ti - t0) + (ti - t1)) / ((t2 - t0) * (t2 - t1));
        let (s0, s1, s2) = (
            2.0 / ((t0 - t1) * (t0 - t2)),
            2.0 / ((t1 - t0) * (t1 - t2)),
            2.0 / ((t2 - t0) * (t2 - t1)),
        );
        for j in 0..dof {
            let (x0, x1, x2) = (x[(c - 1) * dof + j], x[c * dof + j], x[(c + 1) * dof + j]);
            d1[i * dof + j] = l0 * x0 + l1 * x1 + l2 * x2;
            d2[i * dof + j] = s0 * x0 + s1 * x1 + s2 * x2;
        }
    }
    (d1, d2)
}
