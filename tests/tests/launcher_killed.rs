//! Issue 14, row 3: SIGKILL of slam-launch. Its stages die with it instead of living on with
//! parent 1 (the kernel sends them SIGTERM as it dies), map-sink still writes the run's
//! results from what it received, no stage panics on the pipes the launcher no longer
//! reads, and the next start reclaims the dead run's shared memory at once.

use std::process::Stdio;
use std::time::{Duration, Instant};

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(120);

#[test]
fn stages_die_with_a_killed_launcher_and_map_sink_writes_its_results() {
    // The stages come to this process when slam-launch dies.
    become_subreaper();
    let domain = domain("killed");
    let out = scratch("launcher-killed");
    // In real time the office loop takes about 100 s: it is mid-run when killed.
    let mut launcher = spawn_launch(
        &domain,
        &out,
        &["--world", "office", "--rate", "40"],
        Stdio::null(),
    );
    // Under way: a second of poses recorded.
    wait_for_poses(&mut launcher, &out, 40, LIMIT);
    let stages = children_of(pid_of(&launcher));
    let mut names: Vec<&str> = stages.iter().map(|(_, name)| name.as_str()).collect();
    names.sort_unstable();
    assert_eq!(
        names,
        [
            "feature-proc",
            "graph-proc",
            "lidar-sim",
            "map-sink",
            "slam-proc"
        ],
        "{stages:?}"
    );

    launcher.kill().expect("SIGKILL slam-launch");
    launcher.wait().expect("reap slam-launch");

    // Every stage ends, without anyone stopping it but the kernel's death signal.
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut running = stages.clone();
    let mut ended = Vec::new();
    while !running.is_empty() {
        running.retain(|(pid, name)| match try_reap(*pid) {
            Some(status) => {
                ended.push((name.clone(), status));
                false
            }
            None => true,
        });
        if Instant::now() > deadline {
            for (pid, _) in &running {
                kill_and_reap(*pid);
            }
            panic!("still running 60 s after slam-launch was killed: {running:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }

    // Every stage stopped as on Ctrl-C, cleanly: its closing lines go to a pipe nobody
    // reads any more, which is no reason to panic (exit 101).
    let unclean: Vec<String> = ended
        .iter()
        .filter(|(_, status)| !matches!(status, WaitStatus::Exited(_, 0)))
        .map(|(name, status)| format!("{name}: {status:?}"))
        .collect();
    // map-sink stopped after writing what it had.
    assert!(
        unclean.is_empty(),
        "{unclean:?}; map-sink's log: {}",
        std::fs::read_to_string(out.join("logs/map-sink.log")).unwrap_or_default()
    );
    assert!(
        ended.iter().any(|(name, _)| name == "map-sink"),
        "map-sink ended"
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
    assert!(metrics.frames_processed >= 40, "{metrics:?}");
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
