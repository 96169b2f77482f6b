//! A run's recording: each pipeline message to its channel(s), written to an [`Output`]
//! (the MCAP file, or a live view).

use std::path::{Path, PathBuf};

use ipc_types::{
    Features, GridCells, GridPieces, GroundTruthPose, Header, LaserScan, MapSnapshot, Odometry,
    ParticleCloud, PathChunk, PoseEstimate, WorldCorners,
};

use crate::error::RecordError;
use crate::features_scene::FeaturesScenes;
use crate::grid::{GraphGridMessage, GridMessage};
use crate::ground_truth::GroundTruthMessage;
use crate::map_scene::MapScenes;
use crate::mcap_file::{ChannelCount, McapFile};
use crate::output::Output;
use crate::own::MapMessage;
use crate::particles::{ParticlePieces, ParticlesMessage};
use crate::path::{GraphPathMessage, MapPathMessage, PathChunks, PathMessage};
use crate::pose::{MAP_FRAME, PoseMessage};
use crate::scan::ScanMessage;
use crate::schema::ChannelMessage;
use crate::transform::{BASE_FRAME, TransformMessage};

/// The recording's file name in the run's directory.
pub const RECORDING_FILE: &str = "run.mcap";

/// A map snapshot (and its scene) is recorded at most once per this much data time, and the
/// last one at the end: each holds the whole map, so a run's recording would otherwise grow
/// with the square of its length (a 40 Hz run sends one every half second), and one every
/// four seconds is plenty to watch the map grow.
pub const MAP_PERIOD_NS: u64 = 4_000_000_000;

/// What a finished recording holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecordingSummary {
    pub path: PathBuf,
    /// Per channel, in topic order.
    pub channels: Vec<ChannelCount>,
    /// Path chunks that did not continue the path (the path was then not recorded).
    pub path_chunks_out_of_place: u64,
    /// Map snapshots left out as less than [`MAP_PERIOD_NS`] after the last one recorded.
    pub maps_left_out: u64,
    /// Pieces of map-sink's path and grid that did not continue them (then not recorded).
    pub final_map_pieces_out_of_place: u64,
    /// Particle clouds left out because a piece of them was lost (real time only).
    pub particle_clouds_incomplete: u64,
}

/// A recording being written to `O`. End-of-stream markers carry no data and are not
/// recorded.
#[derive(Debug)]
pub struct Recording<O: Output = McapFile> {
    file: O,
    chunks: PathChunks,
    /// The scan frames already placed on the robot (`base_link` → frame).
    sensor_frames: Vec<String>,
    /// Data time of the last map snapshot recorded.
    last_map_ns: Option<u64>,
    /// The newest snapshot left out, with its stamp and send time: written at the end if
    /// no later one was recorded, so the file ends with the run's final map.
    held_map: Option<(MapMessage, u64, u64)>,
    maps_left_out: u64,
    map_path: PathChunks,
    graph_path: PathChunks,
    graph_grid: GridPieces,
    grid: GridPieces,
    particles: ParticlePieces,
    /// The recorded map snapshots drawn as scenes.
    map_scenes: MapScenes,
    /// The features drawn as scenes, a few a second.
    features_scenes: FeaturesScenes,
}

impl Recording {
    /// Creates `dir/run.mcap`.
    pub fn create(dir: &Path) -> Result<Self, RecordError> {
        let path = dir.join(RECORDING_FILE);
        Ok(Self::to(McapFile::create(&path)?))
    }

    /// Writes the last map snapshot if it was held back, and closes the file with its
    /// summary and indexes.
    pub fn finish(mut self) -> Result<RecordingSummary, RecordError> {
        self.write_held_map()?;
        let out_of_place = self.chunks.out_of_place;
        Ok(RecordingSummary {
            path: self.file.path().to_path_buf(),
            channels: self.file.finish()?,
            path_chunks_out_of_place: out_of_place,
            maps_left_out: self.maps_left_out,
            final_map_pieces_out_of_place: self.map_path.out_of_place + self.grid.out_of_place,
            particle_clouds_incomplete: self.particles.incomplete,
        })
    }
}

