//! Steps S102–S103 of the hit pipeline: the hit configuration (IK, branch nearest the current
//! state) and the hit joint velocities (J⁻¹V, or weighted least norm for the 5-D racket task).

use nalgebra::{DMatrix, IsometryMatrix3, Vector3};

use super::{Hit, HitPlanner, HitStatus, HitTask};
use crate::chain::JacobianFrame;
use crate::clik::{self, ClikOptions, ClikStatus, TaskTrajectory};
use crate::error::Error;
use crate::ik::{wrap, Analytic, DifferentialIk, IkSolver, LimitFilter};
use crate::joint::JointType;
use crate::redundancy::limit_gradient;
use crate::task::{racket_coordinates, tangent_basis, Task};
use crate::wholebody::WholeBody;

/// Duration (s) and rate (Hz) of the virtual task-space line the CLIK tracker follows from the
/// current racket pose to the hit pose (only its end configuration is kept).
const TRACK_DURATION: f64 = 1.0;
const TRACK_RATE: f64 = 500.0;

/// Cost factor of a prismatic joint in the weighted least norm of the 5-D racket task: on
/// seed 000's mobile8 joint 1 is the heavy base rolling on its wheels; it should move little.
const PRISMATIC_COST: f64 = 10.0;

/// Largest 5-D task residual (m and rad) accepted at the end of the tracked line.
const TRACK_TOLERANCE: f64 = 1e-6;

/// The hit configuration and velocities.
pub(super) struct HitState {
    pub q: Vec<f64>,
    pub qd: Vec<f64>,
    pub sigma_min: f64,
    pub branches: usize,
}

type Outcome = std::result::Result<HitState, (HitStatus, String)>;

/// Hit configuration and velocities for `hit` from the current configuration `current`.
pub(super) fn hit_state(p: &HitPlanner, hit: &Hit, tool_target: &IsometryMatrix3<f64>, current: &[f64]) -> Outcome {
    let task = match p.options.task {
        HitTask::Auto if p.chain.dof() > 6 => HitTask::Racket5,
        HitTask::Auto => HitTask::Pose,
        t => t,
    };
    match task {
        HitTask::Racket5 => racket5(p, hit, tool_target, current),
        _ => pose(p, hit, tool_target, current),
    }
}

fn unreachable(e: Error) -> (HitStatus, String) {
    (HitStatus::Unreachable, e.to_string())
}

/// Full-pose hit: analytic IK (nearest branch within the limits) or numeric IK from `current`,
/// then q̇ = J⁻¹V.
fn pose(p: &HitPlanner, hit: &Hit, tool_target: &IsometryMatrix3<f64>, current: &[f64]) -> Outcome {
    let chain = &p.chain;
    let (q, branches) = match &p.analytic {
        Some(Analytic::Gantry6(g)) => g.nearest_within_limits(tool_target, current).map_err(unreachable)?,
        Some(a) => {
            let sols = a
                .solve(tool_target, Some(current), LimitFilter::Enforce)
                .map_err(unreachable)?;
            let q = a
                .nearest(tool_target, current, LimitFilter::Enforce)
                .map_err(unreachable)?;
            (q, sols.len())
        }
        None => {
            let r = IkSolver::default()
                .solve(chain, tool_target, current)
                .map_err(unreachable)?;
            if !r.success {
                return Err((
                    HitStatus::Unreachable,
                    format!(
                        "numeric IK did not reach the racket pose (position error {:.2e} m, orientation error \
                         {:.2e} rad)",
                        r.position_error, r.orientation_error
                    ),
                ));
            }
            (r.q, 1)
        }
    };
    let twist = p.mount.tool_twist(tool_target, &hit.twist);
    let v = DifferentialIk::default()
        .solve(chain, &q, &twist, None)
        .map_err(|e| (HitStatus::Singular, e.to_string()))?;
    if v.singular {
        return Err((
            HitStatus::Singular,
            format!(
                "the hit configuration is singular (σ_min = {:.2e}): the racket twist cannot be produced",
                v.sigma_min
            ),
        ));
    }
    Ok(HitState {
        q,
        qd: v.qd,
        sigma_min: v.sigma_min,
        branches,
    })
}

