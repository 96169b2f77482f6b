//! The bag reader over small bags written here with the MCAP library: topics chosen,
//! odometry from `/tf` paired with the scans, the mount from `/tf_static`, messages out of
//! order, of another type and of other topics.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use slam_geom::Pose2;

use super::decode::{Decoded, Plan};
use super::messages::tests::{laser_scan, odometry, tf_message};
use super::storage::{Channel, RawMessage};
use super::topics::choose;
use super::*;
use crate::error::ReadError;
use crate::lines::never;
use crate::record::LogRecord;

const S: u64 = 1_000_000_000;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("lidar-replay-rosbag-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An MCAP file of ROS 2 messages: (topic, type, bag time, CDR) each, in file order.
fn write_mcap(path: &Path, messages: &[(&str, &str, u64, Vec<u8>)]) {
    let file = std::fs::File::create(path).unwrap();
    let mut writer = mcap::Writer::new(std::io::BufWriter::new(file)).unwrap();
    let mut channels: BTreeMap<(String, String), u16> = BTreeMap::new();
    for (sequence, (topic, type_name, time, data)) in messages.iter().enumerate() {
        let key = (topic.to_string(), type_name.to_string());
        let channel = match channels.get(&key) {
            Some(id) => *id,
            None => {
                let schema = writer.add_schema(type_name, "ros2msg", b"").unwrap();
                let id = writer
                    .add_channel(schema, topic, "cdr", &BTreeMap::new())
                    .unwrap();
                channels.insert(key, id);
                id
            }
        };
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: sequence as u32,
            log_time: *time,
            publish_time: *time,
        };
        writer.write_to_known_channel(&header, data).unwrap();
    }
    writer.finish().unwrap();
}

fn stamp(ns: u64) -> (i32, u32) {
    ((ns / S) as i32, (ns % S) as u32)
}

fn scan_at(ns: u64) -> Vec<u8> {
    laser_scan(true, stamp(ns), "laser", &[1.0, 2.0, 3.0], &[])
}

fn tf_at(ns: u64, x: f64) -> Vec<u8> {
    tf_message(&[
        (stamp(ns), "odom", "base_link", x, 0.0, 0.0),
        // Another transform of the tree, not the odometry.
        (stamp(ns), "base_link", "wheel", 0.0, 0.1, 0.0),
    ])
}

/// A bag: the mount, odometry on /tf every 0.1 s from 1 s, scans at 1.05, 1.15 (written
/// after 1.25) and 1.25 s, a String on /scan and a camera image.
fn small_bag(path: &Path) {
    let ms = |n: u64| n * 1_000_000;
    write_mcap(
        path,
        &[
            (
                TF_STATIC_TOPIC,
                TF_MESSAGE,
                ms(1000),
                tf_message(&[(stamp(ms(1000)), "base_link", "laser", 0.1, 0.0, 0.0)]),
            ),
            (TF_TOPIC, TF_MESSAGE, ms(1000), tf_at(ms(1000), 1.0)),
            ("/scan", LASER_SCAN, ms(1050), scan_at(ms(1050))),
            (TF_TOPIC, TF_MESSAGE, ms(1100), tf_at(ms(1100), 1.1)),
            (
                "/camera",
                "sensor_msgs/msg/Image",
                ms(1110),
                vec![0, 1, 0, 0],
            ),
            (
                "/scan",
                "std_msgs/msg/String",
                ms(1120),
                vec![0, 1, 0, 0, 2, 0, 0, 0, b'x', 0],
            ),
            (TF_TOPIC, TF_MESSAGE, ms(1200), tf_at(ms(1200), 1.2)),
            ("/scan", LASER_SCAN, ms(1250), scan_at(ms(1250))),
            ("/scan", LASER_SCAN, ms(1260), scan_at(ms(1150))),
            (TF_TOPIC, TF_MESSAGE, ms(1300), tf_at(ms(1300), 1.3)),
        ],
    );
}

