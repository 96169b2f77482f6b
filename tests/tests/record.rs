//! `slam-launch --record` (issue 16): a short simulated office run recorded into run.mcap,
//! read back with the mcap crate's reader and checked against the run's own counters
//! (metrics.json) and files (ground_truth.tum, trajectory.tum); and the same run without
//! the recorder gives the same results bit for bit.

use std::collections::BTreeMap;

use tests::*;

const FRAMES: u64 = 200;
/// slam-launch's `PARTICLE_CLOUD_EVERY`: a recorded run's particle cloud every this many
/// scans.
const CLOUD_EVERY: u64 = 40;

/// What one topic of the file holds.
#[derive(Debug, Default)]
struct TopicRead {
    messages: u64,
    first_log_time: Option<u64>,
    last_log_time: u64,
    last: Option<serde_json::Value>,
}

#[test]
fn a_recorded_office_run_reads_back_with_every_topic_and_count() {
    let frames = FRAMES.to_string();
    // With odometry, so that every topic is recorded.
    let args = [
        "--world",
        "office",
        "--frames",
        &frames,
        "--rate",
        "0",
        "--odometry",
    ];
    let out = scratch("record");
    let output = launch(
        &domain("record"),
        &out,
        &[&args[..], &["--record"]].concat(),
    );
    assert_success(&output);
    // The recorder reports its losses like every stage.
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(console.contains("nothing lost (every stage"), "{console}");
    // The recorder is one more subscriber the publishers wait for: the run is the same.
    let plain = scratch("record-plain");
    assert_success(&launch(&domain("record-plain"), &plain, &args));
    for file in ["trajectory.tum", "map_corners.csv", "dead_reckoning.tum"] {
        assert_eq!(
            std::fs::read(out.join(file)).expect("recorded run's file"),
            std::fs::read(plain.join(file)).expect("plain run's file"),
            "{file} differs with --record"
        );
    }
    let _ = std::fs::remove_dir_all(&plain);
    let metrics = metrics(&out);
    let published = metrics.frames_published;
    let processed = metrics.frames_processed;
    let map_corners = metrics.map_corners as u64;
    assert_eq!(published, FRAMES);
    assert_eq!(processed, FRAMES, "lockstep loses nothing");

    let bytes = std::fs::read(out.join("run.mcap")).expect("run.mcap");
    let summary = mcap::Summary::read(&bytes)
        .expect("a readable summary")
        .expect("the file was finished with a summary");

    // Schemas: Foxglove's where they fit, ours otherwise; all JSON schemas.
    let expected: BTreeMap<&str, &str> = [
        ("/lidar/scan", "foxglove.LaserScan"),
        ("/tf", "foxglove.FrameTransform"),
        ("/slam/pose", "foxglove.PoseInFrame"),
        ("/slam/path", "foxglove.PosesInFrame"),
        ("/graph/path", "foxglove.PosesInFrame"),
        ("/graph/grid", "foxglove.Grid"),
        ("/sim/ground_truth", "foxglove.PoseInFrame"),
        ("/perception/features", "slam.Features"),
        ("/slam/map", "slam.MapSnapshot"),
        ("/slam/map_scene", "foxglove.SceneUpdate"),
        ("/perception/scene", "foxglove.SceneUpdate"),
        ("/sim/world_corners", "slam.WorldCorners"),
        ("/robot/odometry", "slam.Odometry"),
        ("/slam/particles", "foxglove.PosesInFrame"),
        ("/map/path", "foxglove.PosesInFrame"),
        ("/map/grid", "foxglove.Grid"),
    ]
    .into_iter()
    .collect();
    let mut channels = BTreeMap::new();
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().expect("every channel has a schema");
        assert_eq!(schema.encoding, "jsonschema", "{}", channel.topic);
        assert_eq!(channel.message_encoding, "json", "{}", channel.topic);
        let text: serde_json::Value =
            serde_json::from_slice(&schema.data).expect("the schema is JSON");
        assert_eq!(text["title"], schema.name.as_str());
        channels.insert(channel.topic.as_str(), schema.name.as_str());
    }
    assert_eq!(channels, expected);

    // Every message, decoded and counted by topic.
    let mut topics: BTreeMap<String, TopicRead> = BTreeMap::new();
    let mut tf_children: BTreeMap<String, u64> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("a readable file") {
        let message = message.expect("every message reads");
        let json: serde_json::Value =
            serde_json::from_slice(&message.data).expect("every message is JSON");
        if message.channel.topic == "/tf" {
            let child = json["child_frame_id"].as_str().unwrap_or("").to_owned();
            *tf_children.entry(child).or_default() += 1;
        }
        let topic = topics.entry(message.channel.topic.clone()).or_default();
        topic.messages += 1;
        topic.first_log_time.get_or_insert(message.log_time);
        assert!(message.log_time >= topic.last_log_time, "in stamp order");
        topic.last_log_time = message.log_time;
        topic.last = Some(json);
    }
    let count = |topic: &str| topics.get(topic).map_or(0, |t| t.messages);
    assert_eq!(count("/lidar/scan"), published);
    assert_eq!(count("/perception/features"), published);
    assert_eq!(count("/sim/ground_truth"), published);
    assert_eq!(count("/slam/pose"), processed);
    assert_eq!(count("/sim/world_corners"), 1);
    assert_eq!(count("/slam/path"), 1);
    // The back end's path and grid as they stand every few seconds of the run, then their
    // final ones.
    assert!(count("/graph/path") >= 1);
    assert!(count("/graph/grid") >= 1);
    assert_eq!(count("/map/path"), 1);
    assert_eq!(count("/map/grid"), 1);
    assert_eq!(count("/slam/particles"), processed / CLOUD_EVERY);
    assert!(count("/robot/odometry") > 0);
    // A map every 20 scans (0.5 s), recorded at most every 4 s of data, and the last.
    let maps = count("/slam/map");
    assert!((2..FRAMES / 20).contains(&maps), "{maps} maps");
    // Each drawn as a scene; the features drawn twice a second of data (every twentieth
    // scan at 40 Hz).
    assert_eq!(count("/slam/map_scene"), maps);
    assert_eq!(count("/perception/scene"), FRAMES.div_ceil(20));
    // map → base_link at every pose, base_link → laser once.
    assert_eq!(tf_children.get("base_link"), Some(&processed));
    assert_eq!(tf_children.get("laser"), Some(&1));
    assert_eq!(count("/tf"), processed + 1);

    // The summary's statistics say the same as the messages.
    let stats = summary.stats.as_ref().expect("statistics");
    let total: u64 = topics.values().map(|t| t.messages).sum();
    assert_eq!(stats.message_count, total);
    for (id, channel) in &summary.channels {
        assert_eq!(
            stats.channel_message_counts.get(id).copied(),
            Some(count(&channel.topic)),
            "{}",
            channel.topic
        );
    }

    // First and last stamps: the scans' are the ground truth's (map-sink's file), and the
    // final path's last pose is the trajectory's last.
    let truth = read_tum(&out.join("ground_truth.tum"));
    let scans = &topics["/lidar/scan"];
    assert_eq!(scans.first_log_time, Some(truth[0].stamp_ns));
    assert_eq!(scans.last_log_time, truth[truth.len() - 1].stamp_ns);
    assert_eq!(stats.message_start_time, scans.first_log_time.unwrap_or(0));
    assert_eq!(stats.message_end_time, scans.last_log_time);
    let poses = &topics["/slam/pose"];
    assert_eq!(poses.first_log_time, scans.first_log_time);
    assert_eq!(poses.last_log_time, scans.last_log_time);

    // trajectory.tum is the back end's path, as recorded.
    let trajectory = read_tum(&out.join("trajectory.tum"));
    let path = topics["/graph/path"].last.as_ref().expect("the path");
    let path_poses = path["poses"].as_array().expect("poses");
    assert_eq!(path_poses.len(), trajectory.len());
    let last = &trajectory[trajectory.len() - 1];
    let last_pose = &path_poses[path_poses.len() - 1]["position"];
    assert!((last_pose["x"].as_f64().unwrap() - last.position[0]).abs() < 1e-5);
    assert!((last_pose["y"].as_f64().unwrap() - last.position[1]).abs() < 1e-5);
    assert_eq!(
        path["stamps_ns"].as_array().map(Vec::len),
        Some(trajectory.len())
    );

    // The last map is the map map-sink wrote, and its scene draws each of its corners.
    let map = topics["/slam/map"].last.as_ref().expect("a map");
    assert_eq!(
        map["corners"].as_array().map(|c| c.len() as u64),
        Some(map_corners)
    );
    let scene = topics["/slam/map_scene"]
        .last
        .as_ref()
        .expect("a map scene");
    assert_eq!(
        scene["entities"].as_array().map(|e| e.len() as u64),
        Some(map_corners)
    );
    assert_eq!(
        topics["/slam/map_scene"].last_log_time,
        topics["/slam/map"].last_log_time
    );
    // A scan holds its beams.
    let scan = scans.last.as_ref().expect("a scan");
    let beams = scan["ranges"].as_array().map_or(0, Vec::len);
    // The simulator gives no intensities: none are written (ROS's rule for LaserScan).
    assert_eq!(scan["intensities"].as_array().map(Vec::len), Some(0));
    assert!(beams > 100, "{beams} beams");
    assert_eq!(scan["frame_id"], "laser");

    let _ = std::fs::remove_dir_all(&out);
}

