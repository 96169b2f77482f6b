//! Issue 14, row 3: SIGKILL of slam-launch. Its stages die with it instead of living on with
//! parent 1 (the kernel sends them SIGTERM as it dies), map-sink still writes the run's
//! results from what it received, no stage panics on the pipes the launcher no longer
//! reads, and the next start reclaims the dead run's shared memory at once.

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(120);

#[test]
fn stages_die_with_a_killed_launcher_and_map_sink_writes_its_results() {
    // Orphans are handed to the nearest living ancestor that is a subreaper: make that us,
    // so the stages come to this process when slam-launch dies and can be reaped and
    // their exit statuses read (pid 1 of a container may never reap them).
    // SAFETY: prctl(2) with a valid option on this process.
    assert_eq!(
        unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) },
        0
    );
    let domain = domain("killed");
    let out = scratch("launcher-killed");
    // In real time the office loop takes about 100 s: it is mid-run when killed.
    let mut launcher = Command::new(bin("slam-launch"))
        .args(["--quiet", "--domain", &domain, "--out"])
        .arg(&out)
        .args(["--world", "office", "--rate", "40"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start slam-launch");
    let launcher_pid = libc::pid_t::try_from(launcher.id()).expect("pid");

    // Under way: a second of poses recorded (map-sink flushes the online path as it grows).
    let online = out.join("trajectory_online.tum");
    let deadline = Instant::now() + LIMIT;
    while lines_in(&online) < 40 {
        if let Some(status) = launcher.try_wait().expect("try_wait") {
            panic!("slam-launch ended before the test killed it: {status}");
        }
        if Instant::now() > deadline {
            let _ = launcher.kill();
            let _ = launcher.wait();
            panic!("no poses recorded in {LIMIT:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let stages = children_of(launcher_pid);
    let mut names: Vec<&str> = stages.iter().map(|(_, name)| name.as_str()).collect();
    names.sort_unstable();
    assert_eq!(
        names,
        ["feature-proc", "lidar-sim", "map-sink", "slam-proc"],
        "{stages:?}"
    );

    launcher.kill().expect("SIGKILL slam-launch");
    launcher.wait().expect("reap slam-launch");

    // Every stage ends, without anyone stopping it but the kernel's death signal.
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut running = stages.clone();
    let mut ended = Vec::new();
    while !running.is_empty() {
        running.retain(|(pid, name)| {
            let mut status = 0;
            // SAFETY: waitpid(2) on a process handed to us as its subreaper.
            match unsafe { libc::waitpid(*pid, &mut status, libc::WNOHANG) } {
                0 => true,
                -1 => panic!(
                    "{name} ({pid}) is not ours to wait for: {}",
                    std::io::Error::last_os_error()
                ),
                _ => {
                    ended.push((name.clone(), status));
                    false
                }
            }
        });
        if Instant::now() > deadline {
            for (pid, _) in &running {
                // SAFETY: kill(2) on a process of this test; it is reaped below.
                unsafe {
                    libc::kill(*pid, libc::SIGKILL);
                    libc::waitpid(*pid, std::ptr::null_mut(), 0);
                }
            }
            panic!("still running 60 s after slam-launch was killed: {running:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }

    // Every stage stopped as on Ctrl-C, cleanly: its closing lines go to a pipe nobody
    // reads any more, which is no reason to panic (exit 101).
    let unclean: Vec<String> = ended
        .iter()
        .filter(|(_, status)| !(libc::WIFEXITED(*status) && libc::WEXITSTATUS(*status) == 0))
        .map(|(name, status)| format!("{name}: wait status {status:#x}"))
        .collect();
    assert!(unclean.is_empty(), "{unclean:?}");
    // map-sink stopped after writing what it had.
    let sink = ended
        .iter()
        .find(|(name, _)| name == "map-sink")
        .map(|&(_, status)| status)
        .expect("map-sink ended");
    assert!(
        libc::WIFEXITED(sink) && libc::WEXITSTATUS(sink) == 0,
        "map-sink ended with wait status {sink:#x}: {}",
        std::fs::read_to_string(out.join("logs/map-sink.log")).unwrap_or_default()
    );
    for file in [
        "metrics.json",
        "map.svg",
        "trajectory.tum",
        "map_corners.csv",
    ] {
        assert!(
            out.join(file).is_file(),
            "{file} missing in {}",
            out.display()
        );
    }
    let metrics = metrics(&out);
    assert!(number(&metrics, "frames_processed") >= 40.0, "{metrics}");
    assert!(read_tum(&out.join("trajectory.tum")).len() >= 40);

    // The next start, in a domain of its own, reclaims what the dead run left in /dev/shm
    // (the domain's management segment and its owner file) at once: its launcher is known
    // to be dead, so there is no minute to wait for the files to age.
    assert!(
        !shm_leftovers(&domain).is_empty(),
        "nothing left to reclaim"
    );
    let next = launch(
        &format!("{domain}-next"),
        &scratch("launcher-killed-next"),
        &["--world", "hall", "--frames", "5"],
    );
    assert_success(&next);
    assert_eq!(shm_leftovers(&domain), Vec::<String>::new());
}
