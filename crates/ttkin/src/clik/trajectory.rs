//! A task trajectory sampled at the control rate ([`TaskTrajectory`]): what [`super::track`]
//! follows.

use crate::error::{check_finite, Error, Result};
use crate::task::Task;
use crate::traj::cartesian::TimeLaw;

/// A task trajectory sampled at the control rate: task coordinates ([`Task::coordinates`]) and
/// their rates per sample, row-major N × dim each.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskTrajectory {
    task: Task,
    rate_hz: f64,
    x: Vec<f64>,
    xdot: Vec<f64>,
}

impl TaskTrajectory {
    /// A trajectory from samples `x` and rates `xdot` (row-major N × dim, task coordinates and
    /// their rates; for the pose task rows 3–5 of `xdot` are the angular velocity) at `rate_hz`.
    pub fn new(task: Task, rate_hz: f64, x: Vec<f64>, xdot: Vec<f64>) -> Result<Self> {
        check_rate(rate_hz)?;
        let d = task.dim();
        if x.is_empty() || !x.len().is_multiple_of(d) {
            return Err(Error::shape(
                "task_trajectory",
                format!("N × {d} values, N ≥ 2"),
                x.len(),
            ));
        }
        if x.len() < 2 * d {
            return Err(Error::invalid("task_trajectory", "needs at least 2 samples"));
        }
        if xdot.len() != x.len() {
            return Err(Error::shape("task velocities", x.len(), xdot.len()));
        }
        check_finite("task_trajectory", &x)?;
        check_finite("task velocities", &xdot)?;
        Ok(TaskTrajectory { task, rate_hz, x, xdot })
    }

    /// A trajectory from samples alone; rates by central differences (one-sided at the ends; the
    /// azimuth of the racket task is unwrapped; the pose task's angular velocity from the relative
    /// rotation of neighbouring samples).
    pub fn from_samples(task: Task, rate_hz: f64, x: Vec<f64>) -> Result<Self> {
        check_rate(rate_hz)?;
        let d = task.dim();
        let count = x.len() / d;
        if !x.len().is_multiple_of(d) || count < 2 {
            return Err(Error::shape(
                "task_trajectory",
                format!("N × {d} values, N ≥ 2"),
                x.len(),
            ));
        }
        check_finite("task_trajectory", &x)?;
        let mut xdot = vec![0.0; x.len()];
        for k in 0..count {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(count - 1));
            let h = (b - a) as f64 / rate_hz;
            let (xa, xb) = (&x[a * d..(a + 1) * d], &x[b * d..(b + 1) * d]);
            let out = &mut xdot[k * d..(k + 1) * d];
            for i in 0..d {
                out[i] = (xb[i] - xa[i]) / h;
            }
            match task {
                Task::Racket { .. } => {
                    let mut da = xb[4] - xa[4];
                    da -= (da / std::f64::consts::TAU).round() * std::f64::consts::TAU;
                    out[4] = da / h;
                }
                Task::Pose => {
                    let ra = nalgebra::Rotation3::new(nalgebra::Vector3::new(xa[3], xa[4], xa[5]));
                    let rb = nalgebra::Rotation3::new(nalgebra::Vector3::new(xb[3], xb[4], xb[5]));
                    let w = (rb * ra.inverse()).scaled_axis() / h;
                    out[3..6].copy_from_slice(w.as_slice());
                }
                Task::Position => {}
            }
        }
        Self::new(task, rate_hz, x, xdot)
    }

    /// A straight line in task coordinates from `x0` to `x1` over `duration` s with the quintic
    /// rest-to-rest time law s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, sampled at `rate_hz` (both ends included).
    /// Not for the pose task (its rotation-vector coordinates do not interpolate to a geodesic).
    pub fn line(task: Task, x0: &[f64], x1: &[f64], duration: f64, rate_hz: f64) -> Result<Self> {
        check_rate(rate_hz)?;
        let d = task.dim();
        if task == Task::Pose {
            return Err(Error::invalid("task", "line() supports 'position' and 'racket5'"));
        }
        crate::error::check_vector("x0", x0, d)?;
        crate::error::check_vector("x1", x1, d)?;
        crate::error::check_positive("duration", duration, "s")?;
        let steps = (duration * rate_hz).round() as usize;
        if !(1..=100_000_000).contains(&steps) {
            return Err(Error::invalid("duration", "duration × rate must give 1..1e8 steps"));
        }
        let mut x = Vec::with_capacity((steps + 1) * d);
        let mut xdot = Vec::with_capacity((steps + 1) * d);
        for k in 0..=steps {
            let [s, sd, _, _] = TimeLaw::Quintic.eval(k as f64 / steps as f64 * duration, duration);
            for i in 0..d {
                x.push(x0[i] + s * (x1[i] - x0[i]));
                xdot.push(sd * (x1[i] - x0[i]));
            }
        }
        Self::new(task, rate_hz, x, xdot)
    }

    /// The task.
    pub fn task(&self) -> Task {
        self.task
    }

    /// Control rate (Hz).
    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    /// Number of samples N.
    pub fn len(&self) -> usize {
        self.x.len() / self.task.dim()
    }

    /// True when there is no sample (never, for a constructed trajectory).
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Task coordinates of sample k.
    pub fn x(&self, k: usize) -> &[f64] {
        let d = self.task.dim();
        &self.x[k * d..(k + 1) * d]
    }

    /// Every sample's task coordinates, N × dim row-major.
    pub fn positions(&self) -> &[f64] {
        &self.x
    }

    /// Every sample's task rates, N × dim row-major.
    pub fn rates(&self) -> &[f64] {
        &self.xdot
    }

    /// Task rates of sample k.
    pub fn xdot(&self, k: usize) -> &[f64] {
        let d = self.task.dim();
        &self.xdot[k * d..(k + 1) * d]
    }
}

fn check_rate(rate_hz: f64) -> Result<()> {
    crate::error::check_positive("rate_hz", rate_hz, "Hz").map(|_| ())
}
