//! Helpers for the end-to-end tests: find the release binaries, run `slam-launch`, read what
//! a run wrote.
//!
//! The binaries must have been built first (`cargo build --release --workspace`, as the
//! README's test command does); the helpers say so instead of running stale ones silently.
//!
//! Processes are signalled, waited for and reaped through `nix`'s safe wrappers, so no test
//! needs `unsafe`.

pub mod map_server;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Output, Stdio};
use std::time::{Duration, Instant};

pub use nix::sys::signal::Signal;
pub use nix::sys::wait::WaitStatus;
use nix::sys::wait::{WaitPidFlag, waitpid};
pub use nix::unistd::Pid;

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

/// `slam-launch` with `args`, quietly, in `domain`, writing into `out`, not started yet.
pub fn launch_command(domain: &str, out: &Path, args: &[&str]) -> Command {
    let mut command = Command::new(bin("slam-launch"));
    command
        .args(["--quiet", "--domain", domain, "--out"])
        .arg(out)
        .args(args);
    command
}

/// Runs `slam-launch` with `args`, quietly, in `domain`, writing into `out`.
pub fn launch(domain: &str, out: &Path, args: &[&str]) -> Output {
    launch_command(domain, out, args)
        .output()
        .expect("run slam-launch")
}

/// Runs `slam-launch` on the recorded log `log` (`--replay LOG`) with `args`, as [`launch`].
pub fn launch_replay(domain: &str, out: &Path, log: &Path, args: &[&str]) -> Output {
    let log = log.to_str().expect("a UTF-8 path");
    launch(domain, out, &[&["--replay", log], args].concat())
}

/// A finished, successful run of `slam-launch`: its domain, its output directory and what
/// it printed.
pub struct Run {
    pub domain: String,
    pub out: PathBuf,
    pub output: Output,
}

/// Runs `slam-launch` with `args` as [`launch`] does, in a domain and a scratch directory of
/// its own both named by `tag`, and panics unless it succeeded.
pub fn launched(tag: &str, args: &[&str]) -> Run {
    let domain = domain(tag);
    let out = scratch(tag);
    let output = launch(&domain, &out, args);
    assert_success(&output);
    Run {
        domain,
        out,
        output,
    }
}

/// [`launched`] on the recorded log `log` (`--replay LOG`).
pub fn replayed(tag: &str, log: &Path, args: &[&str]) -> Run {
    let log = log.to_str().expect("a UTF-8 path");
    launched(tag, &[&["--replay", log], args].concat())
}

/// Runs `slam-launch` on the (emulated) Hokuyo at `addr` for its first `frames` scans (the
/// driver's `[hokuyo] frames`, from a config file written into `out`) with `args`, as
/// [`launch`].
pub fn launch_hokuyo(domain: &str, out: &Path, addr: &str, frames: u32, args: &[&str]) -> Output {
    std::fs::create_dir_all(out).expect("the run's directory");
    let config = out.join("hokuyo.toml");
    std::fs::write(&config, format!("[hokuyo]\nframes = {frames}\n")).expect("hokuyo.toml");
    let config = config.to_str().expect("a UTF-8 path");
    let source = ["--source", "hokuyo", "--addr", addr, "--config", config];
    launch(domain, out, &[&source, args].concat())
}

/// Starts `slam-launch` as [`launch`] runs it, in the background: its output discarded and
/// its console (stderr) as `console` says (`Stdio::piped()` to read it).
pub fn spawn_launch(domain: &str, out: &Path, args: &[&str], console: Stdio) -> Child {
    launch_command(domain, out, args)
        .stdout(Stdio::null())
        .stderr(console)
        .spawn()
        .expect("start slam-launch")
}

/// Collects `child`'s console (its piped stderr) on a thread, line by line, so the child
/// never blocks on a full pipe; the thread returns the lines joined once the child has
/// closed it.
pub fn read_console(child: &mut Child) -> std::thread::JoinHandle<String> {
    use std::io::{BufRead, BufReader};
    let stderr = child.stderr.take().expect("the console is piped");
    std::thread::spawn(move || {
        BufReader::new(stderr)
            .lines()
            .map_while(Result::ok)
            .collect::<Vec<_>>()
            .join("\n")
    })
}