impl<O: Output> Recording<O> {
    /// Converts the messages into `output`.
    pub fn to(output: O) -> Self {
        Self {
            file: output,
            chunks: PathChunks::default(),
            sensor_frames: Vec::new(),
            last_map_ns: None,
            held_map: None,
            maps_left_out: 0,
            map_path: PathChunks::default(),
            graph_path: PathChunks::default(),
            graph_grid: GridPieces::default(),
            grid: GridPieces::default(),
            particles: ParticlePieces::default(),
            map_scenes: MapScenes::default(),
            features_scenes: FeaturesScenes::default(),
        }
    }

    /// The output, to look at its state.
    pub fn output(&self) -> &O {
        &self.file
    }

    /// Has the next scan of each sensor frame put that frame on the robot again
    /// (`base_link` → frame on `/tf`), as its first one did. A file needs it once; a live
    /// view says it again now and then for the clients that connected since.
    pub fn restate_sensor_frames(&mut self) {
        self.sensor_frames.clear();
    }

    /// A scan on `/lidar/scan`; the first scan of a frame other than `base_link` also puts
    /// that frame on the robot (identity: the lidar sits at the robot's origin,
    /// docs/CONVENTIONS.md), so the viewer can draw the scan in the map.
    pub fn scan(&mut self, scan: &LaserScan) -> Result<(), RecordError> {
        if scan.header.is_end_of_stream() {
            return Ok(());
        }
        let frame = scan.header.frame_id();
        if frame != BASE_FRAME && !self.sensor_frames.iter().any(|f| f == frame) {
            let tf = TransformMessage::planar(
                scan.header.stamp_ns,
                BASE_FRAME,
                frame,
                ipc_types::Pose2::default(),
            );
            self.file
                .write(&tf, scan.header.stamp_ns, scan.header.sent_ns)?;
            self.sensor_frames.push(frame.to_owned());
        }
        let h = scan.header;
        self.file
            .write(&ScanMessage::new(scan), h.stamp_ns, h.sent_ns)
    }

    pub fn odometry(&mut self, odometry: &Odometry) -> Result<(), RecordError> {
        self.data(odometry.header, || *odometry)
    }

    /// The features on `/perception/features` and, a few a second, as a scene.
    pub fn features(&mut self, features: &Features) -> Result<(), RecordError> {
        self.data(features.header, || features.to_record())?;
        let h = features.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        match self.features_scenes.scene(features) {
            Some(scene) => self.file.write(&scene, h.stamp_ns, h.sent_ns),
            None => Ok(()),
        }
    }

    /// The estimate on `/slam/pose`, and `map → base_link` at it on `/tf`.
    pub fn pose(&mut self, pose: &PoseEstimate) -> Result<(), RecordError> {
        let h = pose.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        self.file
            .write(&PoseMessage::new(pose), h.stamp_ns, h.sent_ns)?;
        let tf = TransformMessage::planar(h.stamp_ns, MAP_FRAME, BASE_FRAME, pose.mean);
        self.file.write(&tf, h.stamp_ns, h.sent_ns)
    }

    /// A map snapshot, at most one per [`MAP_PERIOD_NS`] of data time (and the last).
    pub fn map(&mut self, map: &MapSnapshot) -> Result<(), RecordError> {
        let h = map.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        let message = MapMessage::new(map);
        if self
            .last_map_ns
            .is_some_and(|last| h.stamp_ns < last.saturating_add(MAP_PERIOD_NS))
        {
            if self
                .held_map
                .replace((message, h.stamp_ns, h.sent_ns))
                .is_some()
            {
                self.maps_left_out += 1;
            }
            return Ok(());
        }
        if self.held_map.take().is_some() {
            self.maps_left_out += 1;
        }
        self.last_map_ns = Some(h.stamp_ns);
        self.write_map(&message, h.stamp_ns, h.sent_ns)
    }

    /// A map snapshot on `/slam/map`, and as a scene.
    fn write_map(
        &mut self,
        message: &MapMessage,
        stamp_ns: u64,
        sent_ns: u64,
    ) -> Result<(), RecordError> {
        self.file.write(message, stamp_ns, sent_ns)?;
        let scene = self.map_scenes.scene(message);
        self.file.write(&scene, stamp_ns, sent_ns)
    }

