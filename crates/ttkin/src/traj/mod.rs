//! Trajectory generation: joint-space polynomials and via-point splines, task-space lines and arcs
//! under a time law, limit checks and minimal durations, and the table-tennis hitting stroke.
//!
//! Every joint-space trajectory is a [`JointTrajectory`]: piecewise polynomials of degree ≤ 5 in
//! time, one per joint and segment, vectorised over joints. Build one with
//! [`JointTrajectory::cubic`], [`JointTrajectory::quintic`], the via-point constructors of [`via`],
//! or [`stroke::stroke`]; then [`JointTrajectory::sample`] it at any time into preallocated
//! slices, or at a control rate with [`JointTrajectory::sample_rate`]. Task-space motions are
//! [`cartesian::CartesianTrajectory`]s of tool poses, turned into joint samples by a caller's IK.
//!
//! Units: time in s, joint values in rad (revolute) or m (prismatic), their derivatives per s,
//! s², s³. Time runs from 0 to [`JointTrajectory::duration`].

/// Default rate (Hz) at which sampled trajectories are handed out (Python's `sample`, `check_limits`,
/// task trajectories: their `rate_hz`).
pub const SAMPLE_HZ: f64 = 1000.0;

/// Deprecated name of [`SAMPLE_HZ`] (a rate in Hz is named `*_hz`, see the glossary).
#[deprecated(since = "0.1.0", note = "use SAMPLE_HZ (a rate in Hz is named *_hz)")]
pub const SAMPLE_RATE: f64 = SAMPLE_HZ;

/// Default number of evenly spaced samples of a sampled segment (`traj_quintic_samples`).
pub const SAMPLES: usize = 101;

pub mod cartesian;
pub mod duration;
pub mod jerk;
pub mod limits;
pub mod poly;
pub mod stroke;
pub mod via;

use crate::error::{check_finite, check_vector, Error, Result};
use poly::Coeffs;

pub use cartesian::{CartesianState, CartesianTrajectory, Path, TimeLaw};
pub use limits::{KinematicLimits, Quantity, Violation};
pub use stroke::{stroke, Stroke};

/// Coefficient rows per segment in [`JointTrajectory`]: q (6), q̇ (5), q̈ (4).
const ROWS: usize = 15;

/// Relative slack on the time interval: times in [−ε·T, (1 + ε)·T] are clamped into [0, T].
const TIME_SLACK: f64 = 1e-9;

/// A joint state: positions (rad or m), velocities (per s) and accelerations (per s²), one entry
/// per joint.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointState {
    /// Joint positions (rad or m).
    pub q: Vec<f64>,
    /// Joint velocities (rad/s or m/s).
    pub qd: Vec<f64>,
    /// Joint accelerations (rad/s² or m/s²).
    pub qdd: Vec<f64>,
}

impl JointState {
    /// A state at rest at `q`.
    pub fn rest(q: &[f64]) -> Self {
        JointState {
            q: q.to_vec(),
            qd: vec![0.0; q.len()],
            qdd: vec![0.0; q.len()],
        }
    }

    /// Coefficients (ascending powers of τ, s) of joint `j`'s quintic from this state to `end` in
    /// `duration` s; `j` must be a joint of both.
    pub(crate) fn quintic_to(&self, end: &JointState, j: usize, duration: f64) -> poly::Coeffs {
        poly::quintic(
            self.q[j],
            self.qd[j],
            self.qdd[j],
            end.q[j],
            end.qd[j],
            end.qdd[j],
            duration,
        )
    }

    /// Number of joints, after checking that the three vectors agree and are finite.
    pub fn check(&self, what: &str) -> Result<usize> {
        let n = self.q.len();
        if n == 0 {
            return Err(Error::shape(format!("{what}.q"), "at least one joint", "0 values"));
        }
        check_vector(&format!("{what}.q"), &self.q, n)?;
        check_vector(&format!("{what}.qd"), &self.qd, n)?;
        check_vector(&format!("{what}.qdd"), &self.qdd, n)?;
        Ok(n)
    }

