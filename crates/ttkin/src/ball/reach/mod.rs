//! The robot's reachable region, defined from its geometry, physics and joint limits alone (no
//! planner): which incoming balls the robot could **return**.
//!
//! A ball is **in reach** when, after its bounce on the robot's half and before any other contact,
//! its true flight (sampled every `step` s while it still moves toward the robot, x velocity < 0)
//! has a point p at a time t such that
//! 1. p lies in the **hitting volume** (world box: the height band above the surface and the
//!    region behind the table the racket may sweep; the axis strokes are checked by IK, item 3);
//! 2. a **return shot** of a fixed grid exists there (`reach/returns.rs`): for a landing target of
//!    `targets` (x ∈ {0.4, 0.8, 1.2} m, y ∈ {−0.5, 0, 0.5} m on the opponent's half) and a return
//!    time T of `return_times` ({0.45, 0.6, 0.75, 0.9, 1.05} s), the drag-free parabola's
//!    v_out = (goal − p − ½·g·T²)/T, the racket normal and velocity of the impact model that give
//!    it ([`super::impact::RacketImpact::solve`]), and the ball leaving with v_out and that racket's
//!    outgoing spin **really** returns: in the flight model (drag and Magnus, 10 ms RK4) its first
//!    contact is the table on the opponent's half (so it clears the net);
//! 3. the racket can be **placed** for that shot: for some roll of `rolls` ({0, ±30°, ±60°}) of
//!    the handle about the shot's normal n, the racket centre p − r·n has an analytic IK solution q
//!    within every joint position limit (which include the d1 and d2 strokes);
//! 4. the joints can **move the racket** at the hit: q̇ = J⁻¹(q)·V for the racket twist V (the
//!    shot's racket velocity, no rotation) is within every joint's velocity limit (a singular J
//!    fails: no exact q̇);
//! 5. the robot can **get there in time**: for that q, the per-joint minimum time from rest at the
//!    ready configuration under the joint's speed limit v and acceleration limit a,
//!    Δ = |q_i − q_ready,i|: √(2Δ/a) when Δ ≤ v²/(2a), else Δ/v + v/(2a) (full acceleration, then
//!    full speed; any arrival speed), is at most t − now for every joint.
//!
//! Items 4 and 5 are necessary conditions for a stroke, so the region is an outer bound of the
//! balls any planner could return with these joints through these shots: a return rate over it is
//! not flattered by the planner's own choices. The grids are fixed, never the planner's.
//!
//! Why the drag-free parabola with the real landing check, and not the real model's shooting: a
//! shooting solve costs about 46 µs (six flights), the landing check of one flight about 8 µs, and
//! the region tries up to 45 shots at each of some 30 samples of a ball it rejects; the shot tried
//! is then not exactly at its grid target, but it is a real return (it lands on the opponent's
//! half in the same flight model), which is what "a return is possible" asks.
//!
//! [`ReachRegion::classify_touch`] keeps the earlier, weaker region for comparison: a ball the
//! racket can **touch** (some orientation of a fixed grid of 45 has IK at the ball in time),
//! whether or not any of them returns it.

mod returns;

use super::flight::{BallState, EventKind, Flight};
use super::impact::RacketImpact;
use crate::chain::Chain;
use crate::error::{Error, Result};
use crate::ik::{Analytic, LimitFilter};
use crate::traj::limits::KinematicLimits;
use nalgebra::{IsometryMatrix3, Matrix3, Rotation3, Translation3, Vector3};

