//! Cholesky factorisation A = L·Lᵀ of a symmetric positive definite n × n matrix, in place on a
//! row-major slice (stride n), and the solve L·Lᵀ·x = b with the factor. The one Cholesky of the
//! crate: forward dynamics solves with the mass matrix, redundancy resolution with the Gram matrix
//! J·W⁻¹·Jᵀ. The factor stores 1/L_jj on its diagonal, so the solves multiply instead of divide.
//!
//! Only the lower triangle of `a` is read. A column-major symmetric matrix (a nalgebra
//! `DMatrix`) is its own row-major transpose, so its slice can be passed as it is. Both kernels
//! are `#[inline(always)]`: called with a constant `n` (as the fixed-size redundancy kernels do)
//! the loops unroll.

// Index loops over one triangle read like the textbook algorithm.
#![allow(clippy::needless_range_loop)]

/// Pivots at or below this value count as "not positive definite" (to working precision).
pub const MIN_PIVOT: f64 = 1e-300;

/// The factorisation failed: pivot `pivot` (0-based) was `value` ≤ [`MIN_PIVOT`] (or NaN).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotPositiveDefinite {
    /// Index of the failing pivot.
    pub pivot: usize,
    /// The value of the pivot before its square root.
    pub value: f64,
}

/// Factors the lower triangle of the row-major n × n matrix `a` (first n² values) into L in place,
/// with 1/L_jj stored on the diagonal; the strict upper triangle is left untouched.
#[inline(always)]
pub fn factor_in_place(a: &mut [f64], n: usize) -> Result<(), NotPositiveDefinite> {
    debug_assert!(a.len() >= n * n);
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if !(d > MIN_PIVOT) {
            return Err(NotPositiveDefinite { pivot: j, value: d });
        }
        let inv = 1.0 / d.sqrt();
        a[j * n + j] = inv;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s * inv;
        }
    }
    Ok(())
}

/// Solves L·Lᵀ·x = b in place (first n values of `b`) with a factor from [`factor_in_place`].
#[inline(always)]
pub fn solve_in_place(l: &[f64], n: usize, b: &mut [f64]) {
    debug_assert!(l.len() >= n * n && b.len() >= n);
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s * l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s * l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// For A = B·Bᵀ + I, the solve returns x with A·x = b.
        #[test]
        fn solve_inverts_a_random_spd_matrix(
            n in 1usize..8,
            vals in proptest::collection::vec(-2.0f64..2.0, 64),
            rhs in proptest::collection::vec(-5.0f64..5.0, 8),
        ) {
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] = (0..n).map(|k| vals[i * 8 + k] * vals[j * 8 + k]).sum::<f64>()
                        + if i == j { 1.0 } else { 0.0 };
                }
            }
            let mut l = a.clone();
            factor_in_place(&mut l, n).unwrap();
            let mut x = rhs[..n].to_vec();
            solve_in_place(&l, n, &mut x);
            for i in 0..n {
                let ax: f64 = (0..n).map(|j| a[i * n + j] * x[j]).sum();
                prop_assert!((ax - rhs[i]).abs() < 1e-9 * (1.0 + rhs[i].abs()));
            }
        }
    }

    /// A symmetric indefinite matrix is refused at the pivot that turns negative.
    #[test]
    fn indefinite_matrix_is_refused() {
        let mut a = [1.0, 2.0, 2.0, 1.0];
        let e = factor_in_place(&mut a, 2).unwrap_err();
        assert_eq!(e.pivot, 1);
        assert!(e.value < 0.0);
    }
}
