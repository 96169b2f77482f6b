//! SIGKILL of slam-bench: the slam-launch it is running stops with it (a parent-death
//! signal, SIGTERM, as slam-launch gives its stages), as on Ctrl-C, instead of running on
//! with nobody to read its results.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(120);

/// Waits until `pid`, a child of this process, has ended; its wait status.
fn reap(pid: libc::pid_t, what: &str) -> i32 {
    let deadline = Instant::now() + LIMIT;
    loop {
        let mut status = 0;
        // SAFETY: waitpid(2) on a process that is ours (a child, or handed to us as
        // subreaper).
        match unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) } {
            0 => {}
            -1 => panic!("{what} ({pid}): {}", std::io::Error::last_os_error()),
            _ => return status,
        }
        if Instant::now() > deadline {
            // SAFETY: kill(2) on a process of this test; it is reaped right after.
            unsafe {
                libc::kill(pid, libc::SIGKILL);
                libc::waitpid(pid, std::ptr::null_mut(), 0);
            }
            panic!("{what} still running {LIMIT:?} after slam-bench was killed");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_killed_slam_bench_takes_its_slam_launch_with_it() {
    // The orphans come to us, to be reaped and their statuses read (see launcher_killed).
    // SAFETY: prctl(2) with a valid option on this process.
    assert_eq!(
        unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) },
        0
    );
    let carmen = data_dir().join("carmen");
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
    let bench_pid = libc::pid_t::try_from(bench.id()).expect("pid");

    // A slam-launch of slam-bench's, with its stages up.
    let deadline = Instant::now() + LIMIT;
    let (launcher, stages) = loop {
        let launchers = children_of(bench_pid);
        if let Some(&(pid, _)) = launchers.iter().find(|(_, name)| name == "slam-launch") {
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
    let status = reap(launcher, "slam-launch");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 130,
        "slam-launch ended with wait status {status:#x}"
    );
    // It stopped and reaped its stages before it ended, as on Ctrl-C.
    for (pid, name) in stages {
        assert!(
            !std::path::Path::new(&format!("/proc/{pid}")).exists(),
            "{name} ({pid}) outlived slam-launch"
        );
    }
}
