//! The driver binary against the emulated sensor over TCP on 127.0.0.1, publishing into a
//! test domain: handshake, continuous data, time stamps across the counter's wrap, damaged
//! scans, dropped connections, a clean stop, windows, clusters and intensities.

mod common;

use std::collections::BTreeSet;
use std::f64::consts::TAU;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

use common::*;
use lidar_hokuyo::emulator::{Emulator, EmulatorConfig, EmulatorStats, Faults, intensity_of};
use lidar_hokuyo::scip::{DataKind, Ranging};
use lidar_hokuyo::{Connect, Sensor, TcpConnector};
use test_child::{finish, terminate};

const LIMIT: Duration = Duration::from_secs(60);

fn emulator(configure: impl FnOnce(&mut EmulatorConfig)) -> Emulator {
    let mut config = EmulatorConfig::utm_30lx(seed_hall().to_vec());
    configure(&mut config);
    Emulator::start(config, "127.0.0.1:0").unwrap()
}

fn stderr_of(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn assert_contiguous(scans: &[Received]) {
    let seqs: Vec<u64> = scans.iter().map(|s| s.header.seq).collect();
    assert_eq!(seqs, (0..scans.len() as u64).collect::<Vec<_>>());
}

#[test]
fn streams_the_recording_with_the_sensors_geometry_and_stamps() {
    // The sensor's counter wraps 1.8 s after the emulator starts: during the 2 s of the
    // stream unless the driver takes longer than 1.7 s to start.
    let emulator = emulator(|c| c.clock_start_ms = (1 << 24) - 1800);
    let domain = unique_domain("stream");
    let mut child = spawn_driver(&emulator.addr().to_string(), &domain, &["--frames", "80"]);
    let (inlet, node) = subscribe(&domain, &mut child);
    let (scans, ended) = receive(&inlet, LIMIT, |_| false);
    let output = finish(child, LIMIT);
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert!(ended);
    assert!(stderr_of(&output).contains("published 80 scans"));

    assert_eq!(scans.len(), 80);
    assert_contiguous(&scans);
    for (i, scan) in scans.iter().enumerate() {
        assert_ranges(&scan.ranges, &seed_hall()[i], &format!("scan {i}"));
        assert!(scan.intensities.iter().all(|&v| v == 0.0));
        assert_eq!(scan.header.frame_id(), "laser");
        // PP: AMIN 0, AMAX 1080, AFRT 540, ARES 1440, DMIN 23, DMAX 60000, SCAN 2400.
        assert_eq!(scan.angle_min, (-540.0 * TAU / 1440.0) as f32);
        assert_eq!(scan.angle_increment, (TAU / 1440.0) as f32);
        assert_eq!(scan.scan_time, 0.025);
        assert_eq!(scan.time_increment, (0.025 / 1440.0) as f32);
        assert_eq!((scan.range_min, scan.range_max), (0.023, 60.0));
    }

    let stats = emulator.stop();
    assert_eq!(stats.connections, 1);
    // Stamps: the host time of each scan's counter value, across the wrap, within the
    // round trip of the time exchange and the counter's millisecond.
    let sent = &stats.sent[..80];
    assert!(
        sent.first().unwrap().counter_ms > sent.last().unwrap().counter_ms,
        "no wrap"
    );
    for (scan, sent) in scans.iter().zip(sent) {
        let error_ms = (scan.header.stamp_ns as f64 - sent.stamp_ns as f64) / 1e6;
        assert!(
            error_ms.abs() < 5.0,
            "scan {}: stamp off by {error_ms} ms",
            scan.header.seq
        );
    }
    // At least a revolution apart (more if the emulator stalled under load).
    for pair in scans.windows(2) {
        let step_ms = (pair[1].header.stamp_ns as f64 - pair[0].header.stamp_ns as f64) / 1e6;
        assert!(step_ms > 23.5, "stamps {step_ms} ms apart");
    }
    // The handshake, the time synchronisation, the ranging command and the final QT.
    let commands = &stats.commands;
    let tm1 = commands.iter().filter(|c| *c == "TM1").count();
    assert_eq!(tm1, 10);
    assert_eq!(commands[..5], ["QT", "VV", "PP", "II", "TM0"]);
    assert_eq!(commands[15..17], ["TM2", "MD0000108001000"]);
    assert_eq!(commands.last().map(String::as_str), Some("QT"));
    drop((inlet, node));
    clean_up(&domain);
}

/// Runs the driver for 30 scans against an emulator with the faults `inject` sets, in a
/// domain named after `tag`, and checks that all 30 came, in order and without gaps.
/// Returns them, the driver's stderr and the emulator's account.
fn thirty_scans_with(
    tag: &str,
    inject: impl FnOnce(&mut Faults),
) -> (Vec<Received>, String, EmulatorStats) {
    let emulator = emulator(|c| inject(&mut c.faults));
    let domain = unique_domain(tag);
    let mut child = spawn_driver(&emulator.addr().to_string(), &domain, &["--frames", "30"]);
    let (inlet, node) = subscribe(&domain, &mut child);
    let (scans, _) = receive(&inlet, LIMIT, |_| false);
    let output = finish(child, LIMIT);
    let log = stderr_of(&output);
    assert!(output.status.success(), "{log}");
    assert_eq!(scans.len(), 30);
    assert_contiguous(&scans);
    let stats = emulator.stop();
    drop((inlet, node));
    clean_up(&domain);
    (scans, log, stats)
}

#[test]
fn a_damaged_scan_is_dropped_and_the_stream_goes_on() {
    let (scans, log, stats) = thirty_scans_with("damaged", |f| f.corrupt = BTreeSet::from([5]));
    assert!(
        log.contains("dropped 1 damaged scans, 1 connections"),
        "{log}"
    );
    assert!(log.contains("checksum"), "{log}");
    let rows: Vec<usize> = (0..5).chain(6..31).collect();
    for (scan, &row) in scans.iter().zip(&rows) {
        assert_ranges(&scan.ranges, &seed_hall()[row], &format!("row {row}"));
    }
    assert_eq!(stats.connections, 1);
    assert!(stats.sent[5].corrupted);
}

#[test]
fn a_connection_dropped_mid_scan_resumes_without_gaps() {
    let (scans, log, stats) = thirty_scans_with("dropped", |f| f.drop = BTreeSet::from([7]));
    assert!(log.contains("reconnecting in 100ms"), "{log}");
    assert!(
        log.contains("dropped 0 damaged scans, 2 connections"),
        "{log}"
    );

    for (row, scan) in scans.iter().enumerate() {
        assert_ranges(&scan.ranges, &seed_hall()[row], &format!("row {row}"));
    }
    // The second connection synchronised the clock again: stamps still increase.
    assert!(
        scans
            .windows(2)
            .all(|p| p[1].header.stamp_ns > p[0].header.stamp_ns)
    );
    assert_eq!((stats.connections, stats.dropped_connections), (2, 1));
}

#[test]
fn sigterm_sends_qt_and_exits_cleanly() {
    let emulator = emulator(|c| c.looping = true);
    let domain = unique_domain("sigterm");
    let mut child = spawn_driver(&emulator.addr().to_string(), &domain, &[]);
    let (inlet, node) = subscribe(&domain, &mut child);
    let (mut scans, ended) = receive(&inlet, LIMIT, |scans| scans.len() >= 10);
    assert!(!ended);
    terminate(&child);
    // The driver ends the stream on its way out.
    let (rest, ended) = receive(&inlet, LIMIT, |_| false);
    assert!(ended);
    scans.extend(rest);
    let output = finish(child, LIMIT);
    let log = stderr_of(&output);
    assert_eq!(output.status.code(), Some(0), "{log}");
    assert!(log.contains("stopped: published"), "{log}");
    assert_contiguous(&scans);

    let stats = emulator.stop();
    assert_eq!(stats.commands.last().map(String::as_str), Some("QT"));
    assert_eq!(stats.quits, 2, "one at the handshake, one at the stop");
    drop((inlet, node));
    clean_up(&domain);
}

#[test]
fn a_window_with_clusters_and_intensities() {
    let emulator = emulator(|_| {});
    let domain = unique_domain("window");
    let args = [
        "--frames",
        "10",
        "--intensities",
        "--min-angle",
        "-1.0",
        "--max-angle",
        "1.0",
        "--cluster",
        "3",
        "--frame-id",
        "front_laser",
    ];
    let mut child = spawn_driver(&emulator.addr().to_string(), &domain, &args);
    let (inlet, node) = subscribe(&domain, &mut child);
    let (scans, _) = receive(&inlet, LIMIT, |_| false);
    let output = finish(child, LIMIT);
    assert!(output.status.success(), "{}", stderr_of(&output));
    assert_eq!(scans.len(), 10);

    // 1 rad = 229.18 steps of 2 pi / 1440 around the front step 540: steps 311 to 769,
    // 459 steps in 153 clusters of 3.
    let step = TAU / 1440.0;
    for (row, scan) in scans.iter().enumerate() {
        let values: Vec<u32> = seed_hall()[row][311..=769]
            .chunks(3)
            .map(|group| {
                let valid = group.iter().copied().filter(|&v| v >= 23).min();
                valid.unwrap_or_else(|| *group.iter().min().unwrap())
            })
            .collect();
        assert_ranges(&scan.ranges, &values, &format!("row {row}"));
        let intensities: Vec<f32> = values.iter().map(|&v| intensity_of(v, 23) as f32).collect();
        assert_eq!(scan.intensities, intensities);
        assert_eq!(scan.header.frame_id(), "front_laser");
        // The first beam sits at the middle step of its cluster, 312.
        assert_eq!(scan.angle_min, ((312.0 - 540.0) * step) as f32);
        assert_eq!(scan.angle_increment, (3.0 * step) as f32);
        assert_eq!(scan.time_increment, (3.0 * 0.025 / 1440.0) as f32);
    }
    let stats = emulator.stop();
    assert!(stats.commands.contains(&"ME0311076903000".to_owned()));
    // The sensor stamps step 0; the first beam passes 312 steps later.
    let delay_ns = 312.0 * 0.025 / 1440.0 * 1e9;
    for (scan, sent) in scans.iter().zip(&stats.sent) {
        let error_ms = (scan.header.stamp_ns as f64 - sent.stamp_ns as f64 - delay_ns) / 1e6;
        assert!(error_ms.abs() < 5.0, "stamp off by {error_ms} ms");
    }
    drop((inlet, node));
    clean_up(&domain);
}

#[test]
fn the_emulator_binary_serves_a_sensor_client() {
    let mut emulator = Command::new(env!("CARGO_BIN_EXE_hokuyo-emulator"))
        .args(["--port", "0", "--rpm", "6000", "--file"])
        .arg(seed_hall_csv())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(emulator.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .trim()
        .strip_prefix("listening on ")
        .unwrap_or_else(|| panic!("unexpected first line {line:?}"))
        .to_owned();

    let mut connector = TcpConnector::new(&addr, Duration::from_secs(2), Duration::from_millis(50));
    let mut sensor = Sensor::new(connector.connect().unwrap(), Duration::from_secs(2));
    let identity = sensor.connect().unwrap();
    assert_eq!(identity.params.scan_rpm, 6000);
    assert_eq!(identity.params.afrt, 540);
    assert!(identity.version.get("PROD").unwrap().contains("UTM-30LX"));
    sensor.sync_clock(3, &ipc_types::now_ns).unwrap();
    let ranging = Ranging::new(DataKind::Ranges3, 0, 1080, 1, 0, 0).unwrap();
    sensor.start_ranging(ranging).unwrap();
    for row in 0..3 {
        assert_eq!(sensor.next_scan().unwrap().ranges, seed_hall()[row]);
    }
    sensor.quit(Duration::from_secs(2)).unwrap();
    drop(sensor);

    terminate(&emulator);
    let output = finish(emulator, LIMIT);
    let log = stderr_of(&output);
    assert!(output.status.success(), "{log}");
    // A scan or two more may have gone out before the QT arrived.
    assert!(log.contains("stopped: sent"), "{log}");
    assert!(log.contains("scans to 1 connections"), "{log}");
}
