//! Helpers shared by the integration tests.
#![allow(dead_code)]

use nalgebra::{IsometryMatrix3, Matrix6xX};
use ttkin::{Chain, JacobianFrame};

/// All built-in robots.
pub fn robots() -> Vec<Chain> {
    vec![
        ttkin::robots::mobile8(),
        ttkin::robots::gantry6(),
        ttkin::robots::arm4(),
        ttkin::robots::ur5(),
    ]
}

/// A configuration from numbers in [0, 1): within limits where finite, within ±π (±1 m) otherwise.
pub fn config_from_unit(chain: &Chain, u: &[f64]) -> Vec<f64> {
    chain
        .limits()
        .iter()
        .zip(u)
        .map(|(l, &x)| {
            let (lo, hi) = if l.lower.is_finite() && l.upper.is_finite() {
                (l.lower, l.upper)
            } else {
                (-3.0, 3.0)
            };
            lo + (hi - lo) * x
        })
        .collect()
}

/// Largest absolute difference between two transforms (rotation and translation entries).
pub fn pose_diff(a: &IsometryMatrix3<f64>, b: &IsometryMatrix3<f64>) -> f64 {
    (a.to_homogeneous() - b.to_homogeneous()).abs().max()
}

/// Central finite-difference geometric Jacobian of `fk` (linear part at the tool point).
pub fn numeric_jacobian(chain: &Chain, q: &[f64], frame: JacobianFrame) -> Matrix6xX<f64> {
    let h = 1e-6;
    let n = chain.dof();
    let t0 = chain.fk(q).unwrap();
    let mut j = Matrix6xX::zeros(n);
    for i in 0..n {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[i] += h;
        qm[i] -= h;
        let (tp, tm) = (chain.fk(&qp).unwrap(), chain.fk(&qm).unwrap());
        let v = (tp.translation.vector - tm.translation.vector) / (2.0 * h);
        // ω̂ = Ṙ Rᵀ
        let rdot = (tp.rotation.matrix() - tm.rotation.matrix()) / (2.0 * h);
        let w_hat = rdot * t0.rotation.matrix().transpose();
        let mut w = nalgebra::Vector3::new(w_hat[(2, 1)], w_hat[(0, 2)], w_hat[(1, 0)]);
        let mut v = v;
        if frame == JacobianFrame::Tool {
            let rt = t0.rotation.matrix().transpose();
            v = rt * v;
            w = rt * w;
        }
        j.fixed_view_mut::<3, 1>(0, i).copy_from(&v);
        j.fixed_view_mut::<3, 1>(3, i).copy_from(&w);
    }
    j
}
