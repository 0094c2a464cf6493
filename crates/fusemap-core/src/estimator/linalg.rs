//! Small fixed-size matrices for the filter.
//!
//! The estimator's state has five components and its measurements at most three, so every
//! matrix is a stack array of known size: no allocation per step, and the compiler unrolls
//! the loops. A dependency (nalgebra) would give the same speed; these ~100 lines avoid a
//! new crate in the core's build for the handful of operations a Kalman filter and an
//! RTS smoother need (product, transpose, sum, Cholesky inverse of a symmetric positive
//! definite matrix).

// Index loops read like the formulas they implement (`m[i][j] += a[i][k] * b[k][j]`).
#![allow(clippy::needless_range_loop)]

/// A row-major `R × C` matrix.
pub(crate) type Mat<const R: usize, const C: usize> = [[f64; C]; R];

/// The identity matrix.
pub(crate) fn identity<const N: usize>() -> Mat<N, N> {
    let mut m = [[0.0; N]; N];
    for (i, row) in m.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    m
}

/// `a × b`.
pub(crate) fn mul<const R: usize, const K: usize, const C: usize>(a: &Mat<R, K>, b: &Mat<K, C>) -> Mat<R, C> {
    let mut m = [[0.0; C]; R];
    for i in 0..R {
        for k in 0..K {
            let aik = a[i][k];
            if aik == 0.0 {
                continue;
            }
            for j in 0..C {
                m[i][j] += aik * b[k][j];
            }
        }
    }
    m
}

/// `a × v`.
pub(crate) fn mul_vec<const R: usize, const C: usize>(a: &Mat<R, C>, v: &[f64; C]) -> [f64; R] {
    let mut out = [0.0; R];
    for i in 0..R {
        out[i] = (0..C).map(|j| a[i][j] * v[j]).sum();
    }
    out
}

/// `aᵀ`.
pub(crate) fn transpose<const R: usize, const C: usize>(a: &Mat<R, C>) -> Mat<C, R> {
    let mut m = [[0.0; R]; C];
    for i in 0..R {
        for j in 0..C {
            m[j][i] = a[i][j];
        }
    }
    m
}

/// `a + b`.
pub(crate) fn add<const R: usize, const C: usize>(a: &Mat<R, C>, b: &Mat<R, C>) -> Mat<R, C> {
    let mut m = *a;
    for i in 0..R {
        for j in 0..C {
            m[i][j] += b[i][j];
        }
    }
    m
}

/// `a − b`.
pub(crate) fn sub<const R: usize, const C: usize>(a: &Mat<R, C>, b: &Mat<R, C>) -> Mat<R, C> {
    let mut m = *a;
    for i in 0..R {
        for j in 0..C {
            m[i][j] -= b[i][j];
        }
    }
    m
}

/// `a × b × aᵀ` (propagating a covariance `b` through a linear map `a`).
pub(crate) fn sandwich<const R: usize, const C: usize>(a: &Mat<R, C>, b: &Mat<C, C>) -> Mat<R, R> {
    symmetrize(&mul(&mul(a, b), &transpose(a)))
}

/// `(a + aᵀ) / 2`: removes the asymmetry rounding leaves in a covariance.
pub(crate) fn symmetrize<const N: usize>(a: &Mat<N, N>) -> Mat<N, N> {
    let mut m = *a;
    for i in 0..N {
        for j in (i + 1)..N {
            let v = 0.5 * (a[i][j] + a[j][i]);
            m[i][j] = v;
            m[j][i] = v;
        }
    }
    m
}

/// True when every entry is finite.
pub(crate) fn all_finite<const R: usize, const C: usize>(a: &Mat<R, C>) -> bool {
    a.iter().flatten().all(|v| v.is_finite())
}

/// The lower Cholesky factor `L` with `L Lᵀ = a`, or `None` when `a` is not (numerically)
/// symmetric positive definite or not finite.
pub(crate) fn cholesky<const N: usize>(a: &Mat<N, N>) -> Option<Mat<N, N>> {
    let mut l = [[0.0; N]; N];
    for i in 0..N {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

/// The inverse of a symmetric positive definite matrix (through its Cholesky factor), or
/// `None` when it is not positive definite.
pub(crate) fn spd_inverse<const N: usize>(a: &Mat<N, N>) -> Option<Mat<N, N>> {
    let l = cholesky(a)?;
    // Invert L (lower triangular) by forward substitution, then a⁻¹ = L⁻ᵀ L⁻¹.
    let mut li = [[0.0; N]; N];
    for col in 0..N {
        for i in col..N {
            let mut s = if i == col { 1.0 } else { 0.0 };
            for k in col..i {
                s -= l[i][k] * li[k][col];
            }
            li[i][col] = s / l[i][i];
        }
    }
    Some(symmetrize(&mul(&transpose(&li), &li)))
}

/// True when a symmetric matrix is positive definite and finite.
pub(crate) fn is_spd<const N: usize>(a: &Mat<N, N>) -> bool {
    let symmetric = (0..N).all(|i| (0..i).all(|j| (a[i][j] - a[j][i]).abs() <= 1e-9 * (a[i][i].abs() + a[j][j].abs())));
    symmetric && cholesky(a).is_some()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn spd_inverse_is_an_inverse(v in proptest::collection::vec(-2.0..2.0f64, 25), d in 0.1..3.0f64) {
            // B Bᵀ + d I is symmetric positive definite.
            let mut b = [[0.0; 5]; 5];
            for i in 0..5 { for j in 0..5 { b[i][j] = v[i * 5 + j]; } }
            let mut a = mul(&b, &transpose(&b));
            for (i, row) in a.iter_mut().enumerate() { row[i] += d; }
            let inv = spd_inverse(&a).unwrap();
            let id = mul(&a, &inv);
            for i in 0..5 { for j in 0..5 {
                let want = if i == j { 1.0 } else { 0.0 };
                prop_assert!((id[i][j] - want).abs() < 1e-8, "{:?}", id);
            } }
            prop_assert!(is_spd(&a));
        }
    }

    #[test]
    fn indefinite_and_nan_are_refused() {
        assert!(cholesky(&[[1.0, 2.0], [2.0, 1.0]]).is_none());
        assert!(cholesky(&[[f64::NAN, 0.0], [0.0, 1.0]]).is_none());
        assert!(!is_spd(&[[1.0, 0.5], [0.0, 1.0]]));
        assert!(is_spd(&[[1.0, 0.5], [0.5, 1.0]]));
    }
}
