//! The Kalman update of one map corner `(x, y, heading, angle)` by one observation taken
//! to the world with the particle's pose (FastSLAM conditions each map on its pose, so the
//! pose's uncertainty does not enter here).

use std::f64::consts::PI;

use nalgebra::{Matrix4, Vector4};

#[cfg(test)]
use crate::math::linalg::spd_inverse4;
use crate::math::linalg::{joseph_sum, mul4};
use crate::update::corner_model::innovation;
use slam_geom::wrap_angle;

/// The smallest opening angle kept off 0 and pi: an update never turns a corner into a
/// straight wall or a spike.
const ANGLE_MARGIN: f64 = 1e-6;

/// The corner's estimate after observing `observed` with noise covariance `noise` (`H = I`).
/// Joseph form, symmetrised, so the covariance stays symmetric positive definite despite
/// rounding; heading and angle innovations are wrapped. `None` when `P + R` is not
/// positive definite.
#[cfg(test)]
pub(crate) fn update(
    mean: &Vector4<f64>,
    covariance: &Matrix4<f64>,
    observed: &Vector4<f64>,
    noise: &Matrix4<f64>,
) -> Option<(Vector4<f64>, Matrix4<f64>)> {
    let (s_inverse, _) = spd_inverse4(&(covariance + noise))?;
    Some(update_with_inverse(
        mean, covariance, observed, noise, &s_inverse,
    ))
}

/// The update with `(P + R)^-1` already known (association computed it).
///
/// Compiled twice, and the AVX2 build chosen at run time where the CPU has it: three
/// 4x4 products a column at a time are what 256-bit registers are for (on seed-hall the
/// update was a fifth of the filter's instructions, its AVX2 build needs a third of
/// them). Rust does not fuse multiplications and additions unasked, so both builds give
/// the same bits.
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(crate) fn update_with_inverse(
    mean: &Vector4<f64>,
    covariance: &Matrix4<f64>,
    observed: &Vector4<f64>,
    noise: &Matrix4<f64>,
    s_inverse: &Matrix4<f64>,
) -> (Vector4<f64>, Matrix4<f64>) {
    let gain = mul4(covariance, s_inverse);
    let nu = innovation(observed, mean);
    let mut updated = mean + gain * nu;
    updated.z = wrap_angle(updated.z);
    updated.w = updated.w.clamp(ANGLE_MARGIN, PI - ANGLE_MARGIN);
    let i_minus_k = Matrix4::identity() - gain;
    // Both terms are computed as symmetric products (upper triangle mirrored), which is
    // the symmetrisation.
    let joseph = joseph_sum(
        &mul4(&i_minus_k, covariance),
        &i_minus_k,
        &mul4(&gain, noise),
        &gain,
    );
    (updated, joseph)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_hand_computed_diagonal_case() {
        // Per axis: K = P / (P + R); mean += K nu; P' = P R / (P + R).
        let p = Matrix4::from_diagonal(&Vector4::new(0.04, 0.04, 0.01, 0.01));
        let r = Matrix4::from_diagonal(&Vector4::new(0.01, 0.01, 0.01, 0.01));
        let mean = Vector4::new(1.0, 2.0, 0.5, 1.5);
        let observed = Vector4::new(1.1, 1.8, 0.55, 1.5);
        let (m, c) = update(&mean, &p, &observed, &r).unwrap();
        let expected_mean = Vector4::new(1.08, 1.84, 0.525, 1.5);
        let expected_cov = Matrix4::from_diagonal(&Vector4::new(0.008, 0.008, 0.005, 0.005));
        assert!((m - expected_mean).abs().max() < 1e-12, "{m}");
        assert!((c - expected_cov).abs().max() < 1e-12, "{c}");
    }

    #[test]
    fn matches_the_standard_form_with_correlations() {
        // x and heading correlated in the corner; y and angle in the observation.
        let mut p = Matrix4::from_diagonal(&Vector4::new(0.04, 0.02, 0.01, 0.03));
        p[(0, 2)] = 0.01;
        p[(2, 0)] = 0.01;
        let mut r = Matrix4::from_diagonal(&Vector4::new(0.01, 0.02, 0.005, 0.01));
        r[(1, 3)] = 0.005;
        r[(3, 1)] = 0.005;
        let mean = Vector4::new(0.0, 0.0, 0.0, 1.0);
        let observed = Vector4::new(0.2, -0.1, 0.05, 1.1);
        let (m, c) = update(&mean, &p, &observed, &r).unwrap();
        // Reference: K = P (P + R)^-1, P' = (I - K) P, computed independently.
        let k = p * (p + r).try_inverse().unwrap();
        let reference_mean = mean + k * (observed - mean);
        let reference_cov = (Matrix4::identity() - k) * p;
        assert!((m - reference_mean).abs().max() < 1e-12);
        assert!((c - reference_cov).abs().max() < 1e-12);
        assert_eq!(c, c.transpose());
    }

    #[test]
    fn heading_innovation_wraps_across_pi() {
        let p = Matrix4::identity() * 0.01;
        let mean = Vector4::new(0.0, 0.0, 3.1, 1.5);
        let observed = Vector4::new(0.0, 0.0, -3.1, 1.5);
        let (m, _) = update(&mean, &p, &observed, &p).unwrap();
        // Halfway between 3.1 and -3.1 the short way round is pi (or -pi once wrapped),
        // not 0 as plain subtraction would give.
        assert!(wrap_angle(m.z - PI).abs() < 1e-12, "{}", m.z);
        assert!((-PI..PI).contains(&m.z));
    }
}
