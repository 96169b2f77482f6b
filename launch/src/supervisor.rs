//! Runs the stages of a pipeline to completion, failure or interruption.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use ipc_types::Domain;
use nix::sys::signal::Signal;
use stage_kit::{say_err, shutdown};

use crate::losses::Losses;
use crate::stage::{Stage, StageError, StageEvent, describe};
use crate::stall::{StallLimits, StallReport, StallWatch};
use crate::status::Progress;

/// How long every stage has to print `ready`.
const READY_TIMEOUT: Duration = Duration::from_secs(60);
/// How long stopped stages have to finish writing before they are killed.
pub const STOP_GRACE: Duration = Duration::from_secs(30);
/// How often the stages are looked at (and their memory read).
pub const POLL: Duration = Duration::from_millis(50);

/// A process to start.
#[derive(Debug, Clone)]
pub struct StagePlan {
    pub name: String,
    pub program: PathBuf,
    pub args: Vec<String>,
    /// The run goes on without it if it dies (the recorder: the run's results matter more
    /// than its recording); its death is reported, not a failure.
    pub expendable: bool,
    /// It has no end of its own (the live view): the run is over when every other stage
    /// has ended, and then it is stopped.
    pub ends_with_run: bool,
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Every stage exited 0 after the source finished.
    Finished,
    /// Ctrl-C or SIGTERM; every stage was stopped. `source_failure` is the source's last
    /// line on stderr when it exited non-zero all the same (lidar-hokuyo: no scan arrived).
    Interrupted { source_failure: Option<String> },
    /// A stage died or the pipeline stalled; the message says which and why.
    Failed(String),
}

/// How a run ended, what its stages reported losing, and their peak memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Ended {
    pub outcome: Outcome,
    pub losses: Losses,
    /// Each stage's peak resident memory, read while it ran (every [`POLL`]) and told by it
    /// as it ended, KiB.
    pub peak_memory_kib: Vec<(String, u64)>,
}

/// Options of the progress display.
#[derive(Debug, Clone)]
pub struct Display {
    pub label: String,
    pub total_frames: Option<u64>,
    pub quiet: bool,
}