/// How a ball relates to the reachable region (see the module doc), in the order checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reachability {
    /// Its flight does not bounce on the robot's half (net, long, wide, floor).
    NoBounce,
    /// After the bounce it never passes through the hitting volume.
    OutsideVolume,
    /// Touch region only ([`ReachRegion::classify_touch`]): it passes the volume, but no racket
    /// orientation of the grid is within the joint limits there.
    NoPose,
    /// It passes the volume, but no shot of the grid returns it to the opponent's half.
    NoReturn,
    /// Return shots exist, but no racket pose for any of them (rolls of the grid) is within the
    /// joint position limits.
    NoReturnPose,
    /// Racket poses for return shots exist, but every one needs a joint velocity q̇ = J⁻¹·V above
    /// its limit (or a singular configuration) to move the racket at the shot's speed.
    ReturnSpeed,
    /// A pose exists (for the touch region; with the speed condition for the return region), but
    /// every one needs more time from the ready configuration than the ball leaves (too early for
    /// the joints' speed and acceleration limits).
    TooEarly,
    /// In reach: the first feasible point found, its time (s, absolute) and the minimum time
    /// (s) the joints need to get there from the ready configuration.
    InReach {
        /// Ball centre (m, world).
        p: Vector3<f64>,
        /// Time (s, absolute) of the ball at `p`.
        t: f64,
        /// Minimum joint time (s) from the ready configuration to the racket pose.
        min_time: f64,
    },
}

impl Reachability {
    /// The names of the return region's verdicts ([`ReachRegion::classify`]), in the order checked.
    pub const NAMES: [&'static str; 7] = [
        "no_bounce",
        "outside_volume",
        "no_return",
        "no_return_pose",
        "return_speed",
        "too_early",
        "in_reach",
    ];

    /// Short lower-case name ("no_bounce", "outside_volume", "no_pose", "no_return",
    /// "no_return_pose", "return_speed", "too_early", "in_reach").
    pub fn name(&self) -> &'static str {
        match self {
            Reachability::NoBounce => "no_bounce",
            Reachability::OutsideVolume => "outside_volume",
            Reachability::NoPose => "no_pose",
            Reachability::NoReturn => "no_return",
            Reachability::NoReturnPose => "no_return_pose",
            Reachability::ReturnSpeed => "return_speed",
            Reachability::TooEarly => "too_early",
            Reachability::InReach { .. } => "in_reach",
        }
    }

    /// Whether the ball is in reach.
    pub fn in_reach(&self) -> bool {
        matches!(self, Reachability::InReach { .. })
    }
}

/// The reachable region of one robot: chain, placement, ready configuration, hitting volume, the
/// grid of return shots and racket rolls (and the orientation grid of the touch region).
#[derive(Debug, Clone)]
pub struct ReachRegion {
    chain: Chain,
    ik: Analytic,
    limits: KinematicLimits,
    /// Base frame in the world.
    pub placement: Placement,
    /// Ready configuration (m, rad): strokes start from rest here.
    pub ready: Vec<f64>,
    /// Hitting volume of the ball centre (world, m).
    pub volume: Reach,
    /// Landing targets (x, y, m, world) of the return shots, on the opponent's half.
    pub targets: Vec<[f64; 2]>,
    /// Return flight times (s) of the return shots.
    pub return_times: Vec<f64>,
    /// Contact points (m) of the ball on the face, from its centre along the face's direction
    /// closest to world y (across the table): the racket centre is moved by the opposite.
    pub contact_offsets: Vec<f64>,
    /// Rubber of the racket whose impact model gives each shot's normal and velocity.
    pub impact: RacketImpact,
    /// Touch region only: azimuths and elevations (rad) of the face normal, each combination one
    /// normal (cos e·cos a, cos e·sin a, sin e) in the world: toward the opponent.
    pub normal_angles: Vec<f64>,
    /// Rolls (rad) of the racket about its normal, from the handle-up frame.
    pub rolls: Vec<f64>,
    /// Ball radius (m): the racket centre is the ball centre minus r·n.
    pub ball_radius: f64,
    /// Sampling period (s) of the flight.
    pub step: f64,
}

/// Where the robot's base frame sits in the world frame: base = world ∘ (translation, yaw about z).
///
/// gantry6 default: origin at (−2.0, 0, 0.15) m, yaw +90°, so base x = world y (the d2 axis moves
/// across the table), base y = −world x (d1 moves along the table: its axis is −y of the base, i.e.
/// toward the net), base z = world z. The racket then reaches about x ∈ [−2.9, −0.9] m along the
/// table, |y| ≤ 0.6 m across it and 0.15 ± 0.45 m in height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Base-frame origin (m, world).
    pub origin: Vector3<f64>,
    /// Rotation of the base about world z (rad).
    pub yaw: f64,
}

