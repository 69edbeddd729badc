//! Inverse kinematics: analytic solvers for the seed robots, a numeric solver for any chain, and
//! differential IK (joint velocities from a tool twist).
//!
//! - [`gantry`]: closed-form IK of seed 002's 6-joint gantry, every (σ1, σ2) branch.
//! - [`arm4`]: closed-form IK of seed 001's 4-DOF arm, with the exact set of poses it can reach.
//! - [`numeric`]: bounded Levenberg–Marquardt with restarts for any chain and any [`crate::task::Task`].
//! - [`batch`]: the front end every caller shares: method choice and fallback, per-target seeds,
//!   per-thread scratch, a parallel batch with a status per target ([`IkStatus`]).
//! - [`differential`]: q̇ = J⁻¹V with singularity detection and a damped fallback.
//!
//! [`Analytic::for_chain`] finds the analytic solver of a chain by a structural check of its DH
//! table (joint types, twists, link lengths; the lengths and joint offsets are read from the
//! table), so a gantry or arm4 loaded from a robot file gets its analytic solver too. Base and
//! tool transforms are allowed: targets are mapped into the chain's own frames first.
//!
//! Unreachable targets are ordinary outcomes: analytic solvers return
//! [`crate::Error::Unreachable`] naming the constraint that fails, and the numeric solver returns an
//! [`IkResult`] with `success = false` and its best configuration.

pub mod arm4;
pub mod batch;
pub mod differential;
pub mod gantry;
pub mod numeric;
pub mod residual;

use std::f64::consts::PI;

use nalgebra::{IsometryMatrix3, Matrix4};
use rayon::prelude::*;

use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::joint::{Dh, DhConvention, Geometry, JointType, Limits};
use crate::transform::isometry_from_matrix;

pub use arm4::Arm4Ik;
pub use batch::{IkBatchSolver, IkMethod, IkOutcome, IkStatus};
pub use differential::{joint_velocity, DifferentialIk, JointVelocity};
pub use gantry::GantryIk;
pub use numeric::{IkResult, IkScratch, IkSolver};

/// Most joints an analytic solver handles.
pub const MAX_ANALYTIC_DOF: usize = 6;
/// Most branches an analytic solver returns.
pub const MAX_BRANCHES: usize = 4;

/// Whether analytic solutions are filtered by the joint position limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LimitFilter {
    /// Every mathematical branch, revolute angles wrapped to (−π, π].
    #[default]
    Off,
    /// Only branches within the position limits; revolute angles are shifted by multiples of 2π
    /// into the limits where possible. No branch left gives [`Error::Unreachable`].
    Enforce,
}

/// Up to [`MAX_BRANCHES`] joint vectors from an analytic solver (no allocation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Solutions {
    dof: usize,
    count: usize,
    q: [[f64; MAX_ANALYTIC_DOF]; MAX_BRANCHES],
    /// True when the pose lies on a singular set where a continuum of configurations reaches it
    /// (gantry: s45 = 0, θ3 + θ6 or θ3 − θ6 free); the branches are then documented representatives.
    pub family: bool,
}

impl Solutions {
    /// No solution yet, for a `dof`-joint chain.
    pub fn empty(dof: usize) -> Self {
        Solutions {
            dof,
            count: 0,
            q: [[0.0; MAX_ANALYTIC_DOF]; MAX_BRANCHES],
            family: false,
        }
    }

    /// Number of branches.
    pub fn len(&self) -> usize {
        self.count
    }

    /// True when there is no branch.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Branch `i` (m, rad), chain order.
    pub fn get(&self, i: usize) -> &[f64] {
        &self.q[i][..self.dof]
    }

    /// The branches as one (len, dof) row-major table (m, rad).
    pub fn flat(&self) -> Vec<f64> {
        self.iter().flat_map(|q| q.iter().copied()).collect()
    }

