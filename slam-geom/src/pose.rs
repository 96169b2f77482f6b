//! Planar rigid transforms `world_from_robot` (docs/CONVENTIONS.md).

use nalgebra::{Matrix2, Matrix3, Vector2};

use crate::Point2;

use crate::angle::wrap_angle;

/// A planar pose `world_from_robot`: position in metres, yaw in radians in `[-pi, pi)`.
/// A point `p` in the robot frame is `R(yaw) p + (x, y)` in the world.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose2 {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

impl Pose2 {
    /// The identity: the map frame's origin.
    pub const IDENTITY: Self = Self {
        x: 0.0,
        y: 0.0,
        yaw: 0.0,
    };

    /// A pose with its yaw wrapped (a no-op for a yaw already in `[-pi, pi)`).
    pub fn new(x: f64, y: f64, yaw: f64) -> Self {
        Self {
            x,
            y,
            yaw: wrap_angle(yaw),
        }
    }

    /// `self * other`: `other` expressed in the frame of `self` taken to the outer frame.
    pub fn compose(&self, other: &Self) -> Self {
        let (s, c) = self.yaw.sin_cos();
        Self {
            x: self.x + c * other.x - s * other.y,
            y: self.y + s * other.x + c * other.y,
            yaw: wrap_angle(self.yaw + other.yaw),
        }
    }

    /// The inverse transform, `robot_from_world`.
    pub fn inverse(&self) -> Self {
        let (s, c) = self.yaw.sin_cos();
        Self {
            x: -c * self.x - s * self.y,
            y: s * self.x - c * self.y,
            yaw: wrap_angle(-self.yaw),
        }
    }

    /// `self^-1 * other`: the pose of `other` in the frame of `self` (the increment from
    /// `self` to `other`).
    pub fn between(&self, other: &Self) -> Self {
        self.inverse().compose(other)
    }

    /// The position, metres.
    pub fn position(&self) -> Point2 {
        Point2::new(self.x, self.y)
    }

    /// Maps a point of this pose's frame into the outer frame.
    pub fn transform(&self, point: Point2) -> Point2 {
        self.rotation() * point + Vector2::new(self.x, self.y)
    }

    /// The rotation matrix `R(yaw)`.
    pub fn rotation(&self) -> Matrix2<f64> {
        let (s, c) = self.yaw.sin_cos();
        Matrix2::new(c, -s, s, c)
    }

    /// The Jacobian taking `(x, y, yaw)` in this pose's frame to the outer frame: `R(yaw)`
    /// on the translation, the identity on the turn. `J M J^T` turns a covariance into the
    /// outer frame, `J^T M J` an information out of it.
    pub fn frame_jacobian(&self) -> Matrix3<f64> {
        let mut m = Matrix3::identity();
        m.fixed_view_mut::<2, 2>(0, 0).copy_from(&self.rotation());
        m
    }

    /// The Jacobian of `self.compose(mount)` with respect to `self`: how an error of this
    /// pose moves a frame fixed to it at `mount` (its turn swings the mount's offset).
    /// `J M J^T` is the covariance of the mounted frame's pose.
    pub fn mount_jacobian(&self, mount: &Self) -> Matrix3<f64> {
        let offset = self.rotation() * nalgebra::Vector2::new(mount.x, mount.y);
        let mut m = Matrix3::identity();
        m[(0, 2)] = -offset.y;
        m[(1, 2)] = offset.x;
        m
    }

    /// The pose a fraction `t` of the way from `self` to `other`: position along the straight
    /// line, yaw along the shorter arc. `t` outside `[0, 1]` extrapolates at the same rate.
    pub fn interpolate(&self, other: &Self, t: f64) -> Self {
        Self {
            x: self.x + t * (other.x - self.x),
            y: self.y + t * (other.y - self.y),
            yaw: wrap_angle(self.yaw + t * wrap_angle(other.yaw - self.yaw)),
        }
    }

    /// Distance of the translation from the origin, metres.
    pub fn translation_norm(&self) -> f64 {
        self.x.hypot(self.y)
    }

