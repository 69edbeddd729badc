//! The hit pipeline's types: the request ([`Hit`]), the planner's settings ([`HitOptions`],
//! [`StrokeProfile`], [`HitTask`]) and its result ([`HitPlan`], [`HitStatus`]).

use nalgebra::{IsometryMatrix3, Vector3};

use super::racket::{racket_frame, DEFAULT_HANDLE};
use crate::error::{check_finite, Error, Result};
use crate::traj::limits::Violation;
use crate::traj::{JointState, JointTrajectory};

/// Hit parameters: where the racket is, how it moves, and when.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hit {
    /// Racket pose at the hit: racket frame (origin at the centre, z = face normal) in the base
    /// frame (m).
    pub pose: IsometryMatrix3<f64>,
    /// Racket-centre twist at the hit [v (m/s); ω (rad/s)], base axes.
    pub twist: [f64; 6],
    /// Hit time (s from now, > 0).
    pub t: f64,
}

impl Hit {
    /// A hit from its racket pose (base frame, m), racket-centre twist (base axes, m/s, rad/s) and
    /// hit time (s from now); checks finiteness and 0 < t ≤ [`crate::traj::duration::MAX_DURATION`].
    pub fn new(pose: IsometryMatrix3<f64>, twist: [f64; 6], t: f64) -> Result<Hit> {
        check_finite("twist", &twist)?;
        check_finite("pose", pose.translation.vector.as_slice())?;
        check_finite("pose", pose.rotation.matrix().as_slice())?;
        crate::traj::check_duration("t", t)?;
        let max = crate::traj::duration::MAX_DURATION;
        if t > max {
            // A later hit cannot be planned (no stroke is longer); refused here, not as an effort
            // limit with an infinite ratio or a sample count of the stroke.
            return Err(crate::Error::invalid(
                "t",
                // 1e300 as 1e300, not its 301 digits
                format!("the hit time must be at most {max} s from now (the longest stroke), got {t:e} s"),
            ));
        }
        Ok(Hit { pose, twist, t })
    }

    /// N hits from their poses (base frame, m), twists (N × 6, row-major, as in [`Hit::new`]) and
    /// times (N,); an error names the element (`hits[i].t`); N poses, twists and times needed.
    pub fn batch(poses: &[IsometryMatrix3<f64>], twists: &[f64], times: &[f64]) -> Result<Vec<Hit>> {
        let k = poses.len();
        if twists.len() != 6 * k || times.len() != k {
            return Err(Error::shape(
                "hits",
                format!("{k} twists (6 values each) and {k} times for {k} poses"),
                format!("{} twist values and {} times", twists.len(), times.len()),
            ));
        }
        poses
            .iter()
            .zip(twists.chunks_exact(6))
            .zip(times)
            .enumerate()
            .map(|(i, ((pose, w), &t))| {
                Hit::new(*pose, [w[0], w[1], w[2], w[3], w[4], w[5]], t).map_err(|e| e.within(&format!("hits[{i}].")))
            })
            .collect()
    }

    /// A hit from the racket centre (m, base frame), the face normal (any length, base axes), the
    /// racket-centre velocity (m/s, base axes), the hit time (s) and the racket's angular velocity
    /// (rad/s, base axes, zero when `None`). The handle points as close as possible to `handle`
    /// ([`DEFAULT_HANDLE`] when `None`): see [`racket_frame`].
    pub fn from_normal(
        centre: [f64; 3],
        normal: [f64; 3],
        velocity: [f64; 3],
        t: f64,
        omega: Option<[f64; 3]>,
        handle: Option<[f64; 3]>,
    ) -> Result<Hit> {
        check_finite("centre", &centre)?;
        check_finite("velocity", &velocity)?;
        let w = omega.unwrap_or([0.0; 3]);
        check_finite("omega", &w)?;
        let r = racket_frame(&Vector3::from(normal), &Vector3::from(handle.unwrap_or(DEFAULT_HANDLE)))?;
        let pose = IsometryMatrix3::from_parts(Vector3::from(centre).into(), r);
        Hit::new(pose, [velocity[0], velocity[1], velocity[2], w[0], w[1], w[2]], t)
    }

    /// Racket centre (m, base frame).
    pub fn centre(&self) -> Vector3<f64> {
        self.pose.translation.vector
    }

    /// Unit face normal (base axes): the racket frame's z axis.
    pub fn normal(&self) -> Vector3<f64> {
        self.pose.rotation.matrix().column(2).into_owned()
    }
}

/// The family of the hit leg of a stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StrokeProfile {
    /// The quintic when it meets the hit time within the limits, else the jerk-limited stroke.
    Auto,
    /// The patent's quintic (S104); a late hit time is the earliest feasible quintic duration.
    Quintic,
    /// Jerk-limited, time-optimal up to the hit time ([`crate::traj::jerk`]).
    Jerk,
}

