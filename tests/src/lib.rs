//! Helpers for the end-to-end tests: find the release binaries, run `slam-launch`, read what
//! a run wrote.
//!
//! The binaries must have been built first (`cargo build --release --workspace`, as the
//! README's test command does); the helpers say so instead of running stale ones silently.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Directory of the workspace's release binaries (`target/release`).
pub fn bin_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    // target/<profile>/deps/<test> -> target/<profile>
    let profile_dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("target/<profile> directory")
        .to_path_buf();
    let release = profile_dir
        .parent()
        .map(|target| target.join("release"))
        .unwrap_or_else(|| profile_dir.clone());
    assert!(
        release.join("slam-launch").is_file(),
        "{} has no slam-launch: run `cargo build --release --workspace` first",
        release.display()
    );
    release
}

/// A binary of the workspace.
pub fn bin(name: &str) -> PathBuf {
    bin_dir().join(name)
}

/// A fresh directory under the target directory for one test's output.
pub fn scratch(name: &str) -> PathBuf {
    let dir = bin_dir()
        .join("e2e-scratch")
        .join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A domain name no other test uses.
pub fn domain(tag: &str) -> String {
    format!("e2e-{tag}-{}", std::process::id())
}

/// Runs `slam-launch` with `args`, quietly, in `domain`, writing into `out`.
pub fn launch(domain: &str, out: &Path, args: &[&str]) -> Output {
    Command::new(bin("slam-launch"))
        .args(["--quiet", "--domain", domain, "--out"])
        .arg(out)
        .args(args)
        .output()
        .expect("run slam-launch")
}

/// Panics with the run's output unless it succeeded.
pub fn assert_success(output: &Output) {
    assert!(
        output.status.success(),
        "slam-launch failed ({}):\nstdout:\n{}\nstderr:\n{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// The run's metrics.json.
pub fn metrics(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("metrics.json")).expect("metrics.json");
    serde_json::from_str(&text).expect("metrics.json is JSON")
}

/// A number from metrics.json.
pub fn number(metrics: &serde_json::Value, key: &str) -> f64 {
    metrics
        .get(key)
        .and_then(serde_json::Value::as_f64)
        .unwrap_or_else(|| panic!("metrics.json has no number '{key}': {metrics}"))
}

/// The poses of a TUM file: `(stamp, x, y, qz, qw)`; panics on a malformed line.
pub fn read_tum(path: &Path) -> Vec<[f64; 5]> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    slam_geom::parse_tum(&text)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_iter()
        .map(|(_, pose)| {
            let [x, y, _] = pose.position;
            let [_, _, qz, qw] = pose.orientation;
            // The stamp as the file spells it, read as seconds.
            let stamp = slam_geom::format_stamp(pose.stamp_ns)
                .parse()
                .unwrap_or(f64::NAN);
            [stamp, x, y, qz, qw]
        })
        .collect()
}

/// Files of `domain` left in /dev/shm.
pub fn shm_leftovers(domain: &str) -> Vec<String> {
    let prefix = ipc_types::Domain::new(domain)
        .expect("a valid domain name")
        .file_prefix();
    std::fs::read_dir("/dev/shm")
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|name| name.starts_with(&prefix))
                .collect()
        })
        .unwrap_or_default()
}

/// The shared real recordings: `$SLAM_DATA_DIR`, or `../shared/data` beside the workspace.
pub fn data_dir() -> PathBuf {
    let dir = std::env::var_os("SLAM_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data"))
        });
    assert!(
        dir.join("seed-hall/scans.csv").is_file(),
        "the real recordings are missing: set SLAM_DATA_DIR or put them in {}",
        dir.display()
    );
    dir
}

/// Map corners from a run's map_corners.csv: `(x, y, heading, angle)`.
pub fn read_map_corners(out: &Path) -> Vec<[f64; 4]> {
    let text = std::fs::read_to_string(out.join("map_corners.csv")).expect("map_corners.csv");
    text.lines()
        .skip(1)
        .map(|line| {
            let fields: Vec<f64> = line
                .split(',')
                .map(|f| f.parse().unwrap_or_else(|_| panic!("bad csv line {line}")))
                .collect();
            [fields[0], fields[1], fields[2], fields[3]]
        })
        .collect()
}