    /// [`JointState::check`] of two states, `self` named `what` and `other` named `other_what`,
    /// and an error naming `other_what.q` unless both have the same number of joints.
    pub(crate) fn check_pair(&self, what: &str, other: &JointState, other_what: &str) -> Result<usize> {
        let n = self.check(what)?;
        if other.check(other_what)? != n {
            return Err(Error::shape(
                format!("{other_what}.q"),
                format!("{n} values"),
                format!("{} values", other.q.len()),
            ));
        }
        Ok(n)
    }
}

/// Samples of a joint trajectory: times (s) and row-major (sample, joint) arrays of positions,
/// velocities and accelerations.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    /// Number of joints (the row length).
    pub dof: usize,
    /// Sample times (s).
    pub t: Vec<f64>,
    /// Positions (rad or m), `t.len() × dof`, row-major.
    pub q: Vec<f64>,
    /// Velocities (rad/s or m/s), `t.len() × dof`, row-major.
    pub qd: Vec<f64>,
    /// Accelerations (rad/s² or m/s²), `t.len() × dof`, row-major.
    pub qdd: Vec<f64>,
}

/// Sample times at `hz` from 0 to `duration` s: k/hz for k = 0, 1, … while ≤ duration, then
/// `duration` itself if the grid misses it.
pub fn rate_times(duration: f64, hz: f64) -> Result<Vec<f64>> {
    if !(hz > 0.0) || !hz.is_finite() {
        return Err(Error::invalid(
            "hz",
            format!("sample rate must be finite and > 0, got {hz}"),
        ));
    }
    let n = (duration * hz * (1.0 + 1e-12)).floor();
    if n > 1e8 {
        return Err(Error::invalid(
            "hz",
            format!("{hz} Hz over {duration} s gives more than 1e8 samples"),
        ));
    }
    let n = crate::budget::check_bytes("hz", n + 2.0, std::mem::size_of::<f64>())? - 2;
    let mut t: Vec<f64> = (0..=n).map(|k| (k as f64 / hz).min(duration)).collect();
    if duration - t[n] > TIME_SLACK * duration {
        t.push(duration);
    }
    Ok(t)
}

/// Checks a duration: finite and > 0 s.
pub fn check_duration(what: &str, duration: f64) -> Result<()> {
    if !duration.is_finite() {
        return Err(Error::NonFinite {
            what: what.to_string(),
            index: 0,
            value: duration,
        });
    }
    if !(duration > 0.0) {
        return Err(Error::invalid(what, format!("duration must be > 0 s, got {duration}")));
    }
    Ok(())
}

/// Joint-space trajectory: for each of `segments()` time intervals [t_k, t_{k+1}] and each joint, a
/// polynomial of degree ≤ 5 in τ = t − t_k (s). Immutable once built; sampling allocates nothing.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointTrajectory {
    dof: usize,
    /// Segment boundaries (s), strictly increasing, `knots[0] = 0`.
    knots: Vec<f64>,
    /// Row-major table of `ROWS` rows of `dof` values per segment: the coefficients of q, q̇ and q̈
    /// in ascending powers of τ (6 + 5 + 4 rows). Row r of segment k, joint j is at
    /// `powers[(ROWS·k + r)·dof + j]`: one power of all joints is contiguous, so sampling
    /// vectorises over joints and does no multiplication beyond Horner's.
    powers: Vec<f64>,
}

impl JointTrajectory {
    /// Builds from knots (s, strictly increasing from 0) and per-segment, per-joint coefficients.
    /// `coeffs[k·dof + j]` is the polynomial of joint j on segment k.
    pub(crate) fn from_parts(dof: usize, knots: Vec<f64>, coeffs: Vec<Coeffs>) -> Self {
        debug_assert!(knots.len() >= 2 && coeffs.len() == (knots.len() - 1) * dof);
        // Written in storage order (segment, row, joint): no zeroed buffer, no scattered writes.
        let mut powers = Vec::with_capacity(coeffs.len() * ROWS);
        let mut rows: Vec<[f64; ROWS]> = vec![[0.0; ROWS]; dof];
        for seg in coeffs.chunks_exact(dof.max(1)) {
            for (out, c) in rows.iter_mut().zip(seg) {
                let d1 = poly::derivative(c);
                let d2 = poly::derivative(&d1);
                for (o, &v) in out.iter_mut().zip(c.iter().chain(&d1[..5]).chain(&d2[..4])) {
                    *o = v;
                }
            }
            for r in 0..ROWS {
                powers.extend(rows.iter().map(|row| row[r]));
            }
        }
        JointTrajectory { dof, knots, powers }
    }

