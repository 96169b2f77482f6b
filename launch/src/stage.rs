//! One child process of the pipeline: started, watched through its output, stopped.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};

use map_sink::LineFile;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use slam_eval::IncompleteOutput;
use stage_kit::say_err;

use crate::closing::ClosingSummary;

/// Lines of a child's stderr kept to explain its death.
const STDERR_TAIL: usize = 20;

/// What a child said on stdout, line by line.
#[derive(Debug, Clone, PartialEq)]
pub enum StageEvent {
    /// The child's ports are connected (`ready`).
    Ready(usize),
    /// A `status key=value ...` progress line (map-sink's).
    Status(usize, String),
    /// A `progress in:TOPIC=N out:TOPIC=N ...` line: what the stage received and sent
    /// (`ipc_types::progress`), without its first word.
    Progress(usize, String),
    /// A `losses key=count ...` line: what the stage skipped or lost, as it ends
    /// (`ipc_types::losses`).
    Losses(usize, Vec<(String, u64)>),
    /// Any other line.
    Line(usize, String),
}

/// Why a stage could not be started.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    #[error("cannot start {name} ({program}): {source}")]
    Spawn {
        name: String,
        program: String,
        source: std::io::Error,
    },
    #[error("cannot create the stage's log file")]
    Log(#[source] map_sink::SinkError),
}

/// A running child.
#[derive(Debug)]
pub struct Stage {
    pub name: String,
    child: Child,
    stderr_tail: Arc<Mutex<VecDeque<String>>>,
    summary: Arc<Mutex<ClosingSummary>>,
    log_stopped: Arc<Mutex<Option<IncompleteOutput>>>,
    stdout_reader: Option<std::thread::JoinHandle<()>>,
    stderr_reader: Option<std::thread::JoinHandle<()>>,
    exit: Option<ExitStatus>,
    /// The child's peak resident memory at the last reading, KiB.
    peak_kib: Option<u64>,
    /// The peak the child told as it ended (its stdout), KiB; 0 until then.
    told_peak_kib: Arc<AtomicU64>,
}

