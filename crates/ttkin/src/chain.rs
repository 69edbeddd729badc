//! A serial kinematic chain: base transform, joints, tool transform; forward kinematics and the
//! geometric Jacobian, single and batched.
//!
//! The chain is the immutable model (Pinocchio's `Model`): built once, then shared freely between
//! threads. Algorithms take the joint vector `q` (m for prismatic, rad for revolute joints, in
//! chain order) and allocate nothing beyond their result.

use nalgebra::{IsometryMatrix3, Matrix6xX, Vector3};
use rayon::prelude::*;

use crate::error::{check_vector, Error, Result};
use crate::joint::{Joint, JointType, Limits};
use crate::transform::write_row_major;

/// Frame in which a Jacobian's rows are expressed. The linear part is always the velocity of the
/// tool point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JacobianFrame {
    /// Axes of the base frame (Pinocchio's LOCAL_WORLD_ALIGNED).
    Base,
    /// Axes of the tool frame (Pinocchio's LOCAL).
    Tool,
}

/// Configurations per rayon task in batch calls.
pub(crate) const BATCH_CHUNK: usize = 256;

/// A serial chain of revolute and prismatic joints between a base frame and a tool frame.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Chain {
    name: String,
    joints: Vec<Joint>,
    base: IsometryMatrix3<f64>,
    tool: IsometryMatrix3<f64>,
    /// fixed[0] = base·pre_0, fixed[i] = post_{i−1}·pre_i, fixed[n] = post_{n−1}·tool.
    fixed: Vec<IsometryMatrix3<f64>>,
    kinds: Vec<JointType>,
    /// Racket frame in the tool frame (m); identity unless the robot mounts its racket elsewhere.
    racket: IsometryMatrix3<f64>,
    /// Ready (rest) configuration (m, rad), within the limits; `None`: [`Chain::mid_range`].
    ready: Option<Vec<f64>>,
    /// Gravity in the base frame (m/s²): [`crate::dynamics::EARTH_GRAVITY`] (base z up) unless
    /// the robot's base frame is mounted otherwise.
    #[serde(default = "earth_gravity")]
    gravity: [f64; 3],
}

fn earth_gravity() -> [f64; 3] {
    crate::dynamics::EARTH_GRAVITY
}

impl Chain {
    /// Builds a chain; `base` maps the chain's frame 0 into the base frame, `tool` maps the last
    /// link frame to the tool frame.
    pub fn new(
        name: impl Into<String>,
        joints: Vec<Joint>,
        base: IsometryMatrix3<f64>,
        tool: IsometryMatrix3<f64>,
    ) -> Result<Self> {
        let name = name.into();
        if joints.is_empty() {
            return Err(Error::Model(format!("chain '{name}' has no joint")));
        }
        for (what, t) in [("base", &base), ("tool", &tool)] {
            let v = t.translation.vector;
            crate::error::check_finite(&format!("{what} transform of chain '{name}'"), &[v.x, v.y, v.z])?;
            crate::error::check_finite(
                &format!("{what} transform of chain '{name}'"),
                t.rotation.matrix().as_slice(),
            )?;
        }
        let mut seen = std::collections::HashSet::new();
        for j in &joints {
            if !seen.insert(j.name()) {
                return Err(Error::Model(format!(
                    "chain '{name}': joint name '{}' is used twice",
                    j.name()
                )));
            }
        }
        let n = joints.len();
        let mut fixed = Vec::with_capacity(n + 1);
        fixed.push(base * joints[0].pre());
        for i in 1..n {
            fixed.push(joints[i - 1].post() * joints[i].pre());
        }
        fixed.push(joints[n - 1].post() * tool);
        let kinds = joints.iter().map(Joint::kind).collect();
        Ok(Chain {
            name,
            joints,
            base,
            tool,
            fixed,
            kinds,
            racket: IsometryMatrix3::identity(),
            ready: None,
            gravity: crate::dynamics::EARTH_GRAVITY,
        })
    }

    /// The same robot with other joints, base or tool: its racket mount and ready configuration
    /// are kept (the ready configuration is checked against the new joints' limits).
    pub fn with_joints(
        &self,
        joints: Vec<Joint>,
        base: IsometryMatrix3<f64>,
        tool: IsometryMatrix3<f64>,
    ) -> Result<Self> {
        let c = Chain::new(self.name.clone(), joints, base, tool)?
            .with_racket(self.racket)?
            .with_gravity(self.gravity)?;
        match &self.ready {
            Some(r) => c.with_ready(r),
            None => Ok(c),
        }
    }

    /// The same chain with another tool transform (last link frame → tool frame).
    pub fn with_tool(&self, tool: IsometryMatrix3<f64>) -> Result<Self> {
        self.with_joints(self.joints.clone(), self.base, tool)
    }

