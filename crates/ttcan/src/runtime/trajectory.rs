//! Joint trajectories for the controller: the CSV file written by `ttmanip.ctl.write_trajectory`
//! (header `t,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun`, SI, strictly increasing t), a built-in demo
//! motion, and sampling with linear interpolation (no allocation) preceded by a quintic approach
//! from where the axes are to the first sample.
//!
//! A file is checked as the run would meet it: rows at least [`MIN_STEP_S`] apart (a subnormal
//! step made the target jump in zero time, which the drives refuse at run time) and, per joint
//! and step, the change of q equal to the integral of its velocity column within
//! [`POSITION_TOLERANCE`] + [`RELATIVE_TOLERANCE`]·|Δq| (a position jump the velocity column
//! does not show is refused by the drives as a target beyond their step limit, EMCY 0xFF01).
//! The integral is the trapezoid rule with its end correction from the acceleration column,
//! Δt/2·(q̇ₐ + q̇_b) − Δt²/12·(q̈_b − q̈ₐ) (Euler–Maclaurin; exact for a cubic q, that is for
//! piecewise-constant jerk), so files sampled from smooth or jerk-limited strokes pass at any
//! rate down to tens of Hz.

use std::fmt;

/// A sampled joint trajectory, SI (rad or m, rad/s or m/s, N·m or N), `n` joints.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    n: usize,
    t: Vec<f64>,
    /// Rows of `q, qd, qdd, tau` (4n values per sample).
    rows: Vec<f64>,
}

/// What is wrong with a trajectory file.
#[derive(Debug, Clone, PartialEq)]
pub struct TrajectoryError {
    /// 1-based line number (0: the whole file).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for TrajectoryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for TrajectoryError {}

fn err(line: usize, message: impl Into<String>) -> TrajectoryError {
    TrajectoryError {
        line,
        message: message.into(),
    }
}

/// The shortest controller cycle, s (`cycle_hz` ≤ 10 kHz): a trajectory's times must resolve it.
pub const MIN_CYCLE_S: f64 = 1e-4;

/// The shortest step between two rows of a trajectory file, s (1 µs: 100 rows within the
/// shortest controller cycle).
pub const MIN_STEP_S: f64 = 1e-6;

/// Absolute part of the tolerance between a step's change of q and the integral of qd over it,
/// rad or m (files written with 9 significant digits round to about 1e-9 of their values).
pub const POSITION_TOLERANCE: f64 = 1e-6;

/// Relative part of that tolerance (of the larger of |Δq| and |∫qd|).
pub const RELATIVE_TOLERANCE: f64 = 1e-3;

/// The change of q over a step of `dt` s that the velocity and acceleration columns imply:
/// the trapezoid rule with its end correction (exact for a cubic q).
pub fn integrated_step(dt: f64, qd: (f64, f64), qdd: (f64, f64)) -> f64 {
    0.5 * dt * (qd.0 + qd.1) - dt * dt / 12.0 * (qdd.1 - qdd.0)
}

/// Checks the step from row `a` to row `b` (values `t, q1..qn, qd1..qdn, qdd1..qddn, ...`) of a
/// trajectory of `n` joints: [`MIN_STEP_S`] and q against ∫qd (see the module's documentation).
fn check_step(n: usize, cols: &[&str], a: &[f64], b: &[f64], prev_line: usize) -> Result<(), String> {
    let dt = b[0] - a[0];
    if dt < MIN_STEP_S {
        return Err(format!(
            "t steps by {dt:e} s from line {prev_line}, less than the {MIN_STEP_S:e} s rows must be apart"
        ));
    }
    for j in 0..n {
        let (q, qd, qdd) = (1 + j, 1 + n + j, 1 + 2 * n + j);
        let moved = b[q] - a[q];
        let integral = integrated_step(dt, (a[qd], b[qd]), (a[qdd], b[qdd]));
        let tolerance = POSITION_TOLERANCE + RELATIVE_TOLERANCE * moved.abs().max(integral.abs());
        // an overflow to inf or NaN (values near the double range) is refused too
        if !(moved.is_finite() && integral.is_finite() && (moved - integral).abs() <= tolerance) {
            return Err(format!(
                "{} moves by {moved:e} from line {prev_line} in {dt:e} s, but {} and {} integrate to {integral:e}: \
                 a position jump the velocity column does not show (the drives refuse it as a target step); \
                 they must agree within {POSITION_TOLERANCE:e} + {RELATIVE_TOLERANCE:e}·|Δq|",
                cols[q], cols[qd], cols[qdd]
            ));
        }
    }
    Ok(())
}

/// One sample: per joint (q, qd, qdd, tau).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointSample {
    /// Position.
    pub q: f64,
    /// Velocity.
    pub qd: f64,
    /// Acceleration.
    pub qdd: f64,
    /// Torque feed-forward.
    pub tau: f64,
}

