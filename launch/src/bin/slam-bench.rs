//! `slam-bench`: runs slam-launch on every benchmark log of a directory and compares the
//! relative-pose errors with the published ones.
//!
//! It lives in the launch crate because it is a driver of slam-launch: it finds the logs'
//! relations the way slam-launch does, runs slam-launch as a user would and reads each
//! run's typed metrics.json; the scoring itself stays in slam-eval (through map-sink), so
//! slam-eval remains a library of the metric with no process to run.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Parser;
use launch::bench::report::{BenchReport, LogResult, SeedRun};
use launch::bench::seeds::parse_seeds;
use launch::bench::table;
use launch::relations::relations_beside;
use map_sink::write_atomic;
use slam_eval::{METRICS_FILE, Metrics};

/// Runs slam-launch on every log in DIR that has a relations file beside it (CARMEN `.clf`
/// for now), once per seed, and prints a table of the relative-pose errors (Kuemmerle et
/// al. 2009) next to the published ones; writes the same as JSON to OUT/bench.json.
#[derive(Debug, Parser)]
#[command(name = "slam-bench", version)]
struct Args {
    /// Directory with the logs (NAME.clf beside NAME.relations).
    dir: PathBuf,
    /// Particles of the filter.
    #[arg(long, default_value_t = 100)]
    particles: usize,
    /// Seeds to run each log with: a range (1-5), a list (1,2,3) or both (1-3,7).
    #[arg(long, default_value = "1")]
    seeds: String,
    /// Where the runs (OUT/<log>/seed-<n>/) and bench.json go.
    #[arg(long, value_name = "DIR", default_value = "runs/bench")]
    out: PathBuf,
    /// TOML configuration passed to every slam-launch run.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Scans to replay of each log (default: all).
    #[arg(long)]
    frames: Option<u64>,
    /// Replay every N-th scan of each log (all its odometry): harder versions of the logs,
    /// as from a slower sensor.
    #[arg(long, value_name = "N")]
    every: Option<u64>,
    /// Replay the logs' ranges beyond this many metres as no-returns, as from a
    /// shorter-range sensor.
    #[arg(long, value_name = "METRES")]
    max_range: Option<f64>,
}

/// The log format slam-bench knows, by extension, and its name for slam-launch.
const LOG_EXTENSION: &str = "clf";
const LOG_FORMAT: &str = "carmen";
/// The report's file in the output directory.
const REPORT_FILE: &str = "bench.json";

fn main() -> ExitCode {
    stage_kit::run_tool("slam-bench", run)
}

fn run(args: Args) -> Result<()> {
    let seeds = parse_seeds(&args.seeds).context("--seeds")?;
    anyhow::ensure!(args.particles > 0, "--particles must be at least 1");
    let degradation = lidar_replay::Degradation::new(args.every.unwrap_or(1), args.max_range)?;
    if !degradation.is_none() {
        eprintln!("slam-bench: the logs replayed harder: {degradation}");
    }
    let launcher = std::env::current_exe()
        .context("cannot find this program's path")?
        .with_file_name("slam-launch");
    anyhow::ensure!(
        launcher.is_file(),
        "{} not found; build the workspace first (cargo build --release --workspace)",
        launcher.display()
    );
    let logs = benchmark_logs(&args.dir)?;

    let mut results = Vec::new();
    for (log, relations) in logs {
        let name = stem(&log);
        let mut runs = Vec::new();
        for &seed in &seeds {
            let out = args.out.join(&name).join(format!("seed-{seed}"));
            let run = run_once(&launcher, &args, &log, &relations, seed, &out)
                .with_context(|| format!("{name}, seed {seed}"))?;
            eprintln!("{name} seed {seed}: {}", progress(&run));
            runs.push(run);
        }
        results.push(LogResult::new(name, log, relations, runs));
    }

    let report = BenchReport {
        every: args.every,
        max_range_m: args.max_range,
        ..BenchReport::new(
            args.particles,
            seeds,
            args.config.clone(),
            args.frames,
            results,
        )
    };
    print!("{}", table::render(&report));
    let path = args.out.join(REPORT_FILE);
    let mut json = serde_json::to_string_pretty(&report).context("cannot format the report")?;
    json.push('\n');
    write_atomic(&path, json.as_bytes())?;
    eprintln!("written to {}", path.display());
    Ok(())
}

/// The logs of `dir` with a relations file beside them, in name order.
fn benchmark_logs(dir: &Path) -> Result<Vec<(PathBuf, PathBuf)>> {
    let entries = std::fs::read_dir(dir)
        .with_context(|| format!("cannot read directory {}", dir.display()))?;
    let mut logs = Vec::new();
    for entry in entries {
        let path = entry
            .with_context(|| format!("cannot read directory {}", dir.display()))?
            .path();
        if path.extension().is_some_and(|e| e == LOG_EXTENSION)
            && let Some(relations) = relations_beside(&path)
        {
            logs.push((path, relations));
        }
    }
    if logs.is_empty() {
        bail!(
            "{} has no .{LOG_EXTENSION} log with a .relations file beside it",
            dir.display()
        );
    }
    logs.sort();
    Ok(logs)
}

/// Runs slam-launch once and reads what it wrote.
fn run_once(
    launcher: &Path,
    args: &Args,
    log: &Path,
    relations: &Path,
    seed: u64,
    out: &Path,
) -> Result<SeedRun> {
    let mut command = Command::new(launcher);
    command
        .arg("--quiet")
        .arg("--replay")
        .arg(log)
        .args(["--format", LOG_FORMAT])
        .arg("--relations")
        .arg(relations)
        .args(["--particles", &args.particles.to_string()])
        .args(["--seed", &seed.to_string()])
        .arg("--out")
        .arg(out);
    if let Some(config) = &args.config {
        command.arg("--config").arg(config);
    }
    if let Some(every) = args.every {
        command.args(["--replay-every", &every.to_string()]);
    }
    if let Some(metres) = args.max_range {
        command.args(["--replay-max-range", &metres.to_string()]);
    }
    if let Some(frames) = args.frames {
        command.args(["--frames", &frames.to_string()]);
    }
    // A killed slam-bench takes its run with it, as slam-launch does its stages.
    stage_kit::launcher_watch::started_by_this_process(&mut command);
    let started = Instant::now();
    let output = command
        .output()
        .with_context(|| format!("cannot start {}", launcher.display()))?;
    let wall_s = started.elapsed().as_secs_f64();
    if !output.status.success() {
        bail!(
            "slam-launch failed ({}): {}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    let path = out.join(METRICS_FILE);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let metrics: Metrics = serde_json::from_str(&text)
        .with_context(|| format!("{} is not the metrics map-sink writes", path.display()))?;
    Ok(SeedRun {
        seed,
        out: out.to_path_buf(),
        wall_s,
        metrics,
    })
}

/// A run's result in a few words, for the progress on stderr.
fn progress(run: &SeedRun) -> String {
    let error = run
        .metrics
        .relative_pose_error
        .as_ref()
        .and_then(|rpe| rpe.trajectory)
        .and_then(|s| s.errors)
        .map_or_else(
            || "no score".to_owned(),
            |e| format!("{:.3} m", e.translation_m.mean),
        );
    format!("{error} in {:.1} s", run.wall_s)
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
