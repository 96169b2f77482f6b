//! Each recorded message, encoded as the recorder writes it, validated against the schema
//! registered with its channel and, for Foxglove's schemas, against Foxglove's documented
//! definition; and the fields that carry our data decode back to it exactly.

mod foxglove_schemas;

use ipc_types::{
    Corner, Features, GridCells, GridCellsRecord, GridGeometry, GroundTruthPose, Header, LaserScan,
    Line, MapCorner, MapSnapshot, Odometry, Particle, ParticleCloud, PathChunk, Pose2,
    PoseEstimate, ScanMotion, StampedPose, TrueCorner, WorldCorners, Zeroable,
};
use recorder::{
    ChannelMessage, GridMessage, GridPieces, GroundTruthMessage, MapMessage, MapPathMessage,
    ParticlePieces, ParticlesMessage, PathChunks, PathMessage, PoseMessage, ScanMessage,
    TransformMessage,
};
use serde_json::Value;

/// The message as JSON, checked against its registered schema and, when its schema is one
/// of Foxglove's, against Foxglove's.
fn check<M: ChannelMessage>(message: &M) -> Value {
    let json = serde_json::to_value(message).unwrap();
    let registered = M::schema();
    assert_eq!(registered["title"], M::SCHEMA);
    assert_eq!(registered["type"], "object");
    let errors = violations(&registered, &json);
    assert!(
        errors.is_empty(),
        "{} against its own schema: {errors:?}",
        M::TOPIC
    );
    if M::SCHEMA.starts_with("foxglove.") {
        let foxglove = foxglove_schemas::by_name(M::SCHEMA)
            .unwrap_or_else(|| panic!("no Foxglove schema written for {}", M::SCHEMA));
        let errors = violations(&foxglove, &json);
        assert!(
            errors.is_empty(),
            "{} against Foxglove's: {errors:?}",
            M::SCHEMA
        );
        // Every field Foxglove requires is described by the schema we register, with the
        // same type, so a viewer reading our schema sees Foxglove's fields.
        for field in foxglove["required"].as_array().unwrap() {
            let name = field.as_str().unwrap();
            let ours = &registered["properties"][name];
            assert!(
                !ours.is_null(),
                "{}: {name} is not in our schema",
                M::SCHEMA
            );
            assert_eq!(
                ours["type"],
                foxglove["properties"][name]["type"],
                "{}: the type of {name}",
                M::SCHEMA
            );
        }
    } else {
        assert!(M::SCHEMA.starts_with("slam."), "{}", M::SCHEMA);
    }
    json
}

/// What `schema` finds wrong with `json`.
fn violations(schema: &Value, json: &Value) -> Vec<String> {
    jsonschema::validator_for(schema)
        .unwrap()
        .iter_errors(json)
        .map(|e| e.to_string())
        .collect()
}

fn header(seq: u64, stamp_ns: u64, frame: &str) -> Header {
    let mut h = Header::new(seq, stamp_ns, frame);
    h.sent_ns = 1_700_000_000_123_456_789;
    h
}

fn corner(x: f64) -> Corner {
    let mut covariance = [0.0; 16];
    for i in 0..4 {
        covariance[i * 5] = 1e-4 * (i + 1) as f64;
    }
    Corner {
        x,
        y: -x,
        heading: 0.5,
        angle: 1.5,
        covariance,
    }
}

