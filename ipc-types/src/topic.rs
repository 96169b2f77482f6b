//! Service names, each bound to the one message type that travels on it.

use std::marker::PhantomData;

use crate::messages::{
    Features, GridCells, GroundTruthPose, LaserScan, MapSnapshot, Odometry, ParticleCloud,
    PathChunk, PoseEstimate, WorldCorners,
};

/// A service name bound to its message type, so a process cannot open a service with the
/// wrong type. Every topic lives inside a run's [`crate::Domain`].
#[derive(Debug)]
pub struct Topic<T> {
    name: &'static str,
    _message: PhantomData<fn() -> T>,
}

impl<T> Topic<T> {
    const fn new(name: &'static str) -> Self {
        Self {
            name,
            _message: PhantomData,
        }
    }

    /// The iceoryx2 service name.
    pub const fn name(&self) -> &'static str {
        self.name
    }

    /// The event service publishers notify after each send, so subscribers can sleep.
    pub fn event_name(&self) -> String {
        format!("{}/ready", self.name)
    }
}

impl<T> Clone for Topic<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Topic<T> {}

/// Scans from any lidar: a simulator, a replayed log or a live driver.
pub const SCAN: Topic<LaserScan> = Topic::new("lidar/scan");
/// Odometry, when the robot has it.
pub const ODOMETRY: Topic<Odometry> = Topic::new("robot/odometry");
/// The simulator's true pose for each scan.
pub const GROUND_TRUTH: Topic<GroundTruthPose> = Topic::new("sim/ground_truth");
/// The simulator's true world corners, published once with history.
pub const WORLD_CORNERS: Topic<WorldCorners> = Topic::new("sim/world_corners");
/// Lines and corners of each scan.
pub const FEATURES: Topic<Features> = Topic::new("perception/features");
/// The SLAM pose estimate of each scan.
pub const POSE: Topic<PoseEstimate> = Topic::new("slam/pose");
/// The filter's answer for the whole trajectory (the best particle's path), at the end of
/// the stream, in chunks.
pub const PATH: Topic<PathChunk> = Topic::new("slam/path");
/// The back end's path (the pose graph over the front end's steps and the verified loop
/// closures, solved), as it stands every few seconds and final at the end, in chunks.
pub const GRAPH_PATH: Topic<PathChunk> = Topic::new("graph/path");
/// The back end's occupancy grid (its submaps at their solved poses), as it stands every
/// few seconds and final at the end, in pieces.
pub const GRAPH_GRID: Topic<GridCells> = Topic::new("graph/grid");
/// The best particle's map, every few scans and at the end.
pub const MAP: Topic<MapSnapshot> = Topic::new("slam/map");
/// Every particle's pose and weight every few scans, in pieces, for a recording (slam-proc
/// publishes it only when the run is recorded).
pub const PARTICLES: Topic<ParticleCloud> = Topic::new("slam/particles");
/// The final path as map-sink wrote it (`trajectory.tum`, refined against its grid), at the
/// end of the run, in chunks.
pub const MAP_PATH: Topic<PathChunk> = Topic::new("map/path");
/// The occupancy grid as map-sink wrote it (`map.pgm`), at the end of the run, in pieces.
pub const MAP_GRID: Topic<GridCells> = Topic::new("map/grid");
