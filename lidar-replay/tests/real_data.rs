//! The shared real recordings read completely and correctly.

use lidar_replay::{
    LogFormat, LogRecord, OdometryRecord, Records, ReorderConfig, ReorderCounts, ScanRecord,
    open_log,
};

/// What a log yields: scans, odometry, the stamps of every record in order and the
/// reordering window's counts (zero for seed-csv).
struct Read {
    scans: Vec<ScanRecord>,
    odometry: Vec<OdometryRecord>,
    records: Vec<LogRecord>,
    reordering: ReorderCounts,
}

/// Every record of a log; any malformed line fails the test with its message.
fn read_all(format: LogFormat, relative: &str) -> (Vec<ScanRecord>, Vec<OdometryRecord>, Vec<u64>) {
    let read = read_log(format, relative);
    let stamps = read.scans.iter().map(|s| s.stamp_ns).collect();
    (read.scans, read.odometry, stamps)
}

fn read_log(format: LogFormat, relative: &str) -> Read {
    let path = test_data::recording(relative);
    let mut log =
        open_log(format, &path, ReorderConfig::default()).unwrap_or_else(|e| panic!("{e}"));
    let mut read = Read {
        scans: Vec::new(),
        odometry: Vec::new(),
        records: Vec::new(),
        reordering: ReorderCounts::default(),
    };
    for record in log.by_ref() {
        let record = record.unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        match &record {
            LogRecord::Scan(scan) => read.scans.push(scan.clone()),
            LogRecord::Odometry(pose) => read.odometry.push(*pose),
        }
        read.records.push(record);
    }
    read.reordering = log
        .reordering()
        .map(|(_, counts)| counts)
        .unwrap_or_default();
    read
}

fn assert_strictly_increasing(stamps: &[u64]) {
    assert!(
        stamps.windows(2).all(|w| w[1] > w[0]),
        "scan stamps must strictly increase"
    );
}

/// The readings of all `scans` for which `which` holds.
fn count_ranges(scans: &[ScanRecord], which: impl Fn(f32) -> bool) -> usize {
    scans
        .iter()
        .flat_map(|s| &s.ranges)
        .filter(|&&r| which(r))
        .count()
}

#[test]
fn seed_hall_is_400_scans_of_1081_beams() {
    let (scans, odometry, stamps) = read_all(LogFormat::SeedCsv, "seed-hall/scans.csv");
    assert_eq!(scans.len(), 400);
    assert!(odometry.is_empty());
    assert!(scans.iter().all(|s| s.ranges.len() == 1081));
    assert_strictly_increasing(&stamps);
    assert_eq!(stamps[0], 0);
    assert_eq!(stamps[399], 39_900_000_000, "nominal 0.1 s period");
    let readings = 400 * 1081;
    let no_return = count_ranges(&scans, |r| r == f32::INFINITY);
    let errors = count_ranges(&scans, f32::is_nan);
    // FORMAT.md: code 1 on about 9.5 % of the readings, code 19 on 22.
    assert_eq!(errors, 22);
    let share = no_return as f64 / readings as f64;
    assert!((0.09..0.10).contains(&share), "no-return share {share}");
    let longest = scans
        .iter()
        .flat_map(|s| &s.ranges)
        .filter(|r| r.is_finite())
        .fold(0.0_f32, |a, &b| a.max(b));
    assert_eq!(longest, 36.881, "every real return is kept");
}

#[test]
fn mit_csail_is_1988_scans_of_361_beams_with_odometry() {
    let (scans, odometry, stamps) = read_all(LogFormat::Carmen, "carmen/mit-csail.clf");
    assert_eq!(scans.len(), 1988);
    assert_eq!(odometry.len(), 1988, "one odometry pose per FLASER line");
    assert!(scans.iter().all(|s| s.ranges.len() == 361));
    assert_strictly_increasing(&stamps);
    assert_eq!(stamps[0], 1_134_864_629_895_182_000, "first stamp, exact");
    assert_eq!(stamps[1987], 1_134_865_053_892_206_000, "last stamp, exact");
    assert!(
        scans
            .iter()
            .zip(&odometry)
            .all(|(s, o)| s.stamp_ns == o.stamp_ns && s.line == o.line)
    );
    let first = &odometry[0];
    assert_eq!(
        (first.x, first.y, first.yaw),
        (576.536523, 0.106594, -2.255213)
    );
    // About 3 % of the readings are the 81.91 m "no return".
    let readings = 1988 * 361;
    let no_return = count_ranges(&scans, |r| r == f32::INFINITY);
    let share = no_return as f64 / readings as f64;
    assert!((0.02..0.05).contains(&share), "no-return share {share}");
    assert!(scans.iter().flat_map(|s| &s.ranges).all(|r| !r.is_nan()));
}

#[test]
fn aces_comes_out_in_time_order_with_its_odom_lines_as_odometry() {
    let read = read_log(LogFormat::Carmen, "carmen/aces.clf");
    assert_eq!(read.scans.len(), 7374, "no scan lost");
    assert!(read.scans.iter().all(|s| s.ranges.len() == 180));
    let scan_stamps: Vec<u64> = read.scans.iter().map(|s| s.stamp_ns).collect();
    assert_strictly_increasing(&scan_stamps);
    let odometry_stamps: Vec<u64> = read.odometry.iter().map(|o| o.stamp_ns).collect();
    assert!(
        odometry_stamps.windows(2).all(|w| w[1] > w[0]),
        "odometry stamps must strictly increase"
    );
    assert!(
        read.records
            .windows(2)
            .all(|w| w[1].stamp_ns() >= w[0].stamp_ns()),
        "records in time order"
    );
    // The log starts with an ODOM line, so its odometry comes from the 7375 ODOM lines
    // alone (each FLASER carries a stale copy of the last one), one of them written twice.
    // 157 scans and 4 ODOM lines were written up to 0.108 s after later ones.
    assert!(read.odometry[0].stamp_ns < scan_stamps[0]);
    assert_eq!(
        read.reordering,
        ReorderCounts {
            reordered: Records {
                scans: 157,
                odometry: 4
            },
            duplicate: Records {
                scans: 0,
                odometry: 1
            },
            ..ReorderCounts::default()
        }
    );
    assert_eq!(read.odometry.len(), 7375 - 1);
    // 50.00 m is ACES's "no return".
    let no_return = read
        .scans
        .iter()
        .flat_map(|s| &s.ranges)
        .filter(|r| **r == f32::INFINITY)
        .count();
    assert_eq!(no_return, 11_139);
    assert!(
        read.scans
            .iter()
            .flat_map(|s| &s.ranges)
            .all(|r| !r.is_finite() || *r < 50.0)
    );
}
