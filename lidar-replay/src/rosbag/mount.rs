//! Where the laser sits on the robot, from the bag's static transforms (`/tf_static`):
//! the chain from the base frame (REP 105 `base_link`) down to the scans' `frame_id`.

use std::collections::HashMap;

use slam_geom::Pose2;

use super::messages::Transform;

/// A mount leaning more than this from the base frame's plane is refused: the pipeline's
/// scans are planar, and a tilted (or upside-down) laser's are not.
pub const MAX_TILT_DEG: f64 = 10.0;

/// The static transforms of a bag, by child frame (the newest for each).
#[derive(Debug, Default, Clone)]
pub struct StaticTransforms {
    by_child: HashMap<String, Transform>,
}

/// What was found of the laser's mount.
#[derive(Debug, Clone, PartialEq)]
pub enum Mount {
    /// The scans are in the base frame itself.
    AtBase,
    /// The chain of static transforms from the base frame to the scans' frame.
    Found {
        robot_from_sensor: Pose2,
        hops: usize,
    },
    /// No chain: the laser is taken to be at the base frame's origin.
    Missing,
}

impl Mount {
    /// `robot_from_sensor`.
    pub fn pose(&self) -> Pose2 {
        match self {
            Self::Found {
                robot_from_sensor, ..
            } => *robot_from_sensor,
            Self::AtBase | Self::Missing => Pose2::IDENTITY,
        }
    }
}

/// Why a mount cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MountError {
    #[error(
        "the laser's frame {frame} leans {tilt_deg:.0} degrees from {base}'s plane (more than \
         {MAX_TILT_DEG}): lidar-replay replays planar scans only"
    )]
    Tilted {
        frame: String,
        base: String,
        tilt_deg: f64,
    },
    #[error("the static transforms from {base} to {frame} are no rotation: {reason}")]
    Invalid {
        frame: String,
        base: String,
        reason: String,
    },
}

impl StaticTransforms {
    pub fn add(&mut self, transform: Transform) {
        self.by_child
            .insert(transform.child_frame_id.clone(), transform);
    }

    /// The pose of `frame` in `base`, following the chain of parents up from `frame`.
    pub fn mount(&self, base: &str, frame: &str) -> Result<Mount, MountError> {
        if frame == base {
            return Ok(Mount::AtBase);
        }
        let mut chain = Vec::new();
        let mut child = frame;
        while child != base {
            let Some(transform) = self.by_child.get(child) else {
                return Ok(Mount::Missing);
            };
            // A loop of frames has no base in it.
            if chain.len() > self.by_child.len() {
                return Ok(Mount::Missing);
            }
            chain.push(transform);
            child = &transform.header.frame_id;
        }
        let mut robot_from_sensor = Pose2::IDENTITY;
        let mut rotation = [0.0, 0.0, 0.0, 1.0];
        for transform in chain.iter().rev() {
            let step = transform.planar().map_err(|e| MountError::Invalid {
                frame: frame.to_owned(),
                base: base.to_owned(),
                reason: e.to_string(),
            })?;
            robot_from_sensor = robot_from_sensor.compose(&step);
            rotation = hamilton(rotation, transform.rotation);
        }
        let composed = Transform {
            rotation,
            ..chain[0].clone()
        };
        let tilt_deg = composed.tilt().to_degrees();
        if tilt_deg > MAX_TILT_DEG {
            return Err(MountError::Tilted {
                frame: frame.to_owned(),
                base: base.to_owned(),
                tilt_deg,
            });
        }
        Ok(Mount::Found {
            robot_from_sensor,
            hops: chain.len(),
        })
    }
}

/// The quaternion product `a b` (x, y, z, w): `b`'s rotation within `a`'s frame.
fn hamilton(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let [ax, ay, az, aw] = a;
    let [bx, by, bz, bw] = b;
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rosbag::messages::Header;

    fn transform(parent: &str, child: &str, x: f64, yaw: f64, roll: f64) -> Transform {
        // yaw about z, then roll about the new x.
        let (sy, cy) = (yaw / 2.0).sin_cos();
        let (sr, cr) = (roll / 2.0).sin_cos();
        Transform {
            header: Header {
                stamp_ns: 0,
                frame_id: parent.into(),
            },
            child_frame_id: child.into(),
            translation: [x, 0.0, 0.3],
            rotation: hamilton([0.0, 0.0, sy, cy], [sr, 0.0, 0.0, cr]),
        }
    }

    #[test]
    fn the_chain_from_base_to_laser_is_composed() {
        let mut tf = StaticTransforms::default();
        tf.add(transform(
            "base_link",
            "laser_mount",
            0.2,
            std::f64::consts::FRAC_PI_2,
            0.0,
        ));
        tf.add(transform("laser_mount", "laser", 0.05, 0.0, 0.0));
        tf.add(transform("base_link", "camera", 0.1, 0.0, 0.0));
        let Mount::Found {
            robot_from_sensor,
            hops,
        } = tf.mount("base_link", "laser").unwrap()
        else {
            panic!("no mount found");
        };
        assert_eq!(hops, 2);
        assert!((robot_from_sensor.x - 0.2).abs() < 1e-12);
        assert!((robot_from_sensor.y - 0.05).abs() < 1e-12);
        assert!((robot_from_sensor.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert_eq!(tf.mount("base_link", "base_link").unwrap(), Mount::AtBase);
        assert_eq!(tf.mount("base_link", "lidar").unwrap(), Mount::Missing);
        assert_eq!(tf.mount("base_footprint", "laser").unwrap(), Mount::Missing);
    }

    #[test]
    fn a_laser_upside_down_or_tilted_is_refused() {
        let mut tf = StaticTransforms::default();
        tf.add(transform(
            "base_link",
            "laser",
            0.2,
            0.0,
            std::f64::consts::PI,
        ));
        assert!(matches!(
            tf.mount("base_link", "laser"),
            Err(MountError::Tilted { tilt_deg, .. }) if (tilt_deg - 180.0).abs() < 1e-6
        ));
        tf.add(transform("base_link", "laser", 0.2, 1.0, 0.05));
        assert!(matches!(
            tf.mount("base_link", "laser"),
            Ok(Mount::Found { .. })
        ));
    }
}
