//! SIGKILL of slam-bench: the slam-launch it is running stops with it (a parent-death
//! signal, SIGTERM, as slam-launch gives its stages), as on Ctrl-C, instead of running on
//! with nobody to read its results.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(120);

#[test]
fn a_killed_slam_bench_takes_its_slam_launch_with_it() {
    // The orphans come to us, to be reaped and their statuses read.
    become_subreaper();
    let carmen = test_data::carmen_dir();
    let dir = scratch("bench-killed");
    let logs = dir.join("logs");
    std::fs::create_dir_all(&logs).expect("logs");
    for name in ["mit-csail.clf", "mit-csail.relations"] {
        std::os::unix::fs::symlink(carmen.join(name), logs.join(name)).expect("link");
    }
    // Many seeds: slam-bench is still busy whenever it is killed.
    let mut bench = Command::new(bin("slam-bench"))
        .arg(&logs)
        .args(["--seeds", "1-50", "--particles", "30"])
        .arg("--out")
        .arg(dir.join("out"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start slam-bench");
    let bench_pid = pid_of(&bench);

    // A slam-launch of slam-bench's, with its stages up.
    let deadline = Instant::now() + LIMIT;
    let (launcher, stages) = loop {
        if let Some(pid) = child_named(bench_pid, "slam-launch") {
            let stages = children_of(pid);
            if stages.len() == 4 {
                break (pid, stages);
            }
        }
        assert!(
            bench.try_wait().expect("try_wait").is_none(),
            "slam-bench ended before it was killed"
        );
        assert!(Instant::now() < deadline, "no slam-launch under slam-bench");
        std::thread::sleep(Duration::from_millis(10));
    };

    bench.kill().expect("SIGKILL slam-bench");
    bench.wait().expect("reap slam-bench");

    // slam-launch took the SIGTERM as Ctrl-C: its run was interrupted (130), it did not
    // run on to the end of the log.
    let status = reap_within(launcher, LIMIT, "slam-launch after slam-bench was killed");
    assert!(
        matches!(status, WaitStatus::Exited(_, 130)),
        "slam-launch ended with {status:?}"
    );
    // It stopped and reaped its stages before it ended, as on Ctrl-C.
    for (pid, name) in stages {
        assert!(
            !std::path::Path::new(&format!("/proc/{pid}")).exists(),
            "{name} ({pid}) outlived slam-launch"
        );
    }
}
