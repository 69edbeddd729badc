//! Parallel batches of the dynamics algorithms over N samples (N × n row-major inputs and
//! outputs, one scratch space per rayon task, every argument checked before the work starts).

use rayon::prelude::*;

use super::model::{check_wrench, vec3, Dynamics, DynamicsData};
use super::Wrench;
use crate::error::{check_finite, check_len, check_rows as batch_count, Result};

/// Configurations per rayon task in batch calls.
const BATCH_CHUNK: usize = 64;

impl Dynamics {
    /// Batch [`Dynamics::rnea`]: `q`, `qd`, `qdd` are N × n row-major, `out` receives N × n
    /// torques. Runs in parallel; everything is checked first.
    pub fn rnea_batch(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
        out: &mut [f64],
    ) -> Result<()> {
        self.inverse_batch(q, qd, qdd, gravity, wrench, false, out)
    }

    /// [`Dynamics::rnea_batch`], plus joint friction when `friction` is true.
    #[allow(clippy::too_many_arguments)]
    fn inverse_batch(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
        friction: bool,
        out: &mut [f64],
    ) -> Result<()> {
        let g = vec3("gravity", gravity)?;
        check_wrench(wrench)?;
        self.batch3(["qd", "qdd"], q, qd, qdd, out, |data, q, qd, qdd| {
            self.rnea_unchecked(data, q, qd, qdd, &g, wrench);
            if friction {
                self.add_friction(&mut data.tau, qd);
            }
            Ok(data.tau.as_slice())
        })
    }

    /// Batch [`Dynamics::mass_matrix`]: `q` is N × n, `out` receives N row-major n × n matrices.
    pub fn mass_matrix_batch(&self, q: &[f64], out: &mut [f64]) -> Result<()> {
        let n = self.dof();
        let count = batch_count("q", q, n)?;
        check_len("output buffer", out.len(), count, n * n)?;
        out.par_chunks_mut(n * n * BATCH_CHUNK)
            .zip(q.par_chunks(n * BATCH_CHUNK))
            .for_each(|(o, q)| {
                let mut data = DynamicsData::new(self);
                for (o, q) in o.chunks_exact_mut(n * n).zip(q.chunks_exact(n)) {
                    self.crba_unchecked(&mut data, q);
                    // Symmetric: column-major storage is also row-major.
                    o.copy_from_slice(data.mass.as_slice());
                }
            });
        Ok(())
    }

    /// Batch [`Dynamics::gravity`]: `q` is N × n, `out` receives N × n torques.
    pub fn gravity_batch(&self, q: &[f64], gravity: &[f64; 3], out: &mut [f64]) -> Result<()> {
        let zeros = vec![0.0; q.len()];
        self.rnea_batch(q, &zeros, &zeros, gravity, None, out)
    }

    /// Batch [`Dynamics::forward_dynamics`]: `q`, `qd`, `tau` N × n, `out` receives N × n
    /// accelerations.
    pub fn forward_dynamics_batch(
        &self,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
        out: &mut [f64],
    ) -> Result<()> {
        let g = vec3("gravity", gravity)?;
        check_wrench(wrench)?;
        self.batch3(["qd", "tau"], q, qd, tau, out, |data, q, qd, tau| {
            self.forward_unchecked(data, q, qd, tau, &g, wrench, false)?;
            Ok(data.qdd.as_slice())
        })
    }

    /// Batch [`Dynamics::inverse_dynamics`]: [`Dynamics::rnea_batch`] plus joint friction.
    pub fn inverse_dynamics_batch(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        gravity: &[f64; 3],
        wrench: Option<&Wrench>,
        out: &mut [f64],
    ) -> Result<()> {
        self.inverse_batch(q, qd, qdd, gravity, wrench, true, out)
    }

    /// Batch [`Dynamics::coriolis`]: `q`, `qd` N × n, `out` receives N × n torques.
    pub fn coriolis_batch(&self, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<()> {
        self.nonlinear_effects_batch(q, qd, &[0.0; 3], out)
    }

    /// Batch [`Dynamics::nonlinear_effects`]: `q`, `qd` N × n, `out` receives N × n torques.
    pub fn nonlinear_effects_batch(&self, q: &[f64], qd: &[f64], gravity: &[f64; 3], out: &mut [f64]) -> Result<()> {
        let zeros = vec![0.0; q.len()];
        self.rnea_batch(q, qd, &zeros, gravity, None, out)
    }

    /// Batch [`Dynamics::friction`]: joint friction at N × n speeds `qd` into `out` (N × n).
    pub fn friction_batch(&self, qd: &[f64], out: &mut [f64]) -> Result<()> {
        let n = self.dof();
        let count = batch_count("qd", qd, n)?;
        check_len("output buffer", out.len(), count, n)?;
        for (o, v) in out.chunks_exact_mut(n).zip(qd.chunks_exact(n)) {
            for ((o, d), &v) in o.iter_mut().zip(&self.drives).zip(v) {
                *o = d.map_or(0.0, |d| d.friction(v));
            }
        }
        Ok(())
    }

    /// Runs `f` on every row of three N × n inputs in parallel (one scratch per rayon task) and
    /// copies the n values it returns into row k of `out`; checks shapes and finiteness first.
    fn batch3<F>(&self, names: [&str; 2], q: &[f64], b: &[f64], c: &[f64], out: &mut [f64], f: F) -> Result<()>
    where
        F: for<'d> Fn(&'d mut DynamicsData, &[f64], &[f64], &[f64]) -> Result<&'d [f64]> + Sync,
    {
        let n = self.dof();
        let count = batch_count("q", q, n)?;
        check_len(names[0], b.len(), count, n)?;
        check_len(names[1], c.len(), count, n)?;
        check_len("output buffer", out.len(), count, n)?;
        check_finite(names[0], b)?;
        check_finite(names[1], c)?;
        let chunk = n * BATCH_CHUNK;
        out.par_chunks_mut(chunk)
            .zip(q.par_chunks(chunk).zip(b.par_chunks(chunk).zip(c.par_chunks(chunk))))
            .try_for_each(|(o, (q, (b, c)))| {
                let mut data = DynamicsData::new(self);
                for (k, o) in o.chunks_exact_mut(n).enumerate() {
                    let r = k * n..(k + 1) * n;
                    o.copy_from_slice(f(&mut data, &q[r.clone()], &b[r.clone()], &c[r])?);
                }
                Ok(())
            })
    }
}
