//! Our messages that no Foxglove schema fits, recorded whole under schemas of our own
//! (`slam.*`), so that nothing the pipeline said is lost.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::geometry::Planar;
use crate::header::HeaderJson;
use crate::schema::ChannelMessage;

/// `ipc_types::Odometry`.
#[derive(Debug, Serialize, Deserialize, JsonSchema)]
pub struct OdometryMessage {
    pub header: HeaderJson,
    /// `odom_from_robot`.
    pub pose: Planar,
    /// Row-major 3x3 over (x, y, yaw).
    pub covariance: [f64; 9],
    pub linear_velocity: f64,
    pub angular_velocity: f64,
}

impl ChannelMessage for OdometryMessage {
    const TOPIC: &'static str = "/robot/odometry";
    const SCHEMA: &'static str = "slam.Odometry";
}

impl OdometryMessage {
    pub fn new(o: &ipc_types::Odometry) -> Self {
        Self {
            header: (&o.header).into(),
            pose: o.pose.into(),
            covariance: o.covariance,
            linear_velocity: o.linear_velocity,
            angular_velocity: o.angular_velocity,
        }
    }

    /// The odometry this message was made from, bit for bit.
    pub fn to_odometry(&self) -> Box<ipc_types::Odometry> {
        let mut odometry = <ipc_types::Odometry as ipc_types::Zeroable>::boxed_zeroed();
        odometry.header = self.header.to_header();
        odometry.pose = self.pose.into();
        odometry.covariance = self.covariance;
        odometry.linear_velocity = self.linear_velocity;
        odometry.angular_velocity = self.angular_velocity;
        odometry
    }
}

/// A corner (docs/CONVENTIONS.md, "Corner features").
#[derive(Debug, Serialize, JsonSchema)]
pub struct CornerJson {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    pub angle: f64,
    /// Row-major 4x4 over (x, y, heading, angle); absent for the world's true corners.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub covariance: Option<[f64; 16]>,
    /// Scans that saw a map corner.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub observations: Option<u32>,
}

impl From<&ipc_types::Corner> for CornerJson {
    fn from(c: &ipc_types::Corner) -> Self {
        Self {
            x: c.x,
            y: c.y,
            heading: c.heading,
            angle: c.angle,
            covariance: Some(c.covariance),
            observations: None,
        }
    }
}

/// A line `x cos(theta) + y sin(theta) = rho` in the sensor frame.
#[derive(Debug, Serialize, JsonSchema)]
pub struct LineJson {
    pub rho: f64,
    pub theta: f64,
    /// Row-major 2x2 over (rho, theta).
    pub covariance: [f64; 4],
    pub start: [f64; 2],
    pub end: [f64; 2],
    pub point_count: u32,
}

/// The front end's registration of a scan (`ipc_types::ScanMotion`).
#[derive(Debug, Serialize, JsonSchema)]
pub struct MotionJson {
    pub pose: Planar,
    pub increment: Planar,
    pub increment_covariance: [f64; 9],
    /// `ScanMotion::MATCH_*`: 1 first, 2 ok, 3 degenerate, 4 failed.
    pub match_status: u32,
    /// `ScanMotion::ODOMETRY_*`: 0 absent, 1 started, 2 used, 3 rejected.
    pub odometry_status: u32,
    pub points: u32,
    pub inliers: u32,
}

/// The odometry paired with a scan.
#[derive(Debug, Serialize, JsonSchema)]
pub struct OdometryAtScanJson {
    pub pose: Planar,
    pub covariance: [f64; 9],
}

/// `ipc_types::Features`.
#[derive(Debug, Serialize, JsonSchema)]
pub struct FeaturesMessage {
    pub header: HeaderJson,
    pub scan_sent_ns: u64,
    pub processing_ns: u64,
    pub odometry: Option<OdometryAtScanJson>,
    pub motion: Option<MotionJson>,
    pub lines: Vec<LineJson>,
    pub corners: Vec<CornerJson>,
}

impl ChannelMessage for FeaturesMessage {
    const TOPIC: &'static str = "/perception/features";
    const SCHEMA: &'static str = "slam.Features";
}

impl FeaturesMessage {
    pub fn new(f: &ipc_types::Features) -> Self {
        Self {
            header: (&f.header).into(),
            scan_sent_ns: f.scan_sent_ns,
            processing_ns: f.processing_ns,
            odometry: f.odometry().map(|o| OdometryAtScanJson {
                pose: o.pose.into(),
                covariance: o.covariance,
            }),
            motion: f.motion().map(|m| MotionJson {
                pose: m.pose.into(),
                increment: m.increment.into(),
                increment_covariance: m.increment_covariance,
                match_status: m.match_status,
                odometry_status: m.odometry_status,
                points: m.points,
                inliers: m.inliers,
            }),
            lines: f
                .lines()
                .iter()
                .map(|l| LineJson {
                    rho: l.rho,
                    theta: l.theta,
                    covariance: l.covariance,
                    start: l.start,
                    end: l.end,
                    point_count: l.point_count,
                })
                .collect(),
            corners: f.corners().iter().map(CornerJson::from).collect(),
        }
    }
}

/// `ipc_types::MapSnapshot`: the best particle's corners, in the map frame.
#[derive(Debug, Serialize, JsonSchema)]
pub struct MapMessage {
    pub header: HeaderJson,
    pub corners: Vec<CornerJson>,
}

impl ChannelMessage for MapMessage {
    const TOPIC: &'static str = "/slam/map";
    const SCHEMA: &'static str = "slam.MapSnapshot";
}

impl MapMessage {
    pub fn new(m: &ipc_types::MapSnapshot) -> Self {
        Self {
            header: (&m.header).into(),
            corners: m
                .corners()
                .iter()
                .map(|c| CornerJson {
                    observations: Some(c.observations),
                    ..CornerJson::from(&c.corner)
                })
                .collect(),
        }
    }
}

/// `ipc_types::WorldCorners`: the simulated world's true corners, in the world frame.
#[derive(Debug, Serialize, JsonSchema)]
pub struct WorldCornersMessage {
    pub header: HeaderJson,
    pub corners: Vec<CornerJson>,
}

impl ChannelMessage for WorldCornersMessage {
    const TOPIC: &'static str = "/sim/world_corners";
    const SCHEMA: &'static str = "slam.WorldCorners";
}

impl WorldCornersMessage {
    pub fn new(w: &ipc_types::WorldCorners) -> Self {
        Self {
            header: (&w.header).into(),
            corners: w
                .corners()
                .iter()
                .map(|c| CornerJson {
                    x: c.x,
                    y: c.y,
                    heading: c.heading,
                    angle: c.angle,
                    covariance: None,
                    observations: None,
                })
                .collect(),
        }
    }
}