    /// The rigid motion `outer_from_inner` that lays poses of the inner frame on the same
    /// poses as the outer frame has them (`(inner, outer)` pairs): its turn the mean of the
    /// pairs' turns, its translation the one that fits the positions in the least-squares
    /// sense. `None` without pairs.
    pub fn fit(pairs: &[(Pose2, Pose2)]) -> Option<Pose2> {
        if pairs.is_empty() {
            return None;
        }
        let (sin, cos) = pairs.iter().fold((0.0, 0.0), |(s, c), (inner, outer)| {
            let (ds, dc) = (outer.yaw - inner.yaw).sin_cos();
            (s + ds, c + dc)
        });
        let turn = Pose2::new(0.0, 0.0, sin.atan2(cos));
        let offset = pairs
            .iter()
            .map(|(inner, outer)| outer.position() - turn.transform(inner.position()))
            .sum::<Vector2<f64>>()
            / pairs.len() as f64;
        Some(Pose2::new(offset.x, offset.y, turn.yaw))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_fit_recovers_the_motion_between_two_frames_and_averages_their_disagreement() {
        let motion = Pose2::new(-3.0, 4.0, 2.9);
        let inner: Vec<Pose2> = (0..10)
            .map(|k| Pose2::new(0.5 * k as f64, 0.1 * (k * k) as f64, 0.3 * k as f64))
            .collect();
        let pairs: Vec<(Pose2, Pose2)> = inner.iter().map(|p| (*p, motion.compose(p))).collect();
        let fit = Pose2::fit(&pairs).unwrap();
        let error = motion.between(&fit);
        assert!(
            error.translation_norm() < 1e-9 && error.yaw.abs() < 1e-12,
            "{error:?}"
        );
        // Outer poses pushed apart symmetrically about the motion: the fit stays on it.
        let pushed: Vec<(Pose2, Pose2)> = pairs
            .iter()
            .enumerate()
            .map(|(k, (i, o))| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                (*i, Pose2::new(o.x + 0.1 * sign, o.y, o.yaw + 0.01 * sign))
            })
            .collect();
        let error = motion.between(&Pose2::fit(&pushed).unwrap());
        assert!(
            error.translation_norm() < 1e-3 && error.yaw.abs() < 1e-3,
            "{error:?}"
        );
        assert_eq!(Pose2::fit(&[]), None);
    }

    use super::*;

    #[test]
    fn the_mount_jacobian_is_the_derivative_of_composing_the_mount() {
        let pose = Pose2::new(1.0, -2.0, 0.7);
        let mount = Pose2::new(0.25, 0.1, 0.3);
        let j = pose.mount_jacobian(&mount);
        let h = 1e-6;
        for k in 0..3 {
            let mut moved = [pose.x, pose.y, pose.yaw];
            moved[k] += h;
            let a = Pose2::new(moved[0], moved[1], moved[2]).compose(&mount);
            let b = pose.compose(&mount);
            let d = [
                (a.x - b.x) / h,
                (a.y - b.y) / h,
                wrap_angle(a.yaw - b.yaw) / h,
            ];
            for r in 0..3 {
                assert!(
                    (d[r] - j[(r, k)]).abs() < 1e-5,
                    "d{r}/d{k}: {} vs {}",
                    d[r],
                    j[(r, k)]
                );
            }
        }
    }

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-12
            && (a.y - b.y).abs() < 1e-12
            && wrap_angle(a.yaw - b.yaw).abs() < 1e-12
    }

    #[test]
    fn compose_inverse_and_between_agree() {
        let a = Pose2::new(1.0, -2.0, 2.5);
        let b = Pose2::new(-0.3, 0.7, -2.9);
        assert!(close(&a.compose(&a.inverse()), &Pose2::IDENTITY));
        assert!(close(&a.compose(&a.between(&b)), &b));
        let p = Vector2::new(0.4, 1.1);
        let there = a.compose(&b).transform(p);
        let stepwise = a.transform(b.transform(p));
        assert!((there - stepwise).norm() < 1e-12);
        assert!(a.compose(&b).yaw >= -std::f64::consts::PI);
    }

    #[test]
    fn interpolation_takes_the_shorter_arc() {
        let a = Pose2::new(0.0, 0.0, 3.0);
        let b = Pose2::new(2.0, -4.0, -3.0);
        assert!(close(&a.interpolate(&b, 0.0), &a));
        assert!(close(&a.interpolate(&b, 1.0), &b));
        // From 3 rad to -3 rad is 0.28 rad through pi, not 6 rad through 0.
        let half = a.interpolate(&b, 0.5);
        assert!(close(&half, &Pose2::new(1.0, -2.0, -std::f64::consts::PI)));
        let beyond = a.interpolate(&b, 2.0);
        assert!(close(
            &beyond,
            &Pose2::new(4.0, -8.0, -3.0 + (2.0 * std::f64::consts::PI - 6.0))
        ));
    }
}