#[test]
fn a_bare_mcap_replays_its_scans_with_odometry_from_tf_in_stamp_order() {
    let dir = scratch("tf");
    let path = dir.join("small.mcap");
    small_bag(&path);
    assert_eq!(is_ros2_mcap(&path), Some(true));
    assert_eq!(
        crate::LogFormat::detect(&path),
        Some(crate::LogFormat::Rosbag)
    );

    let (reader, info) = open_bag_until(&path, &BagOptions::default(), never).unwrap();
    assert_eq!(info.scan_topic, "/scan");
    assert_eq!(info.scan_frame, "laser");
    assert_eq!(info.odometry, Some(OdometryStream::Tf));
    let Mount::Found {
        robot_from_sensor, ..
    } = info.mount
    else {
        panic!("no mount: {:?}", info.mount);
    };
    assert!((robot_from_sensor.x - 0.1).abs() < 1e-12);

    let mut reader = reader;
    let mut records = Vec::new();
    let mut problems = Vec::new();
    for next in reader.by_ref() {
        match next {
            Ok(record) => records.push(record),
            Err(ReadError::Line(e)) => problems.push(e.category()),
            Err(e) => panic!("{e}"),
        }
    }
    assert_eq!(problems, ["/scan: message of another type"]);
    let stamps: Vec<(char, u64)> = records
        .iter()
        .map(|record| match record {
            LogRecord::Odometry(o) => ('o', o.stamp_ns / 1_000_000),
            LogRecord::Scan(s) => ('s', s.stamp_ns / 1_000_000),
        })
        .collect();
    assert_eq!(
        stamps,
        [
            ('o', 1050),
            ('s', 1050),
            ('o', 1150),
            ('s', 1150),
            ('o', 1250),
            ('s', 1250)
        ]
    );
    for record in &records {
        match record {
            // The pose between the /tf readings around the scan.
            LogRecord::Odometry(o) => {
                assert!((o.x - o.stamp_ns as f64 * 1e-9).abs() < 1e-9, "{o:?}")
            }
            LogRecord::Scan(s) => {
                assert_eq!(s.robot_from_sensor, robot_from_sensor);
                assert_eq!(s.ranges, [1.0, 2.0, 3.0]);
            }
        }
    }
    let LogRecord::Scan(second) = &records[3] else {
        unreachable!()
    };
    // The message's own geometry.
    assert_eq!(second.geometry.scan_time, f64::from(0.025_f32));
    assert_eq!(second.geometry.range_min, f64::from(0.1_f32));
    let (_, counts) = reader.reordering();
    assert_eq!(counts.reordered.scans, 1);
    assert_eq!(
        reader.passed_over().iter().collect::<Vec<_>>(),
        [
            (&"/camera".to_owned(), &1),
            (&TF_STATIC_TOPIC.to_owned(), &1)
        ]
    );
    assert_eq!(reader.messages_read(), 10);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bag_cut_short_is_refused_before_its_first_scan_and_replayed_up_to_the_cut_after() {
    let dir = scratch("cut");
    let path = dir.join("small.mcap");
    small_bag(&path);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..40]).unwrap();
    let error = check_bag(&path, &BagOptions::default()).unwrap_err();
    assert!(
        matches!(error, BagError::Damaged { .. } | BagError::NoScan { .. }),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

fn topic(name: &str, type_name: &str) -> Topic {
    Topic {
        name: name.into(),
        type_name: type_name.into(),
        messages: None,
    }
}

#[test]
fn topics_are_chosen_or_the_refusal_lists_them() {
    let topics = [
        topic("/scan", LASER_SCAN),
        topic("/odom", ODOMETRY),
        topic(TF_TOPIC, TF_MESSAGE),
        topic("/rear/scan", LASER_SCAN),
    ];
    let options = BagOptions::default();
    assert_eq!(
        choose(&topics, &options).unwrap_err(),
        "the bag has 2 sensor_msgs/msg/LaserScan topics (/scan, /rear/scan): choose one with \
         --scan-topic"
    );
    let front = BagOptions {
        scan_topic: Some("/scan".into()),
        ..BagOptions::default()
    };
    assert_eq!(
        choose(&topics, &front).unwrap(),
        ("/scan".into(), Some(OdometryStream::Topic("/odom".into())))
    );
    let from_tf = BagOptions {
        odometry: OdometryFrom::Tf,
        ..front.clone()
    };
    assert_eq!(
        choose(&topics, &from_tf).unwrap().1,
        Some(OdometryStream::Tf)
    );
    // An Odometry topic named for odometry read from /tf is a contradiction, not a hint.
    let both = BagOptions {
        odometry_topic: Some("/odom".into()),
        ..from_tf.clone()
    };
    assert_eq!(
        choose(&topics, &both).unwrap_err(),
        "--odom-topic /odom names a nav_msgs/msg/Odometry topic, but --odom-source tf reads \
         the odometry from /tf: give one or the other"
    );
    let wrong = BagOptions {
        scan_topic: Some("/odom".into()),
        ..BagOptions::default()
    };
    assert!(
        choose(&topics, &wrong)
            .unwrap_err()
            .starts_with("/odom (--scan-topic) is nav_msgs/msg/Odometry, not sensor_msgs/msg/LaserScan; the bag's topics: /scan (sensor_msgs/msg/LaserScan), ")
    );
    // Without an Odometry topic or /tf there is no odometry, unless one is asked for.
    let scans_only = [topic("/scan", LASER_SCAN)];
    assert_eq!(choose(&scans_only, &options).unwrap().1, None);
    let odom = BagOptions {
        odometry: OdometryFrom::Odom,
        ..BagOptions::default()
    };
    assert_eq!(
        choose(&scans_only, &odom).unwrap_err(),
        "--odom-source odom: the bag has no nav_msgs/msg/Odometry topic; its topics: /scan \
         (sensor_msgs/msg/LaserScan)"
    );
    assert!(
        choose(&[], &options)
            .unwrap_err()
            .contains("its topics: none")
    );
}

#[test]
fn odometry_of_another_frame_is_counted_and_skipped() {
    let plan = Plan {
        scan_topic: "/scan".into(),
        odometry: Some(OdometryStream::Topic("/odom".into())),
        base_frame: "base_link".into(),
        odom_frame: "odom".into(),
        mount: Pose2::IDENTITY,
    };
    let message = |child: &str| RawMessage {
        channel: std::sync::Arc::new(Channel {
            topic: "/odom".into(),
            type_name: ODOMETRY.into(),
            encoding: "cdr".into(),
        }),
        log_time_ns: 7,
        data: odometry(true, (0, 0), "odom", child, (1.0, 2.0, 0.5), 0.0, 0.0, 0.0),
    };
    let Ok(Decoded::Odometry(record)) = plan.decode(3, &message("base_link")) else {
        panic!("base_link's odometry not decoded");
    };
    // A header never stamped: the bag's time.
    assert_eq!(record.stamp_ns, 7);
    assert_eq!((record.x, record.y), (1.0, 2.0));
    let Err(error) = plan.decode(4, &message("base_footprint")) else {
        panic!("another frame's odometry decoded");
    };
    assert_eq!(error.category(), "/odom: odometry of another frame");

    // Odometry on /tf never stamped: the bag's time too.
    let from_tf = Plan {
        odometry: Some(OdometryStream::Tf),
        ..plan
    };
    let tf = RawMessage {
        channel: std::sync::Arc::new(Channel {
            topic: TF_TOPIC.into(),
            type_name: TF_MESSAGE.into(),
            encoding: "cdr".into(),
        }),
        log_time_ns: 9,
        data: tf_at(0, 1.5),
    };
    let Ok(Decoded::Tf(records)) = from_tf.decode(5, &tf) else {
        panic!("/tf not decoded");
    };
    assert_eq!(
        records
            .iter()
            .map(|r| (r.stamp_ns, r.x))
            .collect::<Vec<_>>(),
        [(9, 1.5)]
    );
}

#[test]
fn a_bag_directory_names_what_it_lacks() {
    let dir = scratch("dir");
    let error = check_bag(&dir, &BagOptions::default()).unwrap_err();
    assert!(matches!(error, BagError::NoMetadata { .. }), "{error}");
    std::fs::write(
        dir.join(METADATA_FILE),
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: \
         [bag_0.mcap]\n  topics_with_message_count: []\n",
    )
    .unwrap();
    let error = check_bag(&dir, &BagOptions::default()).unwrap_err();
    assert_eq!(
        error.to_string(),
        format!(
            "{} names {}, which is missing",
            dir.join(METADATA_FILE).display(),
            dir.join("bag_0.mcap").display()
        )
    );
    small_bag(&dir.join("bag_0.mcap"));
    // The metadata says which topics there are: none, so no scan topic.
    let error = check_bag(&dir, &BagOptions::default()).unwrap_err();
    assert!(
        error.to_string().ends_with(
            "the bag has no sensor_msgs/msg/LaserScan topic to replay; its topics: none"
        ),
        "{error}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
