//! Compile-time checks of the message layouts: the contract between processes built
//! separately. A change here is a change of the wire format and needs a new type-name version.

use core::mem::{align_of, offset_of, size_of};

use crate::header::Header;
use crate::messages::*;

const _: () = {
    assert!(size_of::<Header>() == 64 && align_of::<Header>() == 8);
    assert!(offset_of!(Header, frame_id) == 24 && offset_of!(Header, flags) == 56);
    assert!(size_of::<Pose2>() == 24);
    assert!(size_of::<Corner>() == 160);
    assert!(size_of::<TrueCorner>() == 32);
    assert!(size_of::<MapCorner>() == 168);
    assert!(size_of::<Line>() == 88);
    assert!(size_of::<StageTiming>() == 40);

    assert!(size_of::<LaserScan>() == 64 + 64 + 2 * 4 * crate::MAX_BEAMS);
    assert!(align_of::<LaserScan>() == 8);
    assert!(offset_of!(LaserScan, robot_from_sensor) == 88);
    assert!(offset_of!(LaserScan, source_stamp_offset_ns) == 112);
    assert!(offset_of!(LaserScan, beam_count) == 120);
    assert!(offset_of!(LaserScan, ranges) == 128);

    assert!(size_of::<Odometry>() == 176);
    assert!(size_of::<GroundTruthPose>() == 88);
    assert!(size_of::<PoseEstimate>() == 296);
    assert!(offset_of!(PoseEstimate, map_beams_judged) == 280);
    assert!(offset_of!(PoseEstimate, timing) == 232);
    assert!(offset_of!(PoseEstimate, localization) == 272);

    assert!(size_of::<ScanMotion>() == 168);
    assert!(offset_of!(ScanMotion, wheel_increment) == 120);
    assert!(offset_of!(ScanMotion, has_wheel_increment) == 160);
    assert!(offset_of!(Features, odometry) == 88);
    assert!(offset_of!(Features, motion) == 192);
    assert!(offset_of!(Features, lines) == 360);
    assert!(
        size_of::<Features>() == 360 + 88 * crate::MAX_LINES + 160 * crate::MAX_FEATURE_CORNERS
    );
    assert!(size_of::<WorldCorners>() == 72 + 32 * crate::MAX_WORLD_CORNERS);
    assert!(size_of::<MapSnapshot>() == 72 + 168 * crate::MAX_MAP_CORNERS);
    assert!(size_of::<StampedPose>() == 32);
    // A bounded array is its count, 4 reserved bytes, then its items: the count at the
    // offset below, the items 8 bytes after it.
    assert!(size_of::<BoundedArray<StampedPose, 1>>() == 8 + 32);
    assert!(offset_of!(WorldCorners, corners) == 64);
    assert!(offset_of!(MapSnapshot, corners) == 64);
    assert!(offset_of!(PathChunk, poses) == 80);
    assert!(size_of::<PathChunk>() == 88 + 32 * crate::MAX_PATH_CHUNK_POSES);
    assert!(size_of::<Particle>() == 32);
    assert!(offset_of!(ParticleCloud, particles) == 80);
    assert!(size_of::<ParticleCloud>() == 88 + 32 * crate::MAX_CLOUD_CHUNK_PARTICLES);
    assert!(size_of::<GridGeometry>() == 32);
    assert!(offset_of!(GridCells, grid) == 64);
    assert!(offset_of!(GridCells, first) == 96);
    assert!(offset_of!(GridCells, cells) == 112);
    assert!(size_of::<GridCells>() == 120 + crate::MAX_GRID_CHUNK_CELLS);
};