/// Seed 000's 5-D racket hit: the weighted least-norm tracker follows a line in task coordinates
/// from the current racket to the hit racket; at its end the Chan–Dubey weighted least-norm
/// joint velocities (a prismatic joint, the base, costs [`PRISMATIC_COST`]) of the task velocity [v_centre; u1·ω; u2·ω] ((u1, u2) spanning the face),
/// (a joint beyond its speed limit is reported by the stroke planner).
fn racket5(p: &HitPlanner, hit: &Hit, tool_target: &IsometryMatrix3<f64>, current: &[f64]) -> Outcome {
    let chain = &p.chain;
    let offset = p.mount.in_tool.translation.vector.z;
    let seed = super::RacketMount::seed000();
    if (p.mount.in_tool.rotation.matrix() - seed.in_tool.rotation.matrix()).norm() > 1e-12
        || p.mount.in_tool.translation.vector.xy().norm() > 1e-12
    {
        return Err((
            HitStatus::Unreachable,
            "the 5-D racket task needs seed 000's racket mount (face normal = tool x, centre on tool z)".into(),
        ));
    }
    let task = Task::Racket { offset };
    let model = WholeBody::fixed(chain.clone());
    let now = chain.fk(current).map_err(unreachable)?;
    let x0 = racket_coordinates(&now, offset);
    let mut x1 = racket_coordinates(tool_target, offset);
    x1[4] = x0[4] + wrap(x1[4] - x0[4]);
    let line = TaskTrajectory::line(task, &x0, &x1, TRACK_DURATION, TRACK_RATE).map_err(unreachable)?;
    let base_cost: Vec<f64> = chain
        .joints()
        .iter()
        .map(|j| {
            if j.kind() == JointType::Prismatic {
                PRISMATIC_COST
            } else {
                1.0
            }
        })
        .collect();
    let options = ClikOptions {
        input_weights: Some(base_cost.clone()),
        ..ClikOptions::default()
    };
    let r = clik::track(&model, current, &line, options).map_err(unreachable)?;
    if let ClikStatus::Failed { reason, .. } = &r.status {
        return Err((HitStatus::Unreachable, format!("racket task tracker: {reason}")));
    }
    let last = r.len() - 1;
    let q = r.q[last * r.nq..(last + 1) * r.nq].to_vec();
    let err = r.error[last];
    if !(err <= TRACK_TOLERANCE) {
        return Err((
            HitStatus::Unreachable,
            format!("the racket task tracker ends {err:.2e} (m, rad) from the hit racket pose (limits or reach)"),
        ));
    }
    let n = chain.dof();
    let jac = chain.jacobian(&q, JacobianFrame::Base).map_err(unreachable)?;
    let tool = chain.fk_unchecked(&q);
    let lever = p.mount.lever(&tool);
    let normal = tool.rotation.matrix().column(0).into_owned();
    let (u1, u2) = tangent_basis(&normal);
    let mut jt = DMatrix::<f64>::zeros(5, n);
    for c in 0..n {
        let v = Vector3::new(jac[(0, c)], jac[(1, c)], jac[(2, c)]);
        let w = Vector3::new(jac[(3, c)], jac[(4, c)], jac[(5, c)]);
        let vc = v + w.cross(&lever);
        jt[(0, c)] = vc.x;
        jt[(1, c)] = vc.y;
        jt[(2, c)] = vc.z;
        jt[(3, c)] = u1.dot(&w);
        jt[(4, c)] = u2.dot(&w);
    }
    let w = Vector3::new(hit.twist[3], hit.twist[4], hit.twist[5]);
    let xdot = [hit.twist[0], hit.twist[1], hit.twist[2], u1.dot(&w), u2.dot(&w)];
    let limits = chain.limits();
    let weights: Vec<f64> = q
        .iter()
        .zip(&limits)
        .zip(&base_cost)
        .map(|((&qi, l), c)| c * (1.0 + limit_gradient(qi, l.lower, l.upper).abs()))
        .collect();
    let mut jw = jt.clone();
    for (c, w) in weights.iter().enumerate() {
        jw.column_mut(c).scale_mut(1.0 / w.sqrt());
    }
    let sigma_min = jw.singular_values().min();
    // Seed 000's (20): q̇ = W⁻¹Jᵀ(JW⁻¹Jᵀ)⁻¹ẋ, J of full row rank (checked by σ_min).
    let winv_jt = DMatrix::from_fn(n, 5, |r, c| jt[(c, r)] / weights[r]);
    let gram = &jt * &winv_jt;
    let y = gram
        .lu()
        .solve(&nalgebra::DVector::from_column_slice(&xdot))
        .unwrap_or_else(|| nalgebra::DVector::from_element(5, f64::NAN));
    let qd: Vec<f64> = (winv_jt * y).iter().copied().collect();
    if !(sigma_min > 1e-6) || qd.iter().any(|v| !v.is_finite()) {
        return Err((
            HitStatus::Singular,
            format!("the racket task is singular at the hit configuration (σ_min = {sigma_min:.2e})"),
        ));
    }
    Ok(HitState {
        q,
        qd,
        sigma_min,
        branches: 1,
    })
}