impl Trajectory {
    /// Parses the CSV text of a trajectory file (lines starting with `#` are comments).
    pub fn parse(text: &str) -> Result<Self, TrajectoryError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
        let (hl, header) = lines.next().ok_or_else(|| err(0, "empty trajectory file"))?;
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        if cols.first() != Some(&"t") || cols.len() < 5 || !(cols.len() - 1).is_multiple_of(4) {
            return Err(err(hl + 1, "header must be t,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun"));
        }
        let n = (cols.len() - 1) / 4;
        let (mut t, mut rows) = (Vec::new(), Vec::new());
        let mut prev: Option<(usize, Vec<f64>)> = None;
        for (k, line) in lines {
            let vals: Result<Vec<f64>, _> = line.split(',').map(|s| s.trim().parse::<f64>()).collect();
            let vals = vals.map_err(|e| err(k + 1, format!("not a number: {e}")))?;
            if vals.len() != cols.len() {
                return Err(err(
                    k + 1,
                    format!("{} values, the header has {}", vals.len(), cols.len()),
                ));
            }
            if let Some(bad) = vals.iter().position(|v| !v.is_finite()) {
                return Err(err(k + 1, format!("column {} ({}) is not finite", bad + 1, cols[bad])));
            }
            // the controller samples at up to 10 kHz from t[0] + t: far from zero float64 times
            // are too coarse for that (at 1e17 s they are 16 s apart) and the targets would jump
            if let Err(e) = ttkin::budget::check_clock("t", vals[0], MIN_CYCLE_S) {
                return Err(err(k + 1, e.to_string()));
            }
            if t.last().is_some_and(|&p| vals[0] <= p) {
                return Err(err(k + 1, "t must increase strictly"));
            }
            if let Some((line, a)) = &prev {
                check_step(n, &cols, a, &vals, *line).map_err(|m| err(k + 1, m))?;
            }
            t.push(vals[0]);
            rows.extend_from_slice(&vals[1..]);
            prev = Some((k + 1, vals));
        }
        if t.len() < 2 {
            return Err(err(0, "a trajectory needs at least two samples"));
        }
        Ok(Trajectory { n, t, rows })
    }

    /// The demo motion: every joint moves by `amplitude` and back, a cosine bump over `duration` s,
    /// sampled at 1 kHz; joint k has phase k/n of a period so the axes do not move in step.
    pub fn demo(n: usize, amplitude: f64, duration: f64) -> Self {
        let samples = (duration * 1000.0).round().max(2.0) as usize;
        let (mut t, mut rows) = (
            Vec::with_capacity(samples + 1),
            Vec::with_capacity(4 * n * (samples + 1)),
        );
        let w = 2.0 * std::f64::consts::PI / duration;
        for s in 0..=samples {
            let tt = s as f64 * duration / samples as f64;
            t.push(tt);
            let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            for j in 0..n {
                let a = amplitude * if j % 2 == 0 { 1.0 } else { -1.0 };
                q[j] = 0.5 * a * (1.0 - (w * tt).cos());
                qd[j] = 0.5 * a * w * (w * tt).sin();
                qdd[j] = 0.5 * a * w * w * (w * tt).cos();
            }
            rows.extend(q);
            rows.extend(qd);
            rows.extend(qdd);
            rows.extend(std::iter::repeat_n(0.0, n));
        }
        Trajectory { n, t, rows }
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.n
    }

    /// The samples of joint `j` in file order (`j` < [`Self::joints`]).
    pub fn samples(&self, j: usize) -> impl Iterator<Item = JointSample> + '_ {
        let n = self.n;
        self.rows.chunks_exact(4 * n).map(move |r| JointSample {
            q: r[j],
            qd: r[n + j],
            qdd: r[2 * n + j],
            tau: r[3 * n + j],
        })
    }

    /// Duration from the first to the last sample, s.
    pub fn duration(&self) -> f64 {
        self.t[self.t.len() - 1] - self.t[0]
    }

    /// Sample of joint `j` at time `t` (s from the first sample; clamped to the ends; linear
    /// interpolation between samples). Never allocates.
    pub fn sample(&self, j: usize, t: f64) -> JointSample {
        let tt = self.t[0] + t.clamp(0.0, self.duration());
        let k = match self.t.binary_search_by(|x| x.total_cmp(&tt)) {
            Ok(k) => k.min(self.t.len() - 2),
            Err(k) => k.clamp(1, self.t.len() - 1) - 1,
        };
        let s = ((tt - self.t[k]) / (self.t[k + 1] - self.t[k])).clamp(0.0, 1.0);
        let w = 4 * self.n;
        let at = |c: usize| {
            let a = self.rows[k * w + c * self.n + j];
            let b = self.rows[(k + 1) * w + c * self.n + j];
            a + s * (b - a)
        };
        JointSample {
            q: at(0),
            qd: at(1),
            qdd: at(2),
            tau: at(3),
        }
    }
}