/// Pairs of map corners closer than `distance` with headings within `heading` radians:
/// the same wall corner mapped twice.
pub fn duplicate_corners(corners: &[[f64; 4]], distance: f64, heading: f64) -> Vec<(usize, usize)> {
    let mut pairs = Vec::new();
    for (i, a) in corners.iter().enumerate() {
        for (j, b) in corners.iter().enumerate().skip(i + 1) {
            let d = (a[0] - b[0]).hypot(a[1] - b[1]);
            let dh = (a[2] - b[2] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            if d < distance && dh.abs() < heading {
                pairs.push((i, j));
            }
        }
    }
    pairs
}

/// The children of `parent`, by /proc: `(pid, command name)`.
pub fn children_of(parent: libc::pid_t) -> Vec<(libc::pid_t, String)> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir("/proc")
        .expect("/proc")
        .filter_map(Result::ok)
    {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<libc::pid_t>() else {
            continue;
        };
        // "pid (comm) state ppid ...": comm may hold spaces, so split after its ')'.
        let Ok(stat) = std::fs::read_to_string(entry.path().join("stat")) else {
            continue;
        };
        let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let mut rest = stat[close + 1..].split_whitespace();
        let ppid = rest.nth(1).and_then(|p| p.parse::<libc::pid_t>().ok());
        if ppid == Some(parent) {
            found.push((pid, stat[open + 1..close].to_owned()));
        }
    }
    found
}

/// Lines of a file, 0 while it does not exist.
pub fn lines_in(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |text| text.lines().count())
}

/// Runs `command` with its output captured, killing it after `limit`: `None` if it had to
/// be killed, so a test of a refusal fails instead of hanging on a program that does not
/// refuse.
pub fn output_within(command: &mut Command, limit: std::time::Duration) -> Option<Output> {
    use std::process::Stdio;
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the command");
    let deadline = std::time::Instant::now() + limit;
    while std::time::Instant::now() < deadline {
        if child.try_wait().expect("poll the command").is_some() {
            return Some(child.wait_with_output().expect("read the command's output"));
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// An emulated Hokuyo (`hokuyo-emulator`) serving the scans of `file` on a free port, and
/// its `HOST:PORT`. The caller kills and reaps it.
pub fn start_hokuyo_emulator(file: &Path) -> (std::process::Child, String) {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let mut emulator = Command::new(bin("hokuyo-emulator"))
        .args(["--port", "0", "--file"])
        .arg(file)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("hokuyo-emulator");
    let mut first = String::new();
    BufReader::new(emulator.stdout.take().expect("the emulator's stdout"))
        .read_line(&mut first)
        .expect("the emulator's address");
    let addr = first
        .trim()
        .strip_prefix("listening on ")
        .unwrap_or_else(|| panic!("emulator said {first:?}"))
        .to_owned();
    (emulator, addr)
}

/// A localization run's `trajectory.tum` against `reference` (a TUM file) moved into the
/// map's frame by `map_from_reference`, from the scan at which the run converged on
/// (`converged_at_stamp` in metrics.json; every pose when `from_convergence` is false).
/// Panics when the run never converged and `from_convergence` is set.
pub fn localization_gaps(
    run: &Path,
    reference: &Path,
    map_from_reference: &slam_eval::Pose,
    from_convergence: bool,
) -> slam_eval::Gaps {
    let estimate = slam_eval::Trajectory::read_tum(&run.join("trajectory.tum"))
        .unwrap_or_else(|e| panic!("{e}"));
    let reference = slam_eval::Trajectory::read_tum(reference).unwrap_or_else(|e| panic!("{e}"));
    let from_ns = if from_convergence {
        let stamp = metrics(run)
            .get("converged_at_stamp")
            .and_then(serde_json::Value::as_str)
            .map(str::to_owned)
            .unwrap_or_else(|| panic!("{} never converged", run.display()));
        slam_geom::parse_stamp_ns(&stamp).unwrap_or_else(|e| panic!("{stamp}: {e}"))
    } else {
        0
    };
    slam_eval::position_gaps(
        &estimate,
        &reference,
        map_from_reference,
        from_ns,
        slam_eval::DEFAULT_TOLERANCE_NS,
    )
}

/// The inverse of the first pose of a TUM file: the map frame of the run that wrote it
/// (its first pose at the origin) from the file's frame.
pub fn frame_of_first_pose(path: &Path) -> slam_eval::Pose {
    let trajectory = slam_eval::Trajectory::read_tum(path).unwrap_or_else(|e| panic!("{e}"));
    let (_, first) = trajectory
        .iter()
        .next()
        .unwrap_or_else(|| panic!("{} has no pose", path.display()));
    first.inverse()
}