/// Every message of `topic` in the recording, as JSON, in the file's order.
fn messages_on(bytes: &[u8], topic: &str) -> Vec<serde_json::Value> {
    mcap::MessageStream::new(bytes)
        .expect("a readable file")
        .map(|m| m.expect("every message reads"))
        .filter(|m| m.channel.topic == topic)
        .map(|m| serde_json::from_slice(&m.data).expect("JSON"))
        .collect()
}

/// Standard base64 with padding, as Foxglove's `bytes` travel in JSON.
fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => c - b'A',
        b'a'..=b'z' => c - b'a' + 26,
        b'0'..=b'9' => c - b'0' + 52,
        b'+' => 62,
        b'/' => 63,
        _ => panic!("not base64: {c}"),
    };
    let mut bytes = Vec::new();
    for group in text.as_bytes().chunks(4) {
        let digits: Vec<u8> = group
            .iter()
            .filter(|&&c| c != b'=')
            .map(|&c| value(c))
            .collect();
        let n = digits
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &d)| n | u32::from(d) << (18 - 6 * i));
        bytes.extend_from_slice(&n.to_be_bytes()[1..digits.len()]);
    }
    bytes
}

/// map.pgm's width, height and pixels (rows from the top), read by the Netpbm rules for the
/// header map-sink writes (no comments).
fn read_pgm(bytes: &[u8]) -> (usize, usize, Vec<u8>) {
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        let start = at;
        while !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        fields.push(std::str::from_utf8(&bytes[start..at]).unwrap().to_owned());
        at += 1;
    }
    assert_eq!(fields[0], "P5");
    let width: usize = fields[1].parse().unwrap();
    let height: usize = fields[2].parse().unwrap();
    (width, height, bytes[at..].to_vec())
}