impl Default for Placement {
    fn default() -> Self {
        Placement {
            origin: Vector3::new(-2.0, 0.0, 0.15),
            yaw: std::f64::consts::FRAC_PI_2,
        }
    }
}

impl Placement {
    /// Where the rally places `chain` by the table: the default placement when the ball planner
    /// plays with it (an analytic-IK chain, the gantry6 structure: [`Analytic::for_chain`], as
    /// [`crate::ball::hitplan::ReturnPlanner::new`] requires), `None` for any other robot. A fact
    /// of the chain's structure, whatever its name.
    pub fn for_chain(chain: &Chain) -> Option<Placement> {
        Analytic::for_chain(chain).map(|_| Placement::default())
    }

    /// The base frame in the world frame.
    pub fn world_from_base(&self) -> IsometryMatrix3<f64> {
        IsometryMatrix3::from_parts(
            Translation3::from(self.origin),
            Rotation3::from_axis_angle(&Vector3::z_axis(), self.yaw),
        )
    }
}

/// An axis-aligned box of ball-centre positions (world frame, m): the hitting volume.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reach {
    /// Lower corner (m, world).
    pub lo: Vector3<f64>,
    /// Upper corner (m, world).
    pub hi: Vector3<f64>,
}

impl Default for Reach {
    /// The hitting volume of gantry6 (world, m): behind the table up to 7 cm over its end line,
    /// x ∈ [−3.0, −1.3] (the d1 stroke decides by IK), |y| ≤ 1.0 (the d2 stroke decides), and the
    /// height band z ∈ [0.06, 0.45] (the racket stays above the table top's level).
    fn default() -> Self {
        Reach {
            lo: Vector3::new(-3.0, -1.0, 0.06),
            hi: Vector3::new(-1.3, 1.0, 0.45),
        }
    }
}

impl Reach {
    /// Whether the world point `p` (m) lies in the box.
    pub fn contains(&self, p: &Vector3<f64>) -> bool {
        (0..3).all(|k| p[k] >= self.lo[k] && p[k] <= self.hi[k])
    }
}

/// Racket frame (world) for the face normal `n`: z = n, x (the handle) as close to world up as
/// possible (world x when n is within 18° of vertical), then turned by `roll` (rad) about n.
pub fn racket_rotation(n: &Vector3<f64>, roll: f64) -> Rotation3<f64> {
    // Roll 0 (the first one tried, the most frequent) without the sin/cos: the same values.
    racket_rotation_turned(n, if roll == 0.0 { (0.0, 1.0) } else { roll.sin_cos() })
}

/// [`racket_rotation`] for the roll given by its (sine, cosine): for callers turning many
/// normals by the same few rolls.
pub fn racket_rotation_turned(n: &Vector3<f64>, (sin, cos): (f64, f64)) -> Rotation3<f64> {
    let z = n.normalize();
    let hint = if z.z.abs() < 0.95 { Vector3::z() } else { Vector3::x() };
    let r0 = crate::hit::racket_axes(&z, &hint);
    let (x0, y0) = (r0.matrix().column(0), r0.matrix().column(1));
    let x = cos * x0 + sin * y0;
    Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[x, z.cross(&x), z]))
}

pub use crate::hit::leg::min_joint_time;

impl ReachRegion {
    /// The region of `chain` (analytic IK) placed by `placement`, starting from `ready`, with the
    /// default volume, targets x ∈ {0.4, 0.8, 1.2} m × y ∈ {−0.5, 0, 0.5} m, return times 0.45 to
    /// 1.05 s by 0.15 s, the default racket rubber, rolls 0, ±30°, ±60° (and, for the touch
    /// region, normals at 0, ±30° azimuth and elevation).
    pub fn new(chain: &Chain, placement: Placement, ready: Vec<f64>, ball_radius: f64) -> Result<Self> {
        let ik = Analytic::for_chain(chain)
            .ok_or_else(|| Error::Model("the reachable region needs a chain with analytic IK (gantry6)".into()))?;
        crate::error::check_vector("ready", &ready, chain.dof())?;
        let deg = std::f64::consts::PI / 180.0;
        let targets = [0.4, 0.8, 1.2]
            .iter()
            .flat_map(|&x| [-0.5, 0.0, 0.5].map(|y| [x, y]))
            .collect();
        Ok(ReachRegion {
            chain: chain.clone(),
            ik,
            limits: KinematicLimits::from_chain(chain, None)?,
            placement,
            ready,
            volume: Reach::default(),
            targets,
            return_times: vec![0.45, 0.6, 0.75, 0.9, 1.05],
            impact: RacketImpact::default(),
            contact_offsets: vec![0.0],
            normal_angles: vec![-30.0 * deg, 0.0, 30.0 * deg],
            rolls: vec![-60.0 * deg, -30.0 * deg, 0.0, 30.0 * deg, 60.0 * deg],
            ball_radius,
            step: 0.005,
        })
    }

