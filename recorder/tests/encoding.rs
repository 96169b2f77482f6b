//! Each recorded message, encoded as the recorder writes it, validated against the schema
//! registered with its channel and, for Foxglove's schemas, against Foxglove's documented
//! definition; and the fields that carry our data decode back to it exactly.

mod foxglove_schemas;

use ipc_types::{
    Corner, Features, GridCells, GridCellsRecord, GridGeometry, GridPieces, GroundTruthPose,
    Header, LaserScan, Line, MapCorner, MapSnapshot, Odometry, Particle, ParticleCloud, PathChunk,
    Pose2, PoseEstimate, ScanMotion, StampedPose, TrueCorner, WorldCorners, Zeroable,
};
use recorder::{
    ARM_LENGTH, ChannelMessage, FEATURES_SCENE_PERIOD_NS, FeaturesScenes, GridMessage,
    GroundTruthMessage, MapMessage, MapPathMessage, MapScenes, ParticlePieces, ParticlesMessage,
    PathChunks, PathMessage, PoseMessage, ScanMessage, TransformMessage, features_scene,
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
    let whole = whole.expect("the second piece completes the grid");
    let (stamp_ns, geometry, got) = (whole.header.stamp_ns, whole.geometry, whole.cells);
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
            r#"{{"header":{},"scan_sent_ns":3,"processing_ns":4,"odometry":{{"pose":{{"x":1.0,"y":0.0,"yaw":0.0}},"covariance":[{}]}},"motion":{{"pose":{origin},"increment":{origin},"increment_covariance":[{}],"wheel_increment":{origin},"match_status":2,"odometry_status":0,"points":500,"inliers":480,"has_wheel_increment":0}},"lines":[{{"rho":2.0,"theta":0.5,"covariance":[1.0,0.0,0.0,0.5],"start":[1.0,1.0],"end":[2.0,0.5],"point_count":40}}],"corners":[{{{corner_json}}}]}}"#,
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

/// A map corner at `tip` whose walls run along `d1` and `d2`, with a position covariance of
/// standard deviations `sigmas` along axes turned by `yaw`.
fn map_corner(tip: (f64, f64), d1: f64, d2: f64, sigmas: (f64, f64), yaw: f64) -> MapCorner {
    let unit = |a: f64| slam_geom::Point2::new(a.cos(), a.sin());
    let truth =
        slam_geom::TrueCorner::from_arms(slam_geom::Point2::new(tip.0, tip.1), unit(d1), unit(d2));
    let (c, s) = (yaw.cos(), yaw.sin());
    let (major, minor) = (sigmas.0 * sigmas.0, sigmas.1 * sigmas.1);
    let mut covariance = [0.0; 16];
    covariance[0] = c * c * major + s * s * minor;
    covariance[1] = c * s * (major - minor);
    covariance[4] = covariance[1];
    covariance[5] = s * s * major + c * c * minor;
    covariance[10] = 1e-4;
    covariance[15] = 1e-4;
    MapCorner {
        corner: Corner {
            x: truth.x,
            y: truth.y,
            heading: truth.heading,
            angle: truth.angle,
            covariance,
        },
        observations: 5,
        reserved: 0,
    }
}

fn map_of(seq: u64, stamp_ns: u64, corners: &[MapCorner]) -> MapMessage {
    let mut map = MapSnapshot::boxed_zeroed();
    map.header = header(seq, stamp_ns, "map");
    map.set(corners).unwrap();
    MapMessage::new(&map)
}

/// `[x, y]` of a JSON `Vector3` on the z = 0 plane.
fn xy(point: &Value) -> [f64; 2] {
    assert_eq!(point["z"], 0.0);
    [point["x"].as_f64().unwrap(), point["y"].as_f64().unwrap()]
}

fn near(a: [f64; 2], b: [f64; 2], tolerance: f64) -> bool {
    (a[0] - b[0]).hypot(a[1] - b[1]) <= tolerance
}

#[test]
fn a_map_is_a_foxglove_scene_update_of_one_entity_per_corner() {
    let turn = 0.5;
    let corners = [
        // Walls along +x and +y from (1, 2): a room's corner, position known to 2 cm by 1 cm
        // along axes turned by 0.5 rad.
        map_corner(
            (1.0, 2.0),
            0.0,
            std::f64::consts::FRAC_PI_2,
            (0.02, 0.01),
            turn,
        ),
        map_corner((-3.0, 0.5), 2.0, 3.5, (0.004, 0.004), 0.0),
        map_corner((4.0, -1.0), -1.0, 1.0, (0.01, 0.005), -1.0),
    ];
    let mut scenes = MapScenes::default();
    let json = check(&scenes.scene(&map_of(20, 4_000_000_001, &corners)));
    assert_eq!(json["deletions"], serde_json::json!([]));
    let entities = json["entities"].as_array().unwrap();
    assert_eq!(entities.len(), 3);
    for (index, entity) in entities.iter().enumerate() {
        assert_eq!(entity["id"], format!("corner {index}"));
        assert_eq!(entity["frame_id"], "map");
        assert_eq!(entity["timestamp"]["sec"], 4);
        assert_eq!(entity["timestamp"]["nsec"], 1);
        // Shown until a later snapshot replaces or deletes it, where the map had it.
        assert_eq!(entity["lifetime"], serde_json::json!({"sec": 0, "nsec": 0}));
        assert_eq!(entity["frame_locked"], false);
        // The arms: from the end of one wall's arm through the tip to the other's.
        let corner = corners[index].corner;
        let strip = &entity["lines"][0];
        assert_eq!(strip["type"], 0, "a line strip");
        let points: Vec<[f64; 2]> = strip["points"].as_array().unwrap().iter().map(xy).collect();
        assert_eq!(points.len(), 3);
        assert!(near(points[1], [corner.x, corner.y], 1e-3), "{points:?}");
        for end in [points[0], points[2]] {
            let length = (end[0] - corner.x).hypot(end[1] - corner.y);
            assert!((length - ARM_LENGTH).abs() < 2e-3, "{length}");
        }
    }
    // The first corner's walls run along +x and +y: its arms end there.
    let strip = &entities[0]["lines"][0]["points"];
    let ends = [xy(&strip[0]), xy(&strip[2])];
    let along_x = [1.0 + ARM_LENGTH, 2.0];
    let along_y = [1.0, 2.0 + ARM_LENGTH];
    assert!(
        (near(ends[0], along_x, 1e-3) && near(ends[1], along_y, 1e-3))
            || (near(ends[0], along_y, 1e-3) && near(ends[1], along_x, 1e-3)),
        "{ends:?}"
    );
    // Its ellipse: 2 sigma each way (8 cm by 4 cm across), the long axis turned by 0.5 rad,
    // flat, see-through.
    let sphere = &entities[0]["spheres"][0];
    assert_eq!(sphere["size"]["x"], 0.08);
    assert_eq!(sphere["size"]["y"], 0.04);
    assert!(sphere["size"]["z"].as_f64().unwrap() < 0.01);
    let q = &sphere["pose"]["orientation"];
    assert!((q["z"].as_f64().unwrap() - (0.5 * turn).sin()).abs() < 1e-4);
    assert!((q["w"].as_f64().unwrap() - (0.5 * turn).cos()).abs() < 1e-4);
    assert_eq!(xy(&sphere["pose"]["position"]), [1.0, 2.0]);
    assert!(sphere["color"]["a"].as_f64().unwrap() < 1.0);

    // The next snapshot has one corner: the two shown before and gone are deleted, as of
    // the new snapshot's stamp (Foxglove deletes only what is older).
    let json = check(&scenes.scene(&map_of(21, 6_000_000_000, &corners[..1])));
    assert_eq!(json["entities"].as_array().unwrap().len(), 1);
    assert_eq!(
        json["deletions"],
        serde_json::json!([
            {"timestamp": {"sec": 6, "nsec": 0}, "type": 0, "id": "corner 1"},
            {"timestamp": {"sec": 6, "nsec": 0}, "type": 0, "id": "corner 2"}
        ])
    );
    // A corner that is not finite is not drawn and what was shown in its place goes; the
    // scene stays valid JSON for Foxglove (no nulls).
    let mut broken = corners[..2].to_vec();
    broken[0].corner.x = f64::NAN;
    let json = check(&scenes.scene(&map_of(22, 8_000_000_000, &broken)));
    let ids: Vec<&Value> = json["entities"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| &e["id"])
        .collect();
    assert_eq!(ids, ["corner 1"]);
    assert_eq!(json["deletions"][0]["id"], "corner 0");
    assert_eq!(json["deletions"].as_array().unwrap().len(), 1);
}

fn features_of(stamp_ns: u64) -> Box<Features> {
    let mut features = Features::boxed_zeroed();
    features.header = header(9, stamp_ns, "laser");
    let line = |start: [f64; 2], end: [f64; 2]| Line {
        rho: 0.0,
        theta: 0.0,
        covariance: [1e-4, 0.0, 0.0, 1e-4],
        start,
        end,
        point_count: 30,
        reserved: 0,
    };
    let lines = [
        line([2.000_4, -1.234_56], [2.0, 1.0]),
        line([2.0, 1.0], [-0.5, 1.0]),
        line([f64::NAN, 0.0], [1.0, 1.0]),
    ];
    let corner = map_corner(
        (2.0, 1.0),
        -std::f64::consts::FRAC_PI_2,
        std::f64::consts::PI,
        (0.03, 0.01),
        0.2,
    )
    .corner;
    let mut hidden = corner;
    hidden.angle = f64::INFINITY;
    features.set(&lines, &[corner, hidden]).unwrap();
    features
}

#[test]
fn a_scans_features_are_a_foxglove_scene_update_in_the_scans_frame() {
    let json = check(&features_scene(&features_of(12_500_000_000)));
    assert_eq!(json["deletions"], serde_json::json!([]));
    let entities = json["entities"].as_array().unwrap();
    let ids: Vec<&Value> = entities.iter().map(|e| &e["id"]).collect();
    assert_eq!(ids, ["lines", "corners"]);
    for entity in entities {
        // Drawn where the sensor was at the scan, and kept there.
        assert_eq!(entity["frame_id"], "laser");
        assert_eq!(entity["frame_locked"], false);
        assert_eq!(entity["timestamp"]["sec"], 12);
        assert_eq!(entity["timestamp"]["nsec"], 500_000_000);
    }
    // The lines as segments between their ends, to the millimetre; the one that is not
    // finite is left out.
    let segments = &entities[0]["lines"][0];
    assert_eq!(segments["type"], 2, "a line list");
    let points: Vec<[f64; 2]> = segments["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(xy)
        .collect();
    assert_eq!(points, [[2.0, -1.235], [2.0, 1.0], [2.0, 1.0], [-0.5, 1.0]]);
    // The finite corner: its arms as two segments from the tip, and its ellipse.
    let corners = &entities[1];
    let arms: Vec<[f64; 2]> = corners["lines"][0]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(xy)
        .collect();
    assert_eq!(arms.len(), 4);
    assert_eq!(arms[1], [2.0, 1.0]);
    assert_eq!(arms[2], [2.0, 1.0]);
    let spheres = corners["spheres"].as_array().unwrap();
    assert_eq!(spheres.len(), 1);
    assert_eq!(spheres[0]["size"]["x"], 0.12);
    assert_eq!(spheres[0]["size"]["y"], 0.04);
}

#[test]
fn features_are_drawn_at_most_once_a_period() {
    // A second of 40 Hz scans: one scene per period, from the first scan on.
    let mut scenes = FeaturesScenes::default();
    let drawn: Vec<u64> = (0..40)
        .map(|i| 25_000_000 * i)
        .filter(|&stamp| scenes.scene(&features_of(stamp)).is_some())
        .collect();
    let expected: Vec<u64> = (0..1_000_000_000)
        .step_by(FEATURES_SCENE_PERIOD_NS as usize)
        .collect();
    assert_eq!(drawn, expected);
}

#[test]
fn foxglove_refuses_a_scene_it_would_not_read() {
    // The scene checks mean something only if Foxglove's published schema refuses a bad
    // scene: a deletion of an unknown kind, a primitive kind left out, a null coordinate.
    let foxglove = jsonschema::validator_for(&foxglove_schemas::scene_update()).unwrap();
    let map = map_of(1, 5, &[map_corner((1.0, 1.0), 0.0, 1.0, (0.01, 0.01), 0.0)]);
    let mut scenes = MapScenes::default();
    scenes.scene(&map);
    let good = serde_json::to_value(scenes.scene(&map_of(2, 6, &[]))).unwrap();
    assert!(foxglove.is_valid(&good));
    let mut bad = good.clone();
    *bad.pointer_mut("/deletions/0/type").unwrap() = serde_json::json!(2);
    assert!(!foxglove.is_valid(&bad));
    let good = serde_json::to_value(scenes.scene(&map)).unwrap();
    assert!(foxglove.is_valid(&good));
    let mut bad = good.clone();
    bad.pointer_mut("/entities/0")
        .unwrap()
        .as_object_mut()
        .unwrap()
        .remove("models");
    assert!(!foxglove.is_valid(&bad));
    let mut bad = good.clone();
    *bad.pointer_mut("/entities/0/lines/0/points/1/x").unwrap() = Value::Null;
    assert!(!foxglove.is_valid(&bad));
}
