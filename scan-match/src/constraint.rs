//! What a scan fixes of the pose and what it leaves open: the eigen-decomposition of the
//! fit's Hessian, with yaw scaled to metres by the scan's spread so the three directions
//! compare. A direction whose information is a small fraction of the strongest one's is
//! degenerate (the length of a corridor, the angle in a round room): the scan says nothing
//! reliable about it, and the prior alone decides it.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// Levenberg damping of the degenerate directions' steps, as a share of the strongest
/// direction's information: a weak direction moves a little on real evidence, a void one
/// not at all.
const DAMPING_SHARE: f64 = 0.02;

/// The scan's constraint on a pose `(x, y, yaw)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Constraint {
    /// Metres per radian: yaw `u = length * yaw` in the scaled space.
    length: f64,
    /// Eigenvectors (columns) of the Hessian in the scaled space `(x, y, length * yaw)`.
    vectors: Matrix3<f64>,
    values: Vector3<f64>,
    degenerate: [bool; 3],
}

impl Constraint {
    /// From the Hessian `hessian` over `(x, y, yaw)` (yaw column in metres per radian,
    /// as a point-to-line fit makes it), points at RMS distance `length` from the robot.
    pub fn new(hessian: &Matrix3<f64>, length: f64, degeneracy_ratio: f64) -> Self {
        let length = if length.is_finite() && length > 1e-3 {
            length
        } else {
            1.0
        };
        let scale = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0 / length));
        let scaled = scale * hessian * scale;
        let scaled = 0.5 * (scaled + scaled.transpose());
        let eigen = SymmetricEigen::new(scaled);
        let strongest = eigen.eigenvalues.max();
        let mut degenerate = [false; 3];
        for (flag, &value) in degenerate.iter_mut().zip(eigen.eigenvalues.iter()) {
            *flag = !(value > degeneracy_ratio * strongest && value > 0.0);
        }
        Self {
            length,
            vectors: eigen.eigenvectors,
            values: eigen.eigenvalues,
            degenerate,
        }
    }

    fn damping(&self) -> f64 {
        self.values.max().max(0.0) * DAMPING_SHARE
    }

    fn scaling(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, self.length))
    }

    /// Whether no direction is constrained at all.
    pub fn is_void(&self) -> bool {
        self.degenerate.iter().all(|&d| d)
    }

    /// The degenerate directions, unit vectors over `(x, y, yaw)` in the scaled metric.
    pub fn degenerate_directions(&self) -> impl Iterator<Item = Vector3<f64>> + '_ {
        (0..3).filter(|&i| self.degenerate[i]).map(|i| {
            let v = self.vectors.column(i);
            Vector3::new(v[0], v[1], v[2] / self.length)
        })
    }

    /// The Gauss-Newton step `-H^+ g` over the constrained directions; the degenerate ones
    /// stay where the prior put them rather than drift on noise, or, with `weak_steps`,
    /// take a step damped by a share of the strongest direction's information, so they
    /// move only as far as their own evidence clearly says.
    pub fn step(&self, gradient: &Vector3<f64>, weak_steps: bool) -> Vector3<f64> {
        // Gradients transform with the inverse of the coordinates.
        let from_scaled = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 1.0 / self.length));
        let g = from_scaled * gradient;
        let mut step = Vector3::zeros();
        let damping = self.damping();
        for i in 0..3 {
            let v = self.vectors.column(i);
            if self.degenerate[i] {
                if weak_steps && self.values[i] > 0.0 {
                    step -= v * (v.dot(&g) / (self.values[i] + damping));
                }
                continue;
            }
            step -= v * (v.dot(&g) / self.values[i]);
        }
        from_scaled * step
    }

    /// The information over `(x, y, yaw)` for residual variance `variance`: in full along
    /// the constrained directions, `weak_share` of it along the degenerate ones (zero: the
    /// prior alone decides them).
    pub fn information(&self, variance: f64, weak_share: f64) -> Matrix3<f64> {
        let mut scaled = Matrix3::zeros();
        for i in 0..3 {
            let v = self.vectors.column(i);
            let share = if self.degenerate[i] { weak_share } else { 1.0 };
            scaled += v * v.transpose() * (share * self.values[i].max(0.0) / variance);
        }
        let to_scaled = self.scaling();
        to_scaled * scaled * to_scaled
    }

    /// Squared Mahalanobis distance of `difference` (another estimate minus this fit's,
    /// over `(x, y, yaw)`) along the constrained directions, under this fit's covariance
    /// plus `other_covariance`.
    pub fn mahalanobis_squared(
        &self,
        difference: &Vector3<f64>,
        other_covariance: &Matrix3<f64>,
        variance: f64,
    ) -> f64 {
        let to_scaled = self.scaling();
        let e = self.vectors.transpose() * (to_scaled * difference);
        let other =
            self.vectors.transpose() * (to_scaled * other_covariance * to_scaled) * self.vectors;
        let mut combined = Matrix3::identity();
        let mut c = Vector3::zeros();
        for i in 0..3 {
            if self.degenerate[i] {
                continue;
            }
            c[i] = e[i];
            for j in 0..3 {
                if !self.degenerate[j] {
                    combined[(i, j)] = other[(i, j)];
                }
            }
            combined[(i, i)] += variance / self.values[i];
        }
        match combined.try_inverse() {
            Some(inverse) => c.dot(&(inverse * c)),
            None => f64::INFINITY,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_corridor_along_x_leaves_x_open() {
        // Walls along x: every normal is +-y; yaw is constrained through the lever arms.
        let hessian = Matrix3::new(1e-3, 0.0, 0.0, 0.0, 200.0, 10.0, 0.0, 10.0, 2000.0);
        let c = Constraint::new(&hessian, 4.0, 0.02);
        let open: Vec<_> = c.degenerate_directions().collect();
        assert_eq!(open.len(), 1);
        assert!(open[0].x.abs() > 0.999);
        // A gradient along x as small as its information allows (|g_x| <= sqrt(H_xx) x the
        // residuals' norm): the undamped step would be 10 m; the damped one is millimetres.
        assert_eq!(c.step(&Vector3::new(0.01, 2.0, 0.0), false).x, 0.0);
        let step = c.step(&Vector3::new(0.01, 2.0, 0.0), true);
        assert!(step.x < 0.0 && step.x.abs() < 0.01, "{step:?}");
        assert!(step.y < 0.0);
        let info = c.information(1.0, 0.0);
        assert!(info[(0, 0)].abs() < 1e-9 && info[(1, 1)] > 100.0);
        let weak = c.information(1.0, 0.1);
        assert!((weak[(0, 0)] - 1e-4).abs() < 1e-9);
        assert!((weak[(1, 1)] - info[(1, 1)]).abs() < 1e-9);
        // A disagreement along the corridor is no evidence against the other estimate.
        let far_along =
            c.mahalanobis_squared(&Vector3::new(100.0, 0.0, 0.0), &Matrix3::identity(), 1.0);
        assert!(far_along < 1e-9);
        let across =
            c.mahalanobis_squared(&Vector3::new(0.0, 10.0, 0.0), &Matrix3::identity(), 1.0);
        assert!(across > 50.0);
    }
}
