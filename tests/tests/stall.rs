//! Issue 14, row 5: a stage frozen in lockstep (SIGSTOP). The console names it after the
//! warning time, and after the limit the run fails with that reason; the stages it holds
//! up are not named, and map-sink still writes the results.

use std::process::Stdio;
use std::time::Duration;

use tests::*;

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(120);
const STAGES: [&str; 4] = ["map-sink", "slam-proc", "feature-proc", "lidar-sim"];

/// Freezes `stage` mid-run with a 2 s warning and a 6 s limit, checks that the run failed
/// naming that stage alone, and returns slam-launch's console (stderr).
fn freeze(stage: &str) -> String {
    let domain = domain(&format!("stall-{stage}"));
    let out = scratch(&format!("stall-{stage}"));
    // Lockstep: the office loop's 3958 scans take several seconds, one frozen stage holds
    // every other one up. Quiet: a stall is reported all the same.
    let mut launcher = spawn_launch(
        &domain,
        &out,
        &[
            "--world",
            "office",
            "--stall-warning",
            "2",
            "--stall-limit",
            "6",
        ],
        Stdio::piped(),
    );
    let console = read_console(&mut launcher);
    wait_for_poses(&mut launcher, &out, 100, LIMIT);
    let Some(pid) = child_named(pid_of(&launcher), stage) else {
        stop(&mut launcher);
        panic!("no {stage} among slam-launch's children");
    };
    send(pid, Signal::SIGSTOP);

    let Some(status) = wait_within(&mut launcher, LIMIT) else {
        // Woken, so it can be stopped.
        send(pid, Signal::SIGCONT);
        stop(&mut launcher);
        panic!("slam-launch still running {LIMIT:?} after {stage} froze");
    };
    let console = console.join().expect("console");
    // The frozen stage was woken and stopped with the others: map-sink wrote what it had
    // (even when it was the frozen one).
    assert!(out.join("metrics.json").is_file(), "{console}");
    // The run failed, and the frozen stage is the one named.
    assert_eq!(status.code(), Some(1), "{console}");
    assert_eq!(named(&console), [stage], "{console}");
    console
}

/// The stages the console reported as making no progress.
fn named(console: &str) -> Vec<&str> {
    STAGES
        .into_iter()
        .filter(|stage| console.contains(&format!("slam-launch: {stage} has made no progress")))
        .collect()
}

#[test]
fn a_frozen_stage_in_the_middle_is_named_not_the_stages_waiting_on_it() {
    // slam-proc frozen: feature-proc is blocked sending to it and the simulator is blocked
    // sending to feature-proc, and map-sink waits for poses: only slam-proc is stuck.
    let console = freeze("slam-proc");
    assert!(
        console.contains(
            "slam-launch: slam-proc has made no progress for 2 s (a message waits for it on \
             'perception/features')"
        ),
        "{console}"
    );
    // The closing reason.
    assert!(
        console.contains(
            "slam-launch: slam-proc stalled: no progress for 6 s (a message waits for it on \
             'perception/features')"
        ),
        "{console}"
    );
}

#[test]
fn a_frozen_source_is_named() {
    // Nothing is pending anywhere: the next scan is the simulator's to send.
    let console = freeze("lidar-sim");
    assert!(
        console.contains(
            "slam-launch: lidar-sim stalled: no progress for 6 s (the next scan is its to send)"
        ),
        "{console}"
    );
}