    /// What "in reach" means for this region, in one sentence built from its grids (targets,
    /// return times, rolls): the definition the rally's summary states.
    pub fn definition(&self) -> String {
        fn distinct(mut v: Vec<f64>) -> String {
            v.sort_by(f64::total_cmp);
            v.dedup();
            v.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(", ")
        }
        let xs = distinct(self.targets.iter().map(|t| t[0]).collect());
        let ys = distinct(self.targets.iter().map(|t| t[1]).collect());
        let (t_lo, t_hi) = self
            .return_times
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
                (lo.min(t), hi.max(t))
            });
        let mut rolls: Vec<f64> = self.rolls.iter().map(|r| r.to_degrees().abs().round()).collect();
        rolls.sort_by(f64::total_cmp);
        rolls.dedup();
        let signed = |r: &f64| {
            let both = self.rolls.iter().any(|&x| x.to_degrees().round() == -r) && *r != 0.0;
            if both {
                format!("+-{r}")
            } else {
                format!("{r}")
            }
        };
        let rolls = rolls.iter().map(signed).collect::<Vec<_>>().join(", ");
        format!(
            "a return is possible: after its bounce on the robot's half the true flight has a point in \
             the hitting volume where a shot of a fixed grid (drag-free parabola to x in {{{xs}}} m, y in \
             {{{ys}}} m in {t_lo} to {t_hi} s) with the racket of the impact model lands on the opponent's \
             half in the real flight model, a racket pose for it (roll {rolls} deg) has IK within the \
             joint position limits, q_dot = J^-1 V is within the velocity limits and the joints' minimum \
             time from rest at the ready configuration is at most the time left (ttkin::ball::reach); \
             independent of the planner"
        )
    }

    /// Minimum time (s) from rest at the ready configuration to `q` (m, rad) over every joint.
    pub fn min_time(&self, q: &[f64]) -> f64 {
        q.iter()
            .zip(&self.ready)
            .enumerate()
            .map(|(i, (qi, ri))| min_joint_time(qi - ri, self.limits.velocity[i], self.limits.acceleration[i]))
            .fold(0.0, f64::max)
    }

    /// The smallest minimum time (s) over the admissible racket poses for a ball centre at `p`
    /// (m, world), or `None` when `p` is outside the volume or no pose is within the joint limits.
    pub fn placement_time(&self, p: &Vector3<f64>) -> Option<f64> {
        if !self.volume.contains(p) {
            return None;
        }
        let base_from_world = self.placement.world_from_base().inverse();
        let mut best: Option<f64> = None;
        for &az in &self.normal_angles {
            for &el in &self.normal_angles {
                let n = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
                for &roll in &self.rolls {
                    let rot = racket_rotation(&n, roll);
                    let c = p - self.ball_radius * n;
                    let pose = base_from_world * IsometryMatrix3::from_parts(Translation3::from(c), rot);
                    let Ok(sols) = self.ik.solve(&pose, Some(&self.ready), LimitFilter::Enforce) else {
                        continue;
                    };
                    for q in sols.iter() {
                        let t = self.min_time(q);
                        if best.is_none_or(|b| t < b) {
                            best = Some(t);
                        }
                    }
                }
            }
        }
        best
    }

    /// Classifies the ball `ball` (true state), flying by `flight` (the return shots fly by its
    /// model and table), for a stroke starting at rest at the ready configuration at time `now`
    /// (s): in reach, or the deepest condition of the module doc that no sample met.
    pub fn classify(&self, flight: &Flight, ball: &BallState, now: f64) -> Reachability {
        let mut deepest = returns::Stage::Nothing;
        let mut found = None;
        let bounced = walk_after_bounce(flight, ball, self.step, false, |s| {
            if s.p.x < self.volume.lo.x {
                return false;
            }
            if !self.volume.contains(&s.p) {
                return true;
            }
            match self.return_at(flight, s, now, &mut deepest) {
                Some(min_time) => {
                    found = Some(Reachability::InReach {
                        p: s.p,
                        t: s.t,
                        min_time,
                    });
                    false
                }
                None => true,
            }
        });
        match (found, bounced) {
            (Some(r), _) => r,
            (None, false) => Reachability::NoBounce,
            (None, true) => deepest.verdict(),
        }
    }

    /// The touch region (the region before the return conditions, kept for comparison): classifies
    /// `ball` (true state), flying by `flight`, by items 1 and 5 of the module doc with the racket
    /// placed for any orientation of the grid (`normal_angles` × `normal_angles` × `rolls`) instead
    /// of a return shot's: `NoBounce`, `OutsideVolume`, `NoPose`, `TooEarly` or `InReach`.
    pub fn classify_touch(&self, flight: &Flight, ball: &BallState, now: f64) -> Reachability {
        let (mut in_volume, mut placeable, mut found) = (false, false, None);
        let bounced = walk_after_bounce(flight, ball, self.step, false, |s| {
            if s.p.x < self.volume.lo.x {
                return false;
            }
            if !self.volume.contains(&s.p) {
                return true;
            }
            in_volume = true;
            if let Some(min_time) = self.placement_time(&s.p) {
                placeable = true;
                if min_time <= s.t - now {
                    found = Some(Reachability::InReach {
                        p: s.p,
                        t: s.t,
                        min_time,
                    });
                    return false;
                }
            }
            true
        });
        match (found, bounced, in_volume, placeable) {
            (Some(r), ..) => r,
            (None, false, _, _) => Reachability::NoBounce,
            (None, true, false, _) => Reachability::OutsideVolume,
            (None, true, true, false) => Reachability::NoPose,
            (None, true, true, true) => Reachability::TooEarly,
        }
    }
}