    /// This trajectory, then `next` (m or rad, s; same joints) from this one's end: its time 0 at
    /// this one's duration. An error when the joint counts differ.
    pub fn then(self, next: JointTrajectory) -> Result<Self> {
        if next.dof() != self.dof() {
            return Err(Error::shape(
                "next",
                format!("{} joints", self.dof()),
                format!("{}", next.dof()),
            ));
        }
        Ok(self.append(next))
    }

    /// Appends the segments of `next` (same dof) after this trajectory's end.
    pub(crate) fn append(mut self, next: JointTrajectory) -> Self {
        let end = self.duration();
        self.knots.extend(next.knots[1..].iter().map(|t| end + t));
        self.powers.extend(next.powers);
        self
    }

    /// Cubic from `q0` to `q1` (rad or m) in `duration` s with boundary velocities `v0`, `v1`
    /// (zero when `None`): the corrected seed-001 formulas (see [`poly`]).
    pub fn cubic(q0: &[f64], q1: &[f64], v0: Option<&[f64]>, v1: Option<&[f64]>, duration: f64) -> Result<Self> {
        let n = check_ends(q0, q1, duration)?;
        let (v0, v1) = (optional("v0", v0, n)?, optional("v1", v1, n)?);
        let coeffs = (0..n)
            .map(|j| poly::cubic(q0[j], q1[j], v0(j), v1(j), duration))
            .collect();
        Ok(Self::from_parts(n, vec![0.0, duration], coeffs))
    }

    /// Quintic from `q0` to `q1` (rad or m) in `duration` s with boundary velocities `v0`, `v1` and
    /// accelerations `a0`, `a1` (zero when `None`): the patent's step S104 (see [`poly`]).
    pub fn quintic(
        q0: &[f64],
        q1: &[f64],
        v0: Option<&[f64]>,
        v1: Option<&[f64]>,
        a0: Option<&[f64]>,
        a1: Option<&[f64]>,
        duration: f64,
    ) -> Result<Self> {
        let n = check_ends(q0, q1, duration)?;
        let (v0, v1) = (optional("v0", v0, n)?, optional("v1", v1, n)?);
        let (a0, a1) = (optional("a0", a0, n)?, optional("a1", a1, n)?);
        let coeffs = (0..n)
            .map(|j| poly::quintic(q0[j], v0(j), a0(j), q1[j], v1(j), a1(j), duration))
            .collect();
        Ok(Self::from_parts(n, vec![0.0, duration], coeffs))
    }

    /// Quintic between two full joint states in `duration` s.
    pub fn quintic_between(start: &JointState, end: &JointState, duration: f64) -> Result<Self> {
        start.check_pair("start", end, "end")?;
        check_duration("duration", duration)?;
        Ok(Self::quintic_unchecked(start, end, duration))
    }

