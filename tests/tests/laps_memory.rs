//! Issue 45: a robot that keeps driving the same building does not keep growing. The office
//! loop driven three times (`--laps 3`) peaks within 10 % of once, per process, by the
//! peaks slam-launch writes to `memory.json`.

use std::collections::BTreeMap;
use std::path::Path;

use tests::*;

/// How much more a process may peak at after three laps than after one.
const GROWTH: f64 = 0.10;
/// On top of [`GROWTH`], KiB: a process's peak moves by up to 0.8 MiB between identical
/// one-lap runs (slam-proc 12.8 to 13.5 MiB, feature-proc 13.4 to 14.0 MiB: allocator
/// arenas, thread stacks, the iceoryx2 pages touched), which is 10 % of lidar-sim's 7 MiB
/// on its own.
const SLACK_KIB: u64 = 2048;

/// The office loop, `laps` times, as the other office tests run it; its `memory.json`
/// peaks by process, KiB.
fn office(laps: u32) -> (slam_eval::Metrics, BTreeMap<String, u64>) {
    let laps = laps.to_string();
    let args = [
        "--world",
        "office",
        "--seed",
        "1",
        "--particles",
        "100",
        "--laps",
        &laps,
    ];
    let run = launched(&format!("laps-memory-{laps}"), &args);
    (metrics(&run.out), peaks(&run.out))
}

fn peaks(out: &Path) -> BTreeMap<String, u64> {
    let path = out.join("memory.json");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let memory: serde_json::Value = serde_json::from_str(&text).expect("memory.json is JSON");
    memory["peak_resident_kib"]
        .as_object()
        .expect("memory.json has peak_resident_kib")
        .iter()
        .map(|(name, kib)| (name.clone(), kib.as_u64().expect("KiB as a count")))
        .collect()
}

#[test]
fn the_office_driven_three_times_peaks_within_10_percent_of_once_per_process() {
    let (once_metrics, once) = office(1);
    let (thrice_metrics, thrice) = office(3);
    // Three laps are three laps' scans, every one processed.
    let ratio = thrice_metrics.frames_published as f64 / once_metrics.frames_published as f64;
    assert!((2.9..3.0).contains(&ratio), "{ratio} times the scans");
    assert_eq!(thrice_metrics.frames_dropped, 0, "{thrice_metrics:?}");
    let stages = [
        "lidar-sim",
        "feature-proc",
        "slam-proc",
        "graph-proc",
        "map-sink",
        "slam-launch",
    ];
    let mut table = String::new();
    let mut over = Vec::new();
    for name in stages {
        let (Some(&one), Some(&three)) = (once.get(name), thrice.get(name)) else {
            panic!("{name} missing from memory.json: {once:?} {thrice:?}");
        };
        let limit = (one as f64 * (1.0 + GROWTH)) as u64 + SLACK_KIB;
        table.push_str(&format!(
            "\n  {name:<13} {one:>8} KiB once, {three:>8} KiB three laps ({:.2}x)",
            three as f64 / one as f64
        ));
        if three > limit {
            over.push(format!("{name} ({three} KiB > {limit} KiB)"));
        }
    }
    eprintln!("peak resident memory:{table}");
    assert!(
        over.is_empty(),
        "over 10 % + 2 MiB: {}{table}",
        over.join(", ")
    );
}
