//! The TUM trajectory format: exact stamps, quaternions, round trips, torn last lines.

mod common;

use std::f64::consts::PI;
use std::fs;
use std::io::Write;

use map_sink::{Pose2, TumWriter};
use slam_geom::format_stamp;
use slam_geom::{TumReadError, format_tum_line, read_tum, yaw_quaternion};

#[test]
fn stamp_keeps_every_nanosecond() {
    assert_eq!(
        format_stamp(1_234_567_890_123_456_789),
        "1234567890.123456789"
    );
    assert_eq!(format_stamp(0), "0.000000000");
    assert_eq!(format_stamp(1), "0.000000001");
    assert_eq!(format_stamp(5_000_000_000), "5.000000000");
    assert_eq!(format_stamp(u64::MAX), "18446744073.709551615");
}

#[test]
fn yaw_becomes_a_rotation_about_z() {
    let [qx, qy, qz, qw] = yaw_quaternion(PI / 2.0);
    assert_eq!((qx, qy), (0.0, 0.0));
    assert!((qz - (PI / 4.0).sin()).abs() < 1e-15);
    assert!((qw - (PI / 4.0).cos()).abs() < 1e-15);
    assert_eq!(yaw_quaternion(0.0), [0.0, 0.0, 0.0, 1.0]);
    let [_, _, qz, qw] = yaw_quaternion(-PI);
    assert!((qz + 1.0).abs() < 1e-15 && qw.abs() < 1e-15);
}

#[test]
fn line_is_exact() {
    let line = format_tum_line(1_234_567_890_123_456_789, &Pose2::new(1.5, -2.25, 0.0));
    assert_eq!(line, "1234567890.123456789 1.5 -2.25 0 0 0 0 1\n");
}

#[test]
fn round_trip_through_read_tum() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::scratch_dir("tum-round-trip");
    fs::create_dir_all(&dir)?;
    let path = dir.join("t.tum");
    let poses: Vec<(u64, Pose2)> = (0..50_u64)
        .map(|i| {
            let yaw = -PI + 0.1234567 * i as f64;
            (
                1_700_000_000_000_000_000 + i * 33_333_333,
                Pose2::new(0.1 * i as f64 - 3.0, 1.0 / (i + 1) as f64, yaw),
            )
        })
        .collect();
    let mut writer = TumWriter::create(&path)?;
    for (stamp, pose) in &poses {
        writer.append(*stamp, *pose)?;
    }
    writer.sync()?;
    let read = read_tum(&path)?;
    assert_eq!(read.len(), poses.len());
    for ((_, r), (stamp, pose)) in read.iter().zip(&poses) {
        assert_eq!(r.stamp_ns, *stamp);
        assert_eq!(r.position, [pose.x, pose.y, 0.0]);
        assert!(
            (r.yaw() - pose.yaw).abs() < 1e-12,
            "{} vs {}",
            r.yaw(),
            pose.yaw
        );
    }
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}

#[test]
fn torn_last_line_is_skipped_and_bad_lines_are_named() -> Result<(), Box<dyn std::error::Error>> {
    let dir = common::scratch_dir("tum-torn");
    fs::create_dir_all(&dir)?;
    let path = dir.join("t.tum");
    let mut file = fs::File::create(&path)?;
    file.write_all(format_tum_line(1_000_000_000, &Pose2::new(1.0, 2.0, 0.5)).as_bytes())?;
    file.write_all(format_tum_line(2_000_000_000, &Pose2::new(3.0, 4.0, 0.5)).as_bytes())?;
    // What a power cut in the middle of a write could leave; it even parses as numbers.
    file.write_all(b"3.000000000 5.0 6")?;
    drop(file);
    let poses = read_tum(&path)?;
    assert_eq!(poses.len(), 2);
    assert_eq!(poses[1].1.position, [3.0, 4.0, 0.0]);

    fs::write(
        &path,
        "# comment\n1.0 0 0 0 0 0 0 1\n\n2.0 0 0 zero 0 0 0 1\n",
    )?;
    match read_tum(&path) {
        Err(TumReadError::Malformed { line, problem, .. }) => {
            assert_eq!(line, 4);
            assert!(problem.to_string().contains("zero"), "{problem}");
        }
        other => panic!("expected a malformed-line error, got {other:?}"),
    }
    let _ = fs::remove_dir_all(&dir);
    Ok(())
}
