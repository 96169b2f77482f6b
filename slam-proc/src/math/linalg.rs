//! Small symmetric positive definite solves, written out for 3x3 and 4x4: every particle
//! does several per observation, and the generic decompositions spend more time on loop
//! control than on arithmetic at these sizes.

// Index loops are the clearest way to write out matrix factorisations.
#![allow(clippy::needless_range_loop)]

use nalgebra::{ArrayStorage, Matrix3, Matrix4, Vector3};

/// `L`, `D` and the reciprocals of `D`.
type Ldl<const N: usize> = ([[f64; N]; N], [f64; N], [f64; N]);

/// `A = L D L^T` of an `N x N` matrix given by `a(i, j)`: `L` unit lower triangular,
/// returned with the reciprocals of `D`; `None` unless the matrix is positive definite (a
/// NaN is not). No square roots and one division per pivot: at this size the latency of
/// those, not the multiplications, is the cost.
#[inline]
fn ldl<const N: usize>(a: impl Fn(usize, usize) -> f64) -> Option<Ldl<N>> {
    let mut l = [[0.0; N]; N];
    let mut d = [0.0; N];
    let mut r = [0.0; N];
    for j in 0..N {
        let mut pivot = a(j, j);
        for k in 0..j {
            pivot -= l[j][k] * l[j][k] * d[k];
        }
        if pivot.is_nan() || pivot <= 0.0 {
            return None;
        }
        d[j] = pivot;
        r[j] = 1.0 / pivot;
        l[j][j] = 1.0;
        for i in j + 1..N {
            let mut s = a(i, j);
            for k in 0..j {
                s -= l[i][k] * l[j][k] * d[k];
            }
            l[i][j] = s * r[j];
        }
    }
    Some((l, d, r))
}

/// `ln det A = ln prod D`: one logarithm (covariance entries in metres and radians are
/// far from over- or underflow).
#[inline]
fn log_det<const N: usize>(d: &[f64; N]) -> f64 {
    d.iter().product::<f64>().ln()
}

/// `a b` for 4x4 matrices, as combinations of `a`'s columns on the raw column-major
/// arrays: that form inlines and vectorises, the generic product does neither at this size.
#[inline]
pub(crate) fn mul4(a: &Matrix4<f64>, b: &Matrix4<f64>) -> Matrix4<f64> {
    let (a, b) = (&a.data.0, &b.data.0);
    let mut c = [[0.0; 4]; 4];
    for j in 0..4 {
        for k in 0..4 {
            let bkj = b[j][k];
            for i in 0..4 {
                c[j][i] += a[k][i] * bkj;
            }
        }
    }
    Matrix4::from_data(ArrayStorage(c))
}

/// `a b^T + c d^T` for 4x4 matrices whose sum is known to be symmetric (the two terms
/// of the Joseph form), made exactly symmetric by mirroring its upper triangle.
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(crate) fn joseph_sum(
    a: &Matrix4<f64>,
    b: &Matrix4<f64>,
    c: &Matrix4<f64>,
    d: &Matrix4<f64>,
) -> Matrix4<f64> {
    // Column-major storage: x[k][i] is row i of column k. Column j of the sum is the
    // columns of `a` and `c` combined with row j of `b` and `d`: whole-column
    // operations, which vectorise, where entry by entry would not.
    let (a, b, c, d) = (&a.data.0, &b.data.0, &c.data.0, &d.data.0);
    let mut m = [[0.0; 4]; 4];
    for j in 0..4 {
        for k in 0..4 {
            let (bjk, djk) = (b[k][j], d[k][j]);
            for i in 0..4 {
                m[j][i] += a[k][i] * bjk + c[k][i] * djk;
            }
        }
    }
    for j in 0..4 {
        for i in j + 1..4 {
            m[j][i] = m[i][j];
        }
    }
    Matrix4::from_data(ArrayStorage(m))
}

/// The inverse of a symmetric positive definite 4x4 matrix and its log-determinant.
#[inline]
pub(crate) fn spd_inverse4(m: &Matrix4<f64>) -> Option<(Matrix4<f64>, f64)> {
    let (l, d, r) = ldl::<4>(|i, j| m[(i, j)])?;
    // L^-1 (unit lower) by forward substitution, then A^-1 = L^-T D^-1 L^-1.
    let mut li = [[0.0; 4]; 4];
    for j in 0..4 {
        li[j][j] = 1.0;
        for i in j + 1..4 {
            let mut s = 0.0;
            for k in j..i {
                s -= l[i][k] * li[k][j];
            }
            li[i][j] = s;
        }
    }
    let mut inverse = Matrix4::zeros();
    for i in 0..4 {
        for j in 0..=i {
            let mut s = 0.0;
            for k in i..4 {
                s += li[k][i] * r[k] * li[k][j];
            }
            inverse[(i, j)] = s;
            inverse[(j, i)] = s;
        }
    }
    Some((inverse, log_det(&d)))
}