    /// The same chain with another base transform (base frame → chain frame 0).
    pub fn with_base(&self, base: IsometryMatrix3<f64>) -> Result<Self> {
        self.with_joints(self.joints.clone(), base, self.tool)
    }

    /// The same chain carrying its racket at `racket`: the racket frame (origin at the centre,
    /// z = face normal, x = handle; `crate::hit::racket`) in the tool frame, m.
    pub fn with_racket(&self, racket: IsometryMatrix3<f64>) -> Result<Self> {
        let v = racket.translation.vector;
        crate::error::check_finite(&format!("racket mount of chain '{}'", self.name), &[v.x, v.y, v.z])?;
        crate::error::check_finite(
            &format!("racket mount of chain '{}'", self.name),
            racket.rotation.matrix().as_slice(),
        )?;
        Ok(Chain { racket, ..self.clone() })
    }

    /// The same chain with the ready (rest) configuration `q` (m, rad): where a stroke starts and
    /// returns to. Refused unless it has one finite value per joint within the joint limits.
    pub fn with_ready(&self, q: &[f64]) -> Result<Self> {
        check_vector("ready", q, self.dof())?;
        for (i, (v, l)) in q.iter().zip(self.limits()).enumerate() {
            if *v < l.lower || *v > l.upper {
                return Err(Error::Model(format!(
                    "chain '{}': ready[{i}] = {v} is outside joint '{}''s limits [{}, {}]",
                    self.name,
                    self.joints[i].name(),
                    l.lower,
                    l.upper
                )));
            }
        }
        Ok(Chain {
            ready: Some(q.to_vec()),
            ..self.clone()
        })
    }

    /// The same chain under the gravity `g` (m/s², base frame): a fact of how the robot's base is
    /// mounted, the default of every dynamics computation on it. Refused unless finite.
    pub fn with_gravity(&self, g: [f64; 3]) -> Result<Self> {
        crate::error::check_finite(&format!("gravity of chain '{}'", self.name), &g)?;
        Ok(Chain {
            gravity: g,
            ..self.clone()
        })
    }

    /// Gravity in the base frame (m/s²): (0, 0, −9.81) unless the robot says otherwise (mobile8's
    /// base frame has x up, [`crate::robots::MOBILE8_GRAVITY`]; robot-file key `gravity`).
    pub fn gravity(&self) -> [f64; 3] {
        self.gravity
    }

    /// Racket frame in the tool frame (m): where this robot carries its racket.
    pub fn racket(&self) -> &IsometryMatrix3<f64> {
        &self.racket
    }

    /// The ready (rest) configuration (m, rad): the robot's own if it has one, else
    /// [`Chain::mid_range`] clamped into the limits.
    pub fn ready(&self) -> Vec<f64> {
        match &self.ready {
            Some(q) => q.clone(),
            None => self
                .mid_range()
                .iter()
                .zip(self.limits())
                .map(|(v, l)| v.clamp(l.lower, l.upper))
                .collect(),
        }
    }

    /// True when the robot gives its own ready configuration (not the mid range).
    pub fn has_ready(&self) -> bool {
        self.ready.is_some()
    }

    /// An upper bound (m) on the distance from the base-frame origin of joint 1's frame
    /// (`base · pre_0`) to the tool point over every configuration within the limits: the sum of
    /// the fixed translations plus the largest travel of each prismatic joint (rotations keep
    /// lengths). +∞ when a prismatic joint is unbounded. A target farther than this is unreachable.
    pub fn reach(&self) -> f64 {
        let fixed: f64 = self.fixed[1..].iter().map(|t| t.translation.vector.norm()).sum();
        let travel: f64 = self
            .joints
            .iter()
            .filter(|j| j.kind() == JointType::Prismatic)
            .map(|j| j.limits().lower.abs().max(j.limits().upper.abs()))
            .sum();
        fixed + travel
    }

    /// Origin of joint 1's frame (`base · pre_0`) in the base frame, m: the centre of [`Chain::reach`].
    pub fn reach_centre(&self) -> Vector3<f64> {
        self.fixed[0].translation.vector
    }

