//! Issue 47: hostile files and absurd settings. Nothing a run opens may block it, follow a
//! link planted in a shared directory, or fill the memory; every setting and input is judged
//! before any stage starts, and the refusal names the file or the key.
//!
//! The files planted in /dev/shm are made by a second user (`nobody`, through `setpriv`)
//! where the test runs as root, as the two-users test does; otherwise by this user, whose
//! FIFO and link are refused alike (not a regular file).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

use tests::*;

/// `nobody`.
const OTHER_UID: u32 = 65534;
/// The acceptance's bound on a refusal or a start despite a planted file; generous against
/// a busy machine, far below a hang.
const START_LIMIT: Duration = Duration::from_secs(5);
/// A stop by Ctrl-C once the run is under way.
const STOP_LIMIT: Duration = Duration::from_secs(2);
/// A hostile file given as world, log or map image is refused within this.
const REFUSAL_LIMIT: Duration = Duration::from_secs(2);
/// The data segment a refusing slam-launch runs under: reading a device or a sparse file
/// whole would exceed it and abort instead of refusing.
const REFUSAL_DATA_BYTES: u64 = 100 << 20;

/// Runs `program args` as `nobody` where this test runs as root, else as this user.
fn as_other(program: &str, args: &[&str]) {
    let mut command = if nix::unistd::geteuid().is_root() {
        let mut command = Command::new("setpriv");
        command.args([
            &format!("--reuid={OTHER_UID}"),
            &format!("--regid={OTHER_UID}"),
            "--clear-groups",
            program,
        ]);
        command
    } else {
        Command::new(program)
    };
    let status = command
        .args(args)
        .status()
        .expect("run the planting command");
    assert!(status.success(), "{program} {args:?}: {status}");
}

/// The owner file of `domain` of this user in /dev/shm.
fn owner_file(domain: &str) -> PathBuf {
    Path::new("/dev/shm").join(format!("{}{domain}_owner.lock", ipc_types::user_prefix()))
}

/// The console lines of `child` as they come.
fn console_lines(child: &mut std::process::Child) -> Receiver<String> {
    let stderr = child.stderr.take().expect("the console is piped");
    let (send, receive) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            if send.send(line).is_err() {
                break;
            }
        }
    });
    receive
}

/// Waits for a console line containing `text`, at most `limit`; the lines seen on the way.
fn wait_for_line(lines: &Receiver<String>, text: &str, limit: Duration) -> Result<String, String> {
    let deadline = Instant::now() + limit;
    let mut seen = String::new();
    while let Some(left) = deadline.checked_duration_since(Instant::now()) {
        match lines.recv_timeout(left) {
            Ok(line) if line.contains(text) => return Ok(line),
            Ok(line) => seen.push_str(&(line + "\n")),
            Err(_) => break,
        }
    }
    Err(seen)
}

#[test]
fn a_fifo_or_link_planted_in_dev_shm_neither_holds_up_nor_misleads_a_run() {
    let fifo_domain = domain("planted-fifo");
    let link_domain = domain("planted-link");
    let (fifo, link) = (owner_file(&fifo_domain), owner_file(&link_domain));
    let fifo_text = fifo.to_str().expect("a UTF-8 path");
    let link_text = link.to_str().expect("a UTF-8 path");
    as_other("mkfifo", &["-m", "666", fifo_text]);
    as_other("ln", &["-s", "/dev/zero", link_text]);

    // A run in a fresh domain sweeps past both, says so, and starts, at a sensor's pace.
    let out = scratch("planted").join("run");
    let args = ["--world", "office", "--rate", "40"];
    let mut launcher = launch_command(&domain("planted-run"), &out, &args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start slam-launch");
    let lines = console_lines(&mut launcher);
    let reported = wait_for_line(&lines, "is not this user's file", START_LIMIT);
    if reported.is_err() {
        stop(&mut launcher);
    }
    let planted_line = reported.expect("the planted files reported");
    assert!(
        planted_line.contains(fifo_text) || planted_line.contains(link_text),
        "{planted_line}"
    );
    wait_for_poses(&mut launcher, &out, 1, START_LIMIT);
    send(pid_of(&launcher), Signal::SIGINT);
    let stopped = wait_within(&mut launcher, STOP_LIMIT);
    if stopped.is_none() {
        stop(&mut launcher);
    }
    assert!(
        stopped.is_some(),
        "Ctrl-C stopped the run in {STOP_LIMIT:?}"
    );

    // A run asked to use the planted domain refuses it, naming the file.
    for (planted_domain, planted) in [(&fifo_domain, fifo_text), (&link_domain, link_text)] {
        let out = scratch("planted-claim");
        let mut command = launch_command(planted_domain, &out, &["--world", "office"]);
        let output = output_within(&mut command, START_LIMIT).expect("refused in time");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{stderr}");
        assert!(
            stderr.contains(&format!("cannot claim domain '{planted_domain}'"))
                && stderr.contains(planted),
            "{stderr}"
        );
    }
    // Another user's files are theirs: left in place.
    assert!(fifo.symlink_metadata().is_ok() && link.symlink_metadata().is_ok());
    let _ = std::fs::remove_file(&fifo);
    let _ = std::fs::remove_file(&link);
}

/// slam-launch with `args` under a data limit of [`REFUSAL_DATA_BYTES`]: its output, and
/// how long it took. Panics unless it ended within [`START_LIMIT`].
fn refusal(tag: &str, args: &[&str]) -> (String, Duration) {
    let out = scratch(tag).join("run");
    let mut command = Command::new("prlimit");
    command
        .arg(format!("--data={REFUSAL_DATA_BYTES}"))
        .arg(bin("slam-launch"))
        .args(["--quiet", "--domain", &domain(tag), "--out"])
        .arg(&out)
        .args(args);
    let started = Instant::now();
    let output = output_within(&mut command, START_LIMIT)
        .unwrap_or_else(|| panic!("{tag}: not refused within {START_LIMIT:?}"));
    let took = started.elapsed();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(2), "{tag}: {stderr}");
    assert!(
        !out.exists(),
        "{tag}: refused before the run's directory was made"
    );
    (stderr, took)
}

