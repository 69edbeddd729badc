//! Fixed-size kernels of the task-space solve, monomorphised per task dimension m ≤ 6 so the
//! loops unroll: the Gram matrix J_F·W⁻¹·J_Fᵀ of the free inputs and the Cholesky factor and
//! solve (the crate's one Cholesky, [`crate::linalg::cholesky`], called with a constant size);
//! and the manipulability measure built on them.

use super::MAX_TASK_DIM;
use crate::linalg::cholesky::{factor_in_place, solve_in_place};

/// Cholesky factorisation of an M × M row-major matrix in place (lower triangle).
pub(super) type FactorFn = fn(&mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]) -> bool;
/// Solve with a Cholesky factor in place.
pub(super) type SolveFn = fn(&[f64; MAX_TASK_DIM * MAX_TASK_DIM], &mut [f64; MAX_TASK_DIM]);
/// Gram matrix of the free columns.
pub(super) type GramFn = fn(&[f64], &[f64], &[bool], &mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]);

/// The factor/solve pair for task dimension `m` (1..=6), monomorphised so the loops unroll.
pub(super) fn kernels(m: usize) -> (FactorFn, SolveFn, GramFn) {
    match m {
        1 => (cholesky::<1>, cholesky_solve::<1>, gram::<1>),
        2 => (cholesky::<2>, cholesky_solve::<2>, gram::<2>),
        3 => (cholesky::<3>, cholesky_solve::<3>, gram::<3>),
        4 => (cholesky::<4>, cholesky_solve::<4>, gram::<4>),
        5 => (cholesky::<5>, cholesky_solve::<5>, gram::<5>),
        _ => (cholesky::<6>, cholesky_solve::<6>, gram::<6>),
    }
}

/// In-place Cholesky G = L Lᵀ of the lower triangle of an M × M row-major matrix (stride M),
/// storing 1/L_jj on the diagonal; false when G is not positive definite (to working precision).
fn cholesky<const M: usize>(a: &mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]) -> bool {
    factor_in_place(&mut a[..], M).is_ok()
}

/// Solves L Lᵀ x = b in place with the factor from [`cholesky`].
fn cholesky_solve<const M: usize>(l: &[f64; MAX_TASK_DIM * MAX_TASK_DIM], b: &mut [f64; MAX_TASK_DIM]) {
    solve_in_place(&l[..], M, &mut b[..]);
}

/// Gram matrix G = J_F W⁻¹ J_Fᵀ (lower triangle, stride M) over the free inputs.
fn gram<const M: usize>(jac: &[f64], winv: &[f64], free: &[bool], g: &mut [f64; MAX_TASK_DIM * MAX_TASK_DIM]) {
    g[..M * M].fill(0.0);
    for ((col, &wk), &f) in jac.chunks_exact(M).zip(winv).zip(free) {
        if !f {
            continue;
        }
        let mut c = [0.0; M];
        c.copy_from_slice(col);
        for r in 0..M {
            let jr = c[r] * wk;
            for k in 0..=r {
                g[r * M + k] += jr * c[k];
            }
        }
    }
}

/// Manipulability √det(J Jᵀ) of an m × n task Jacobian (column-major slice), 0 when rank-deficient.
pub fn manipulability(jac: &[f64], m: usize) -> f64 {
    if m == 0 || m > MAX_TASK_DIM || !jac.len().is_multiple_of(m) {
        return 0.0;
    }
    let n = jac.len() / m;
    let (factor, _, gram) = kernels(m);
    let ones = [1.0; 64];
    let free = [true; 64];
    if n > ones.len() {
        return 0.0;
    }
    let mut g = [0.0; MAX_TASK_DIM * MAX_TASK_DIM];
    gram(jac, &ones[..n], &free[..n], &mut g);
    if !factor(&mut g) {
        return 0.0;
    }
    (0..m).map(|j| 1.0 / g[j * m + j]).product()
}