#[test]
fn a_scan_is_a_foxglove_laser_scan_that_loses_nothing() {
    let mut scan = LaserScan::boxed_zeroed();
    scan.header = header(7, 12_500_000_001, "laser");
    scan.angle_min = -2.356_194_5;
    scan.angle_increment = 0.004_363_323;
    scan.time_increment = 2.5e-5;
    scan.scan_time = 0.025;
    scan.range_min = 0.1;
    scan.range_max = 30.0;
    let ranges = [1.25, f32::NAN, f32::INFINITY, 3.5, f32::NEG_INFINITY, 0.05];
    scan.set_beams(&ranges, &[10.0, 0.0, 0.0, 20.0, 0.0, 5.0])
        .unwrap();

    let json = check(&ScanMessage::new(&scan));
    assert_eq!(json["timestamp"]["sec"], 12);
    assert_eq!(json["timestamp"]["nsec"], 500_000_001);
    assert_eq!(json["frame_id"], "laser");
    // Foxglove's ranges are numbers; the non-finite ones are listed by kind.
    let written: Vec<f64> = json["ranges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(written, [1.25, 0.0, 0.0, 3.5, 0.0, 0.05_f32 as f64]);
    assert_eq!(json["nan"], serde_json::json!([1]));
    assert_eq!(json["inf"], serde_json::json!([2]));
    assert_eq!(json["neg_inf"], serde_json::json!([4]));
    // The f32 fields read back to the same f32 bits.
    for (key, value) in [
        ("angle_min", scan.angle_min),
        ("angle_increment", scan.angle_increment),
        ("range_min", scan.range_min),
        ("range_max", scan.range_max),
        ("time_increment", scan.time_increment),
        ("scan_time", scan.scan_time),
    ] {
        assert_eq!(json[key].as_f64().unwrap() as f32, value, "{key}");
    }
    let end = json["end_angle"].as_f64().unwrap();
    let expected = f64::from(scan.angle_min) + 5.0 * f64::from(scan.angle_increment);
    assert!((end - expected).abs() < 1e-12);
    assert_eq!(json["seq"], 7);
    assert_eq!(json["sent_ns"], 1_700_000_000_123_456_789_u64);
}

#[test]
fn a_pose_estimate_is_a_foxglove_pose_in_frame_in_the_map() {
    let mut pose = PoseEstimate::boxed_zeroed();
    pose.header = header(3, 75_000_000, "map");
    pose.mean = Pose2::new(1.0, 2.0, std::f64::consts::FRAC_PI_2);
    pose.best = Pose2::new(1.1, 2.1, 1.5);
    pose.dead_reckoning = Pose2::new(0.9, 1.9, 1.6);
    pose.covariance[0] = 0.01;
    pose.effective_particles = 42.5;
    pose.particle_count = 100;
    pose.map_corners = 12;
    pose.timing.total_ns = 123_456;

    let json = check(&PoseMessage::new(&pose));
    assert_eq!(json["frame_id"], "map");
    assert_eq!(json["pose"]["position"]["x"], 1.0);
    let q = &json["pose"]["orientation"];
    let half = std::f64::consts::FRAC_PI_4;
    assert!((q["z"].as_f64().unwrap() - half.sin()).abs() < 1e-15);
    assert!((q["w"].as_f64().unwrap() - half.cos()).abs() < 1e-15);
    assert_eq!(json["best"]["x"], 1.1);
    assert_eq!(json["dead_reckoning"]["yaw"], 1.6);
    assert_eq!(json["effective_particles"], 42.5);
    assert_eq!(json["timing"]["total_ns"], 123_456);
    // The estimate follows whole, in its serde form.
    assert_eq!(json["header"]["seq"], 3);
    assert_eq!(json["localization"], PoseEstimate::MAPPING);
}

#[test]
fn a_transform_is_a_foxglove_frame_transform() {
    let tf = TransformMessage::planar(5, "map", "base_link", Pose2::new(3.0, -1.0, -0.5));
    let json = check(&tf);
    assert_eq!(json["parent_frame_id"], "map");
    assert_eq!(json["child_frame_id"], "base_link");
    assert_eq!(json["translation"]["y"], -1.0);
    assert!((json["rotation"]["z"].as_f64().unwrap() - (-0.25f64).sin()).abs() < 1e-15);
}

#[test]
fn the_ground_truth_is_a_foxglove_pose_in_the_world_frame() {
    let mut truth = GroundTruthPose::boxed_zeroed();
    truth.header = header(4, 100_000_000, "map");
    truth.pose = Pose2::new(5.0, 6.0, 0.25);
    let json = check(&GroundTruthMessage::new(&truth));
    assert_eq!(json["frame_id"], "world");
    assert_eq!(json["planar"]["yaw"], 0.25);
    assert_eq!(json["seq"], 4);
}

#[test]
fn the_final_path_is_one_foxglove_poses_in_frame_from_its_chunks() {
    let poses: Vec<StampedPose> = (0..5)
        .map(|i| StampedPose {
            stamp_ns: 25_000_000 * i,
            pose: Pose2::new(i as f64, 0.0, 0.1 * i as f64),
        })
        .collect();
    let mut chunks = PathChunks::default();
    let mut whole = None;
    for (first, part) in [(0, &poses[..3]), (3, &poses[3..])] {
        let mut chunk = PathChunk::boxed_zeroed();
        chunk.first = first;
        chunk.total = 5;
        chunk.set(part).unwrap();
        assert!(whole.is_none());
        whole = chunks.add(&chunk);
    }
    let whole = whole.expect("the second chunk completes the path");
    assert_eq!(whole, poses);

    let json = check(&PathMessage::new(&whole));
    assert_eq!(json["frame_id"], "map");
    assert_eq!(json["poses"].as_array().unwrap().len(), 5);
    assert_eq!(json["stamps_ns"][4], 100_000_000);
    assert_eq!(json["timestamp"]["nsec"], 100_000_000);
    assert_eq!(json["planar"][2]["yaw"], 0.2);

    // A chunk out of place is counted and completes nothing.
    let mut chunk = PathChunk::boxed_zeroed();
    chunk.first = 3;
    chunk.total = 5;
    chunk.set(&poses[3..]).unwrap();
    assert!(chunks.add(&chunk).is_none());
    assert_eq!(chunks.out_of_place, 1);
}

#[test]
fn map_sink_s_path_is_a_foxglove_poses_in_frame_on_its_own_topic() {
    let poses = [StampedPose {
        stamp_ns: 7,
        pose: Pose2::new(1.0, 2.0, 0.5),
    }];
    let json = check(&MapPathMessage(PathMessage::new(&poses)));
    assert_eq!(MapPathMessage::TOPIC, "/map/path");
    assert_eq!(
        json,
        serde_json::to_value(PathMessage::new(&poses)).unwrap()
    );
}

/// A cloud of `n` particles at scan `seq`, in pieces of at most `piece` particles.
fn cloud_pieces(seq: u64, n: usize, piece: usize) -> Vec<Box<ParticleCloud>> {
    let particles: Vec<Particle> = (0..n)
        .map(|i| Particle {
            pose: Pose2::new(1.000_4 + i as f64, -2.123_456, 0.600_4),
            weight: 1.0 / n as f64,
        })
        .collect();
    particles
        .chunks(piece)
        .enumerate()
        .map(|(k, part)| {
            let mut message = ParticleCloud::boxed_zeroed();
            message.header = header(seq, 50_000_000 * seq, "map");
            message.first = (k * piece) as u64;
            message.total = n as u64;
            message.set(part).unwrap();
            message
        })
        .collect()
}

#[test]
fn a_particle_cloud_is_a_foxglove_poses_in_frame_rounded_for_display() {
    let mut pieces = ParticlePieces::default();
    let sent = cloud_pieces(40, 3, 2);
    assert!(pieces.add(&sent[0]).is_none());
    let (header, particles) = pieces.add(&sent[1]).expect("the second piece completes it");
    assert_eq!(particles.len(), 3);
    let json = check(&ParticlesMessage::new(&header, &particles));
    assert_eq!(json["frame_id"], "map");
    assert_eq!(json["seq"], 40);
    assert_eq!(json["timestamp"]["sec"], 2);
    assert_eq!(json["poses"].as_array().unwrap().len(), 3);
    // Millimetres, and the quaternion of the yaw at a milliradian to four decimals.
    let first = &json["poses"][0];
    assert_eq!(first["position"]["x"], 1.0);
    assert_eq!(first["position"]["y"], -2.123);
    assert_eq!(first["orientation"]["z"], 0.2955);
    assert_eq!(first["orientation"]["w"], 0.9553);
    assert_eq!(json["weights"][2], 0.333);
    assert_eq!(pieces.incomplete, 0);

    // A cloud whose last piece is lost is left out and counted when the next one starts.
    let next = cloud_pieces(60, 3, 2);
    assert!(pieces.add(&next[0]).is_none());
    let after = cloud_pieces(80, 3, 2);
    assert!(pieces.add(&after[0]).is_none());
    assert_eq!(pieces.incomplete, 1);
    // A piece whose first one was lost completes nothing.
    assert!(pieces.add(&next[1]).is_none());
    assert_eq!(pieces.incomplete, 2);
}

#[test]
fn the_grid_is_a_foxglove_grid_of_rgba_cells_from_its_pieces() {
    // Three columns, two rows from the lowest y: occupied, free, unknown, then free ones.
    let cells = [0u8, 254, 205, 254, 254, 0];
    let mut pieces = GridPieces::default();
    let mut whole = None;
    for (first, part) in [(0, &cells[..4]), (4, &cells[4..])] {
        let mut piece = GridCells::boxed_zeroed();
        piece.header = header(first / 4, 9_000_000_000, "map");
        piece.grid = GridGeometry {
            resolution: 0.05,
            origin: [-1.5, 2.25],
            width: 3,
            height: 2,
        };
        piece.first = first;
        piece.total = 6;
        piece.set(part).unwrap();
        assert!(whole.is_none());
        whole = pieces.add(&piece);
    }
    let (stamp_ns, geometry, got) = whole.expect("the second piece completes the grid");
    assert_eq!(got, cells);
    let json = check(&GridMessage::new(stamp_ns, &geometry, &got));
    assert_eq!(json["frame_id"], "map");
    assert_eq!(json["timestamp"]["sec"], 9);
    assert_eq!(json["pose"]["position"]["x"], -1.5);
    assert_eq!(json["pose"]["position"]["y"], 2.25);
    assert_eq!(json["pose"]["orientation"]["w"], 1.0);
    assert_eq!(json["column_count"], 3);
    assert_eq!(json["row_count"], 2);
    assert_eq!(json["cell_size"]["x"], 0.05);
    assert_eq!(json["cell_stride"], 4);
    assert_eq!(json["row_stride"], 12);
    let names: Vec<&str> = json["fields"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["red", "green", "blue", "alpha"]);
    // The grey of each pixel, opaque where known: the RGBA bytes, base64.
    let rgba: Vec<u8> = cells
        .iter()
        .flat_map(|&p| [p, p, p, if p == 205 { 0 } else { 255 }])
        .collect();
    assert_eq!(json["data"], recorder::base64(&rgba));
    assert_eq!(json["data"].as_str().unwrap().len(), 32);

    // A piece out of place (its grid's start never came) completes nothing and is counted.
    let stray = GridCells::from_record(&GridCellsRecord {
        header: header(1, 9_000_000_000, "map"),
        grid: geometry,
        first: 4,
        total: 6,
        cells: cells[4..].into(),
    })
    .unwrap();
    assert!(pieces.add(&stray).is_none());
    assert_eq!(pieces.out_of_place, 1);
}

#[test]
fn the_validators_refuse_what_foxglove_would_not_read() {
    // The checks above mean something only if a bad message fails them: a null range (what
    // serde_json makes of a NaN), a negative stamp, a missing field.
    let foxglove = jsonschema::validator_for(&foxglove_schemas::laser_scan()).unwrap();
    let mut scan = LaserScan::boxed_zeroed();
    scan.set_beams(&[1.0, 2.0], &[]).unwrap();
    let good = serde_json::to_value(ScanMessage::new(&scan)).unwrap();
    assert!(foxglove.is_valid(&good));
    let registered = jsonschema::validator_for(&ScanMessage::schema()).unwrap();
    assert!(registered.is_valid(&good));
    for (pointer, bad) in [
        ("/ranges/1", Value::Null),
        ("/timestamp/sec", serde_json::json!(-1)),
        ("/timestamp/nsec", serde_json::json!(1_000_000_000)),
    ] {
        let mut message = good.clone();
        *message.pointer_mut(pointer).unwrap() = bad;
        assert!(!foxglove.is_valid(&message), "{pointer}");
        assert!(!registered.is_valid(&message), "{pointer}");
    }
    let mut message = good.clone();
    message.as_object_mut().unwrap().remove("start_angle");
    assert!(!foxglove.is_valid(&message));
    assert!(!registered.is_valid(&message));

    // A grid field of a numeric type Foxglove does not have, a negative stride.
    let grid = jsonschema::validator_for(&foxglove_schemas::grid()).unwrap();
    let geometry = GridGeometry {
        resolution: 0.05,
        origin: [0.0, 0.0],
        width: 1,
        height: 1,
    };
    let good = serde_json::to_value(GridMessage::new(0, &geometry, &[0])).unwrap();
    assert!(grid.is_valid(&good));
    for (pointer, bad) in [
        ("/fields/0/type", serde_json::json!(9)),
        ("/row_stride", serde_json::json!(-4)),
    ] {
        let mut message = good.clone();
        *message.pointer_mut(pointer).unwrap() = bad;
        assert!(!grid.is_valid(&message), "{pointer}");
    }
}

#[test]
fn odometry_features_maps_and_world_corners_are_their_messages_in_serde_form() {
    // The text a recording holds on our own channels, to the byte: the fields in the
    // message's order, the frame as text, no padding, a map corner's observations beside its
    // fields. Tools that read recordings rely on it.
    let zeros = |n: usize| vec!["0.0"; n].join(",");
    let head = |seq: u64, frame: &str| header(seq, 5, frame);
    let head_json = |seq: u64, frame: &str| {
        format!(
            r#"{{"seq":{seq},"stamp_ns":5,"sent_ns":1700000000123456789,"frame_id":"{frame}","flags":0}}"#
        )
    };
    // The text as the file gets it, after the schema checks.
    fn text<M: ChannelMessage>(message: &M) -> String {
        check(message);
        serde_json::to_string(message).unwrap()
    }

    let mut odometry = Odometry::boxed_zeroed();
    odometry.header = head(2, "odom");
    odometry.pose = Pose2::new(0.5, 0.25, 0.125);
    odometry.covariance[8] = 2.0;
    odometry.linear_velocity = 1.5;
    odometry.angular_velocity = -0.5;
    assert_eq!(
        text(&*odometry),
        format!(
            r#"{{"header":{},"pose":{{"x":0.5,"y":0.25,"yaw":0.125}},"covariance":[{},2.0],"linear_velocity":1.5,"angular_velocity":-0.5}}"#,
            head_json(2, "odom"),
            zeros(8)
        )
    );

    let mut features = Features::boxed_zeroed();
    features.header = head(9, "laser");
    features.scan_sent_ns = 3;
    features.processing_ns = 4;
    let line = Line {
        rho: 2.0,
        theta: 0.5,
        covariance: [1.0, 0.0, 0.0, 0.5],
        start: [1.0, 1.0],
        end: [2.0, 0.5],
        point_count: 40,
        reserved: 0,
    };
    let mut corner = corner(1.0);
    corner.covariance = [0.0; 16];
    features.set(&[line], &[corner]).unwrap();
    assert!(text(&features.to_record()).contains(r#""odometry":null,"motion":null,"#));
    features.set_odometry(Some(ipc_types::OdometryAtScan {
        pose: Pose2::new(1.0, 0.0, 0.0),
        covariance: [0.0; 9],
    }));
    features.set_motion(Some(ScanMotion {
        match_status: ScanMotion::MATCH_OK,
        points: 500,
        inliers: 480,
        ..ScanMotion::default()
    }));
    let origin = r#"{"x":0.0,"y":0.0,"yaw":0.0}"#;
    let corner_json = format!(
        r#""x":1.0,"y":-1.0,"heading":0.5,"angle":1.5,"covariance":[{}]"#,
        zeros(16)
    );
    assert_eq!(
        text(&features.to_record()),
        format!(
            r#"{{"header":{},"scan_sent_ns":3,"processing_ns":4,"odometry":{{"pose":{{"x":1.0,"y":0.0,"yaw":0.0}},"covariance":[{}]}},"motion":{{"pose":{origin},"increment":{origin},"increment_covariance":[{}],"match_status":2,"odometry_status":0,"points":500,"inliers":480}},"lines":[{{"rho":2.0,"theta":0.5,"covariance":[1.0,0.0,0.0,0.5],"start":[1.0,1.0],"end":[2.0,0.5],"point_count":40}}],"corners":[{{{corner_json}}}]}}"#,
            head_json(9, "laser"),
            zeros(9),
            zeros(9)
        )
    );

    let mut map = MapSnapshot::boxed_zeroed();
    map.header = head(20, "map");
    map.set(&[MapCorner {
        corner,
        observations: 17,
        reserved: 0,
    }])
    .unwrap();
    assert_eq!(
        text(&MapMessage::new(&map)),
        format!(
            r#"{{"header":{},"corners":[{{{corner_json},"observations":17}}]}}"#,
            head_json(20, "map")
        )
    );

    let mut world = WorldCorners::boxed_zeroed();
    world.header = head(0, "map");
    world
        .set(&[TrueCorner {
            x: 1.0,
            y: 2.0,
            heading: 0.0,
            angle: 1.0,
        }])
        .unwrap();
    assert_eq!(
        text(&world.to_record()),
        format!(
            r#"{{"header":{},"corners":[{{"x":1.0,"y":2.0,"heading":0.0,"angle":1.0}}]}}"#,
            head_json(0, "map")
        )
    );
}
