//! A particle count the machine cannot hold is refused before it is tried: by slam-launch
//! before it starts anything, and by slam-proc run alone, each with the estimate and the
//! memory available.

use std::process::Command;
use std::time::Duration;

use tests::*;

/// Far more than a refusal takes; a program that does not refuse is killed after it.
const LIMIT: Duration = Duration::from_secs(15);
const PARTICLES: usize = 1_000_000;

/// Whether this machine is too small for a million particles (it is, unless it has more
/// memory free than the estimate, about 150 GiB).
fn too_many_here() -> bool {
    let Some(available) = slam_proc::memory::available() else {
        eprintln!("no figure of available memory here: nothing to refuse");
        return false;
    };
    let fits = slam_proc::memory::estimate_bytes(PARTICLES) <= available.bytes;
    if fits {
        eprintln!(
            "{PARTICLES} particles fit in {} bytes here",
            available.bytes
        );
    }
    !fits
}

fn assert_refused(what: &str, output: Option<std::process::Output>) -> String {
    let output = output.unwrap_or_else(|| panic!("{what} took {PARTICLES} particles"));
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(!output.status.success(), "{what}: {stderr}");
    assert!(
        stderr.contains(&format!(
            "refusing to start: {PARTICLES} particles would need about"
        )),
        "{what}: {stderr}"
    );
    assert!(stderr.contains("MiB is available ("), "{what}: {stderr}");
    assert!(stderr.contains("particles fit"), "{what}: {stderr}");
    stderr
}

#[test]
fn slam_launch_refuses_more_particles_than_memory_before_starting_anything() {
    if !too_many_here() {
        return;
    }
    let out = scratch("memory-launch").join("run");
    let name = domain("memory-launch");
    let output = output_within(
        Command::new(bin("slam-launch"))
            .args(["--quiet", "--domain", &name, "--out"])
            .arg(&out)
            .args(["--world", "office", "--frames", "50", "--particles"])
            .arg(PARTICLES.to_string()),
        LIMIT,
    );
    assert_refused("slam-launch", output);
    assert!(!out.exists(), "refused before the run's directory was made");
    assert!(shm_leftovers(&name).is_empty(), "nothing was started");
}

#[test]
fn slam_proc_alone_refuses_more_particles_than_memory() {
    if !too_many_here() {
        return;
    }
    let output = output_within(
        Command::new(bin("slam-proc"))
            .args(["--domain", &domain("memory-proc"), "--particles"])
            .arg(PARTICLES.to_string()),
        LIMIT,
    );
    assert_refused("slam-proc", output);
}