    /// Every branch, in a fixed order (σ1 = +1 first, then σ2 = +1 first).
    pub fn iter(&self) -> impl Iterator<Item = &[f64]> + '_ {
        self.q[..self.count].iter().map(move |q| &q[..self.dof])
    }

    /// Appends a branch unless an equal one (to 1e-12 in every joint) is already there.
    fn push(&mut self, q: &[f64]) {
        let dup = self.q[..self.count]
            .iter()
            .any(|p| p[..self.dof].iter().zip(q).all(|(a, b)| (a - b).abs() < 1e-12));
        if !dup && self.count < MAX_BRANCHES {
            self.q[self.count][..self.dof].copy_from_slice(q);
            self.count += 1;
        }
    }

    /// Drops the branches outside `limits` (after shifting revolute angles by 2πk); returns why
    /// each dropped branch failed as (branch, joint, value), formatted only when no branch is left.
    fn filter(&mut self, kinds: &[JointType], limits: &[Limits]) -> Vec<(usize, usize, f64)> {
        let mut why = Vec::new();
        self.retain_map(|b, i, q| {
            let fitted = fit_to_limits(q, kinds[i], &limits[i]);
            if fitted.is_none() {
                why.push((b, i, q));
            }
            fitted
        });
        why
    }

    /// Keeps the branches whose every joint value `fit(branch, joint, value)` maps to a value, with
    /// the mapped values (e.g. a revolute angle shifted by 2πk into its limits), in order; `fit`
    /// is not asked for the joints after a branch's first `None`.
    pub fn retain_map(&mut self, mut fit: impl FnMut(usize, usize, f64) -> Option<f64>) {
        let mut kept = 0;
        for b in 0..self.count {
            let mut q = self.q[b];
            if (0..self.dof).all(|i| fit(b, i, q[i]).map(|v| q[i] = v).is_some()) {
                self.q[kept] = q;
                kept += 1;
            }
        }
        self.count = kept;
    }

    /// Applies `filter` and turns "no branch left" into [`Error::Unreachable`].
    fn apply(&mut self, filter: LimitFilter, chain_info: &ChainInfo) -> Result<()> {
        if filter == LimitFilter::Enforce {
            let why = self.filter(&chain_info.kinds, &chain_info.limits);
            if self.is_empty() {
                let (names, limits) = (&chain_info.names, &chain_info.limits);
                let why: Vec<String> = why
                    .iter()
                    .map(|&(b, i, q)| {
                        format!(
                            "branch {b}: {} = {q:.6} outside [{}, {}]",
                            names[i], limits[i].lower, limits[i].upper
                        )
                    })
                    .collect();
                return Err(Error::Unreachable(format!(
                    "every IK branch violates a joint limit ({})",
                    why.join("; ")
                )));
            }
        }
        Ok(())
    }

    /// The branch nearest to `current` (sum of squared joint differences, revolute angles shifted
    /// by 2πk towards `current` within the limits when `filter` enforces them).
    fn nearest(&self, current: &[f64], info: &ChainInfo, filter: LimitFilter) -> Vec<f64> {
        let mut best = (f64::INFINITY, vec![0.0; self.dof]);
        for q in self.iter() {
            let mut cand = q.to_vec();
            for i in 0..self.dof {
                if info.kinds[i] == JointType::Revolute {
                    let shifted = current[i] + wrap(cand[i] - current[i]);
                    let l = &info.limits[i];
                    if filter == LimitFilter::Off || (shifted >= l.lower && shifted <= l.upper) {
                        cand[i] = shifted;
                    }
                }
            }
            let d: f64 = cand.iter().zip(current).map(|(a, b)| (a - b) * (a - b)).sum();
            if d < best.0 {
                best = (d, cand);
            }
        }
        best.1
    }
}

/// Joint types, limits and names of a chain, kept by the analytic solvers for filtering.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChainInfo {
    pub kinds: Vec<JointType>,
    pub limits: Vec<Limits>,
    pub names: Vec<String>,
    pub base_inv: IsometryMatrix3<f64>,
    pub tool_inv: IsometryMatrix3<f64>,
    /// True when base and tool are both the identity (targets are already in chain frames).
    pub plain: bool,
}

impl ChainInfo {
    pub(crate) fn of(chain: &Chain) -> Self {
        ChainInfo {
            kinds: chain.joints().iter().map(|j| j.kind()).collect(),
            limits: chain.limits(),
            names: chain.joints().iter().map(|j| j.name().to_string()).collect(),
            base_inv: chain.base().inverse(),
            tool_inv: chain.tool().inverse(),
            plain: *chain.base() == IsometryMatrix3::identity() && *chain.tool() == IsometryMatrix3::identity(),
        }
    }

    /// Target tool pose (base frame) → pose of the last DH frame in the chain's frame 0.
    pub(crate) fn to_chain(&self, target: &IsometryMatrix3<f64>) -> IsometryMatrix3<f64> {
        if self.plain {
            *target
        } else {
            self.base_inv * target * self.tool_inv
        }
    }
}

/// The analytic solver of a chain, if it has one.
#[derive(Debug, Clone, PartialEq)]
pub enum Analytic {
    /// Seed 002's gantry (see [`gantry`]).
    Gantry6(GantryIk),
    /// Seed 001's 4-DOF arm (see [`arm4`]).
    Arm4(Arm4Ik),
}

impl Analytic {
    /// The analytic solver matching the chain's structure (DH table), or `None`. The check reads
    /// joint types and the DH rows: twists, zero lengths and the row pattern must match to 1e-12;
    /// free lengths and joint offsets are taken from the table.
    pub fn for_chain(chain: &Chain) -> Option<Analytic> {
        if let Some(g) = GantryIk::from_chain(chain) {
            return Some(Analytic::Gantry6(g));
        }
        Arm4Ik::from_chain(chain).map(Analytic::Arm4)
    }

