//! A ball's path over an observation window together with its sensitivities to the velocity and
//! spin at the window's end (the variational equations), for the estimator's Gauss–Newton fit.
//!
//! With position p, velocity v and constant spin ω (world frame), ṗ = v and
//! v̇ = a(v, ω) = g − k_d·|v|·v + k_m·ω × v. The position enters no derivative, so ∂p(t)/∂p0 = I;
//! the sensitivities S_p = ∂p/∂(v0, ω) and S_v = ∂v/∂(v0, ω) (3 × 6 each, v0 and ω at the end
//! time t0) obey Ṡ_p = S_v, Ṡ_v = A_v·S_v + [0 | A_ω] with A_v = ∂a/∂v =
//! −k_d·(|v|·I + v·vᵀ/|v|) + k_m·\[ω\]× and A_ω = ∂a/∂ω = −k_m·\[v\]×.
//!
//! The window is integrated backward from t0 in equal steps of at most the given step: the state
//! by RK4 (the same step as [`super::flight::Flight::rk4`]), the sensitivities alongside by the
//! midpoint rule on RK4's midpoint velocity (they only steer the Gauss–Newton step and scale the
//! covariance: O(h²), within 0.1 % of finite differences for the v0 columns at 10 and 20 ms, and
//! within 3 % (10 ms) and 5 % (20 ms, the estimator's default) for the ω columns, tested). Between
//! nodes the position is the cubic Hermite interpolant of p and v (with RK4, within 1e-7 m of a
//! 0.1 ms reference at 10 and 20 ms, tested), and the same for the sensitivities from S_p and S_v.
//! [`Knot`] holds an offset's interval and Hermite weights, which depend only on the offset and
//! the step: the estimator computes them once per observation and reuses them every iteration.

use super::model::BallModel;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// Sensitivity of a position or velocity (3 rows) to (v0, ω) (6 columns: v0 then ω).
pub type Sens = SMatrix<f64, 3, 6>;

/// One node of the path: time offset τ from t0 (s, ≤ 0), position (m) and velocity (m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Time offset from the window's end (s, ≤ 0).
    pub tau: f64,
    /// Ball centre (m, world).
    pub p: Vector3<f64>,
    /// Velocity (m/s, world).
    pub v: Vector3<f64>,
}

/// The path over [t0 − span, t0] at equal steps, node 0 at τ = 0 and nodes going back in time.
#[derive(Debug, Clone, PartialEq)]
pub struct WindowPath {
    /// Nodes at τ_j = −j·|h| (s).
    pub nodes: Vec<Node>,
    /// ∂p/∂(v0, ω) and ∂v/∂(v0, ω) at each node; empty when not asked for.
    pub sens: Vec<(Sens, Sens)>,
    /// Step length |h| (s).
    pub step: f64,
}

/// ∂a/∂v at velocity `v` (m/s) and spin `w` (rad/s): −k_d·(|v|·I + v·vᵀ/|v|) + k_m·[ω]×.
fn dadv(m: &BallModel, v: &Vector3<f64>, w: &Vector3<f64>) -> Matrix3<f64> {
    let speed = v.norm();
    let drag = if speed > 0.0 {
        Matrix3::identity() * speed + v * v.transpose() / speed
    } else {
        Matrix3::zeros()
    };
    w.cross_matrix() * m.k_magnus - drag * m.k_drag
}

/// Ṡ_v = A_v·S_v + [0 | −k_m·[v]×] (the ω columns only when `spin`).
fn sens_rate(m: &BallModel, v: &Vector3<f64>, w: &Vector3<f64>, sv: &Sens, spin: bool) -> Sens {
    let mut out = dadv(m, v, w) * sv;
    if spin {
        let aw = v.cross_matrix() * (-m.k_magnus);
        let mut cols = out.fixed_view_mut::<3, 3>(0, 3);
        cols += aw;
    }
    out
}

/// Where an offset τ falls on a [`WindowPath`]: the interval [τ_(j+1), τ_j] and the cubic
/// Hermite weights of (value at j, rate at j, value at j+1, rate at j+1) there (rates in s).
/// Depends only on τ and the step, so a fit computes it once per observation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Knot {
    /// Interval index j (node j is the later end).
    pub j: usize,
    /// Weights of p_j, v_j, p_(j+1), v_(j+1) (the rate weights include the step, s).
    pub c: [f64; 4],
}