    /// A chunk of the final path; the path is recorded once all of it is in.
    pub fn path_chunk(&mut self, chunk: &PathChunk) -> Result<(), RecordError> {
        let h = chunk.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        if let Some(poses) = self.chunks.add(chunk) {
            let stamp = poses.last().map_or(h.stamp_ns, |p| p.stamp_ns);
            self.file
                .write(&PathMessage::new(&poses), stamp, h.sent_ns)?;
        }
        Ok(())
    }

    /// A piece of a particle cloud; the cloud is recorded once all of it is in.
    pub fn particles(&mut self, piece: &ParticleCloud) -> Result<(), RecordError> {
        if piece.header.is_end_of_stream() {
            return Ok(());
        }
        if let Some((header, particles)) = self.particles.add(piece) {
            let message = ParticlesMessage::new(&header, &particles);
            self.file
                .write(&message, header.stamp_ns, piece.header.sent_ns)?;
        }
        Ok(())
    }

    /// A chunk of the final path map-sink wrote; recorded once all of it is in.
    pub fn map_path_chunk(&mut self, chunk: &PathChunk) -> Result<(), RecordError> {
        let h = chunk.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        if let Some(poses) = self.map_path.add(chunk) {
            let message = MapPathMessage(PathMessage::new(&poses));
            self.file.write(&message, h.stamp_ns, h.sent_ns)?;
        }
        Ok(())
    }

    /// A chunk of the back end's path; recorded once all of it is in.
    pub fn graph_path_chunk(&mut self, chunk: &PathChunk) -> Result<(), RecordError> {
        let h = chunk.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        if let Some(poses) = self.graph_path.add(chunk) {
            let message = GraphPathMessage(PathMessage::new(&poses));
            self.file.write(&message, h.stamp_ns, h.sent_ns)?;
        }
        Ok(())
    }

    /// A piece of the back end's grid; recorded once all of it is in.
    pub fn graph_grid_cells(&mut self, piece: &GridCells) -> Result<(), RecordError> {
        let h = piece.header;
        if let Some(grid) = self.graph_grid.add(piece) {
            let stamp_ns = grid.header.stamp_ns;
            let message = GraphGridMessage(GridMessage::new(stamp_ns, &grid.geometry, &grid.cells));
            self.file.write(&message, stamp_ns, h.sent_ns)?;
        }
        Ok(())
    }

    /// A piece of the grid map-sink wrote; recorded once all of it is in.
    pub fn grid_cells(&mut self, piece: &GridCells) -> Result<(), RecordError> {
        let h = piece.header;
        if h.is_end_of_stream() {
            return Ok(());
        }
        if let Some(grid) = self.grid.add(piece) {
            let stamp_ns = grid.header.stamp_ns;
            let message = GridMessage::new(stamp_ns, &grid.geometry, &grid.cells);
            self.file.write(&message, stamp_ns, h.sent_ns)?;
        }
        Ok(())
    }

    pub fn ground_truth(&mut self, truth: &GroundTruthPose) -> Result<(), RecordError> {
        self.data(truth.header, || GroundTruthMessage::new(truth))
    }

    pub fn world_corners(&mut self, world: &WorldCorners) -> Result<(), RecordError> {
        self.data(world.header, || world.to_record())
    }

    /// Records the message `make` makes of a pipeline message with `header`, stamped as it
    /// was; an end-of-stream marker carries no data and is not recorded.
    fn data<M: ChannelMessage>(
        &mut self,
        header: Header,
        make: impl FnOnce() -> M,
    ) -> Result<(), RecordError> {
        if header.is_end_of_stream() {
            return Ok(());
        }
        self.file.write(&make(), header.stamp_ns, header.sent_ns)
    }

    /// Writes the last map snapshot if it was held back (the run's final map).
    pub fn write_held_map(&mut self) -> Result<(), RecordError> {
        if let Some((message, stamp_ns, sent_ns)) = self.held_map.take() {
            self.write_map(&message, stamp_ns, sent_ns)?;
        }
        Ok(())
    }
}
