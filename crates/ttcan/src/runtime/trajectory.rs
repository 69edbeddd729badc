//! Joint trajectories for the controller: the CSV file written by `ttmanip.ctl.write_trajectory`
//! (header `t,q1..qn,qd1..qdn,qdd1..qddn,tau1..taun`, SI, strictly increasing t), a built-in demo
//! motion, and sampling with linear interpolation (no allocation) preceded by a quintic approach
//! from where the axes are to the first sample.

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
            t.push(vals[0]);
            rows.extend_from_slice(&vals[1..]);
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
        let tr =
            Trajectory::parse("t,q1,q2,qd1,qd2,qdd1,qdd2,tau1,tau2\n0,1,2,3,4,5,6,7,8\n1,9,10,11,12,13,14,15,16\n")
                .unwrap();
        let s: Vec<_> = tr.samples(1).map(|s| (s.q, s.qd, s.qdd, s.tau)).collect();
        assert_eq!(s, vec![(2.0, 4.0, 6.0, 8.0), (10.0, 12.0, 14.0, 16.0)]);
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
