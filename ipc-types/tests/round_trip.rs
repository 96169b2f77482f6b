//! Every message survives serde + bincode unchanged: that is how runs are recorded to disk.

use std::borrow::Cow;

use ipc_types::*;

fn encode<T: serde::Serialize + ?Sized>(value: &T) -> Vec<u8> {
    bincode::serde::encode_to_vec(value, bincode::config::standard()).expect("encode")
}

fn decode<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> T {
    let (value, used) =
        bincode::serde::decode_from_slice(bytes, bincode::config::standard()).expect("decode");
    assert_eq!(used, bytes.len(), "trailing bytes");
    value
}

/// Checks that `message` survives encoding: its record decodes and rebuilds it unchanged.
fn assert_rebuilds<M, R>(message: &M, from_record: fn(&R) -> Result<Box<M>, CapacityError>)
where
    M: serde::Serialize + PartialEq + std::fmt::Debug,
    R: serde::de::DeserializeOwned,
{
    let record: R = decode(&encode(message));
    assert_eq!(*from_record(&record).unwrap(), *message);
}

fn header(seq: u64) -> Header {
    let mut header = Header::new(seq, 1_234_567_890_123_456_789, "laser");
    header.sent_ns = 42;
    header
}

fn corner(i: usize) -> Corner {
    let mut covariance = [0.0; 16];
    for (k, c) in covariance.iter_mut().enumerate() {
        *c = (i * 16 + k) as f64 * 1e-4;
    }
    Corner {
        x: i as f64 * 0.5,
        y: -(i as f64),
        heading: 0.1 * i as f64,
        angle: 1.5,
        covariance,
    }
}

fn map_corner(i: usize) -> MapCorner {
    MapCorner {
        corner: corner(i),
        observations: i as u32,
        reserved: 0,
    }
}

fn true_corner(i: usize) -> TrueCorner {
    TrueCorner {
        x: i as f64,
        y: 2.0 * i as f64,
        heading: 0.01 * i as f64,
        angle: 1.57,
    }
}

#[test]
fn laser_scan_round_trips_with_rep117_values() {
    let mut scan = LaserScan::boxed_zeroed();
    scan.header = header(7);
    scan.angle_min = -2.356_194_5;
    scan.angle_increment = 0.004_363_323;
    scan.time_increment = 1.0 / 43_200.0;
    scan.scan_time = 0.025;
    scan.range_min = 0.1;
    scan.range_max = 30.0;
    // A scan re-stamped by its source: its own stamp lies 0.4 s after the header's.
    scan.source_stamp_offset_ns = 400_000_000;
    let ranges: Vec<f32> = (0..1081)
        .map(|i| match i % 97 {
            0 => f32::INFINITY,
            1 => f32::NEG_INFINITY,
            _ => 0.5 + i as f32 * 0.01,
        })
        .collect();
    let intensities: Vec<f32> = (0..1081).map(|i| i as f32).collect();
    scan.set_beams(&ranges, &intensities).unwrap();

    let bytes = encode(&*scan);
    // Only the beams in use are written, not the 8192-beam capacity.
    assert!(bytes.len() < 1081 * 2 * 4 + 200, "{} bytes", bytes.len());
    let record: LaserScanRecord = decode(&bytes);
    let back = LaserScan::from_record(&record).unwrap();
    assert_eq!(*back, *scan);
    assert_eq!(back.header.frame_id(), "laser");
    assert_eq!(back.ranges().len(), 1081);
    assert_eq!(back.source_stamp_ns(), 1_234_567_890_523_456_789);
}

#[test]
fn nan_ranges_survive_bitwise() {
    let mut scan = LaserScan::boxed_zeroed();
    scan.set_beams(&[f32::NAN, 1.0], &[]).unwrap();
    let record: LaserScanRecord = decode(&encode(&*scan));
    let back = LaserScan::from_record(&record).unwrap();
    assert!(back.ranges()[0].is_nan());
    assert_eq!(back.ranges()[1], 1.0);
}

