//! The weighted least-squares rigid SE(2) alignment of two paired point sets: the one the
//! filter fits matched corners with, and the one a trajectory is aligned to the truth with
//! before it is scored (docs/CONVENTIONS.md, "Ground truth and scoring").

use nalgebra::Matrix2;

use crate::{MapCorner, Point2, Pose2, wrap_angle};

/// A rigid planar transform `p -> R(rotation) * p + translation`, from the frame of the
/// source points into the frame of the targets (for scoring: the SLAM frame into the world).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Se2Alignment {
    /// Radians, in `[-pi, pi)`.
    pub rotation: f64,
    pub translation: [f64; 2],
}

impl Se2Alignment {
    pub const IDENTITY: Self = Self {
        rotation: 0.0,
        translation: [0.0, 0.0],
    };

    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.rotation.sin_cos();
        [
            c * p[0] - s * p[1] + self.translation[0],
            s * p[0] + c * p[1] + self.translation[1],
        ]
    }

    pub fn apply_pose(&self, pose: Pose2) -> Pose2 {
        let [x, y] = self.apply(pose.position().into());
        Pose2::new(x, y, wrap_angle(pose.yaw + self.rotation))
    }

    /// Moves a corner's position and heading; angle, covariance shape and observations are
    /// unaffected by a rigid motion (the covariance is left as is: it is not drawn or scored).
    pub fn apply_corner(&self, corner: &MapCorner) -> MapCorner {
        let [x, y] = self.apply([corner.x, corner.y]);
        MapCorner {
            x,
            y,
            heading: wrap_angle(corner.heading + self.rotation),
            ..*corner
        }
    }

    /// The transform taking target coordinates back into source coordinates.
    pub fn inverse(&self) -> Self {
        let (s, c) = self.rotation.sin_cos();
        let [tx, ty] = self.translation;
        Self {
            rotation: wrap_angle(-self.rotation),
            translation: [-(c * tx + s * ty), s * tx - c * ty],
        }
    }

    /// The same transform as a pose `target_from_source`.
    pub fn to_pose(&self) -> Pose2 {
        Pose2::new(self.translation[0], self.translation[1], self.rotation)
    }
}

/// A source point, the target point it should land on, and the pair's weight (an inverse
/// variance, or 1 for all pairs alike).
pub type WeightedPair = (Point2, Point2, f64);