/// Starts `plan` in order (the source last), supervises it and stops it; a stage that
/// makes no progress is reported and fails the run after `stall`'s times (see
/// [`crate::stall`]). The stages must all use `domain`.
pub fn run(
    plan: &[StagePlan],
    domain: &Domain,
    log_dir: &Path,
    display: &Display,
    stall: &StallLimits,
) -> Result<Ended, StageError> {
    let (sender, events) = mpsc::channel();
    let mut stages = Vec::with_capacity(plan.len());
    for (index, stage) in plan.iter().enumerate() {
        match Stage::spawn(
            index,
            &stage.name,
            &stage.program,
            &stage.args,
            log_dir,
            sender.clone(),
        ) {
            Ok(stage) => stages.push(stage),
            Err(e) => {
                stop_all(&mut stages, domain);
                return Err(e);
            }
        }
    }
    drop(sender);

    let mut printer = Printer::new(display);
    let mut progress = Progress::default();
    let mut ready = vec![false; stages.len()];
    let started = Instant::now();
    let mut last_progress = (0, Instant::now());
    let source = stages.len().saturating_sub(1);
    let names: Vec<String> = stages.iter().map(|s| s.name.clone()).collect();
    let mut watch = StallWatch::new(&names, source, *stall, Instant::now());
    let mut all_ready = false;
    let mut losses = Losses::new(&names);
    let expendable: Vec<bool> = plan.iter().map(|p| p.expendable).collect();
    let ends_with_run: Vec<bool> = plan.iter().map(|p| p.ends_with_run).collect();
    let mut lost = vec![false; stages.len()];

    let outcome = loop {
        for stage in &mut stages {
            stage.sample_memory();
        }
        while let Ok(event) = events.try_recv() {
            match event {
                StageEvent::Ready(i) => ready[i] = true,
                StageEvent::Status(_, line) => progress.update(&line),
                StageEvent::Progress(i, line) => {
                    if let Some(StallReport::Resumed { stage, after }) =
                        watch.update(i, &line, Instant::now())
                    {
                        printer.warn(&format!(
                            "{stage} moves again after {:.1} s",
                            after.as_secs_f64()
                        ));
                    }
                }
                StageEvent::Losses(i, counts) => losses.record(i, counts),
                StageEvent::Line(i, line) => printer.line(&stages[i].name, &line),
            }
        }
        printer.progress(&progress);

        if shutdown::requested() {
            stop_all(&mut stages, domain);
            // A source may fail its run even when stopped: a live one that got no scan.
            let source_failure = stages.get_mut(source).and_then(|stage| {
                if stage.poll_exit().is_none_or(|status| status.success()) {
                    return None;
                }
                // Its own last word: iceoryx2's log lines may come after it.
                let own = format!("{}: ", stage.name);
                let tail = stage.stderr_tail();
                let last = tail.iter().rev().find(|line| line.starts_with(&own));
                Some(last.or(tail.last()).cloned().unwrap_or_default())
            });
            break Outcome::Interrupted { source_failure };
        }

        let mut all_done = true;
        let mut failure = None;
        for (i, stage) in stages.iter_mut().enumerate() {
            match stage.poll_exit() {
                None if ends_with_run[i] => {}
                None => all_done = false,
                Some(status) if status.success() => {}
                Some(_) if lost[i] => {}
                Some(status) if expendable[i] => {
                    lost[i] = true;
                    // Its node is dead: clean it up at once so no publisher blocks on it.
                    domain.cleanup_dead_nodes();
                    let tail = stage.stderr_tail();
                    printer.warn(&format!(
                        "{} died ({}); the run goes on without it; last lines of its \
                         stderr:\n  {}",
                        stage.name,
                        describe(status),
                        tail.join("\n  ")
                    ));
                }
                Some(status) => {
                    failure.get_or_insert_with(|| {
                        let tail = stage.stderr_tail();
                        format!(
                            "{} died ({}); last lines of its stderr:\n  {}",
                            stage.name,
                            describe(status),
                            tail.join("\n  ")
                        )
                    });
                }
            }
        }
        if let Some(message) = failure {
            // Its node is dead: clean it up at once so no publisher blocks on it.
            domain.cleanup_dead_nodes();
            stop_all(&mut stages, domain);
            break Outcome::Failed(message);
        }
        if all_done {
            stop_those_left(&mut stages, domain);
            break Outcome::Finished;
        }

        if !ready.iter().all(|&r| r) && started.elapsed() > READY_TIMEOUT {
            let waiting: Vec<String> = stages
                .iter()
                .zip(&ready)
                .filter(|(_, r)| !**r)
                .map(|(s, _)| s.name.clone())
                .collect();
            stop_all(&mut stages, domain);
            break Outcome::Failed(format!(
                "not ready after {} s: {}",
                READY_TIMEOUT.as_secs(),
                waiting.join(", ")
            ));
        }
        if !all_ready && ready.iter().all(|&r| r) {
            // Starting is the ready timeout's business, not a stall.
            all_ready = true;
            watch.restart(Instant::now());
        }
        if all_ready {
            let running: Vec<bool> = stages.iter_mut().map(|s| s.poll_exit().is_none()).collect();
            let mut failed = None;
            for report in watch.check(&running, Instant::now()) {
                match report {
                    StallReport::Stalled { message, .. } => printer.warn(&message),
                    StallReport::Failed { message, .. } => {
                        failed.get_or_insert(message);
                    }
                    StallReport::Resumed { .. } => {}
                }
            }
            if let Some(message) = failed {
                stop_all(&mut stages, domain);
                break Outcome::Failed(message);
            }
        }
        if progress.frames() != last_progress.0 {
            last_progress = (progress.frames(), Instant::now());
        }
        // Once the source has ended no stage may have input pending and yet the run not be
        // over: one finishing its output for ever (the final path, the picture).
        let source_done = stages
            .get_mut(source)
            .is_some_and(|s| s.poll_exit().is_some());
        let moved = watch
            .last_moved()
            .map_or(last_progress.1, |t| t.max(last_progress.1));
        if source_done && moved.elapsed() > stall.limit {
            let still: Vec<String> = stages
                .iter_mut()
                .filter_map(|s| s.poll_exit().is_none().then(|| s.name.clone()))
                .collect();
            stop_all(&mut stages, domain);
            break Outcome::Failed(format!(
                "no progress for {} s after the source finished (stalled at {} scans; still \
                 running: {})",
                stall.limit.as_secs_f64(),
                progress.frames(),
                still.join(", ")
            ));
        }
        std::thread::sleep(POLL);
    };
    // Every stage has ended: once their readers are done, every event is in the channel.
    for stage in &mut stages {
        stage.join_stdout();
    }
    while let Ok(event) = events.try_recv() {
        match event {
            StageEvent::Status(_, line) => progress.update(&line),
            StageEvent::Losses(i, counts) => losses.record(i, counts),
            _ => {}
        }
    }
    printer.finish(&progress);
    // Even in quiet mode: what a stage could not do is part of the result.
    for stage in &mut stages {
        for line in stage.closing_summary() {
            say_err(&line);
        }
    }
    for stage in &mut stages {
        if let Some(stopped) = stage.log_stopped() {
            say_err(&format!("slam-launch: incomplete: {}", stopped.line()));
        }
    }
    let peak_memory_kib = stages
        .iter()
        .filter_map(|s| Some((s.name.clone(), s.peak_memory_kib()?)))
        .collect();
    Ok(Ended {
        outcome,
        losses,
        peak_memory_kib,
    })
}

