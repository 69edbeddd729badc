//! A whole-trajectory run ([`CoupledSim::run`]): the setpoints it hands to the drives, the linear
//! interpolation of the input samples, and what it records.

use super::{check_len, CoupledSim, MAX_RUN_TICKS};
use crate::error::{Error, Result};

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

impl CoupledSim {
    /// Runs a reference trajectory sampled at `times` (s from now, increasing, at any rate; q, qd,
    /// qdd and the optional torque feed-forward K × n row-major), handing setpoints to the drives
    /// every `setpoint_period` s (linear interpolation between the samples, each sent one period
    /// ahead, see [`crate::setpoint`]) until the last sample's time; records every tick. Every
    /// sample must keep the joints' limits ([`CoupledSim::set_setpoint`]); one that does not is
    /// refused before the first tick.
    pub fn run(
        &mut self,
        times: &[f64],
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        tau_ff: Option<&[f64]>,
        setpoint_period: f64,
    ) -> Result<CoupledTrace> {
        self.run_until(times, q, qd, qdd, tau_ff, setpoint_period, &|| false)
    }

    /// [`CoupledSim::run`] that ends early with an error when `stop()` turns true (a caller's
    /// cancellation, polled every [`ttkin::budget::STOP_POLL_STEPS`] ticks); the simulation is
    /// then left where the run stopped.
    #[allow(clippy::too_many_arguments)]
    pub fn run_until(
        &mut self,
        times: &[f64],
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        tau_ff: Option<&[f64]>,
        setpoint_period: f64,
        stop: ttkin::budget::Stop<'_>,
    ) -> Result<CoupledTrace> {
        let n = self.dof();
        let k = times.len();
        if k < 2 {
            return Err(Error::InvalidParameter {
                what: "t".into(),
                value: k as f64,
                reason: "needs at least two samples".into(),
            });
        }
        for (name, v) in [("t", times), ("q", q), ("qd", qd), ("qdd", qdd)] {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::NonFinite {
                    what: format!("{name}[{i}]"),
                    value: v[i],
                });
            }
        }
        if let Some(i) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(Error::InvalidParameter {
                what: format!("t[{}]", i + 1),
                value: times[i + 1],
                reason: "times must increase".into(),
            });
        }
        for (name, v) in [("q", q), ("qd", qd), ("qdd", qdd)] {
            check_len(name, v, k * n)?;
        }
        if let Some(t) = tau_ff {
            check_len("tau_ff", t, k * n)?;
            if let Some(i) = t.iter().position(|x| !x.is_finite()) {
                return Err(Error::NonFinite {
                    what: format!("tau_ff[{i}]"),
                    value: t[i],
                });
            }
        }
        // every sample within the joints' limits before the first tick (the interpolated
        // setpoints lie between samples, so within them too)
        for (i, (qi, qdi)) in q.chunks_exact(n).zip(qd.chunks_exact(n)).enumerate() {
            self.check_within_limits(Some(i), qi, qdi)?;
        }
        crate::error::positive("setpoint period (s)", setpoint_period)?;
        let ticks_per_setpoint = (setpoint_period / self.period).round().max(1.0) as u64;
        let t0 = times[0];
        let duration = times[k - 1] - t0;
        for (i, &t) in [(0, &times[0]), (k - 1, &times[k - 1])] {
            ttkin::budget::check_clock("t", t, self.period).map_err(|e| Error::InvalidParameter {
                what: format!("t[{i}]"),
                value: t,
                reason: crate::error::ttkin_reason(e),
            })?;
        }
        // Counted in f64 and compared before the cast: 1e15 s at 20 kHz is 2e19 ticks, which
        // saturated u64 and wrapped to 0 rows when one was added.
        let total = (duration / self.period).round() + 1.0;
        if total.is_nan() || total > MAX_RUN_TICKS as f64 {
            return Err(Error::InvalidParameter {
                what: "t".into(),
                value: duration,
                reason: format!(
                    "a run of {duration} s is {total:.3e} ticks at {} Hz; at most {MAX_RUN_TICKS} ticks \
                     (the trace keeps every tick): run it in pieces",
                    1.0 / self.period
                ),
            });
        }
        let total = total as u64;
        let mut trace = CoupledTrace::with_capacity(total as usize, n);
        let mut buf = vec![0.0; 4 * n];
        let lead = if self.axes[0].config().setpoint_period.is_some() {
            ticks_per_setpoint as f64 * self.period
        } else {
            0.0
        };
        let start_tick = self.ticks;
        for tick in 0..total {
            if (tick + 1).is_multiple_of(ttkin::budget::STOP_POLL_STEPS) && stop() {
                return Err(crate::error::stopped());
            }
            let t_rel = tick as f64 * self.period;
            if tick % ticks_per_setpoint == 0 {
                interpolate(times, t0 + t_rel + lead, n, q, qd, qdd, tau_ff, &mut buf);
                let (a, rest) = buf.split_at(n);
                let (b, rest) = rest.split_at(n);
                let (c, d) = rest.split_at(n);
                self.set_setpoint(a, b, c, if tau_ff.is_some() { Some(d) } else { None })?;
            }
            interpolate(times, t0 + t_rel, n, q, qd, qdd, None, &mut buf);
            trace.push(self, &buf[..n]);
            self.tick();
        }
        let _ = start_tick;
        trace.faults = self.fault_names();
        Ok(trace)
    }
}