impl Stage {
    /// Starts `program args` as stage `index`; stdout lines become events, stderr goes to
    /// `log_dir/<name>.log` (whole lines; a log that cannot be written, a full disk, stops
    /// there and says so on the console) and its last lines are kept. The child is sent
    /// SIGTERM when the calling thread ends (`stage_kit::launcher_watch`): call it from the
    /// thread that lives as long as the run, the main thread.
    pub fn spawn(
        index: usize,
        name: &str,
        program: &Path,
        args: &[String],
        log_dir: &Path,
        events: Sender<StageEvent>,
    ) -> Result<Self, StageError> {
        let log_path = log_dir.join(format!("{name}.log"));
        let mut log = LineFile::create(&log_path).map_err(StageError::Log)?;
        let log_stopped = Arc::new(Mutex::new(None));
        let mut log_line = {
            let log_stopped = Arc::clone(&log_stopped);
            let file_name = format!("logs/{name}.log");
            let mut writing = true;
            move |line: &str| {
                if !writing {
                    return;
                }
                if let Err(e) = log.append(&format!("{line}\n")) {
                    writing = false;
                    let what = format!("stopped after {} lines", log.lines());
                    let stopped = IncompleteOutput::new(&file_name, &what, &e);
                    say_err(&format!("slam-launch: {}", stopped.line()));
                    if let Ok(mut slot) = log_stopped.lock() {
                        *slot = Some(stopped);
                    }
                }
            }
        };
        log_line(&format!("$ {} {}", program.display(), args.join(" ")));
        let mut command = Command::new(program);
        command
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            // Each stage reports what it took in and sent out (see ipc_types::progress),
            // which is how the supervisor tells which stage has stalled.
            .env(ipc_types::progress::ENV, "1");
        // The child dies with this process, however it dies (SIGKILL included), so no
        // stage outlives the launcher holding its shared memory with nobody to stop it.
        stage_kit::launcher_watch::started_by_this_process(&mut command);
        let mut child = command.spawn().map_err(|source| StageError::Spawn {
            name: name.to_owned(),
            program: program.display().to_string(),
            source,
        })?;
        let mut stdout_reader = None;
        let told_peak_kib = Arc::new(AtomicU64::new(0));
        if let Some(stdout) = child.stdout.take() {
            let told_peak_kib = Arc::clone(&told_peak_kib);
            stdout_reader = Some(std::thread::spawn(move || {
                for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                    if let Some(kib) = line
                        .strip_prefix(ipc_types::peak_memory::PREFIX)
                        .and_then(ipc_types::peak_memory::parse)
                    {
                        told_peak_kib.fetch_max(kib, Ordering::Relaxed);
                        continue;
                    }
                    let event = if line == "ready" {
                        StageEvent::Ready(index)
                    } else if let Some(rest) = line.strip_prefix("status ") {
                        StageEvent::Status(index, rest.to_owned())
                    } else if let Some(rest) = line
                        .strip_prefix(ipc_types::progress::PREFIX)
                        .filter(|rest| rest.is_empty() || rest.starts_with(' '))
                    {
                        StageEvent::Progress(index, rest.to_owned())
                    } else if let Some(rest) = line
                        .strip_prefix(ipc_types::losses::PREFIX)
                        .filter(|rest| rest.is_empty() || rest.starts_with(' '))
                    {
                        StageEvent::Losses(index, ipc_types::losses::parse(rest))
                    } else {
                        StageEvent::Line(index, line)
                    };
                    if events.send(event).is_err() {
                        break;
                    }
                }
            }));
        }
        let stderr_tail = Arc::new(Mutex::new(VecDeque::with_capacity(STDERR_TAIL)));
        let summary = Arc::new(Mutex::new(ClosingSummary::new(name)));
        let mut stderr_reader = None;
        if let Some(stderr) = child.stderr.take() {
            let tail = Arc::clone(&stderr_tail);
            let summary = Arc::clone(&summary);
            stderr_reader = Some(std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                    log_line(&line);
                    if let Ok(mut summary) = summary.lock() {
                        summary.take(&line);
                    }
                    if let Ok(mut tail) = tail.lock() {
                        if tail.len() == STDERR_TAIL {
                            tail.pop_front();
                        }
                        tail.push_back(line);
                    }
                }
            }));
        }
        Ok(Self {
            name: name.to_owned(),
            child,
            stderr_tail,
            summary,
            log_stopped,
            stdout_reader,
            stderr_reader,
            exit: None,
            peak_kib: None,
            told_peak_kib,
        })
    }

    /// The exit status once the child has ended (polls without blocking).
    pub fn poll_exit(&mut self) -> Option<ExitStatus> {
        if self.exit.is_none() {
            self.exit = self.child.try_wait().ok().flatten();
        }
        self.exit
    }

    /// Reads the child's peak resident memory so far, while it runs (once it has ended,
    /// /proc no longer tells).
    pub fn sample_memory(&mut self) {
        if self.poll_exit().is_none()
            && let Some(kib) = crate::memory::peak_resident_kib(Some(self.child.id()))
        {
            self.peak_kib = Some(kib);
        }
    }

    /// The child's peak resident memory, KiB: the larger of the last reading and what it
    /// told as it ended (once [`Stage::join_stdout`] has read that).
    pub fn peak_memory_kib(&self) -> Option<u64> {
        let told = Some(self.told_peak_kib.load(Ordering::Relaxed)).filter(|&kib| kib > 0);
        self.peak_kib.max(told)
    }

    /// The last lines the child wrote to stderr; once it has ended, all of them up to its end.
    pub fn stderr_tail(&mut self) -> Vec<String> {
        self.join_stderr();
        self.stderr_tail
            .lock()
            .map(|tail| tail.iter().cloned().collect())
            .unwrap_or_default()
    }

    /// The stage's closing summary (see [`crate::closing`]); once it has ended, its last.
    pub fn closing_summary(&mut self) -> Vec<String> {
        self.join_stderr();
        self.summary
            .lock()
            .map(|summary| summary.lines().to_vec())
            .unwrap_or_default()
    }

    /// The stage's log file, if it could not be written to the end; once it has ended, for
    /// good.
    pub fn log_stopped(&mut self) -> Option<IncompleteOutput> {
        self.join_stderr();
        self.log_stopped
            .lock()
            .ok()
            .and_then(|stopped| stopped.clone())
    }

    /// Once the child has ended, waits until every event of its stdout has been sent (its
    /// last line, the losses, may come after the exit was seen).
    pub fn join_stdout(&mut self) {
        if self.poll_exit().is_some()
            && let Some(reader) = self.stdout_reader.take()
        {
            // The pipe closes with the child, so this returns as soon as the last line is in.
            let _ = reader.join();
        }
    }

    /// Once the child has ended, waits until its last stderr line is in.
    fn join_stderr(&mut self) {
        if self.poll_exit().is_some()
            && let Some(reader) = self.stderr_reader.take()
        {
            // The pipe closes with the child, so this returns as soon as the last line is in.
            let _ = reader.join();
        }
    }

    /// Sends `signal` unless the child has already ended (and so not to a pid that may have
    /// been given to another process since it was reaped).
    pub fn signal(&mut self, signal: Signal) {
        if self.poll_exit().is_some() {
            return;
        }
        if let Ok(pid) = i32::try_from(self.child.id()) {
            // A child that ends just now is a zombie until we reap it: the pid is still ours.
            let _ = kill(Pid::from_raw(pid), signal);
        }
    }

    /// Kills the child for good and reaps it.
    pub fn kill(&mut self) {
        if self.poll_exit().is_none() {
            let _ = self.child.kill();
            self.exit = self.child.wait().ok();
        }
    }
}

/// Describes how a child ended, e.g. `exit status 2` or `killed by signal 9`; a SIGBUS with
/// what /dev/shm has left (see [`crate::shm_room`]).
pub fn describe(status: ExitStatus) -> String {
    use std::os::unix::process::ExitStatusExt;
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exit status {code}"),
        (None, Some(signal)) if signal == nix::sys::signal::Signal::SIGBUS as i32 => {
            crate::shm_room::sigbus_explanation()
        }
        (None, Some(signal)) => format!("killed by signal {signal}"),
        _ => status.to_string(),
    }
}
