//! Least-squares rigid SE(2) alignment of two paired point sets.

use slam_geom::{MapCorner, Pose2, wrap_angle};

/// A rigid planar transform `p -> R(rotation) * p + translation`, taking estimate
/// coordinates (the SLAM frame) into truth coordinates (the world frame).
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

    /// The transform taking truth coordinates back into estimate coordinates.
    pub fn inverse(&self) -> Self {
        let (s, c) = self.rotation.sin_cos();
        let [tx, ty] = self.translation;
        Self {
            rotation: wrap_angle(-self.rotation),
            translation: [-(c * tx + s * ty), s * tx - c * ty],
        }
    }
}

/// The rigid transform minimising `sum |T(est_i) - truth_i|^2` (Umeyama without scale, as
/// `evo_ape -a`). Points are paired by index; any beyond the shorter slice are ignored. No
/// pairs give the identity and a single pair a pure translation.
pub fn align_se2(est: &[[f64; 2]], truth: &[[f64; 2]]) -> Se2Alignment {
    let n = est.len().min(truth.len());
    if n == 0 {
        return Se2Alignment::IDENTITY;
    }
    let centroid = |points: &[[f64; 2]]| {
        let sum = points[..n]
            .iter()
            .fold([0.0, 0.0], |acc, p| [acc[0] + p[0], acc[1] + p[1]]);
        [sum[0] / n as f64, sum[1] / n as f64]
    };
    let (ce, ct) = (centroid(est), centroid(truth));
    // In 2-D the SVD of Umeyama's cross-covariance reduces to one angle: the rotation that
    // maximises sum(t_i . R e_i) is atan2 of the summed cross and dot products. A reflection
    // can never come out of it, unlike an unguarded SVD.
    let (mut cross, mut dot) = (0.0, 0.0);
    for (e, t) in est[..n].iter().zip(&truth[..n]) {
        let (ex, ey) = (e[0] - ce[0], e[1] - ce[1]);
        let (tx, ty) = (t[0] - ct[0], t[1] - ct[1]);
        cross += ex * ty - ey * tx;
        dot += ex * tx + ey * ty;
    }
    let rotation = wrap_angle(cross.atan2(dot));
    let (s, c) = rotation.sin_cos();
    Se2Alignment {
        rotation,
        translation: [
            ct[0] - (c * ce[0] - s * ce[1]),
            ct[1] - (s * ce[0] + c * ce[1]),
        ],
    }
}
