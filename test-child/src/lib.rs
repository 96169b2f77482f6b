//! # test-child
//!
//! What the integration tests of the process crates (lidar-sim, lidar-replay, lidar-hokuyo,
//! slam-eval's `slam-score`, the end-to-end tests) do with the process under test the same
//! way: give it an input file, read its console as it comes, wait for it with a deadline, stop
//! it as a user would (SIGTERM), point it at a port nobody listens on, and check that a bad
//! `--rate` is refused before anything starts.
//!
//! Test support only (a dev-dependency): it panics where a test should fail.

use std::io::{BufRead, BufReader, Read};
use std::os::fd::{AsRawFd, OwnedFd};
use std::path::PathBuf;
use std::process::{Child, Command, Output};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

/// Writes `text` to the file `name` in a directory of this test process's own (`suite`
/// names the test suite, so two suites running at once do not share it) and returns its path.
pub fn fixture(suite: &str, name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("{suite}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create the fixture directory");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write the fixture");
    path
}

/// A loopback port that refuses connections for as long as this lives.
///
/// A port bound and released again may be taken by another test's server before it is
/// used; this one stays bound to a socket that never listens, so nothing else can take it
/// and a connection to it is refused at once.
#[derive(Debug)]
pub struct ClosedPort {
    _socket: OwnedFd,
    addr: String,
}

impl ClosedPort {
    /// `127.0.0.1:PORT`.
    pub fn addr(&self) -> &str {
        &self.addr
    }
}

/// A new [`ClosedPort`].
pub fn closed_port() -> ClosedPort {
    use nix::sys::socket::{
        AddressFamily, SockFlag, SockType, SockaddrIn, bind, getsockname, socket,
    };
    let socket = socket(
        AddressFamily::Inet,
        SockType::Stream,
        SockFlag::SOCK_CLOEXEC,
        None,
    )
    .expect("a TCP socket");
    bind(socket.as_raw_fd(), &SockaddrIn::new(127, 0, 0, 1, 0)).expect("bind on the loopback");
    let bound: SockaddrIn = getsockname(socket.as_raw_fd()).expect("the bound port");
    ClosedPort {
        _socket: socket,
        addr: format!("127.0.0.1:{}", bound.port()),
    }
}

/// The lines of a child's pipe (its stdout or stderr) as they come, read on a thread of
/// their own so that a test can wait for one with a deadline.
pub fn lines_of(pipe: impl Read + Send + 'static) -> Receiver<String> {
    let (sender, lines) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(pipe).lines().map_while(Result::ok) {
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    lines
}

/// Collects the lines that come into `seen` until one contains `text`. After `limit`
/// without it (or when the pipe closed first), the error says what came instead.
pub fn wait_for_line(
    lines: &Receiver<String>,
    seen: &mut Vec<String>,
    text: &str,
    limit: Duration,
) -> Result<(), String> {
    let deadline = Instant::now() + limit;
    while !seen.iter().any(|line| line.contains(text)) {
        let left = deadline.saturating_duration_since(Instant::now());
        match lines.recv_timeout(left) {
            Ok(line) => seen.push(line),
            Err(e) => {
                return Err(format!(
                    "no line with {text:?} ({e}); so far:\n{}",
                    seen.join("\n")
                ));
            }
        }
    }
    Ok(())
}

/// Sends SIGTERM to `child`, as a user or a supervisor stops a stage.
///
/// Through kill(1) rather than kill(2): a test then needs no `unsafe`, and no binding
/// crate beyond the standard library.
pub fn terminate(child: &Child) {
    let status = Command::new("kill")
        .args(["-s", "TERM", &child.id().to_string()])
        .status()
        .expect("run kill(1)");
    assert!(status.success(), "kill -s TERM {}: {status}", child.id());
}

/// A child stopped with SIGTERM: its exit status and output, and how long it took to go.
pub struct Stopped {
    pub output: Output,
    pub took: Duration,
}

/// Sends SIGTERM to `child` ([`terminate`]) and waits for it at most `limit` ([`finish`]),
/// timing how long it took to stop.
pub fn stop(child: Child, limit: Duration) -> Stopped {
    terminate(&child);
    let signalled = Instant::now();
    let output = finish(child, limit);
    Stopped {
        output,
        took: signalled.elapsed(),
    }
}

/// Waits for `child` at most `limit` and returns its exit status and output; kills it and
/// fails the test past that, with its stderr.
pub fn finish(mut child: Child, limit: Duration) -> Output {
    let deadline = Instant::now() + limit;
    while child.try_wait().expect("poll the child").is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            let output = child.wait_with_output().expect("reap the child");
            panic!(
                "still running after {limit:?}; stderr:\n{}",
                String::from_utf8_lossy(&output.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    child
        .wait_with_output()
        .expect("collect the child's output")
}

/// Runs `command` with each of `rates` as `--rate` and checks that clap refused it (exit
/// status 2) with `range` (the unit's wording of the allowed rates) in the message, no
/// panic, and before the process announced `ready` on stdout.
pub fn assert_rates_refused(command: impl Fn() -> Command, rates: &[&str], range: &str) {
    for rate in rates {
        let output = command()
            .arg(format!("--rate={rate}"))
            .output()
            .expect("run the process");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "--rate {rate}: {stderr}");
        assert!(
            stderr.contains(&format!("invalid value '{rate}' for '--rate <RATE>'")),
            "--rate {rate}: {stderr}"
        );
        assert!(stderr.contains(range), "--rate {rate}: {stderr}");
        assert!(!stderr.contains("panicked"), "--rate {rate}: {stderr}");
        assert!(output.stdout.is_empty(), "refused before announcing ready");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_terminated_child_is_finished_by_the_signal() {
        let child = Command::new("sleep").arg("60").spawn().unwrap();
        terminate(&child);
        let output = finish(child, Duration::from_secs(10));
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(output.status.signal(), Some(15), "SIGTERM");
    }

    #[test]
    fn a_stopped_child_is_timed() {
        let child = Command::new("sleep").arg("60").spawn().unwrap();
        let stopped = stop(child, Duration::from_secs(10));
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(stopped.output.status.signal(), Some(15), "SIGTERM");
        assert!(stopped.took < Duration::from_secs(10), "{:?}", stopped.took);
    }

    #[test]
    fn a_fixture_holds_its_text() {
        let path = fixture("test-child-fixture", "a.txt", "one\ntwo\n");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "one\ntwo\n");
        assert!(path.ends_with("a.txt"));
    }

    #[test]
    fn a_closed_port_refuses_a_connection() {
        let port = closed_port();
        let addr = port.addr();
        let refused = std::net::TcpStream::connect(addr).unwrap_err();
        assert_eq!(
            refused.kind(),
            std::io::ErrorKind::ConnectionRefused,
            "{addr}"
        );
    }

    #[test]
    fn a_line_is_waited_for_and_its_absence_named() {
        let mut child = Command::new("sh")
            .args(["-c", "echo one; echo two"])
            .stdout(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let lines = lines_of(child.stdout.take().unwrap());
        let mut seen = Vec::new();
        wait_for_line(&lines, &mut seen, "two", Duration::from_secs(10)).unwrap();
        assert_eq!(seen, ["one", "two"]);
        let error = wait_for_line(&lines, &mut seen, "three", Duration::from_secs(10));
        assert!(error.unwrap_err().contains("no line with \"three\""));
        child.wait().unwrap();
    }

    #[test]
    #[should_panic(expected = "still running after")]
    fn a_child_past_its_deadline_fails_the_test() {
        let child = Command::new("sleep").arg("60").spawn().unwrap();
        finish(child, Duration::from_millis(100));
    }
}
