//! A domain belongs to one pipeline: a second `slam-launch` given the domain of a running
//! one is refused before it starts anything, and the running one goes on untouched.

use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use tests::*;

/// Stops the first pipeline however the test ends.
struct Running(Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn a_domain_with_live_nodes_is_refused_by_name() {
    let domain = domain("shared");
    let first_out = scratch("shared-first");
    // In real time the office loop takes about 100 s: it is running while the test goes on.
    let mut first = Running(spawn_launch(
        &domain,
        &first_out,
        &["--world", "office", "--rate", "40"],
        Stdio::null(),
    ));

    // Wait until the first pipeline's stages are up in the domain.
    let ipc = ipc_types::Domain::new(&domain).expect("domain");
    let deadline = Instant::now() + Duration::from_secs(60);
    while ipc.alive_nodes() < 3 {
        assert!(
            first.0.try_wait().expect("try_wait").is_none(),
            "the first pipeline ended before its stages were up"
        );
        assert!(
            Instant::now() < deadline,
            "the first pipeline never came up"
        );
        std::thread::sleep(Duration::from_millis(20));
    }

    let second_out = scratch("shared-second");
    let second = launch(
        &domain,
        &second_out,
        &["--world", "office", "--frames", "10"],
    );
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert!(!second.status.success(), "{stderr}");
    assert!(
        stderr.contains(&format!("domain '{domain}'")) && stderr.contains("live node"),
        "{stderr}"
    );
    assert!(!second_out.join("metrics.json").exists());
    // The first run was not disturbed: still running, its nodes still there.
    assert!(first.0.try_wait().expect("try_wait").is_none());
    assert!(ipc.alive_nodes() >= 3);

    // Ctrl-C ends it as an interrupted run.
    send(pid_of(&first.0), Signal::SIGINT);
    let status = wait_within(&mut first.0, Duration::from_secs(60))
        .expect("the first pipeline ends on Ctrl-C");
    assert_eq!(status.code(), Some(130));
}