impl StrokeProfile {
    /// Every profile, in the order the names are listed to users.
    pub const ALL: [StrokeProfile; 3] = [StrokeProfile::Auto, StrokeProfile::Quintic, StrokeProfile::Jerk];

    /// Parses `"auto"`, `"quintic"` or `"jerk"`.
    pub fn from_name(name: &str) -> Result<StrokeProfile> {
        match name {
            "auto" => Ok(StrokeProfile::Auto),
            "quintic" => Ok(StrokeProfile::Quintic),
            "jerk" | "ruckig" => Ok(StrokeProfile::Jerk),
            other => Err(Error::invalid(
                "profile",
                format!("unknown stroke profile '{other}'; choose 'auto', 'quintic' or 'jerk'"),
            )),
        }
    }

    /// The name `from_name` parses.
    pub fn name(&self) -> &'static str {
        match self {
            StrokeProfile::Auto => "auto",
            StrokeProfile::Quintic => "quintic",
            StrokeProfile::Jerk => "jerk",
        }
    }
}

impl std::str::FromStr for StrokeProfile {
    type Err = Error;

    /// [`StrokeProfile::from_name`].
    fn from_str(s: &str) -> Result<StrokeProfile> {
        StrokeProfile::from_name(s)
    }
}

/// Which part of the racket pose the hit prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum HitTask {
    /// Full pose for a chain of ≤ 6 joints, the 5-D racket task for a redundant chain.
    Auto,
    /// The full 6-D racket pose and twist.
    Pose,
    /// Seed 000's 5-D racket task: centre and face normal (rotation about the normal free), the
    /// centre velocity and the normal's rate.
    Racket5,
}

impl std::str::FromStr for HitTask {
    type Err = Error;

    /// Parses `"auto"`, `"pose"` or `"racket5"` (the names [`HitTask::name`] gives).
    fn from_str(s: &str) -> Result<HitTask> {
        match s {
            "auto" => Ok(HitTask::Auto),
            "pose" => Ok(HitTask::Pose),
            "racket5" => Ok(HitTask::Racket5),
            other => Err(Error::invalid(
                "task",
                format!("expected 'auto', 'pose' or 'racket5', got '{other}'"),
            )),
        }
    }
}

impl HitTask {
    /// The name `str::parse` reads back.
    pub fn name(&self) -> &'static str {
        match self {
            HitTask::Auto => "auto",
            HitTask::Pose => "pose",
            HitTask::Racket5 => "racket5",
        }
    }
}

/// Planner settings.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HitOptions {
    /// Family of the hit leg.
    pub profile: StrokeProfile,
    /// Which part of the hit the IK must meet.
    pub task: HitTask,
    /// Jerk limits (rad/s³ or m/s³, one per joint); `None` for
    /// [`super::DEFAULT_JERK_PER_ACCELERATION`] × the acceleration limits.
    pub jerk: Option<Vec<f64>>,
    /// Gravity (m/s², base frame) for the torques; `None`: the robot's own ([`crate::Chain::gravity`]:
    /// base z up unless the robot file says otherwise, x up for mobile8).
    pub gravity: Option<[f64; 3]>,
    /// Check (and retime for) the effort limits by inverse dynamics; off: kinematic limits only.
    pub check_effort: bool,
    /// Tolerance (ratio units) of the reported [`HitPlan::effort_ratio`]: the certified bound of
    /// the peak |τ|/limit is within it of the ratio reported (> 0; the feasibility decision itself
    /// is exact, [`crate::dynamics::peak`]).
    pub effort_tolerance: f64,
    /// Latest hit time (s) the earliest-feasible search tries.
    pub max_t_hit: f64,
}

impl Default for HitOptions {
    /// Auto profile and task, default jerk limits, the robot's gravity, effort ratio to 1e-4,
    /// search up to 10 s.
    fn default() -> Self {
        HitOptions {
            profile: StrokeProfile::Auto,
            task: HitTask::Auto,
            jerk: None,
            gravity: None,
            check_effort: true,
            effort_tolerance: 1e-4,
            max_t_hit: 10.0,
        }
    }
}

/// How a plan came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum HitStatus {
    /// On time and within every limit.
    Ok,
    /// The requested hit time is earlier than feasible: the plan is made for
    /// [`HitPlan::earliest_t_hit`].
    TooEarly,
    /// No configuration within the position limits reaches the racket pose.
    Unreachable,
    /// The hit configuration is singular: the twist cannot be produced.
    Singular,
    /// The hit joint velocity exceeds a speed limit: no hit time can help.
    HitSpeedLimit,
    /// The stroke leaves the position limits.
    PositionLimit,
    /// The torques exceed an effort limit for every hit time up to the search limit.
    EffortLimit,
    /// No stroke within the velocity, acceleration and jerk limits reaches the hit state.
    NoStroke,
}