#[test]
fn too_many_beams_is_an_error_not_a_panic() {
    let mut scan = LaserScan::boxed_zeroed();
    let err = scan.set_beams(&vec![1.0; MAX_BEAMS + 1], &[]).unwrap_err();
    assert_eq!(err.capacity, MAX_BEAMS);
    let record = LaserScanRecord {
        header: header(0),
        angle_min: 0.0,
        angle_increment: 0.1,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: 0.0,
        range_max: 1.0,
        robot_from_sensor: Default::default(),
        source_stamp_offset_ns: 0,
        ranges: Cow::Owned(vec![1.0; 3]),
        intensities: Cow::Owned(vec![1.0; 2]),
    };
    assert!(
        LaserScan::from_record(&record).is_err(),
        "mismatched intensities"
    );
}

#[test]
fn a_corrupt_count_cannot_read_past_the_capacity() {
    let mut scan = LaserScan::boxed_zeroed();
    scan.beam_count = u32::MAX;
    assert_eq!(scan.ranges().len(), MAX_BEAMS);
}

#[test]
fn features_round_trip() {
    let mut features = Features::boxed_zeroed();
    features.header = header(3);
    features.scan_sent_ns = 99;
    features.processing_ns = 12_345;
    features.set_odometry(Some(OdometryAtScan {
        pose: Pose2::new(1.5, -2.0, 0.25),
        covariance: [1e-3, 1e-5, 0.0, 1e-5, 2e-3, 0.0, 0.0, 0.0, 1e-4],
    }));
    features.set_motion(Some(ScanMotion {
        pose: Pose2::new(3.0, 4.0, -1.0),
        increment: Pose2::new(0.05, -0.001, 0.01),
        increment_covariance: [1e-6, 0.0, 0.0, 0.0, 4e-6, 0.0, 0.0, 0.0, 1e-7],
        wheel_increment: Pose2::new(0.07, 0.002, 0.012),
        match_status: ScanMotion::MATCH_DEGENERATE,
        odometry_status: ScanMotion::ODOMETRY_REJECTED,
        points: 300,
        inliers: 280,
        has_wheel_increment: 1,
        reserved: 0,
    }));
    let lines: Vec<Line> = (0..5)
        .map(|i| Line {
            rho: i as f64,
            theta: -0.3 * i as f64,
            covariance: [1e-4, 1e-6, 1e-6, 1e-5],
            start: [0.0, i as f64],
            end: [1.0, i as f64],
            point_count: 10 + i,
            reserved: 0,
        })
        .collect();
    let corners: Vec<Corner> = (0..4).map(corner).collect();
    features.set(&lines, &corners).unwrap();
    assert_rebuilds(&*features, Features::from_record);
}

#[test]
fn map_snapshot_round_trips_at_full_capacity() {
    let mut map = MapSnapshot::boxed_zeroed();
    map.header = header(1199);
    let corners: Vec<MapCorner> = (0..MAX_MAP_CORNERS).map(map_corner).collect();
    map.set(&corners).unwrap();
    assert_rebuilds(&*map, MapSnapshot::from_record);
}

#[test]
fn path_chunk_round_trips_at_full_capacity_and_refuses_more() {
    let mut chunk = PathChunk::boxed_zeroed();
    chunk.header = header(2);
    chunk.first = 2 * MAX_PATH_CHUNK_POSES as u64;
    chunk.total = 3 * MAX_PATH_CHUNK_POSES as u64 - 5;
    let poses: Vec<StampedPose> = (0..MAX_PATH_CHUNK_POSES)
        .map(|i| StampedPose {
            stamp_ns: 1_000 + i as u64,
            pose: Pose2::new(i as f64, -0.5 * i as f64, 0.001 * i as f64),
        })
        .collect();
    chunk.set(&poses).unwrap();
    assert_rebuilds(&*chunk, PathChunk::from_record);
    let mut more = poses.clone();
    more.push(poses[0]);
    assert!(chunk.set(&more).is_err());
}

