//! Poses as rigid 3D transforms, so planar and full 3D inputs are scored alike.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

/// A pose `world_from_body` (or a relative pose `first_from_second`).
pub type Pose = Isometry3<f64>;

/// A TUM pose: position and the quaternion `[qx, qy, qz, qw]`, normalised here because
/// writers round it. `None` for a quaternion too short to have a direction.
pub fn from_tum(position: [f64; 3], quaternion: [f64; 4]) -> Option<Pose> {
    let [qx, qy, qz, qw] = quaternion;
    let q = Quaternion::new(qw, qx, qy, qz);
    let norm = q.norm();
    if norm.is_nan() || norm <= 1e-9 {
        return None;
    }
    let [x, y, z] = position;
    Some(Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_quaternion(q),
    ))
}

/// A relation's pose: translation and roll, pitch, yaw (about x, then y, then z, as in the
/// relations files of Kuemmerle et al.).
pub fn from_xyz_rpy(xyz: [f64; 3], roll: f64, pitch: f64, yaw: f64) -> Pose {
    let [x, y, z] = xyz;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

/// The translational and rotational size of an error transform: `|t|` in metres and the
/// rotation angle in radians, in `[0, pi]` (for a planar error, `|yaw|` wrapped).
pub fn magnitude(error: &Pose) -> (f64, f64) {
    (error.translation.vector.norm(), error.rotation.angle())
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn planar_rotation_angle_is_the_wrapped_yaw() {
        let pose = from_xyz_rpy([3.0, 4.0, 0.0], 0.0, 0.0, 1.5 * PI);
        let (t, r) = magnitude(&pose);
        assert!((t - 5.0).abs() < 1e-12);
        assert!((r - 0.5 * PI).abs() < 1e-12);
    }

    #[test]
    fn tum_quaternions_are_normalised_and_zero_refused() {
        let (s, c) = (0.25_f64).sin_cos();
        let pose = from_tum([1.0, 2.0, 0.0], [0.0, 0.0, 2.0 * s, 2.0 * c]).unwrap();
        assert!((pose.rotation.euler_angles().2 - 0.5).abs() < 1e-12);
        assert!(from_tum([0.0; 3], [0.0; 4]).is_none());
        assert!(from_tum([0.0; 3], [f64::NAN, 0.0, 0.0, 1.0]).is_none());
    }
}
