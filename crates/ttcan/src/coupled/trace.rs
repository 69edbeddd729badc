//! What a whole-trajectory run records, and the linear interpolation of the input samples.

use super::CoupledSim;

/// What [`CoupledSim::run`] records, one row per tick (K rows, n columns, row-major).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CoupledTrace {
    /// Number of axes.
    pub dof: usize,
    /// Time of each row, s from the start of the run.
    pub t: Vec<f64>,
    /// True joint positions, rad or m.
    pub q: Vec<f64>,
    /// True joint speeds, rad/s or m/s.
    pub qd: Vec<f64>,
    /// Reference positions (the input trajectory at the row's time), rad or m.
    pub q_ref: Vec<f64>,
    /// Winding currents, A.
    pub current: Vec<f64>,
    /// Current references after limiting, A.
    pub current_ref: Vec<f64>,
    /// Joint-side motor torques, N·m or N.
    pub torque: Vec<f64>,
    /// Fault of each axis at the end ("" when none).
    pub faults: Vec<String>,
}

impl CoupledTrace {
    pub(super) fn with_capacity(k: usize, n: usize) -> Self {
        let v = || Vec::with_capacity(k * n);
        CoupledTrace {
            dof: n,
            t: Vec::with_capacity(k),
            q: v(),
            qd: v(),
            q_ref: v(),
            current: v(),
            current_ref: v(),
            torque: v(),
            faults: Vec::new(),
        }
    }

    pub(super) fn push(&mut self, s: &CoupledSim, q_ref: &[f64]) {
        self.t.push(self.t.len() as f64 * s.period);
        self.q.extend_from_slice(&s.q);
        self.qd.extend_from_slice(&s.qd);
        self.q_ref.extend_from_slice(q_ref);
        self.current.extend_from_slice(&s.current);
        self.current_ref.extend(s.axes.iter().map(|a| a.current_reference()));
        self.torque.extend_from_slice(&s.torque);
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True if nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

#[allow(clippy::too_many_arguments)]
pub(super) fn interpolate(
    times: &[f64],
    t: f64,
    n: usize,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    tau: Option<&[f64]>,
    out: &mut [f64],
) {
    let k = times.len();
    let (i, s) = if t <= times[0] {
        (0, 0.0)
    } else if t >= times[k - 1] {
        (k - 2, 1.0)
    } else {
        let i = times.partition_point(|x| *x <= t).saturating_sub(1).min(k - 2);
        (i, (t - times[i]) / (times[i + 1] - times[i]))
    };
    let at_end = t >= times[k - 1];
    for (slot, src) in [q, qd, qdd].into_iter().enumerate() {
        for j in 0..n {
            let (a, b) = (src[i * n + j], src[(i + 1) * n + j]);
            out[slot * n + j] = a + s * (b - a);
            if at_end && slot > 0 {
                out[slot * n + j] = b;
            }
        }
    }
    if let Some(src) = tau {
        for j in 0..n {
            let (a, b) = (src[i * n + j], src[(i + 1) * n + j]);
            out[3 * n + j] = a + s * (b - a);
        }
    }
}