/// Stops the stages still running once the run is over (those that end with it).
fn stop_those_left(stages: &mut [Stage], domain: &Domain) {
    if stages.iter_mut().any(|s| s.poll_exit().is_none()) {
        stop_all(stages, domain);
    }
}

/// SIGTERM to every stage, the source first so the stream ends; then waits for them to
/// finish writing and kills whoever has not after the grace period.
fn stop_all(stages: &mut [Stage], domain: &Domain) {
    for stage in stages.iter_mut().rev() {
        stage.signal(Signal::SIGTERM);
        // A stage frozen by SIGSTOP (a stall, or Ctrl-Z sent to it alone) would sit on
        // the SIGTERM until the grace period ends and it is killed: wake it so it stops
        // as the others do (map-sink writing its results). A running one ignores it.
        stage.signal(Signal::SIGCONT);
    }
    let deadline = Instant::now() + STOP_GRACE;
    while Instant::now() < deadline && stages.iter_mut().any(|s| s.poll_exit().is_none()) {
        std::thread::sleep(POLL);
    }
    for stage in stages.iter_mut() {
        if stage.poll_exit().is_none() {
            say_err(&format!(
                "{} did not stop within {} s; killed",
                stage.name,
                STOP_GRACE.as_secs()
            ));
            stage.kill();
        }
    }
    domain.cleanup_dead_nodes();
}

/// Writes progress: a live line on a terminal, a plain line every few seconds otherwise.
struct Printer {
    label: String,
    total: Option<u64>,
    quiet: bool,
    live: bool,
    last: Instant,
    shown: bool,
}

impl Printer {
    fn new(display: &Display) -> Self {
        Self {
            label: display.label.clone(),
            total: display.total_frames,
            quiet: display.quiet,
            live: std::io::stderr().is_terminal(),
            last: Instant::now(),
            shown: false,
        }
    }

    fn line(&mut self, stage: &str, line: &str) {
        if self.quiet {
            return;
        }
        self.clear();
        say_err(&format!("[{stage}] {line}"));
    }

    fn progress(&mut self, progress: &Progress) {
        if self.quiet || progress.frames() == 0 {
            return;
        }
        let period = if self.live {
            Duration::from_millis(200)
        } else {
            Duration::from_secs(5)
        };
        if self.last.elapsed() < period {
            return;
        }
        self.last = Instant::now();
        let text = format!("{}: {}", self.label, progress.render(self.total));
        if self.live {
            let _ = write!(std::io::stderr(), "\r\x1b[K{text}");
            let _ = std::io::stderr().flush();
            self.shown = true;
        } else {
            say_err(&text);
        }
    }

    /// A problem of the run, shown even in quiet mode (like the closing summaries).
    fn warn(&mut self, text: &str) {
        self.clear();
        say_err(&format!("slam-launch: {text}"));
    }

    fn clear(&mut self) {
        if self.shown {
            let _ = write!(std::io::stderr(), "\r\x1b[K");
            self.shown = false;
        }
    }

    fn finish(&mut self, progress: &Progress) {
        self.clear();
        if !self.quiet && progress.frames() > 0 {
            say_err(&format!("{}: {}", self.label, progress.render(self.total)));
        }
    }
}