/// Waits until the run `launcher` writes into `out` is under way: `poses` lines in its
/// online trajectory (map-sink flushes it as it grows; `trajectory.tum` comes at the end).
/// Panics when the launcher ends first or `limit` passes, stopping it first.
pub fn wait_for_poses(launcher: &mut Child, out: &Path, poses: usize, limit: Duration) {
    let online = out.join(slam_eval::TRAJECTORY_ONLINE_FILE);
    let deadline = Instant::now() + limit;
    while lines_in(&online) < poses {
        if let Some(status) = launcher.try_wait().expect("poll slam-launch") {
            panic!("slam-launch ended before {poses} poses were recorded: {status}");
        }
        if Instant::now() > deadline {
            stop(launcher);
            panic!("not {poses} poses recorded in {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Stops a slam-launch of a test that failed: SIGTERM, so it stops its stages too, then
/// reaps it.
pub fn stop(launcher: &mut Child) {
    let _ = nix::sys::signal::kill(pid_of(launcher), Signal::SIGTERM);
    let _ = launcher.wait();
}

/// The process id of `child`, as the signal and wait calls take it.
pub fn pid_of(child: &Child) -> Pid {
    Pid::from_raw(i32::try_from(child.id()).expect("a pid fits an i32"))
}

/// Sends `signal` to `pid`, a process of this test's own run; panics when it cannot.
pub fn send(pid: Pid, signal: Signal) {
    nix::sys::signal::kill(pid, signal)
        .unwrap_or_else(|e| panic!("cannot send {signal} to {pid}: {e}"));
}

/// Waits for `child` to end, at most `limit`: `None` while it still runs then.
pub fn wait_within(child: &mut Child, limit: Duration) -> Option<ExitStatus> {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(status) = child.try_wait().expect("poll the child") {
            return Some(status);
        }
        if Instant::now() > deadline {
            return None;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Makes this process the subreaper of its descendants: orphans are handed to the nearest
/// living ancestor that is one, so the stages of a killed launcher come to the test, to be
/// reaped and their exit statuses read (pid 1 of a container may never reap them).
pub fn become_subreaper() {
    nix::sys::prctl::set_child_subreaper(true).expect("become a child subreaper");
}

/// Whether `pid`, a process of ours (a child, or handed to us as subreaper), has ended: its
/// wait status then (reaped), `None` while it runs.
pub fn try_reap(pid: Pid) -> Option<WaitStatus> {
    match waitpid(pid, Some(WaitPidFlag::WNOHANG)) {
        Ok(WaitStatus::StillAlive) => None,
        Ok(status) => Some(status),
        Err(e) => panic!("{pid} is not ours to wait for: {e}"),
    }
}

/// Kills `pid` (see [`try_reap`]) with SIGKILL and reaps it: the end of a test that failed.
pub fn kill_and_reap(pid: Pid) {
    let _ = nix::sys::signal::kill(pid, Signal::SIGKILL);
    let _ = waitpid(pid, None);
}

/// Waits for `pid` (see [`try_reap`]) at most `limit`; past it the process is killed and
/// reaped, and the test fails naming `what`.
pub fn reap_within(pid: Pid, limit: Duration, what: &str) -> WaitStatus {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(status) = try_reap(pid) {
            return status;
        }
        if Instant::now() > deadline {
            kill_and_reap(pid);
            panic!("{what} ({pid}) still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
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

/// The run's metrics.json, read as the typed summary map-sink writes; panics when it is
/// missing or not that summary.
pub fn metrics(out: &Path) -> slam_eval::Metrics {
    let path = out.join(slam_eval::METRICS_FILE);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{} is not the metrics map-sink writes: {e}", path.display()))
}

/// What follows `head` (e.g. `left out:`) on the first line of a stage's summary block on
/// the console, trimmed; panics naming the console if no line has it.
pub fn summary_line(console: &str, head: &str) -> String {
    console
        .lines()
        .find_map(|line| line.trim().strip_prefix(head))
        .unwrap_or_else(|| panic!("no '{head}' line in {console}"))
        .trim()
        .to_owned()
}

/// The count that starts the summary line `head` (`loop closures: 3 verified ...` gives 3).
pub fn summary_count(console: &str, head: &str) -> u64 {
    let line = summary_line(console, head);
    line.split_whitespace()
        .next()
        .and_then(|count| count.parse().ok())
        .unwrap_or_else(|| panic!("'{head} {line}' starts with no count"))
}

/// The poses of a TUM file, read by [`slam_geom::read_tum`]; panics on an unreadable file
/// or a malformed line.
pub fn read_tum(path: &Path) -> Vec<slam_geom::TumPose> {
    slam_geom::read_tum(path)
        .unwrap_or_else(|e| panic!("{e}"))
        .into_iter()
        .map(|(_, pose)| pose)
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
pub fn children_of(parent: Pid) -> Vec<(Pid, String)> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir("/proc")
        .expect("/proc")
        .filter_map(Result::ok)
    {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<i32>() else {
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
        let ppid = rest.nth(1).and_then(|p| p.parse::<i32>().ok());
        if ppid == Some(parent.as_raw()) {
            found.push((Pid::from_raw(pid), stat[open + 1..close].to_owned()));
        }
    }
    found
}

/// The child of `parent` whose command is `name` (a stage of a slam-launch).
pub fn child_named(parent: Pid, name: &str) -> Option<Pid> {
    children_of(parent)
        .into_iter()
        .find(|(_, command)| command == name)
        .map(|(pid, _)| pid)
}

/// Lines of a file, 0 while it does not exist.
pub fn lines_in(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |text| text.lines().count())
}

/// Runs `command` with its output captured, killing it after `limit`: `None` if it had to
/// be killed, so a test of a refusal fails instead of hanging on a program that does not
/// refuse.
pub fn output_within(command: &mut Command, limit: Duration) -> Option<Output> {
    let mut child = command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the command");
    if wait_within(&mut child, limit).is_some() {
        return Some(child.wait_with_output().expect("read the command's output"));
    }
    let _ = child.kill();
    let _ = child.wait();
    None
}

/// An emulated Hokuyo (`hokuyo-emulator`) serving the scans of `file` on a free port, and
/// its `HOST:PORT`. The caller kills and reaps it.
pub fn start_hokuyo_emulator(file: &Path) -> (std::process::Child, String) {
    start_hokuyo_emulator_with(file, &[])
}

/// [`start_hokuyo_emulator`] with more of the emulator's options (`--loop`).
pub fn start_hokuyo_emulator_with(file: &Path, args: &[&str]) -> (std::process::Child, String) {
    use std::io::{BufRead, BufReader};
    let mut emulator = Command::new(bin("hokuyo-emulator"))
        .args(["--port", "0", "--file"])
        .arg(file)
        .args(args)
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
            .converged_at_stamp
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