impl WindowPath {
    /// Integrates backward from (p0, v0, ω) at τ = 0 over `span` (s, ≥ 0) in equal steps of at
    /// most `max_step` (s); `sens` says whether the sensitivities are wanted and `spin` whether
    /// their ω columns are (zero otherwise).
    #[allow(clippy::too_many_arguments)]
    pub fn integrate(
        m: &BallModel,
        p0: &Vector3<f64>,
        v0: &Vector3<f64>,
        w: &Vector3<f64>,
        span: f64,
        max_step: f64,
        spin: bool,
        sens: bool,
    ) -> Self {
        let mut path = WindowPath {
            nodes: Vec::new(),
            sens: Vec::new(),
            step: 0.0,
        };
        path.integrate_into(m, p0, v0, w, span, max_step, spin, sens);
        path
    }

    /// [`WindowPath::integrate`] into this path's buffers (kept from call to call: no allocation
    /// once they are large enough); the sensitivities are cleared when `sens` is false.
    #[allow(clippy::too_many_arguments)]
    pub fn integrate_into(
        &mut self,
        m: &BallModel,
        p0: &Vector3<f64>,
        v0: &Vector3<f64>,
        w: &Vector3<f64>,
        span: f64,
        max_step: f64,
        spin: bool,
        sens: bool,
    ) {
        let steps = ((span / max_step).ceil() as usize).max(1);
        let step = span / steps as f64;
        let h = -step;
        let mut sv = Sens::zeros();
        sv.fixed_view_mut::<3, 3>(0, 0).copy_from(&Matrix3::identity());
        let mut sp = Sens::zeros();
        self.step = step;
        self.nodes.clear();
        self.nodes.reserve(steps + 1);
        self.sens.clear();
        if sens {
            self.sens.reserve(steps + 1);
        }
        let mut cur = Node {
            tau: 0.0,
            p: *p0,
            v: *v0,
        };
        self.nodes.push(cur);
        if sens {
            self.sens.push((sp, sv));
        }
        for j in 1..=steps {
            let a1 = m.acceleration(&cur.v, w);
            let v2 = cur.v + 0.5 * h * a1;
            let a2 = m.acceleration(&v2, w);
            let v3 = cur.v + 0.5 * h * a2;
            let a3 = m.acceleration(&v3, w);
            let v4 = cur.v + h * a3;
            let a4 = m.acceleration(&v4, w);
            if sens {
                let k1 = sens_rate(m, &cur.v, w, &sv, spin);
                let sv_mid = sv + k1 * (0.5 * h);
                let k2 = sens_rate(m, &v2, w, &sv_mid, spin);
                sp += sv_mid * h;
                sv += k2 * h;
                self.sens.push((sp, sv));
            }
            cur = Node {
                tau: -(j as f64) * step,
                p: cur.p + h / 6.0 * (cur.v + 2.0 * v2 + 2.0 * v3 + v4),
                v: cur.v + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            };
            self.nodes.push(cur);
        }
    }

    /// The interval holding `tau` (s, in [−span, 0]) and its cubic Hermite weights.
    pub fn knot(&self, tau: f64) -> Knot {
        // −τ/|h| ≥ 0 up to rounding: the cast truncates (floors) and saturates at 0.
        let j = ((-tau / self.step) as usize).min(self.nodes.len() - 2);
        let s = (self.nodes[j].tau - tau) / self.step;
        let h = -self.step;
        let (s2, s3) = (s * s, s * s * s);
        Knot {
            j,
            c: [
                2.0 * s3 - 3.0 * s2 + 1.0,
                h * (s3 - 2.0 * s2 + s),
                3.0 * s2 - 2.0 * s3,
                h * (s3 - s2),
            ],
        }
    }

    /// Position (m, world) at a knot from [`WindowPath::knot`] of a path with the same span and step.
    pub fn position_at(&self, k: &Knot) -> Vector3<f64> {
        let (a, b) = (&self.nodes[k.j], &self.nodes[k.j + 1]);
        a.p * k.c[0] + a.v * k.c[1] + b.p * k.c[2] + b.v * k.c[3]
    }

    /// ∂p/∂(v0, ω) at a knot, cubic Hermite between nodes; zero when not integrated.
    pub fn sensitivity_at(&self, k: &Knot) -> Sens {
        if self.sens.is_empty() {
            return Sens::zeros();
        }
        let ((pa, va), (pb, vb)) = (&self.sens[k.j], &self.sens[k.j + 1]);
        pa * k.c[0] + va * k.c[1] + pb * k.c[2] + vb * k.c[3]
    }