/// Walks the flight of `ball` every `step` s (at most 2 s) through its first bounce on the robot's
/// half (`bounced`: it already happened), then calls `visit` with every sample free of contact until
/// another contact, the ball moving back toward the net, or `visit` returning false. Returns whether
/// the bounce happened.
pub fn walk_after_bounce(
    flight: &Flight,
    ball: &BallState,
    step: f64,
    bounced: bool,
    visit: impl FnMut(&BallState) -> bool,
) -> bool {
    walk_after_bounce_clip(flight, ball, step, bounced, 0.0, visit)
}

/// [`walk_after_bounce`] where a ball that touches the net with its centre at most `clip` (m)
/// below clearing its top (centre height net + radius) flies on as if there were no net: for a
/// prediction whose error is that large.
pub fn walk_after_bounce_clip(
    flight: &Flight,
    ball: &BallState,
    step: f64,
    mut bounced: bool,
    clip: f64,
    mut visit: impl FnMut(&BallState) -> bool,
) -> bool {
    let mut cur = *ball;
    let t_end = ball.t + 2.0;
    let clear = flight.table.net_height + flight.model.radius;
    let mut net = true;
    while cur.t < t_end {
        let (next, ev) = flight.advance_guarded(&cur, cur.t + step, None, 1, net);
        cur = next;
        if let Some(e) = ev {
            match e.kind {
                EventKind::Table if e.before.p.x < 0.0 && !bounced => bounced = true,
                EventKind::Table | EventKind::Edge if bounced => break,
                // A clip: on from the state just before the contact, without the net.
                EventKind::Net if clip > 0.0 && e.before.p.z >= clear - clip => net = false,
                EventKind::Net | EventKind::Floor => break,
                _ => {}
            }
            continue;
        }
        if cur.v.x >= 0.0 && cur.p.x < 0.0 {
            break;
        }
        if bounced && !visit(&cur) {
            break;
        }
    }
    bounced
}
