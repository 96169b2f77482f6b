//! Foxglove's 3D geometry (`foxglove.Vector3`, `foxglove.Quaternion`, `foxglove.Pose`) made
//! from our planar poses. Where a message carries a planar pose as it is (lossless: no trip
//! through a quaternion), it is `ipc_types::Pose2` in its serde form.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use ipc_types::Pose2;

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    pub const IDENTITY: Self = Self {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };

    /// A rotation by `yaw` about +z (REP 103: z up, so a positive yaw turns x towards y).
    pub fn from_yaw(yaw: f64) -> Self {
        let (s, c) = (0.5 * yaw).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
}

/// A position and orientation in 3D; ours lie in the z = 0 plane.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct Pose {
    pub position: Vector3,
    pub orientation: Quaternion,
}

impl Pose {
    pub const IDENTITY: Self = Self {
        position: Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        },
        orientation: Quaternion::IDENTITY,
    };
}

impl From<Pose2> for Pose {
    fn from(p: Pose2) -> Self {
        Self {
            position: Vector3 {
                x: p.x,
                y: p.y,
                z: 0.0,
            },
            orientation: Quaternion::from_yaw(p.yaw),
        }
    }
}
