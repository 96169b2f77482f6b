//! The fixed-layout messages that cross process boundaries.

mod bounded_array;
mod chunked;
mod corner;
mod corner_list;
mod covariance3;
mod features;
mod grid_cells;
mod ground_truth;
mod laser_scan;
mod line;
mod map_snapshot;
mod odometry;
mod particle_cloud;
mod path_chunk;
mod pose;
mod pose_estimate;
mod scan_motion;
mod world_corners;

pub use bounded_array::BoundedArray;
pub use corner::{Corner, MapCorner, TrueCorner};
pub use corner_list::CornerListRecord;
pub use covariance3::{covariance_from_row_major, covariance_to_row_major};
pub use features::{Features, FeaturesRecord, OdometryAtScan};
pub use grid_cells::{GridCells, GridCellsRecord, GridGeometry};
pub use ground_truth::GroundTruthPose;
pub use laser_scan::{LaserScan, LaserScanRecord};
pub use line::Line;
pub use map_snapshot::{MapSnapshot, MapSnapshotRecord};
pub use odometry::Odometry;
pub use particle_cloud::{Particle, ParticleCloud, ParticleCloudRecord};
pub use path_chunk::{PathChunk, PathChunkRecord, PathForm, StampedPose};
pub use pose::Pose2;
pub use pose_estimate::{PoseEstimate, StageTiming};
pub use scan_motion::ScanMotion;
pub use world_corners::{WorldCorners, WorldCornersRecord};
