//! Issue 47, point 2: a long run costs memory by the area mapped and the particles, not by
//! its length. A robot standing still in a room for 200,000 scans (a CARMEN log the test
//! writes: one scan repeated, stamps 25 ms apart) keeps the filter and the front end small
//! (map-sink is not held to it yet), and with 1000 particles slam-proc stays within the
//! estimate slam-launch checks at start.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine: the standing robot's scans are cheap.
const LIMIT: Duration = Duration::from_secs(1200);
/// How often the stages' peak memory is read while the run lasts.
const POLL: Duration = Duration::from_millis(200);

/// The range of a beam at `bearing` from (0, 0) in the room x in [-2, 4] m, y in [-2, 2] m.
fn room_range(bearing: f64) -> f64 {
    let (sin, cos) = bearing.sin_cos();
    let walls = [(cos, 4.0), (-cos, 2.0), (sin, 2.0), (-sin, 2.0)];
    walls
        .iter()
        .filter(|(towards, _)| *towards > 1e-9)
        .map(|(towards, distance)| distance / towards)
        .fold(f64::INFINITY, f64::min)
}

/// A CARMEN log of `scans` FLASER lines of a robot standing in [`room_range`]'s room.
fn standing_log(dir: &Path, scans: usize) -> PathBuf {
    let ranges: Vec<String> = (0..180)
        .map(|i| {
            let bearing = (-90.0 + f64::from(i)).to_radians();
            format!("{:.3}", room_range(bearing))
        })
        .collect();
    let ranges = ranges.join(" ");
    let path = dir.join("standing.clf");
    let file = std::fs::File::create(&path).expect("the log");
    let mut log = std::io::BufWriter::new(file);
    for k in 0..scans {
        let stamp = 1000.0 + 0.025 * k as f64;
        writeln!(
            log,
            "FLASER 180 {ranges} 0 0 0 0 0 0 {stamp:.6} h {stamp:.6}"
        )
        .expect("write");
    }
    log.flush().expect("flush the log");
    path
}

/// The peak resident memory (`VmHWM`) of `pid`, bytes; `None` once it has gone.
fn peak_bytes(pid: Pid) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Runs `launcher` to its end, reading its stages' peak memory as it goes: the largest
/// seen of each stage, by name.
fn peaks_until_done(launcher: &mut Child) -> Vec<(String, u64)> {
    let deadline = Instant::now() + LIMIT;
    let mut peaks: Vec<(String, u64)> = Vec::new();
    loop {
        for (pid, name) in children_of(pid_of(launcher)) {
            let Some(bytes) = peak_bytes(pid) else {
                continue;
            };
            match peaks.iter_mut().find(|(n, _)| *n == name) {
                Some((_, peak)) => *peak = (*peak).max(bytes),
                None => peaks.push((name, bytes)),
            }
        }
        if let Some(status) = launcher.try_wait().expect("poll slam-launch") {
            assert!(status.success(), "slam-launch: {status}");
            return peaks;
        }
        if Instant::now() > deadline {
            stop(launcher);
            panic!("the run did not end within {LIMIT:?}");
        }
        std::thread::sleep(POLL);
    }
}

fn run_standing(tag: &str, scans: usize, particles: usize) -> Vec<(String, u64)> {
    let dir = scratch(tag);
    let log = standing_log(&dir, scans);
    let particles = particles.to_string();
    let args = [
        "--replay",
        log.to_str().expect("a UTF-8 path"),
        "--format",
        "carmen",
        "--particles",
        &particles,
    ];
    let mut launcher = spawn_launch(&domain(tag), &dir.join("run"), &args, Stdio::null());
    let peaks = peaks_until_done(&mut launcher);
    let trajectory = read_tum(&dir.join("run").join("trajectory.tum"));
    assert_eq!(trajectory.len(), scans, "a pose for every scan");
    peaks
}

#[test]
fn a_robot_standing_for_200000_scans_keeps_every_process_small() {
    let peaks = run_standing("standing-long", 200_000, 100);
    eprintln!("peak memory by stage, bytes: {peaks:?}");
    assert!(
        peaks.iter().any(|(name, _)| name == "slam-proc"),
        "{peaks:?}"
    );
    // map-sink still holds every scan's estimate and latency until it writes its results.
    for (name, bytes) in peaks.iter().filter(|(name, _)| name != "map-sink") {
        assert!(*bytes < 200 << 20, "{name}: {} MiB", bytes >> 20);
    }
}

#[test]
fn a_thousand_particles_stay_within_the_start_up_estimate() {
    let peaks = run_standing("standing-many", 20_000, 1000);
    let estimate = slam_proc::memory::estimate_bytes(1000);
    eprintln!("peak memory by stage, bytes: {peaks:?}");
    let (_, slam_proc) = peaks
        .iter()
        .find(|(name, _)| name == "slam-proc")
        .expect("slam-proc's memory read");
    assert!(
        *slam_proc <= estimate,
        "slam-proc {} MiB, estimate {} MiB",
        slam_proc >> 20,
        estimate >> 20
    );
}
