//! The fixed-layout messages that cross process boundaries.

mod corner;
mod features;
mod ground_truth;
mod laser_scan;
mod line;
mod map_snapshot;
mod odometry;
mod path_chunk;
mod pose;
mod pose_estimate;
mod scan_motion;
mod world_corners;

pub use corner::{Corner, MapCorner, TrueCorner};
pub use features::{Features, FeaturesRecord, OdometryAtScan};
pub use ground_truth::GroundTruthPose;
pub use laser_scan::{LaserScan, LaserScanRecord};
pub use line::Line;
pub use map_snapshot::{MapSnapshot, MapSnapshotRecord};
pub use odometry::Odometry;
pub use path_chunk::{PathChunk, PathChunkRecord, StampedPose};
pub use pose::Pose2;
pub use pose_estimate::{PoseEstimate, StageTiming};
pub use scan_motion::ScanMotion;
pub use world_corners::{WorldCorners, WorldCornersRecord};

crate::zeroed::impl_zeroable!(
    crate::header::Header,
    Pose2,
    Corner,
    TrueCorner,
    MapCorner,
    Line,
    LaserScan,
    Odometry,
    GroundTruthPose,
    WorldCorners,
    Features,
    StageTiming,
    PoseEstimate,
    MapSnapshot,
    StampedPose,
    PathChunk,
    ScanMotion,
);