    /// Every branch reaching `target` (tool pose, base frame, m). On a singular family the
    /// representative uses the values of `hint` (a configuration) for the free joints, 0 without.
    pub fn solve(&self, target: &IsometryMatrix3<f64>, hint: Option<&[f64]>, filter: LimitFilter) -> Result<Solutions> {
        match self {
            Analytic::Gantry6(g) => g.solve(target, hint, filter),
            Analytic::Arm4(a) => a.solve(target, filter),
        }
    }

    /// [`Analytic::solve`] without limit filter and without building error messages: `None` when
    /// the pose is unreachable or not finite (the hit planner's search).
    pub(crate) fn solve_quiet(&self, target: &IsometryMatrix3<f64>, hint: Option<&[f64]>) -> Option<Solutions> {
        match self {
            Analytic::Gantry6(g) => g.solve_quiet(target, hint.map(|h| h.get(2).copied().unwrap_or(0.0))),
            Analytic::Arm4(a) => a.solve(target, LimitFilter::Off).ok(),
        }
    }

    /// The branch nearest to `current` (m, rad): joint-space distance, revolute angles shifted
    /// by 2πk to the copy nearest `current`.
    pub fn nearest(&self, target: &IsometryMatrix3<f64>, current: &[f64], filter: LimitFilter) -> Result<Vec<f64>> {
        let info = self.info();
        crate::error::check_vector("current configuration", current, info.kinds.len())?;
        let sols = self.solve(target, Some(current), filter)?;
        Ok(sols.nearest(current, info, filter))
    }

    /// Batch of [`Analytic::solve`] over poses already read as rigid transforms (e.g. float32 data
    /// accepted to its own precision), in parallel, with an optional `hint` (n,) for every pose
    /// (θ3 on the gantry's s45 = 0 family). Outputs as in [`Analytic::solve_batch`]; an unreachable
    /// pose gives 0 branches and NaN rows.
    pub fn solve_poses(
        &self,
        targets: &[IsometryMatrix3<f64>],
        hint: Option<&[f64]>,
        filter: LimitFilter,
        out: &mut [f64],
        counts: &mut [usize],
    ) -> Result<()> {
        let n = self.dof();
        if let Some(h) = hint {
            crate::error::check_vector("hint", h, n)?;
        }
        let count = targets.len();
        check_branch_buffers(count, n, out, counts)?;
        out.par_chunks_mut(MAX_BRANCHES * n.max(1))
            .zip(counts.par_iter_mut())
            .zip(targets.par_iter())
            .try_for_each(|((oi, ci), pose)| {
                *ci = self.solve_into(pose, hint, filter, oi)?;
                Ok(())
            })
    }

    /// Batch of [`Analytic::solve`] in parallel: `targets` holds N row-major 4×4 tool poses (N × 16),
    /// `out` receives N × [`MAX_BRANCHES`] × n joint values (NaN past each pose's branch count) and
    /// `counts` the N branch counts, 0 for an unreachable pose. A non-rigid or non-finite matrix is
    /// an error for the whole batch (its index is in the message).
    pub fn solve_batch(
        &self,
        targets: &[f64],
        filter: LimitFilter,
        out: &mut [f64],
        counts: &mut [usize],
    ) -> Result<()> {
        let n = self.dof();
        if !targets.len().is_multiple_of(16) {
            return Err(Error::shape("targets", "N × 16 values", targets.len()));
        }
        let count = targets.len() / 16;
        check_branch_buffers(count, n, out, counts)?;
        const CHUNK: usize = 256;
        out.par_chunks_mut(CHUNK * MAX_BRANCHES * n)
            .zip(counts.par_chunks_mut(CHUNK))
            .zip(targets.par_chunks(CHUNK * 16))
            .enumerate()
            .try_for_each(|(chunk, ((o, c), t))| {
                for (i, ((oi, ci), ti)) in o
                    .chunks_exact_mut(MAX_BRANCHES * n)
                    .zip(c.iter_mut())
                    .zip(t.chunks_exact(16))
                    .enumerate()
                {
                    let m = Matrix4::from_row_slice(ti);
                    let pose = isometry_from_matrix("target", &m)
                        .map_err(|e| Error::invalid(format!("targets[{}]", chunk * CHUNK + i), e.to_string()))?;
                    *ci = self.solve_into(&pose, None, filter, oi)?;
                }
                Ok(())
            })
    }