    /// Quintic between states already checked for shape and finiteness.
    pub(crate) fn quintic_unchecked(start: &JointState, end: &JointState, duration: f64) -> Self {
        let coeffs = (0..start.q.len()).map(|j| start.quintic_to(end, j, duration)).collect();
        Self::from_parts(start.q.len(), vec![0.0, duration], coeffs)
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Bytes this trajectory holds on the heap (knots and coefficient table).
    pub fn heap_bytes(&self) -> usize {
        (self.knots.capacity() + self.powers.capacity()) * std::mem::size_of::<f64>()
    }

    /// Heap bytes of the smallest stroke of `dof` joints that has `segments` segments.
    pub fn heap_bytes_at_least(dof: usize, segments: usize) -> usize {
        (segments + 1 + ROWS * segments * dof) * std::mem::size_of::<f64>()
    }

    /// Total duration (s).
    pub fn duration(&self) -> f64 {
        self.knots[self.knots.len() - 1]
    }

    /// Number of polynomial segments.
    pub fn segments(&self) -> usize {
        self.knots.len() - 1
    }

    /// Segment boundaries (s), from 0 to the duration.
    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Coefficients (ascending powers of τ = t − t_k) of joint `joint` on segment `segment`.
    pub fn coefficients(&self, segment: usize, joint: usize) -> Option<Coeffs> {
        if joint >= self.dof || segment >= self.segments() {
            return None;
        }
        let mut c = [0.0; 6];
        for (p, v) in c.iter_mut().enumerate() {
            *v = self.powers[(ROWS * segment + p) * self.dof + joint];
        }
        Some(c)
    }

    /// Every coefficient as one (segments, dof, 6) row-major table: segment, joint, then
    /// ascending powers of the local time τ = t − knot (s), as [`JointTrajectory::coefficients`].
    pub fn coefficient_table(&self) -> Vec<f64> {
        let (k, n) = (self.segments(), self.dof);
        let mut flat = vec![0.0; k * n * 6];
        for (i, c) in flat.chunks_exact_mut(6).enumerate() {
            let (segment, joint) = (i / n, i % n);
            for (p, v) in c.iter_mut().enumerate() {
                *v = self.powers[(ROWS * segment + p) * n + joint];
            }
        }
        flat
    }

    /// The `ROWS` coefficient rows (each `dof` long) of segment `k`: q (τ⁰…τ⁵), q̇ (τ⁰…τ⁴), q̈ (τ⁰…τ³).
    #[inline]
    fn rows(&self, k: usize) -> [&[f64]; ROWS] {
        let n = self.dof;
        let seg = &self.powers[ROWS * k * n..ROWS * (k + 1) * n];
        std::array::from_fn(|r| &seg[r * n..(r + 1) * n])
    }

    /// The segment holding `t` and the local time in it; `t` must lie in [0, duration].
    #[inline]
    fn locate(&self, t: f64) -> (usize, f64) {
        let last = self.knots.len() - 2;
        let k = self.knots[1..=last].partition_point(|&knot| knot <= t);
        (k, t - self.knots[k])
    }

    /// Checks `t` and clamps it into [0, duration] (slack 1e-9 relative for rounding).
    fn check_time(&self, t: f64) -> Result<f64> {
        let d = self.duration();
        if t.is_nan() {
            return Err(Error::NonFinite {
                what: "t".into(),
                index: 0,
                value: t,
            });
        }
        if t < -TIME_SLACK * d || t > d * (1.0 + TIME_SLACK) {
            return Err(Error::invalid("t", format!("time {t} s is outside [0, {d}] s")));
        }
        Ok(t.clamp(0.0, d))
    }

    fn check_out(&self, what: &str, out: &[f64]) -> Result<()> {
        if out.len() != self.dof {
            return Err(Error::shape(
                what,
                format!("{} values", self.dof),
                format!("{} values", out.len()),
            ));
        }
        Ok(())
    }

    /// Writes position, velocity and acceleration of every joint at time `t` (s, in
    /// [0, duration]) into `q`, `qd`, `qdd` (each `dof` long). Allocates nothing.
    pub fn sample(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) -> Result<()> {
        let t = self.check_time(t)?;
        self.check_out("q", q)?;
        self.check_out("qd", qd)?;
        self.check_out("qdd", qdd)?;
        self.sample_unchecked(t, q, qd, qdd);
        Ok(())
    }

    #[inline]
    pub(crate) fn sample_unchecked(&self, t: f64, q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) {
        let (k, tau) = self.locate(t);
        let n = self.dof;
        let rows = self.rows(k);
        // Re-sliced to exactly n so that the compiler drops the bounds checks in the loop.
        let r: [&[f64]; ROWS] = std::array::from_fn(|i| &rows[i][..n]);
        let (q, qd, qdd) = (&mut q[..n], &mut qd[..n], &mut qdd[..n]);
        for j in 0..n {
            let c = |i: usize| r[i][j];
            q[j] = ((((c(5) * tau + c(4)) * tau + c(3)) * tau + c(2)) * tau + c(1)) * tau + c(0);
            qd[j] = (((c(10) * tau + c(9)) * tau + c(8)) * tau + c(7)) * tau + c(6);
            qdd[j] = ((c(14) * tau + c(13)) * tau + c(12)) * tau + c(11);
        }
    }

    /// Writes the jerk (third derivative, per s³) of every joint at time `t` (s) into `jerk`.
    pub fn jerk(&self, t: f64, jerk: &mut [f64]) -> Result<()> {
        let t = self.check_time(t)?;
        self.check_out("jerk", jerk)?;
        let (k, tau) = self.locate(t);
        let r = self.rows(k);
        for j in 0..self.dof {
            // Jerk is the derivative of q̈ = d0 + d1·τ + d2·τ² + d3·τ³ (rows 11–14).
            jerk[j] = (3.0 * r[14][j] * tau + 2.0 * r[13][j]) * tau + r[12][j];
        }
        Ok(())
    }

    /// Samples at the given times (s, each in [0, duration]).
    pub fn sample_times(&self, times: &[f64]) -> Result<Samples> {
        crate::budget::check_bytes("times", times.len() as f64, 8 * (1 + 3 * self.dof))?;
        let m = times.len() * self.dof;
        let mut s = Samples {
            dof: self.dof,
            t: times.to_vec(),
            q: vec![0.0; m],
            qd: vec![0.0; m],
            qdd: vec![0.0; m],
        };
        self.sample_times_into(times, &mut s.q, &mut s.qd, &mut s.qdd)?;
        Ok(s)
    }

    /// Samples at the given times into row-major `times.len() × dof` slices. Allocates nothing.
    pub fn sample_times_into(&self, times: &[f64], q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) -> Result<()> {
        let m = times.len() * self.dof;
        for (what, out) in [("q", &*q), ("qd", &*qd), ("qdd", &*qdd)] {
            if out.len() != m {
                return Err(Error::shape(
                    what,
                    format!("{m} values"),
                    format!("{} values", out.len()),
                ));
            }
        }
        for (i, &t) in times.iter().enumerate() {
            let t = self.check_time(t)?;
            let r = i * self.dof..(i + 1) * self.dof;
            self.sample_unchecked(t, &mut q[r.clone()], &mut qd[r.clone()], &mut qdd[r]);
        }
        Ok(())
    }

    /// Samples at a control rate of `hz`: times k/hz while ≤ duration, plus the end time if the grid
    /// misses it (see [`rate_times`]).
    pub fn sample_rate(&self, hz: f64) -> Result<Samples> {
        // The times and q, qd, qdd: 1 + 3·dof float64 values a sample, bounded before allocating.
        if hz > 0.0 {
            crate::budget::check_bytes("hz", self.duration() * hz + 2.0, 8 * (1 + 3 * self.dof))?;
        }
        self.sample_times(&rate_times(self.duration(), hz)?)
    }

    /// Checks the output lengths of a uniform sampling (n ≥ 2 times, n × dof values each) and
    /// writes the n evenly spaced times from 0 to the duration (the last one exactly) into `t`.
    fn uniform_grid(&self, t: &mut [f64], q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<()> {
        let n = t.len();
        if n < 2 {
            return Err(Error::shape("t", "at least 2 samples", format!("{n} samples")));
        }
        let m = n * self.dof;
        for (what, out) in [("q", q), ("qd", qd), ("qdd", qdd)] {
            if out.len() != m {
                return Err(Error::shape(
                    what,
                    format!("{m} values"),
                    format!("{} values", out.len()),
                ));
            }
        }
        let d = self.duration();
        let step = d / (n - 1) as f64;
        for (i, ti) in t.iter_mut().enumerate() {
            *ti = if i + 1 == n { d } else { i as f64 * step };
        }
        Ok(())
    }

    /// `n ≥ 2` samples evenly spaced from 0 to the duration, into row-major `n × dof` slices and
    /// `t` (n long). Allocates nothing.
    pub fn sample_uniform_into(&self, t: &mut [f64], q: &mut [f64], qd: &mut [f64], qdd: &mut [f64]) -> Result<()> {
        self.uniform_grid(t, q, qd, qdd)?;
        for (i, &ti) in t.iter().enumerate() {
            let r = i * self.dof..(i + 1) * self.dof;
            self.sample_unchecked(ti, &mut q[r.clone()], &mut qd[r.clone()], &mut qdd[r]);
        }
        Ok(())
    }

    /// `n ≥ 2` samples evenly spaced from 0 to the duration, written joint-major: `t` (n long) and
    /// `q[j·n + i]`, `qd[j·n + i]`, `qdd[j·n + i]` for joint j at sample i (an n × dof array in
    /// column-major, numpy's Fortran, order). Same values as [`Self::sample_uniform_into`], about
    /// 1.6× faster (the loop over samples vectorises). Allocates nothing.
    pub fn sample_uniform_columns_into(
        &self,
        t: &mut [f64],
        q: &mut [f64],
        qd: &mut [f64],
        qdd: &mut [f64],
    ) -> Result<()> {
        self.uniform_grid(t, q, qd, qdd)?;
        let n = t.len();
        // Samples [start, end) fall in segment k (the last segment also takes t = duration).
        let mut start = 0;
        for k in 0..self.segments() {
            let end = if k + 1 == self.segments() {
                n
            } else {
                start + t[start..].partition_point(|&ti| ti < self.knots[k + 1])
            };
            let knot = self.knots[k];
            let rows = self.rows(k);
            // `j` picks one column across all fifteen rows: no single iterator to enumerate instead.
            #[allow(clippy::needless_range_loop)]
            for j in 0..self.dof {
                let c: [f64; ROWS] = std::array::from_fn(|r| rows[r][j]);
                let col = j * n + start..j * n + end;
                let (qj, qdj, qddj) = (&mut q[col.clone()], &mut qd[col.clone()], &mut qdd[col]);
                let out = qj.iter_mut().zip(qdj.iter_mut()).zip(qddj.iter_mut());
                for (&ti, ((a, b), e)) in t[start..end].iter().zip(out) {
                    let tau = ti - knot;
                    *a = ((((c[5] * tau + c[4]) * tau + c[3]) * tau + c[2]) * tau + c[1]) * tau + c[0];
                    *b = (((c[10] * tau + c[9]) * tau + c[8]) * tau + c[7]) * tau + c[6];
                    *e = ((c[14] * tau + c[13]) * tau + c[12]) * tau + c[11];
                }
            }
            start = end;
        }
        Ok(())
    }

    /// The state (position, velocity, acceleration) at time `t` (s).
    pub fn state(&self, t: f64) -> Result<JointState> {
        let mut s = JointState::rest(&vec![0.0; self.dof]);
        self.sample(t, &mut s.q, &mut s.qd, &mut s.qdd)?;
        Ok(s)
    }
}

/// Checks the two end positions and the duration of a single segment; returns the joint count.
fn check_ends(q0: &[f64], q1: &[f64], duration: f64) -> Result<usize> {
    let n = q0.len();
    if n == 0 {
        return Err(Error::shape("q0", "at least one joint", "0 values"));
    }
    check_finite("q0", q0)?;
    check_vector("q1", q1, n)?;
    check_duration("duration", duration)?;
    Ok(n)
}

/// An optional per-joint vector as a closure returning 0 when absent.
fn optional<'a>(what: &str, v: Option<&'a [f64]>, n: usize) -> Result<impl Fn(usize) -> f64 + 'a> {
    if let Some(v) = v {
        check_vector(what, v, n)?;
    }
    Ok(move |j: usize| v.map_or(0.0, |v| v[j]))
}