/// A FIFO, a 10 GB sparse file and a link to /dev/zero in `dir`, named `stem` and a suffix.
fn hostile_files(dir: &Path, stem: &str) -> [(PathBuf, &'static str); 3] {
    let fifo = dir.join(format!("{stem}-fifo"));
    let status = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(status.success());
    let sparse = dir.join(format!("{stem}-sparse"));
    std::fs::File::create(&sparse)
        .and_then(|file| file.set_len(10 << 30))
        .expect("a sparse file");
    let zero = dir.join(format!("{stem}-zero"));
    std::os::unix::fs::symlink("/dev/zero", &zero).expect("a link to /dev/zero");
    [
        (fifo, "is a FIFO, not a regular file"),
        (sparse, "bytes or more, above the"),
        (zero, "is a character device, not a regular file"),
    ]
}

#[test]
fn a_device_a_fifo_or_a_huge_file_as_world_log_or_map_is_refused_at_once() {
    let dir = scratch("hostile-files");
    // A real saved map, whose image is then replaced.
    let map = dir.join("map");
    let output = launch(
        &domain("hostile-map"),
        &map,
        &["--world", "office", "--frames", "40"],
    );
    assert_success(&output);
    let image = map.join("map.pgm");
    for (file, why) in hostile_files(&dir, "image") {
        std::fs::remove_file(&image).expect("remove the image");
        std::os::unix::fs::symlink(&file, &image).expect("link the image");
        let (stderr, took) = refusal(
            "hostile-image",
            &["--world", "office", "--map", map.to_str().expect("UTF-8")],
        );
        assert!(
            stderr.contains("map image") && stderr.contains(why),
            "{stderr}"
        );
        assert!(took < REFUSAL_LIMIT, "{took:?}: {stderr}");
    }
    for (file, why) in hostile_files(&dir, "world") {
        let (stderr, took) = refusal("hostile-world", &["--world", file.to_str().expect("UTF-8")]);
        assert!(
            stderr.contains("world file") && stderr.contains(why),
            "{stderr}"
        );
        assert!(took < REFUSAL_LIMIT, "{took:?}: {stderr}");
    }
    for (file, why) in hostile_files(&dir, "log") {
        let log = file.to_str().expect("UTF-8");
        let (stderr, took) = refusal("hostile-log", &["--replay", log, "--format", "carmen"]);
        // A log is read as a stream: the sparse file is refused for the scan it lacks.
        let why = why.replace(
            "bytes or more, above the",
            "no valid scan in its first 64 MiB",
        );
        assert!(stderr.contains(log) && stderr.contains(&why), "{stderr}");
        assert!(took < REFUSAL_LIMIT, "{took:?}: {stderr}");
    }
}

#[test]
fn settings_that_would_exhaust_the_machine_are_refused_with_their_range() {
    let dir = scratch("absurd-settings");
    for (text, key) in [
        ("[front_end]\nvoxel_size = 1e-9\n", "voxel_size"),
        ("[front_end]\nvoxel_size = 1e9\n", "voxel_size"),
        ("[slam]\nview_range = 1e9\n", "view_range"),
        (
            "[slam.localize]\nmax_particles = 1000000000\n",
            "max_particles",
        ),
        (
            "[slam]\nmeasured_xy_variance_per_metre = 1e9\n",
            "measured_xy_variance_per_metre",
        ),
    ] {
        let config = dir.join("run.toml");
        std::fs::write(&config, text).expect("run.toml");
        let (stderr, _) = refusal(
            "absurd-setting",
            &["--config", config.to_str().expect("UTF-8")],
        );
        assert!(
            stderr.contains(&format!("{key} = ")) && stderr.contains("must be "),
            "{text}: {stderr}"
        );
        assert!(
            !stderr.contains("ready"),
            "{text}: no stage started: {stderr}"
        );
    }
}

#[test]
fn absurd_relations_are_refused_with_their_line_before_the_run() {
    let dir = scratch("absurd-relations-file");
    let relations = dir.join("bad.relations");
    std::fs::write(
        &relations,
        "1.0 2.0 0.5 0 0 0 0 0\n2.0 3.0 1e300 0 0 0 0 0\n",
    )
    .expect("relations");
    let (stderr, _) = refusal(
        "absurd-relations",
        &[
            "--world",
            "office",
            "--relations",
            relations.to_str().expect("UTF-8"),
        ],
    );
    assert!(
        stderr.contains("bad.relations, line 2: a motion of"),
        "{stderr}"
    );
}
