//! # recorder
//!
//! Records a run of the pipeline as MCAP (`run.mcap`) that Foxglove opens ready to look at:
//! every topic's messages as JSON, under Foxglove's well-known schemas where one fits
//! (`foxglove.LaserScan`, `foxglove.FrameTransform`, `foxglove.PoseInFrame`,
//! `foxglove.PosesInFrame`, `foxglove.Grid`, and `foxglove.SceneUpdate` for the map's corners
//! and a scan's features drawn in the 3D panel) and under schemas of our own (`slam.*`) where none does. A
//! message of a Foxglove schema carries Foxglove's fields and, after them, whatever of ours
//! they lack, so a scan or a pose can be rebuilt exactly from the file. Our fields are the
//! pipeline's own types in their serde form (`ipc_types`, `slam_geom::ScanGeometry`), with
//! the JSON schemas those types derive, so each field is defined once, where the message is.
//!
//! The file is written as the run goes, in zstd-compressed chunks of about 1 MB that reach
//! the disk as each is closed (at least once a second), so a recorder that dies leaves a file
//! readable up to its last complete chunk. `slam-record` is the process; this library holds
//! the encoding and the file, without shared memory.
//!
//! A recording replays ([`open_recording`], [`RecordingReader`]): the scans and odometry are
//! rebuilt from their records exactly as they were published ([`ReplayedChannel::decode`],
//! the inverse of their encoders).
//!
//! Why JSON with JSON schemas: it is MCAP's and Foxglove's simplest well-supported pairing
//! (no code generation, no descriptor sets), every field is readable in Foxglove's raw
//! message panel, and zstd takes most of its size back.

mod corner_glyph;
mod decode;
mod error;
mod features_scene;
mod geometry;
mod grid;
mod ground_truth;
mod map_scene;
mod mcap_file;
mod output;
mod own;
mod particles;
mod path;
mod pose;
mod pose_in_frame;
mod reader;
mod recording;
mod scan;
mod scene;
mod schema;
mod stamp;
mod transform;

pub use corner_glyph::{ARM_LENGTH, ELLIPSE_SIGMAS};
pub use decode::{DecodeError, Recorded, ReplayedChannel};
pub use error::RecordError;
pub use features_scene::{
    CORNERS_ENTITY, FEATURES_SCENE_PERIOD_NS, FeaturesScene, FeaturesSceneTopic, FeaturesScenes,
    LINES_ENTITY, features_scene,
};
pub use geometry::{Pose, Quaternion, Vector3};
pub use grid::{GraphGridMessage, GridMessage, PackedElementField, Vector2, base64};
pub use ground_truth::{GroundTruthMessage, WORLD_FRAME};
pub use map_scene::{MapScene, MapSceneTopic, MapScenes, corner_entity_id};
pub use mcap_file::{CHUNK_BYTES, ChannelCount, FLUSH_PERIOD, McapFile};
pub use output::Output;
pub use own::MapMessage;
pub use particles::{ParticlePieces, ParticlesMessage};
pub use path::{GraphPathMessage, MapPathMessage, PathChunks, PathMessage};
pub use pose::{MAP_FRAME, PoseMessage};
pub use pose_in_frame::PoseInFrame;
pub use reader::{
    ODOMETRY_LOOKAHEAD, OpenRecordingError, RECORD_LENGTH_LIMIT, RECORDING_INPUT, ReadError,
    RecordingInfo, RecordingReader, SNIFF_MESSAGES, open_recording,
};
pub use recording::{MAP_PERIOD_NS, RECORDING_FILE, Recording, RecordingSummary};
pub use scan::{FiniteRanges, ScanMessage};
pub use scene::{
    Color, DELETE_MATCHING_ID, Duration, LINE_LIST, LINE_STRIP, LinePrimitive, OTHER_PRIMITIVES,
    OtherPrimitives, Placement, Scene, SceneEntity, SceneEntityDeletion, SceneTopic, SceneUpdate,
    SpherePrimitive,
};
pub use schema::{ChannelMessage, MESSAGE_ENCODING, SCHEMA_ENCODING, schema_of};
pub use stamp::Time;
pub use transform::{BASE_FRAME, TransformMessage};