/// `ln det m` of a symmetric positive definite 3x3 `m`.
pub(crate) fn spd_log_det3(m: &Matrix3<f64>) -> Option<f64> {
    ldl::<3>(|i, j| m[(i, j)]).map(|(_, d, _)| log_det(&d))
}

/// `x` with `m x = b` for a symmetric positive definite 3x3 `m`.
#[inline]
pub(crate) fn spd_solve3(m: &Matrix3<f64>, b: &Vector3<f64>) -> Option<Vector3<f64>> {
    let (l, _, r) = ldl::<3>(|i, j| m[(i, j)])?;
    let mut y = [0.0; 3];
    for i in 0..3 {
        let mut s = b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s;
    }
    let mut x = Vector3::zeros();
    for i in (0..3).rev() {
        let mut s = y[i] * r[i];
        for k in i + 1..3 {
            s -= l[k][i] * x[k];
        }
        x[i] = s;
    }
    Some(x)
}

/// A draw from the Gaussian with information matrix `m` (symmetric positive definite) and
/// mean `-m^-1 b`, given three standard normal numbers `n`: the mean plus
/// `L^-T D^-1/2 n` for `m = L D L^T`, whose covariance is `L^-T D^-1 L^-1 = m^-1`. One
/// factorisation for both, and no inverse formed.
pub(crate) fn sample_information_form3(
    m: &Matrix3<f64>,
    b: &Vector3<f64>,
    n: &Vector3<f64>,
) -> Option<Vector3<f64>> {
    let (l, d, r) = ldl::<3>(|i, j| m[(i, j)])?;
    // m x = -b: forward with L, scale by D^-1, then back with L^T; the noise
    // D^-1/2 n joins before the back substitution, which is the same L^T.
    let mut y = [0.0; 3];
    for i in 0..3 {
        let mut s = -b[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s;
    }
    let mut x = Vector3::zeros();
    for i in (0..3).rev() {
        let mut s = y[i] * r[i] + n[i] / d[i].sqrt();
        for k in i + 1..3 {
            s -= l[k][i] * x[k];
        }
        x[i] = s;
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn agrees_with_the_general_routines() {
        let a = Matrix4::new(
            4.0, 1.0, 0.5, 0.2, 1.0, 3.0, 0.3, 0.1, 0.5, 0.3, 2.0, 0.4, 0.2, 0.1, 0.4, 1.5,
        );
        let (inverse, ln_det) = spd_inverse4(&a).unwrap();
        assert!((inverse * a - Matrix4::identity()).abs().max() < 1e-12);
        assert!((ln_det - a.determinant().ln()).abs() < 1e-12);
        let m = Matrix3::new(2.0, 0.5, 0.1, 0.5, 1.0, 0.2, 0.1, 0.2, 3.0);
        let b = Vector3::new(1.0, -2.0, 0.5);
        let x = spd_solve3(&m, &b).unwrap();
        assert!((m * x - b).abs().max() < 1e-12);
        assert!((spd_log_det3(&m).unwrap() - m.determinant().ln()).abs() < 1e-12);
        assert!(spd_inverse4(&(-a)).is_none());
        let c = Matrix4::from_fn(|i, j| (i * 4 + j) as f64 * 0.1 - 0.5);
        assert!((mul4(&a, &c) - a * c).abs().max() < 1e-12);
        assert!(spd_solve3(&(m * f64::NAN), &b).is_none());
        let d = Matrix4::from_fn(|i, j| ((i + 2 * j) % 5) as f64 * 0.3 - 0.4);
        let joseph = c * a * c.transpose() + d * a * d.transpose();
        let sum = joseph_sum(&(c * a), &c, &(d * a), &d);
        assert!((sum - joseph).abs().max() < 1e-12);
        assert_eq!(sum, sum.transpose());
    }

    #[test]
    fn information_form_draws_have_the_right_mean_and_covariance() {
        let m = Matrix3::new(2.0, 0.5, 0.1, 0.5, 1.0, 0.2, 0.1, 0.2, 3.0);
        let b = Vector3::new(1.0, -2.0, 0.5);
        let covariance = m.try_inverse().unwrap();
        let mean = -covariance * b;
        let draw = |n: Vector3<f64>| sample_information_form3(&m, &b, &n).unwrap();
        assert!((draw(Vector3::zeros()) - mean).abs().max() < 1e-12);
        // The draw is affine in n: mean + T n. Then T T^T, the sum over the unit vectors
        // of (draw - mean)(draw - mean)^T, must be the covariance m^-1.
        let mut t_t = Matrix3::zeros();
        for i in 0..3 {
            let column = draw(Vector3::ith(i, 1.0)) - mean;
            t_t += column * column.transpose();
        }
        assert!(
            (t_t - covariance).abs().max() < 1e-12,
            "{t_t} vs {covariance}"
        );
        assert!(sample_information_form3(&(-m), &b, &Vector3::zeros()).is_none());
    }
}