impl HitStatus {
    /// Short snake-case name (`"ok"`, `"too_early"`, `"unreachable"`, `"singular"`,
    /// `"hit_speed_limit"`, `"position_limit"`, `"effort_limit"`, `"no_stroke"`).
    pub fn name(&self) -> &'static str {
        match self {
            HitStatus::Ok => "ok",
            HitStatus::TooEarly => "too_early",
            HitStatus::Unreachable => "unreachable",
            HitStatus::Singular => "singular",
            HitStatus::HitSpeedLimit => "hit_speed_limit",
            HitStatus::PositionLimit => "position_limit",
            HitStatus::EffortLimit => "effort_limit",
            HitStatus::NoStroke => "no_stroke",
        }
    }
}

/// Every product of planning one hit. Joint values in rad or m, times in s from now.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HitPlan {
    /// The request.
    pub hit: Hit,
    /// Outcome.
    pub status: HitStatus,
    /// One line saying what limited the plan (empty when `Ok`).
    pub message: String,
    /// Joint state the stroke starts from (now).
    pub start: JointState,
    /// Rest configuration the stroke returns to.
    pub ready: Vec<f64>,
    /// Tool pose (base frame, m) that puts the racket at the hit pose.
    pub tool_target: IsometryMatrix3<f64>,
    /// Number of IK branches within the limits (1 for numeric or task IK, 0 when unreachable).
    pub branches: usize,
    /// Hit configuration (NaN when unreachable).
    pub q_hit: Vec<f64>,
    /// Hit joint velocities (NaN when unreachable).
    pub qd_hit: Vec<f64>,
    /// Smallest singular value of the (task) Jacobian at the hit (NaN when unreachable).
    pub sigma_min: f64,
    /// Planned hit time (s); NaN when no stroke was planned.
    pub t_hit: f64,
    /// Earliest feasible hit time (s) when planning found it (a late plan); NaN otherwise: then
    /// [`super::HitPlanner::earliest_t_hit`] computes it on demand.
    pub earliest_t_hit: f64,
    /// Profile of the hit leg actually used (`Quintic` or `Jerk`); `Auto` when no stroke.
    pub profile: StrokeProfile,
    /// Hit leg then return leg from 0 s (now); `None` when no stroke was planned.
    pub trajectory: Option<JointTrajectory>,
    /// Duration of the return leg (s).
    pub return_duration: f64,
    /// Kinematic limit violations of the trajectory (exact peaks), empty when within limits.
    pub violations: Vec<Violation>,
    /// Largest |joint torque| (N·m or N, with friction) per joint over the stroke (at the instants
    /// the certified peak search evaluated; within the effort tolerance of the true peak for the
    /// joints whose limit does not depend on speed).
    pub peak_effort: Vec<f64>,
    /// Largest |τ(t)|/effective effort limit over joints and the whole stroke, every instant
    /// ([`crate::effort`]: the robot file's limit or the drive's, whichever is smaller at q̇(t)):
    /// a value the stroke takes, within `effort_tolerance` of the certified peak (0 without
    /// dynamics or limits).
    pub effort_ratio: f64,
}

impl HitPlan {
    /// True when the plan is on time and within every limit.
    pub fn ok(&self) -> bool {
        self.status == HitStatus::Ok
    }

    /// Bytes this plan holds: the struct and everything it owns on the heap.
    pub fn bytes(&self) -> usize {
        let f = std::mem::size_of::<f64>();
        let vectors = self.start.q.capacity()
            + self.start.qd.capacity()
            + self.start.qdd.capacity()
            + self.ready.capacity()
            + self.q_hit.capacity()
            + self.qd_hit.capacity()
            + self.peak_effort.capacity();
        std::mem::size_of::<HitPlan>()
            + vectors * f
            + self.message.capacity()
            + self.violations.capacity() * std::mem::size_of::<Violation>()
            + self.trajectory.as_ref().map_or(0, JointTrajectory::heap_bytes)
    }

    /// A lower bound of [`HitPlan::bytes`] for a robot of `dof` joints: the struct, its seven
    /// per-joint vectors and a stroke of two segments (hit leg and return leg).
    pub fn bytes_at_least(dof: usize) -> usize {
        std::mem::size_of::<HitPlan>()
            + 7 * dof * std::mem::size_of::<f64>()
            + JointTrajectory::heap_bytes_at_least(dof, 2)
    }
}
