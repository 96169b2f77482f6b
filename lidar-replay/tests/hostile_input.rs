//! `lidar-replay` against input no log has: a file without newlines (a sparse file), a
//! device (`/dev/zero`), one huge
//! line in the middle of a log, and a stop while reading an endless line. Each replay runs
//! with its heap capped (RLIMIT_DATA), so a reader that held a whole line would fail here
//! instead of filling the machine's memory.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use test_child::{finish, lines_of, stop, wait_for_line};

/// Heap a replay may have. A replay needs a few MiB plus its longest line (1 MiB); a reader
/// that held a 3 MiB line would get near this only with much more, and one that held
/// `/dev/zero` would hit it within a second.
const HEAP_LIMIT: u64 = 256 << 20;
/// Generous for a loaded 2-core machine; a good run takes well under a second.
const LIMIT: Duration = Duration::from_secs(60);

/// A new file `name` in a directory of this test process's own, to write a log into.
fn fixture(name: &str) -> (PathBuf, File) {
    let dir = std::env::temp_dir().join(format!("lidar-replay-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let file = File::create(&path).unwrap();
    (path, file)
}

/// A FLASER line of 180 beams of 2.5 m with the stamp `stamp`.
fn flaser(stamp: f64) -> String {
    let ranges = vec!["2.50"; 180].join(" ");
    format!("FLASER 180 {ranges} 0 0 0 0 0 0 {stamp} robot 0.1\n")
}

/// Fails the test unless `stderr` says each of `expected`.
fn assert_says(stderr: &str, expected: &[&str]) {
    for text in expected {
        assert!(stderr.contains(text), "{text:?} in {stderr}");
    }
}

/// `lidar-replay` of the CARMEN log `file` with `extra` arguments, scans only, for no
/// subscriber, in a domain of its own; its heap capped at [`HEAP_LIMIT`] by prlimit(1),
/// which then runs it as itself (same process, so a signal reaches the replay).
fn spawn_replay(tag: &str, file: &Path, extra: &[&str]) -> Child {
    Command::new("prlimit")
        .arg(format!("--data={HEAP_LIMIT}"))
        .arg("--")
        .arg(env!("CARGO_BIN_EXE_lidar-replay"))
        .args(["--format", "carmen", "--file"])
        .arg(file)
        .args(["--subscribers", "0", "--no-odometry"])
        .args(extra)
        .args([
            "--domain",
            &format!("replay-hostile-{tag}-{}", std::process::id()),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start lidar-replay under prlimit")
}

#[test]
fn a_file_without_newlines_is_refused_at_once() {
    // Ten gigabytes of zeros: a sparse file, so it takes no disk space.
    let (path, file) = fixture("zeros.clf");
    file.set_len(10 << 30).unwrap();
    drop(file);
    let child = spawn_replay("zeros", &path, &[]);
    let output = finish(child, LIMIT);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert_says(
        &stderr,
        &[
            "zeros.clf is not a carmen log: no valid scan in its first 64 MiB",
            "line 1: 67108864 bytes long, over the 1048576 bytes a line may have",
        ],
    );
    std::fs::remove_file(&path).unwrap();
    // A device is no log at all.
    let child = spawn_replay("zero", Path::new("/dev/zero"), &[]);
    let output = finish(child, LIMIT);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "{stderr}");
    assert_says(
        &stderr,
        &["the log /dev/zero is a character device, not a regular file"],
    );
}

#[test]
fn a_huge_line_is_skipped_and_counted_and_the_log_read_on() {
    let (path, mut file) = fixture("huge-line.clf");
    for k in 0..3 {
        file.write_all(flaser(100.0 + f64::from(k)).as_bytes())
            .unwrap();
    }
    // Line 4: 3 MiB of digits and its newline.
    file.write_all(&vec![b'7'; 3 << 20]).unwrap();
    file.write_all(b"\n").unwrap();
    for k in 3..5 {
        file.write_all(flaser(100.0 + f64::from(k)).as_bytes())
            .unwrap();
    }
    drop(file);
    let child = spawn_replay("huge", &path, &[]);
    let output = finish(child, LIMIT);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    let too_long = format!(
        "line 4: {} bytes long, over the 1048576 bytes a line may have (skipped)",
        (3 << 20) + 1
    );
    assert_says(
        &stderr,
        &[
            &too_long,
            "(6 lines read)",
            "published:       5 scans\n",
            "malformed lines: 1 skipped, by reason:\n    line too long: 1",
        ],
    );
}

#[test]
fn sigterm_ends_a_replay_reading_an_endless_line() {
    // Three scans, a malformed line that tells the test the replay is past them, then a line
    // of zeros a terabyte long: a sparse file, so it takes no disk space.
    let (path, mut file) = fixture("endless.clf");
    file.write_all(flaser(100.0).as_bytes()).unwrap();
    file.write_all(flaser(101.0).as_bytes()).unwrap();
    file.write_all(flaser(102.0).as_bytes()).unwrap();
    file.write_all(b"FLASER oops\n").unwrap();
    let length = file.metadata().unwrap().len();
    file.set_len(length + (1 << 40)).unwrap();
    drop(file);
    let mut child = spawn_replay(
        "endless",
        &path,
        &[
            // Nothing held back for reordering but the newest scan: two go out before the
            // endless line.
            "--reorder-window",
            "0",
        ],
    );
    // Read stderr as it comes; the report of line 4 means the endless line is next.
    let lines = lines_of(child.stderr.take().unwrap());
    let mut seen = Vec::new();
    if let Err(e) = wait_for_line(&lines, &mut seen, "line 4: ", LIMIT) {
        let _ = child.kill();
        panic!("no report of line 4: {e}");
    }
    // Reading a terabyte takes minutes: the replay is inside the endless line.
    let stopped = stop(child, LIMIT);
    let output = stopped.output;
    // The child has gone: the rest of its stderr ends with the pipe.
    seen.extend(lines.iter());
    let stderr = seen.join("\n");
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("stopped early:   interrupted after 2 scans"),
        "{stderr}"
    );
    // The reader asks the stop flag every few KiB: the replay ends within milliseconds. The
    // bound leaves room for a loaded machine and stays far below the minutes of reading on.
    assert!(stopped.took < Duration::from_secs(5), "{:?}", stopped.took);
    std::fs::remove_file(&path).unwrap();
}