/// The rigid transform minimising `sum w_i |T(source_i) - target_i|^2` (weighted Kabsch /
/// Umeyama without scale, as `evo_ape -a` for equal weights), for `(source, target, weight)`
/// pairs. `None` when the pairs do not fix a rotation: no positive total weight, or fewer
/// than two distinct source points.
pub fn align_se2(pairs: &[WeightedPair]) -> Option<Se2Alignment> {
    let total: f64 = pairs.iter().map(|p| p.2).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let source_mean = pairs.iter().map(|(s, _, w)| s * *w).sum::<Point2>() / total;
    let target_mean = pairs.iter().map(|(_, t, w)| t * *w).sum::<Point2>() / total;
    let mut h = Matrix2::zeros();
    let mut spread = 0.0;
    for (s, t, w) in pairs {
        let (ds, dt) = (s - source_mean, t - target_mean);
        h += ds * dt.transpose() * *w;
        spread += ds.norm_squared() * *w;
    }
    if spread < 1e-12 * total {
        return None;
    }
    let svd = h.svd(true, true);
    let (u, v) = (svd.u?, svd.v_t?.transpose());
    // The reflection guard: a least-squares orthogonal matrix may be a reflection when the
    // points are noisy or nearly collinear; flipping the last axis gives the best rotation.
    let d = (v * u.transpose()).determinant().signum();
    let rotation = v * Matrix2::new(1.0, 0.0, 0.0, d) * u.transpose();
    let yaw = rotation[(1, 0)].atan2(rotation[(0, 0)]);
    let t = target_mean - rotation * source_mean;
    Some(Se2Alignment {
        rotation: wrap_angle(yaw),
        translation: [t.x, t.y],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    fn pairs_of(source: &[Point2], alignment: &Se2Alignment) -> Vec<WeightedPair> {
        source
            .iter()
            .map(|s| (*s, Point2::from(alignment.apply([s.x, s.y])), 1.0))
            .collect()
    }

    proptest! {
        #[test]
        fn a_known_transform_is_recovered(
            rotation in -PI..PI,
            tx in -50.0_f64..50.0,
            ty in -50.0_f64..50.0,
            points in prop::collection::vec((-20.0_f64..20.0, -20.0_f64..20.0, 0.1_f64..10.0), 3..30),
        ) {
            let truth = Se2Alignment { rotation, translation: [tx, ty] };
            let source: Vec<Point2> = points.iter().map(|&(x, y, _)| Point2::new(x, y)).collect();
            // Weights change nothing when the fit is exact.
            let pairs: Vec<WeightedPair> = pairs_of(&source, &truth)
                .into_iter()
                .zip(&points)
                .map(|((s, t, _), &(_, _, w))| (s, t, w))
                .collect();
            // Points too close together to fix a rotation are refused, not guessed.
            prop_assume!(source.iter().any(|p| (p - source[0]).norm() > 0.5));
            let fit = align_se2(&pairs).expect("distinct points fix the transform");
            prop_assert!(wrap_angle(fit.rotation - rotation).abs() < 1e-9);
            prop_assert!((fit.translation[0] - tx).abs() < 1e-8);
            prop_assert!((fit.translation[1] - ty).abs() < 1e-8);
        }
    }

    #[test]
    fn weights_pull_the_fit_towards_the_heavy_pairs() {
        // Three pairs agree on a pure shift of +1 in x; a fourth says +3. Weighted 1000:1
        // the shift comes out near 1; evenly it is the mean, 1.5.
        let source = [
            Point2::new(0.0, 0.0),
            Point2::new(4.0, 0.0),
            Point2::new(0.0, 4.0),
            Point2::new(4.0, 4.0),
        ];
        let shifts = [1.0, 1.0, 1.0, 3.0];
        let pairs = |weights: [f64; 4]| -> Vec<WeightedPair> {
            (0..4)
                .map(|i| {
                    (
                        source[i],
                        source[i] + Point2::new(shifts[i], 0.0),
                        weights[i],
                    )
                })
                .collect()
        };
        let even = align_se2(&pairs([1.0; 4])).unwrap();
        let heavy = align_se2(&pairs([1000.0, 1000.0, 1000.0, 1.0])).unwrap();
        let even_shift = even.apply([2.0, 2.0])[0] - 2.0;
        let heavy_shift = heavy.apply([2.0, 2.0])[0] - 2.0;
        assert!((even_shift - 1.5).abs() < 1e-12, "{even_shift}");
        assert!((heavy_shift - 1.0).abs() < 0.01, "{heavy_shift}");
    }

    #[test]
    fn a_reflection_never_comes_out() {
        // A mirrored target: the best proper rotation, not the reflection that fits exactly.
        let pairs: Vec<WeightedPair> = [(1.0, 0.0), (0.0, 1.0), (-1.0, -1.0)]
            .iter()
            .map(|&(x, y)| (Point2::new(x, y), Point2::new(x, -y), 1.0))
            .collect();
        let fit = align_se2(&pairs).unwrap();
        assert!((fit.to_pose().rotation().determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn too_few_pairs_fix_no_rotation() {
        assert!(align_se2(&[]).is_none());
        let one = (Point2::new(1.0, 1.0), Point2::new(0.0, 0.0), 1.0);
        assert!(align_se2(&[one]).is_none());
        assert!(align_se2(&[one, one]).is_none());
        let weightless = (Point2::new(2.0, 1.0), Point2::new(0.0, 0.0), 0.0);
        assert!(align_se2(&[weightless, weightless]).is_none());
    }

    #[test]
    fn the_inverse_undoes_the_transform_and_poses_turn_with_it() {
        let t = Se2Alignment {
            rotation: 2.5,
            translation: [3.0, -1.0],
        };
        let p = [0.7, -4.2];
        let back = t.inverse().apply(t.apply(p));
        assert!((back[0] - p[0]).abs() < 1e-12 && (back[1] - p[1]).abs() < 1e-12);
        let moved = t.apply_pose(Pose2::new(1.0, 0.0, 1.0));
        assert!((moved.yaw - wrap_angle(3.5)).abs() < 1e-12);
        let via_pose = t.to_pose().transform(Point2::new(p[0], p[1]));
        let direct = t.apply(p);
        assert!((via_pose.x - direct[0]).abs() < 1e-12 && (via_pose.y - direct[1]).abs() < 1e-12);
    }
}
