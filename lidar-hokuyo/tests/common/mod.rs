//! Helpers of the end-to-end tests: the recording, domains, the driver process, and what
//! the driver publishes.

#![allow(dead_code)]

use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use ipc_types::prelude::*;
use lidar_hokuyo::emulator::load_scans;

pub use test_data::seed_hall_csv;

/// The 400 seed-hall scans, 1081 values each, in millimetres, read by the emulator's own
/// reader: the emulator serves these raw codes, and the tests check the driver's REP 117
/// conversion of them (lidar-replay's reader gives ranges, converted by the log's rules).
pub fn seed_hall() -> &'static [Vec<u32>] {
    static SCANS: OnceLock<Vec<Vec<u32>>> = OnceLock::new();
    SCANS.get_or_init(|| {
        let scans = load_scans(&seed_hall_csv()).unwrap();
        assert_eq!(scans.len(), 400);
        assert!(scans.iter().all(|s| s.len() == 1081));
        scans
    })
}

/// A domain no other test or run uses.
pub fn unique_domain(tag: &str) -> Domain {
    let nanos = now_ns() % 1_000_000_000;
    Domain::new(&format!("t-hok-{tag}-{}-{nanos}", std::process::id())).unwrap()
}

/// Starts `lidar-hokuyo` on `addr` in `domain`; stderr is kept for the end.
pub fn spawn_driver(addr: &str, domain: &Domain, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_lidar-hokuyo"))
        .args(["--addr", addr, "--domain", domain.name()])
        .args(extra)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// A received scan, copied out of shared memory.
pub type Received = LaserScanRecord<'static>;

/// Subscribes to the scans once the driver has created the topic; fails if the driver
/// dies first. The second value is the subscribing node: keep it as long as the inlet.
pub fn subscribe(domain: &Domain, child: &mut Child) -> (Inlet<LaserScan>, impl Sized + use<>) {
    let node = domain.node("test").unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Some(inlet) = Inlet::try_open(&node, topic::SCAN).unwrap() {
            return (inlet, node);
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("lidar-hokuyo ended with {status} before creating the scan topic");
        }
        assert!(Instant::now() < deadline, "no scan topic after 30 s");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Receives scans until the end of the stream, or until `until` says enough (then
/// returns without the end), within `limit`.
pub fn receive(
    inlet: &Inlet<LaserScan>,
    limit: Duration,
    until: impl Fn(&[Received]) -> bool,
) -> (Vec<Received>, bool) {
    let deadline = Instant::now() + limit;
    let mut scans = Vec::new();
    loop {
        assert!(
            Instant::now() < deadline,
            "no end of stream after {limit:?} and {} scans",
            scans.len()
        );
        wait_any(&[inlet], Duration::from_millis(20)).unwrap();
        while let Some(sample) = inlet.receive().unwrap() {
            if sample.header.is_end_of_stream() {
                return (scans, true);
            }
            scans.push(sample.to_record().into_owned());
        }
        if until(&scans) {
            return (scans, false);
        }
    }
}

/// What a UTM-30LX value should become, by REP 117 (worked out independently of the
/// crate): a distance from DMIN = 23 mm on, +inf for 1 (no return), -inf for 2 and 4 (too
/// close), NaN for other codes.
pub fn expected_range(mm: u32) -> f32 {
    match mm {
        23.. => mm as f32 / 1000.0,
        1 => f32::INFINITY,
        2 | 4 => f32::NEG_INFINITY,
        _ => f32::NAN,
    }
}

/// Asserts that `ranges` are `values` converted: equal as f32 for distances, the same
/// REP 117 code otherwise.
pub fn assert_ranges(ranges: &[f32], values: &[u32], what: &str) {
    assert_eq!(ranges.len(), values.len(), "{what}: beam count");
    for (beam, (&range, &mm)) in ranges.iter().zip(values).enumerate() {
        let expected = expected_range(mm);
        let same = if expected.is_nan() {
            range.is_nan()
        } else {
            range == expected
        };
        assert!(
            same,
            "{what}, beam {beam}: {range} for {mm} mm, expected {expected}"
        );
    }
}

/// Removes what the domain left in /dev/shm, once every process of it has ended.
pub fn clean_up(domain: &Domain) {
    domain.remove_leftovers().unwrap();
}