/// map.yaml's value of `key`.
fn yaml_value(yaml: &str, key: &str) -> String {
    yaml.lines()
        .find_map(|l| l.strip_prefix(&format!("{key}: ")))
        .unwrap_or_else(|| panic!("{key} in map.yaml"))
        .to_owned()
}

#[test]
fn a_recording_holds_the_grid_and_final_path_map_sink_wrote_and_the_particle_clouds() {
    let out = scratch("record-grid");
    let frames = FRAMES.to_string();
    let args = [
        "--world", "office", "--frames", &frames, "--rate", "0", "--record",
    ];
    assert_success(&launch(&domain("record-grid"), &out, &args));
    let bytes = std::fs::read(out.join("run.mcap")).expect("run.mcap");

    // The grid: one message, map.pgm's size, geometry and pixels, rows from the lowest y.
    let grids = messages_on(&bytes, "/map/grid");
    assert_eq!(grids.len(), 1);
    let grid = &grids[0];
    let (width, height, pixels) = read_pgm(&std::fs::read(out.join("map.pgm")).unwrap());
    assert_eq!(grid["column_count"], width as u64);
    assert_eq!(grid["row_count"], height as u64);
    assert_eq!(grid["frame_id"], "map");
    let yaml = std::fs::read_to_string(out.join("map.yaml")).unwrap();
    let resolution: f64 = yaml_value(&yaml, "resolution").parse().unwrap();
    assert_eq!(grid["cell_size"]["x"].as_f64(), Some(resolution));
    let origin: Vec<f64> = yaml_value(&yaml, "origin")
        .trim_matches(['[', ']'])
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    assert!((grid["pose"]["position"]["x"].as_f64().unwrap() - origin[0]).abs() < 1e-9);
    assert!((grid["pose"]["position"]["y"].as_f64().unwrap() - origin[1]).abs() < 1e-9);
    let rgba = base64_decode(grid["data"].as_str().unwrap());
    assert_eq!(rgba.len(), 4 * width * height);
    for row in 0..height {
        // The image's first row is the largest y; the grid's first the lowest.
        let image_row = &pixels[(height - 1 - row) * width..][..width];
        let grid_row: Vec<u8> = rgba[row * width * 4..][..width * 4]
            .chunks(4)
            .map(|cell| cell[0])
            .collect();
        assert_eq!(grid_row, image_row, "row {row} from the bottom");
    }

    // map-sink's path is trajectory.tum's, pose for pose (to the last bit or two: this
    // crate's JSON parser may be an ulp off).
    let trajectory = read_tum(&out.join("trajectory.tum"));
    let paths = messages_on(&bytes, "/map/path");
    assert_eq!(paths.len(), 1);
    let stamps = paths[0]["stamps_ns"].as_array().unwrap();
    let planar = paths[0]["planar"].as_array().unwrap();
    assert_eq!(planar.len(), trajectory.len());
    for ((stamp, pose), tum) in stamps.iter().zip(planar).zip(&trajectory) {
        assert_eq!(stamp.as_u64(), Some(tum.stamp_ns));
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-15 * a.abs().max(1.0);
        assert!(
            close(pose["x"].as_f64().unwrap(), tum.position[0]),
            "{pose}"
        );
        assert!(
            close(pose["y"].as_f64().unwrap(), tum.position[1]),
            "{pose}"
        );
        let yaw = pose["yaw"].as_f64().unwrap();
        assert!((yaw - tum.yaw()).abs() < 1e-9, "{yaw} {}", tum.yaw());
    }

    // A particle cloud every CLOUD_EVERY scans, each of every particle.
    let clouds = messages_on(&bytes, "/slam/particles");
    assert_eq!(clouds.len() as u64, FRAMES / CLOUD_EVERY);
    for (k, cloud) in clouds.iter().enumerate() {
        assert_eq!(
            cloud["seq"],
            CLOUD_EVERY * (k as u64 + 1) - 1,
            "the last scan's of each CLOUD_EVERY"
        );
        assert_eq!(cloud["frame_id"], "map");
        assert_eq!(cloud["poses"].as_array().map(Vec::len), Some(100));
        let total: f64 = cloud["weights"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_f64().unwrap())
            .sum();
        assert!((total - 1.0).abs() < 0.01, "weights sum to {total}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A recording holds the back end's grid as it grew, not only its final one: at a sensor's
/// pace (40 scans a second, 7.5 s) the office run outlasts graph-proc's 5 s grid period.
#[test]
fn a_recording_holds_grids_published_while_the_run_went_on() {
    let out = scratch("record-paced");
    let args = [
        "--world", "office", "--frames", "300", "--rate", "40", "--record",
    ];
    assert_success(&launch(&domain("record-paced"), &out, &args));
    let bytes = std::fs::read(out.join("run.mcap")).expect("run.mcap written");
    let log_times = |topic: &str| -> Vec<u64> {
        mcap::MessageStream::new(&bytes)
            .expect("a readable file")
            .map(|m| m.expect("every message reads"))
            .filter(|m| m.channel.topic == topic)
            .map(|m| m.log_time)
            .collect()
    };
    let grids = log_times("/graph/grid");
    let last_scan = log_times("/lidar/scan")
        .last()
        .copied()
        .expect("scans recorded");
    assert!(grids.len() >= 2, "{} grids recorded", grids.len());
    assert!(
        grids[0] < last_scan,
        "the first grid ({}) came before the last scan ({last_scan})",
        grids[0]
    );
    let _ = std::fs::remove_dir_all(&out);
}
