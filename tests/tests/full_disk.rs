//! Issue 14, row 12: the disk fills in the middle of a run. Every file of the run must
//! still end with a whole line and parse: the trajectory files stop at their last whole
//! line (and say so), whole-file results that do not fit are left out (no half file, no
//! temporary file), the logs stop at a whole line, and the run goes on to its end, which
//! lists what is incomplete.
//!
//! A small disk is a tmpfs over the output directory in a private mount namespace
//! (`unshare -rm`); where the machine allows none, the test says so and passes.

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(300);
/// Room for the start of the run (configuration, logs) and a fraction of the trajectory
/// files of the scans below: they fill it mid-run (measured: about a third of the way).
const SMALL_DISK: &str = "size=64k";
const FRAMES: &str = "400";

/// Every problem of a file of the run: not ending in a newline, or not parsing.
fn problems_of(dir: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    for entry in std::fs::read_dir(dir).expect("output directory") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            problems.extend(problems_of(&path));
            continue;
        }
        let name = path.display().to_string();
        let bytes = std::fs::read(&path).expect("read a file of the run");
        if name.ends_with(".tmp") {
            problems.push(format!("{name}: a temporary file left behind"));
            continue;
        }
        // The binary map files are written whole or not at all (write-then-rename).
        if name.ends_with(".png") || name.ends_with(".pgm") {
            continue;
        }
        if bytes.is_empty() {
            // A stream created but never written to: nothing half there.
            continue;
        }
        if bytes.last() != Some(&b'\n') {
            problems.push(format!("{name}: ends in part of a line"));
            continue;
        }
        let text = String::from_utf8_lossy(&bytes);
        let parsed = if name.ends_with(".tum") {
            slam_geom::parse_tum(&text)
                .map(|_| ())
                .map_err(|e| e.to_string())
        } else if name.ends_with(".json") {
            serde_json::from_str::<serde_json::Value>(&text)
                .map(|_| ())
                .map_err(|e| e.to_string())
        } else if name.ends_with(".csv") {
            let widths: Vec<usize> = text.lines().map(|l| l.split(',').count()).collect();
            if widths.windows(2).all(|w| w[0] == w[1]) {
                Ok(())
            } else {
                Err("rows of different widths".to_owned())
            }
        } else {
            Ok(())
        };
        if let Err(e) = parsed {
            problems.push(format!("{name}: {e}"));
        }
    }
    problems
}

#[test]
fn a_disk_that_fills_mid_run_leaves_whole_files_and_says_what_is_missing() {
    let probe = Command::new("unshare")
        .args(["-rm", "sh", "-c", "mount -t tmpfs tmpfs /mnt"])
        .output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!("skipped: no private mount namespace here (unshare -rm): no small disk");
        return;
    }
    let scratch = scratch("full-disk");
    let disk = scratch.join("disk");
    let kept = scratch.join("kept");
    std::fs::create_dir_all(&disk).expect("mount point");
    // The tmpfs goes with the namespace: what the run wrote is copied out before.
    let script = format!(
        "mount -t tmpfs -o {SMALL_DISK} tmpfs \"$1\" || exit 99; shift; \
         \"$@\"; status=$?; cp -a \"{}\"/. \"{}\"/ || exit 98; exit $status",
        disk.display(),
        kept.display()
    );
    std::fs::create_dir_all(&kept).expect("kept");
    let mut command = Command::new("unshare");
    command
        .args(["-rm", "sh", "-c", &script, "sh"])
        .arg(&disk)
        .arg(bin("slam-launch"))
        .args(["--quiet", "--domain", &domain("full-disk"), "--out"])
        .arg(&disk)
        .args(["--world", "office", "--frames", FRAMES]);
    let output = output_within(&mut command, LIMIT).expect("slam-launch ended in time");
    let console = String::from_utf8_lossy(&output.stderr);
    assert!(
        !matches!(output.status.code(), Some(98 | 99)),
        "mount or copy failed: {console}"
    );

    // Nothing half written, whatever did not fit.
    let problems = problems_of(&kept);
    assert!(problems.is_empty(), "{problems:#?}\n{console}");
    // A trajectory file stopped mid-run, at a whole line, and said why as it happened.
    let stopped = [
        "trajectory_online.tum",
        "dead_reckoning.tum",
        "ground_truth.tum",
    ]
    .iter()
    .find(|name| console.contains(&format!("map-sink: {name}: stopped after ")))
    .unwrap_or_else(|| panic!("no trajectory file reported stopped:\n{console}"));
    assert!(console.contains("No space left on device"), "{console}");
    let lines = lines_in(&kept.join(stopped));
    assert!(
        lines > 0 && lines < FRAMES.parse().expect("frames"),
        "{stopped} has {lines} lines: not stopped mid-run"
    );
    // The run went on to its end: map-sink took every pose, then listed what is missing
    // in its closing summary, and the run fails.
    assert!(
        console.contains(&format!("map-sink: {FRAMES} poses")),
        "{console}"
    );
    assert!(
        console.contains("map-sink: summary: ")
            && console.contains(" of the run's files incomplete"),
        "{console}"
    );
    assert_eq!(output.status.code(), Some(1), "{console}");
    assert!(shm_leftovers(&domain("full-disk")).is_empty());
}