    /// Position (m, world) at offset `tau` (s, in [−span, 0]): cubic Hermite between nodes.
    pub fn position(&self, tau: f64) -> Vector3<f64> {
        self.position_at(&self.knot(tau))
    }

    /// ∂p/∂(v0, ω) at offset `tau` (s), cubic Hermite between nodes; zero when not integrated.
    pub fn sensitivity(&self, tau: f64) -> Sens {
        self.sensitivity_at(&self.knot(tau))
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::ball::flight::{BallState, Flight};

    fn path(v0: Vector3<f64>, w: Vector3<f64>, step: f64) -> WindowPath {
        let p0 = Vector3::new(-0.9, 0.1, 0.25);
        WindowPath::integrate(&BallModel::default(), &p0, &v0, &w, 0.2, step, true, true)
    }

    #[test]
    fn positions_match_the_flight_integrator_between_nodes() {
        // At the estimator's 20 ms step (and at 10 ms) within 1e-7 m of a 0.1 ms RK4 reference.
        let (v0, w) = (Vector3::new(-5.0, 0.4, -1.0), Vector3::new(20.0, -150.0, 60.0));
        let f = Flight {
            step: 1e-4,
            ..Flight::default()
        };
        for step in [0.01, 0.02] {
            let wp = path(v0, w, step);
            let mut s = BallState {
                t: 0.0,
                p: Vector3::new(-0.9, 0.1, 0.25),
                v: v0,
                w,
            };
            for k in 1..=40 {
                let tau = -0.005 * k as f64 + 0.0013;
                while s.t > tau + 1e-15 {
                    s = f.rk4(&s, -(1e-4f64).min(s.t - tau));
                }
                let p = wp.position(tau);
                assert!((p - s.p).norm() < 1e-7, "step {step}, τ = {tau}: {}", (p - s.p).norm());
            }
        }
    }

    #[test]
    fn sensitivities_match_finite_differences() {
        // Midpoint rule, O(h²): v0 columns within 0.1 %, ω columns within 3 % at 10 ms and 5 %
        // at the estimator's 20 ms step.
        let (v0, w) = (Vector3::new(-5.0, 0.4, -1.0), Vector3::new(20.0, -150.0, 60.0));
        for (step, tol_w) in [(0.01, 3e-2), (0.02, 5e-2)] {
            let wp = path(v0, w, step);
            for c in 0..6 {
                let d = if c < 3 { 1e-6 } else { 1e-4 };
                let (mut vp, mut wpl) = (v0, w);
                let (mut vm, mut wm) = (v0, w);
                if c < 3 {
                    vp[c] += d;
                    vm[c] -= d;
                } else {
                    wpl[c - 3] += d;
                    wm[c - 3] -= d;
                }
                let (plus, minus) = (path(vp, wpl, step), path(vm, wm, step));
                // ∂p/∂ω grows as τ³ from 0: within the first step it is ~1e-8, compared from 50 ms on.
                let taus: &[f64] = if c < 3 {
                    &[-0.2, -0.137, -0.05, -0.003]
                } else {
                    &[-0.2, -0.137, -0.05]
                };
                for &tau in taus {
                    let fd = (plus.position(tau) - minus.position(tau)) / (2.0 * d);
                    let an = wp.sensitivity(tau).column(c).into_owned();
                    assert!(
                        (fd - an).norm() < if c < 3 { 1e-3 } else { tol_w } * fd.norm() + 1e-12,
                        "step {step}, column {c}, τ = {tau}: {fd:?} vs {an:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn knot_weights_reproduce_the_interpolant_at_the_nodes() {
        // At a node the Hermite weights are (1, 0, 0, 0): position_at returns the node itself.
        let wp = path(Vector3::new(-5.0, 0.4, -1.0), Vector3::new(20.0, -150.0, 60.0), 0.02);
        for (j, node) in wp.nodes.iter().enumerate().take(wp.nodes.len() - 1) {
            let k = wp.knot(node.tau);
            assert_eq!(k.j, j);
            assert!((wp.position_at(&k) - node.p).norm() < 1e-12);
        }
        let last = wp.nodes.last().expect("nodes");
        assert!((wp.position(last.tau) - last.p).norm() < 1e-12);
    }
}