#[test]
fn a_particle_cloud_piece_round_trips_at_full_capacity_and_refuses_more() {
    let mut cloud = ParticleCloud::boxed_zeroed();
    cloud.header = header(40);
    cloud.first = MAX_CLOUD_CHUNK_PARTICLES as u64;
    cloud.total = 2 * MAX_CLOUD_CHUNK_PARTICLES as u64;
    let particles: Vec<Particle> = (0..MAX_CLOUD_CHUNK_PARTICLES)
        .map(|i| Particle {
            pose: Pose2::new(0.25 * i as f64, -(i as f64), 0.002 * i as f64 - 3.0),
            weight: 1.0 / (1 + i) as f64,
        })
        .collect();
    cloud.set(&particles).unwrap();
    assert!(cloud.is_last_piece());
    assert_rebuilds(&*cloud, ParticleCloud::from_record);
    let mut more = particles.clone();
    more.push(particles[0]);
    assert!(cloud.set(&more).is_err());
    assert_eq!(
        cloud.particles(),
        &particles[..],
        "a refused set keeps the cloud"
    );
}

#[test]
fn grid_cells_round_trip_at_full_capacity_and_refuse_more() {
    let mut grid = GridCells::boxed_zeroed();
    grid.header = header(3);
    grid.grid = GridGeometry {
        resolution: 0.05,
        origin: [-12.35, 4.5],
        width: 955,
        height: 595,
    };
    grid.first = 3 * MAX_GRID_CHUNK_CELLS as u64;
    grid.total = 955 * 595;
    let cells: Vec<u8> = (0..MAX_GRID_CHUNK_CELLS)
        .map(|i| [0, 205, 254][i % 3])
        .collect();
    grid.set(&cells).unwrap();
    assert_rebuilds(&*grid, GridCells::from_record);
    assert!(grid.set(&vec![0; MAX_GRID_CHUNK_CELLS + 1]).is_err());
}

#[test]
fn world_corners_round_trip() {
    let mut world = WorldCorners::boxed_zeroed();
    world.header = header(0);
    let corners: Vec<TrueCorner> = (0..100).map(true_corner).collect();
    world.set(&corners).unwrap();
    assert_rebuilds(&*world, WorldCorners::from_record);
}

#[test]
fn small_messages_round_trip() {
    let odometry = Odometry {
        header: header(5),
        pose: Pose2::new(1.0, -2.0, 0.5),
        covariance: [0.01, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 0.001],
        linear_velocity: 0.7,
        angular_velocity: -0.1,
    };
    assert_eq!(decode::<Odometry>(&encode(&odometry)), odometry);

    let truth = GroundTruthPose {
        header: header(6),
        pose: Pose2::new(3.0, 4.0, -3.0),
    };
    assert_eq!(decode::<GroundTruthPose>(&encode(&truth)), truth);

    let estimate = PoseEstimate {
        header: header(8),
        scan_sent_ns: 17,
        best: Pose2::new(1.0, 2.0, 0.1),
        mean: Pose2::new(1.1, 2.1, 0.11),
        dead_reckoning: Pose2::new(0.9, 2.2, 0.2),
        covariance: [1e-3, 0.0, 0.0, 0.0, 1e-3, 0.0, 0.0, 0.0, 1e-4],
        effective_particles: 63.5,
        particle_count: 100,
        map_corners: 42,
        timing: StageTiming {
            motion_ns: 1,
            predict_ns: 2,
            update_ns: 3,
            resample_ns: 4,
            total_ns: 10,
        },
        localization: PoseEstimate::CONVERGED,
        reserved: 0,
        map_beams_judged: 12_000,
        map_beams_explained: 11_500,
    };
    assert_eq!(decode::<PoseEstimate>(&encode(&estimate)), estimate);
}

#[test]
fn frame_ids_are_cut_at_a_character_boundary() {
    let mut header = Header::new(0, 0, "");
    header.set_frame_id(&"é".repeat(20));
    assert_eq!(header.frame_id(), "é".repeat(16));
    assert!(!header.is_end_of_stream());
}