    /// The middle of each finite joint range, 0 for an unbounded joint (m, rad): the default
    /// start of the numeric solvers.
    pub fn mid_range(&self) -> Vec<f64> {
        self.limits()
            .iter()
            .map(|l| {
                if l.lower.is_finite() && l.upper.is_finite() {
                    0.5 * (l.lower + l.upper)
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Name of the robot.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of joints (degrees of freedom).
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The joints, base to tool.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Base frame → chain frame 0.
    pub fn base(&self) -> &IsometryMatrix3<f64> {
        &self.base
    }

    /// Last link frame → tool frame.
    pub fn tool(&self) -> &IsometryMatrix3<f64> {
        &self.tool
    }

    /// Position and derivative limits of every joint.
    pub fn limits(&self) -> Vec<Limits> {
        self.joints.iter().map(|j| *j.limits()).collect()
    }

    /// Position limits as an (n, 2) row-major table: lower then upper per joint (m or rad;
    /// ±inf where unbounded).
    pub fn position_limit_table(&self) -> Vec<f64> {
        self.joints
            .iter()
            .flat_map(|j| [j.limits().lower, j.limits().upper])
            .collect()
    }

    /// Joint names, in order.
    pub fn joint_names(&self) -> Vec<String> {
        self.joints.iter().map(|j| j.name().to_string()).collect()
    }

    /// Joint type names (`"revolute"`, `"prismatic"`), in order.
    pub fn joint_type_names(&self) -> Vec<&'static str> {
        self.joints.iter().map(|j| j.kind().name()).collect()
    }

    /// Joint types as one letter each (`"PRRRRR"`), the form [`JointType::from_letters`] reads.
    pub fn joint_letters(&self) -> String {
        self.joints.iter().map(|j| j.kind().letter()).collect()
    }

    /// Checks that `q` has one finite value per joint.
    pub fn check_q(&self, what: &str, q: &[f64]) -> Result<()> {
        check_vector(what, q, self.dof())
    }

    /// Tool pose in the base frame at configuration `q` (m, rad). Limits are not enforced.
    pub fn fk(&self, q: &[f64]) -> Result<IsometryMatrix3<f64>> {
        self.check_q("q", q)?;
        Ok(self.fk_unchecked(q))
    }

    /// [`Chain::fk`] without the length and finiteness check (`q.len()` must equal `dof()`).
    pub fn fk_unchecked(&self, q: &[f64]) -> IsometryMatrix3<f64> {
        let mut t = self.fixed[0];
        for (i, &qi) in q.iter().enumerate().take(self.dof()) {
            apply_motion(&mut t, self.kinds[i], qi);
            t *= self.fixed[i + 1];
        }
        t
    }

    /// Every link frame in the base frame at `q`: element i is the frame of the link moved by
    /// joint i (its DH frame i, or its URDF child link), tool transform not applied.
    pub fn fk_all(&self, q: &[f64]) -> Result<Vec<IsometryMatrix3<f64>>> {
        self.check_q("q", q)?;
        let mut out = Vec::with_capacity(self.dof());
        let mut t = self.base;
        for (j, &qi) in self.joints.iter().zip(q) {
            t *= j.pre();
            apply_motion(&mut t, j.kind(), qi);
            t *= j.post();
            out.push(t);
        }
        Ok(out)
    }

    /// Geometric Jacobian (6 × n): rows [v; ω], v the velocity of the tool point, ω the angular
    /// velocity, both in the axes of `frame`; columns per joint (per m/s or rad/s).
    pub fn jacobian(&self, q: &[f64], frame: JacobianFrame) -> Result<Matrix6xX<f64>> {
        self.check_q("q", q)?;
        let mut j = Matrix6xX::zeros(self.dof());
        self.jacobian_into(q, frame, &mut j);
        Ok(j)
    }

    /// [`Chain::jacobian`] into a preallocated 6 × n matrix, unchecked; returns the tool pose.
    pub fn jacobian_into(&self, q: &[f64], frame: JacobianFrame, jac: &mut Matrix6xX<f64>) -> IsometryMatrix3<f64> {
        // Forward pass: each column holds the joint's axis origin (top) and axis (bottom).
        let mut t = self.fixed[0];
        for (i, &qi) in q.iter().enumerate().take(self.dof()) {
            let axis = t.rotation.matrix().column(2).into_owned();
            let origin = t.translation.vector;
            let mut col = jac.column_mut(i);
            match self.kinds[i] {
                JointType::Revolute => {
                    col.fixed_rows_mut::<3>(0).copy_from(&origin);
                    col.fixed_rows_mut::<3>(3).copy_from(&axis);
                }
                JointType::Prismatic => {
                    col.fixed_rows_mut::<3>(0).copy_from(&axis);
                    col.fixed_rows_mut::<3>(3).fill(0.0);
                }
            }
            apply_motion(&mut t, self.kinds[i], qi);
            t *= self.fixed[i + 1];
        }
        let p = t.translation.vector;
        for i in 0..self.dof() {
            if self.kinds[i] == JointType::Revolute {
                let mut col = jac.column_mut(i);
                let z: Vector3<f64> = col.fixed_rows::<3>(3).into_owned();
                let o: Vector3<f64> = col.fixed_rows::<3>(0).into_owned();
                col.fixed_rows_mut::<3>(0).copy_from(&z.cross(&(p - o)));
            }
        }
        if frame == JacobianFrame::Tool {
            let rt = t.rotation.matrix().transpose();
            for i in 0..self.dof() {
                let mut col = jac.column_mut(i);
                let v = rt * col.fixed_rows::<3>(0);
                let w = rt * col.fixed_rows::<3>(3);
                col.fixed_rows_mut::<3>(0).copy_from(&v);
                col.fixed_rows_mut::<3>(3).copy_from(&w);
            }
        }
        t
    }

    /// Batch forward kinematics: `qs` holds N configurations row-major (N × n), `out` receives N
    /// row-major 4×4 tool poses (N × 16). Runs in parallel; every configuration is checked first.
    pub fn fk_batch(&self, qs: &[f64], out: &mut [f64]) -> Result<()> {
        self.for_each_row(
            qs,
            out,
            16,
            || (),
            |_, q, o| {
                write_row_major(&self.fk_unchecked(q), o);
                Ok(())
            },
        )
    }

    /// Batch of every link frame: `out` receives N × n row-major 4×4 frames (N × n × 16).
    pub fn fk_all_batch(&self, qs: &[f64], out: &mut [f64]) -> Result<()> {
        self.for_each_row(
            qs,
            out,
            16 * self.dof(),
            || (),
            |_, q, o| {
                for (frame, dst) in self.fk_all(q)?.iter().zip(o.chunks_exact_mut(16)) {
                    write_row_major(frame, dst);
                }
                Ok(())
            },
        )
    }

    /// Batch Jacobians: `out` receives N row-major 6 × n matrices (N × 6n).
    pub fn jacobian_batch(&self, qs: &[f64], frame: JacobianFrame, out: &mut [f64]) -> Result<()> {
        let n = self.dof();
        self.for_each_row(
            qs,
            out,
            6 * n,
            || Matrix6xX::zeros(n),
            |jac, q, o| {
                self.jacobian_into(q, frame, jac);
                for r in 0..6 {
                    for c in 0..n {
                        o[r * n + c] = jac[(r, c)];
                    }
                }
                Ok(())
            },
        )
    }

    /// The one parallel loop of the batches over configurations: checks `qs` (N × n finite
    /// values) against `out` (N × `per_item` values), then calls `row(scratch, q_i, out_i)` for
    /// every row, in parallel over fixed chunks of rows (so results do not depend on the thread
    /// count), with `scratch` made by `init` once per chunk; the first row error otherwise.
    pub(crate) fn for_each_row<S, I, F>(
        &self,
        qs: &[f64],
        out: &mut [f64],
        per_item: usize,
        init: I,
        row: F,
    ) -> Result<()>
    where
        I: Fn() -> S + Sync,
        F: Fn(&mut S, &[f64], &mut [f64]) -> Result<()> + Sync,
    {
        let n = self.dof();
        self.batch_count(qs, out.len(), per_item)?;
        out.par_chunks_mut(per_item * BATCH_CHUNK)
            .zip(qs.par_chunks(n * BATCH_CHUNK))
            .try_for_each(|(o, q)| {
                let mut scratch = init();
                for (oi, qi) in o.chunks_exact_mut(per_item).zip(q.chunks_exact(n)) {
                    row(&mut scratch, qi, oi)?;
                }
                Ok(())
            })
    }

    /// Validates a batch: `qs` is N × n finite values and `out_len` is N × `per_item`.
    fn batch_count(&self, qs: &[f64], out_len: usize, per_item: usize) -> Result<usize> {
        let count = crate::error::check_rows("q", qs, self.dof())?;
        crate::error::check_len("output buffer", out_len, count, per_item)?;
        Ok(count)
    }
}

/// Applies the joint motion M(q) on the right of `t`: rotation about or translation along local z.
#[inline(always)]
fn apply_motion(t: &mut IsometryMatrix3<f64>, kind: JointType, q: f64) {
    match kind {
        JointType::Revolute => {
            let (s, c) = crate::trig::sin_cos(q);
            // Columns c0, c1 of R·Rz(q): c·c0 + s·c1, −s·c0 + c·c1; c2 and the origin are unchanged.
            let m = t.rotation.matrix_mut_unchecked();
            for r in 0..3 {
                let (x, y) = (m[(r, 0)], m[(r, 1)]);
                m[(r, 0)] = c * x + s * y;
                m[(r, 1)] = c * y - s * x;
            }
        }
        JointType::Prismatic => {
            let z = t.rotation.matrix().column(2).into_owned();
            t.translation.vector += z * q;
        }
    }
}