    /// Batch of [`Analytic::solve`] over `targets`, N row-major 4×4 matrices (N × 16) read as
    /// rigid to within `tolerance` (|RᵀR − I|; [`crate::transform::RIGID_TOLERANCE`] for float64
    /// data, looser for data read from a coarser dtype), with an optional `hint` (n,) for every
    /// pose. Chooses the path: float64 data without a hint goes through [`Analytic::solve_batch`]
    /// (chunked, no intermediate poses), the rest through [`Analytic::solve_poses`]. Outputs as
    /// in [`Analytic::solve_batch`].
    pub fn solve_matrices(
        &self,
        targets: &[f64],
        tolerance: f64,
        hint: Option<&[f64]>,
        filter: LimitFilter,
        out: &mut [f64],
        counts: &mut [usize],
    ) -> Result<()> {
        if hint.is_none() && tolerance <= crate::transform::RIGID_TOLERANCE {
            return self.solve_batch(targets, filter, out, counts);
        }
        if !targets.len().is_multiple_of(16) {
            return Err(Error::shape("T", "N × 16 values", targets.len()));
        }
        let poses = targets
            .chunks_exact(16)
            .enumerate()
            .map(|(i, m)| {
                crate::transform::isometry_from_matrix_within(
                    &format!("T[{i}]"),
                    &Matrix4::from_row_slice(m),
                    tolerance,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        self.solve_poses(&poses, hint, filter, out, counts)
    }

    /// The branches of one pose into a row of [`MAX_BRANCHES`] × n values (NaN past the last);
    /// returns their count, 0 for an unreachable pose.
    fn solve_into(
        &self,
        pose: &IsometryMatrix3<f64>,
        hint: Option<&[f64]>,
        filter: LimitFilter,
        row: &mut [f64],
    ) -> Result<usize> {
        row.fill(f64::NAN);
        match self.solve(pose, hint, filter) {
            Ok(sols) => {
                for (dst, q) in row.chunks_exact_mut(self.dof()).zip(sols.iter()) {
                    dst.copy_from_slice(q);
                }
                Ok(sols.len())
            }
            Err(Error::Unreachable(_)) => Ok(0),
            Err(e) => Err(e),
        }
    }

    /// Number of joints of the chain.
    pub fn dof(&self) -> usize {
        self.info().kinds.len()
    }

    fn info(&self) -> &ChainInfo {
        match self {
            Analytic::Gantry6(g) => &g.info,
            Analytic::Arm4(a) => &a.info,
        }
    }
}

/// Wraps an angle to (−π, π] (rad).
pub fn wrap(angle: f64) -> f64 {
    if angle > -PI && angle <= PI {
        return angle;
    }
    let a = angle.rem_euclid(2.0 * PI);
    if a > PI {
        a - 2.0 * PI
    } else {
        a
    }
}

/// `q` moved into `limits`: revolute angles are shifted by 2πk when that fits; `None` if it can't.
fn fit_to_limits(q: f64, kind: JointType, l: &Limits) -> Option<f64> {
    fit_to_range(q, kind, l.lower, l.upper)
}

/// `q` (m or rad) inside `lo..=hi` (to 1e-12, then clamped), or a revolute angle moved by the
/// smallest 2πk that brings it above `lo` when that fits; `None` otherwise.
pub(crate) fn fit_to_range(q: f64, kind: JointType, lo: f64, hi: f64) -> Option<f64> {
    const SLACK: f64 = 1e-12;
    if q >= lo - SLACK && q <= hi + SLACK {
        return Some(q.clamp(lo, hi));
    }
    if kind == JointType::Revolute && lo.is_finite() {
        let k = ((lo - q) / (2.0 * PI)).ceil();
        let v = q + 2.0 * PI * k;
        if v <= hi + SLACK {
            return Some(v.clamp(lo, hi));
        }
    }
    None
}

/// A DH row with its joint type, for the structural checks.
pub(crate) fn dh_rows(chain: &Chain, convention: DhConvention) -> Option<Vec<(JointType, Dh)>> {
    chain
        .joints()
        .iter()
        .map(|j| match j.geometry() {
            Geometry::Dh(c, dh) if *c == convention => Some((j.kind(), *dh)),
            _ => None,
        })
        .collect()
}

/// True when `a` equals `b` to the structural tolerance 1e-12.
pub(crate) fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12
}

/// Checks the output buffers of a batch of `count` poses of an n-joint chain: N × [`MAX_BRANCHES`]
/// × n joint values and N branch counts.
fn check_branch_buffers(count: usize, n: usize, out: &[f64], counts: &[usize]) -> Result<()> {
    if out.len() != count * MAX_BRANCHES * n || counts.len() != count {
        return Err(Error::shape(
            "output buffers",
            format!("{} and {count} values", count * MAX_BRANCHES * n),
            format!("{} and {}", out.len(), counts.len()),
        ));
    }
    Ok(())
}