/// Quintic blend from `from` to `to` over `duration` s at time `t` (zero velocity and acceleration
/// at both ends): position and velocity.
pub fn approach(from: f64, to: f64, duration: f64, t: f64) -> (f64, f64) {
    if duration <= 0.0 {
        return (to, 0.0);
    }
    let [p, v, _, _] = ttkin::traj::cartesian::TimeLaw::Quintic.eval(t, duration);
    (from + (to - from) * p, (to - from) * v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_sample_and_errors_name_the_line() {
        let text = "# ttctl trajectory v1\nt,q1,qd1,qdd1,tau1\n0,0,1,0,0\n1,1,1,0,0.5\n";
        let tr = Trajectory::parse(text).unwrap();
        assert_eq!(tr.joints(), 1);
        let s = tr.sample(0, 0.25);
        assert!((s.q - 0.25).abs() < 1e-12 && (s.tau - 0.125).abs() < 1e-12);
        assert_eq!(tr.sample(0, 5.0).q, 1.0);
        let e = Trajectory::parse("t,q1,qd1,qdd1,tau1\n0,0,0,0,0\n0,1,x,0,0\n").unwrap_err();
        assert_eq!(e.line, 3);
        let e = Trajectory::parse("t,q1,qd1,qdd1,tau1\n0,0,0,0,0\n0,1,0,0,0\n").unwrap_err();
        assert!(e.message.contains("increase"));
        assert!(Trajectory::parse("t,q1\n0,1\n").is_err());
        // times too far from zero for a 10 kHz cycle are refused with their line
        let e = Trajectory::parse("t,q1,qd1,qdd1,tau1\n1e17,0,0,0,0\n1.0000000000001e17,0,0,0,0\n").unwrap_err();
        assert!(e.line == 2 && e.message.contains("nearer origin"), "{e}");
        assert!(Trajectory::parse("t,q1,qd1,qdd1,tau1\n0,0,0,0,0\n1e300,0,0,0,0\n").is_err());
        let tr = Trajectory::parse("t,q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2\n0,1,2,3,4,5,6,7,8\n1,8,10,11,12,5,6,15,16\n")
            .unwrap();
        let s: Vec<_> = tr.samples(1).map(|s| (s.q, s.qd, s.qdd, s.tau)).collect();
        assert_eq!(s, vec![(2.0, 4.0, 6.0, 8.0), (10.0, 12.0, 6.0, 16.0)]);
    }

    /// The rows of `tr` as the CSV text `ttmanip.ctl.write_trajectory` writes (9 digits).
    fn csv(tr: &Trajectory) -> String {
        let n = tr.joints();
        let mut text = String::from("t");
        for c in ["q", "qd", "qdd", "tau"] {
            for j in 0..n {
                text += &format!(",{c}{}", j + 1);
            }
        }
        text.push('\n');
        for (t, row) in tr.t.iter().zip(tr.rows.chunks_exact(4 * n)) {
            text += &format!("{t:.9e}");
            for v in row {
                text += &format!(",{v:.9e}");
            }
            text.push('\n');
        }
        text
    }

    #[test]
    fn smooth_motions_pass_the_consistency_check_at_coarse_rates() {
        // the demo's cosine bump sampled at 1 kHz, and at 50 Hz (every 20th row)
        let tr = Trajectory::demo(3, 0.3, 2.0);
        assert_eq!(Trajectory::parse(&csv(&tr)).unwrap().joints(), 3);
        let coarse = Trajectory {
            n: 3,
            t: tr.t.iter().step_by(20).copied().collect(),
            rows: tr.rows.chunks_exact(12).step_by(20).flatten().copied().collect(),
        };
        Trajectory::parse(&csv(&coarse)).unwrap();
        // a jerk-limited piece: q = j t³/6 (constant jerk j) at 10 Hz is integrated exactly
        let j = 500.0;
        let mut text = String::from("t,q1,qd1,qdd1,tau1\n");
        for k in 0..6 {
            let t = 0.1 * k as f64;
            text += &format!("{t},{},{},{},0\n", j * t * t * t / 6.0, j * t * t / 2.0, j * t);
        }
        Trajectory::parse(&text).unwrap();
    }

    #[test]
    fn position_jumps_and_subnormal_steps_are_refused_with_their_line() {
        // q jumps by 0.5 rad in 1 ms while qd says the joint stands still
        let e = Trajectory::parse("t,q1,qd1,qdd1,tau1\n0,0,0,0,0\n0.001,0,0,0,0\n0.002,0.5,0,0,0\n").unwrap_err();
        assert_eq!(e.line, 4, "{e}");
        assert!(
            e.message.contains("q1 moves by 5e-1 from line 3") && e.message.contains("qd1"),
            "{e}"
        );
        // the second joint of two: the message names its columns
        let e = Trajectory::parse("t,q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2\n0,0,0,1,0,0,0,0,0\n1,1,-2,1,0,0,0,0,0\n")
            .unwrap_err();
        assert!(e.line == 3 && e.message.starts_with("q2 moves by -2e0"), "{e}");
        // within the tolerance: 1e-7 rad of rounding is no jump
        Trajectory::parse("t,q1,qd1,qdd1,tau1\n0,0,0,0,0\n1,1e-7,0,0,0\n").unwrap();
        // a subnormal step, and one just under the minimum
        for dt in ["5e-324", "9e-7"] {
            let e = Trajectory::parse(&format!("t,q1,qd1,qdd1,tau1\n0,0,0,0,0\n{dt},0,0,0,0\n")).unwrap_err();
            assert!(e.line == 3 && e.message.contains("rows must be apart"), "{e}");
        }
        // velocities that overflow the integral are refused, not compared as inf
        let e = Trajectory::parse("t,q1,qd1,qdd1,tau1\n0,0,1e308,0,0\n1,1e308,1.7e308,0,0\n").unwrap_err();
        assert_eq!(e.line, 3, "{e}");
    }

    #[test]
    fn demo_velocity_matches_finite_difference_of_position() {
        let tr = Trajectory::demo(3, 0.2, 2.0);
        for j in 0..3 {
            for k in 1..19 {
                let t = k as f64 * 0.1;
                let fd = (tr.sample(j, t + 1e-3).q - tr.sample(j, t - 1e-3).q) / 2e-3;
                assert!((fd - tr.sample(j, t).qd).abs() < 1e-3, "joint {j} t {t}");
            }
        }
        let (p, v) = approach(1.0, 2.0, 1.0, 0.5);
        assert!((p - 1.5).abs() < 1e-12 && v > 0.0);
    }
}
