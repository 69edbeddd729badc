//! Reference cases of the drive layer, shared by the tests, the demo's `summary.json` and its
//! figure, so that the numbers quoted anywhere come from one computation.
//!
//! The θ5 case (issue 10): gantry6's demo hitting stroke (the pipeline's default hit request:
//! racket at (0.35, −0.55, 0.05) m, face normal (0.3, −1, −0.2), 3 m/s along the normal at
//! t = 0.3 s, from and back to the ready pose (0, 0, 0, 0.6, 0.6, 0)), joint θ5 (index 4) driven
//! alone by a maxon RE 25 + GP 26 A 14:1 with a 4096-count encoder, its load the mean of the
//! link-only mass-matrix entry M₄₄ along the stroke (the drive's own rotor is in the motor model,
//! so it is counted once), no gravity (as in the demo).

use nalgebra::{Matrix3, Vector3};
use ttkin::ik::{Analytic, LimitFilter};
use ttkin::traj::limits::KinematicLimits;
use ttkin::traj::{stroke::stroke, JointState, JointTrajectory};
use ttkin::{Chain, Dynamics, DynamicsData};

use crate::error::{Error, Result};

/// The gantry6 demo stroke: the planned joint trajectory (m, rad) and its hit time (s).
#[derive(Debug, Clone)]
pub struct DemoStroke {
    /// Hit leg then return leg, starting at 0 s.
    pub trajectory: JointTrajectory,
    /// Planned hit time, s.
    pub t_hit: f64,
}

fn ttkin_error(e: ttkin::Error) -> Error {
    Error::Model(e.to_string())
}

/// Racket rotation whose z axis is the face `normal` and whose x axis is nearest to `hint`.
fn racket_rotation(normal: Vector3<f64>, hint: Vector3<f64>) -> Matrix3<f64> {
    let z = normal.normalize();
    let x = (hint - z * hint.dot(&z)).normalize();
    Matrix3::from_columns(&[x, z.cross(&x), z])
}

/// Plans the demo stroke of gantry6 (the default hit request of `ttmanip.pipeline`).
pub fn gantry6_demo_stroke(chain: &Chain) -> Result<DemoStroke> {
    let normal = Vector3::new(0.3, -1.0, -0.2);
    let rot = racket_rotation(normal, Vector3::z());
    let target = nalgebra::IsometryMatrix3::from_parts(
        nalgebra::Translation3::new(0.35, -0.55, 0.05),
        nalgebra::Rotation3::from_matrix_unchecked(rot),
    );
    let ready = [0.0, 0.0, 0.0, 0.6, 0.6, 0.0];
    let ik = Analytic::for_chain(chain).ok_or_else(|| Error::Model("gantry6 has no analytic IK".into()))?;
    let q_hit = ik.nearest(&target, &ready, LimitFilter::Enforce).map_err(ttkin_error)?;
    let v = normal.normalize() * 3.0;
    let twist = [v.x, v.y, v.z, 0.0, 0.0, 0.0];
    let qd_hit = ttkin::ik::differential::DifferentialIk::default()
        .solve(chain, &q_hit, &twist, None)
        .map_err(ttkin_error)?
        .qdot;
    let limits = KinematicLimits::from_chain(chain, None).map_err(ttkin_error)?;
    let (lower, upper): (Vec<f64>, Vec<f64>) = chain.joints().iter().map(|j| (j.limits().lower, j.limits().upper)).unzip();
    let limits = limits.with_position(&lower, &upper).map_err(ttkin_error)?;
    let hit = JointState {
        q: q_hit.clone(),
        qd: qd_hit.to_vec(),
        qdd: vec![0.0; q_hit.len()],
    };
    let s = stroke(&JointState::rest(&ready), &hit, 0.30, &ready, None, &limits).map_err(ttkin_error)?;
    Ok(DemoStroke {
        trajectory: s.trajectory,
        t_hit: s.t_hit,
    })
}

/// Mean of the mass-matrix diagonal entry of `joint` (the drive armature G²·J included or not), sampled at
/// 50 instants along `trajectory` (kg·m² or kg).
pub fn mean_joint_inertia(chain: &Chain, trajectory: &JointTrajectory, joint: usize, with_armature: bool) -> Result<f64> {
    let dynamics = Dynamics::new(chain).map_err(ttkin_error)?;
    let mut data = DynamicsData::new(&dynamics);
    let n = dynamics.dof();
    let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let samples = 50;
    let mut sum = 0.0;
    for k in 0..samples {
        let t = trajectory.duration() * k as f64 / samples as f64;
        trajectory.sample(t, &mut q, &mut qd, &mut qdd).map_err(ttkin_error)?;
        let m = dynamics.mass_matrix(&mut data, &q).map_err(ttkin_error)?;
        sum += m[(joint, joint)] - if with_armature { 0.0 } else { dynamics.armature()[joint] };
    }
    Ok(sum / samples as f64)
}
