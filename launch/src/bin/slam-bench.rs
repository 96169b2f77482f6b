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
use launch::bench::report::{BenchReport, FailedRun, LogResult, SeedRun, WorldResult};
use launch::bench::seeds::parse_seeds;
use launch::bench::{markdown, provenance, published, table};
use launch::memory::{MEMORY_FILE, RunMemory};
use launch::relations::relations_beside;
use map_sink::write_atomic;
use slam_eval::{METRICS_FILE, Metrics};

/// Runs slam-launch on every log in DIR that has a relations file beside it (CARMEN `.clf`
/// for now), once per seed, and on the simulated worlds, and prints a table of the
/// relative-pose errors (Kuemmerle et al. 2009) next to the published ones; writes the
/// same as JSON to OUT/bench.json.
///
/// It also writes the results as Markdown: to --markdown FILE, or, without that option,
/// to the docs/RESULTS.md of the workspace it was built in when the run is the whole
/// benchmark: DIR holds every log with published figures (aces, fr079, intel, mit-csail)
/// and no option changes the logs or the configuration (--frames, --every, --max-range,
/// --config). --markdown-from OUT/bench.json writes the Markdown of an earlier benchmark
/// without running anything (to --markdown FILE, or to stdout).
#[derive(Debug, Parser)]
#[command(name = "slam-bench", version)]
struct Args {
    /// Directory with the logs (NAME.clf beside NAME.relations).
    #[arg(required_unless_present = "markdown_from")]
    dir: Option<PathBuf>,
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
    /// Simulated worlds to run too, with the same particles and seeds (comma-separated);
    /// `none` for none.
    #[arg(long, value_name = "NAMES", default_value = "hall,office,corridor")]
    worlds: String,
    /// Write the results as Markdown to FILE (docs/RESULTS.md's form).
    #[arg(long, value_name = "FILE")]
    markdown: Option<PathBuf>,
    /// Run nothing: read this bench.json of an earlier benchmark and write its Markdown
    /// (to --markdown FILE, or to stdout).
    #[arg(long, value_name = "BENCH_JSON", conflicts_with = "dir")]
    markdown_from: Option<PathBuf>,
}

/// The workspace's results page, which the whole benchmark rewrites.
const RESULTS_PAGE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/RESULTS.md");

/// The log format slam-bench knows, by extension, and its name for slam-launch.
const LOG_EXTENSION: &str = "clf";
const LOG_FORMAT: &str = "carmen";
/// The report's file in the output directory.
const REPORT_FILE: &str = "bench.json";

fn main() -> ExitCode {
    stage_kit::run_tool("slam-bench", run)
}

fn run(args: Args) -> Result<()> {
    if let Some(json) = &args.markdown_from {
        return markdown_from(json, args.markdown.as_deref());
    }
    let dir = args.dir.clone().context("a directory of logs is needed")?;
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
    let logs = benchmark_logs(&dir)?;
    let started = std::time::SystemTime::now();
    let mut failures = Vec::new();
    let mut results = Vec::new();
    for (log, relations) in &logs {
        let name = stem(log);
        let source = Source::Log { log, relations };
        let runs = run_seeds(&launcher, &args, &seeds, &source, &name, &mut failures);
        results.push(LogResult::new(name, log.clone(), relations.clone(), runs));
    }
    let mut worlds = Vec::new();
    for world in world_names(&args.worlds) {
        let source = Source::World(&world);
        let name = format!("world-{world}");
        let runs = run_seeds(&launcher, &args, &seeds, &source, &name, &mut failures);
        worlds.push(WorldResult { world, runs });
    }
    let report = BenchReport {
        every: args.every,
        max_range_m: args.max_range,
        worlds,
        commit: provenance::commit(Path::new(env!("CARGO_MANIFEST_DIR"))),
        started_utc: Some(provenance::utc_minutes(started)),
        processors: std::thread::available_parallelism().ok().map(|n| n.get()),
        failures,
        ..BenchReport::new(
            args.particles,
            seeds,
            args.config.clone(),
            args.frames,
            results,
        )
    };
    write_report(&args, &logs, &report)?;
    // Written all the same, with the failures listed: a long benchmark is not lost to one
    // run, and the failure is not hidden either.
    anyhow::ensure!(
        report.failures.is_empty(),
        "{} run(s) failed: {}",
        report.failures.len(),
        report
            .failures
            .iter()
            .map(|f| format!("{} seed {}", f.run, f.seed))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// The table on the console, OUT/bench.json and, where it goes, the Markdown.
fn write_report(args: &Args, logs: &[(PathBuf, PathBuf)], report: &BenchReport) -> Result<()> {
    print!("{}", table::render(report));
    let path = args.out.join(REPORT_FILE);
    let mut json = serde_json::to_string_pretty(report).context("cannot format the report")?;
    json.push('\n');
    write_atomic(&path, json.as_bytes())?;
    eprintln!("written to {}", path.display());
    if let Some(page) = results_page(args, logs) {
        write_atomic(&page, markdown::render(report).as_bytes())?;
        eprintln!("results written to {}", page.display());
    }
    Ok(())
}

/// Where the Markdown goes: --markdown, or the workspace's docs/RESULTS.md when the run is
/// the whole benchmark (every log with published figures, whole, default configuration).
fn results_page(args: &Args, logs: &[(PathBuf, PathBuf)]) -> Option<PathBuf> {
    if let Some(file) = &args.markdown {
        return Some(file.clone());
    }
    let names: Vec<String> = logs.iter().map(|(log, _)| stem(log)).collect();
    let every_log = published::logs().all(|log| names.iter().any(|n| n == log));
    let whole = args.frames.is_none()
        && args.every.is_none()
        && args.max_range.is_none()
        && args.config.is_none();
    let page = PathBuf::from(RESULTS_PAGE);
    (every_log && whole && page.parent().is_some_and(Path::is_dir)).then_some(page)
}

/// `--markdown-from`: the Markdown of an earlier benchmark's bench.json.
fn markdown_from(json: &Path, to: Option<&Path>) -> Result<()> {
    let text =
        std::fs::read_to_string(json).with_context(|| format!("cannot read {}", json.display()))?;
    let report: BenchReport = serde_json::from_str(&text)
        .with_context(|| format!("{} is not a report of slam-bench", json.display()))?;
    let page = markdown::render(&report);
    match to {
        Some(file) => {
            write_atomic(file, page.as_bytes())?;
            eprintln!("written to {}", file.display());
        }
        None => print!("{page}"),
    }
    Ok(())
}

/// The worlds of `--worlds`: none for `none`.
fn world_names(list: &str) -> Vec<String> {
    list.split(',')
        .map(str::trim)
        .filter(|w| !w.is_empty() && *w != "none")
        .map(str::to_owned)
        .collect()
}

/// What one series of runs replays or simulates.
enum Source<'a> {
    Log { log: &'a Path, relations: &'a Path },
    World(&'a str),
}

/// Runs `source` once per seed into OUT/<name>/seed-<n>/; a run that fails is added to
/// `failures` and the next one goes on.
fn run_seeds(
    launcher: &Path,
    args: &Args,
    seeds: &[u64],
    source: &Source,
    name: &str,
    failures: &mut Vec<FailedRun>,
) -> Vec<SeedRun> {
    let mut runs = Vec::new();
    for &seed in seeds {
        let out = args.out.join(name).join(format!("seed-{seed}"));
        match run_once(launcher, args, source, seed, &out) {
            Ok(run) => {
                eprintln!("{name} seed {seed}: {}", progress(&run));
                runs.push(run);
            }
            Err(e) => {
                eprintln!("slam-bench: {name}, seed {seed}: {e:#}");
                failures.push(FailedRun::new(name, seed, &format!("{e:#}")));
            }
        }
    }
    runs
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
    source: &Source,
    seed: u64,
    out: &Path,
) -> Result<SeedRun> {
    let mut command = Command::new(launcher);
    command.arg("--quiet");
    match source {
        Source::Log { log, relations } => {
            command
                .arg("--replay")
                .arg(log)
                .args(["--format", LOG_FORMAT])
                .arg("--relations")
                .arg(relations);
            if let Some(every) = args.every {
                command.args(["--replay-every", &every.to_string()]);
            }
            if let Some(metres) = args.max_range {
                command.args(["--replay-max-range", &metres.to_string()]);
            }
        }
        Source::World(world) => {
            command.args(["--world", world]);
        }
    }
    command
        .args(["--particles", &args.particles.to_string()])
        .args(["--seed", &seed.to_string()])
        .arg("--out")
        .arg(out);
    if let Some(config) = &args.config {
        command.arg("--config").arg(config);
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
        peak_memory_kib: read_memory(out),
    })
}

/// The peaks in the run's memory.json; none when it has none (it is a measurement, and its
/// absence is shown as such).
fn read_memory(out: &Path) -> std::collections::BTreeMap<String, u64> {
    std::fs::read_to_string(out.join(MEMORY_FILE))
        .ok()
        .and_then(|text| serde_json::from_str::<RunMemory>(&text).ok())
        .map(|memory| memory.peak_resident_kib)
        .unwrap_or_default()
}

/// A run's result in a few words, for the progress on stderr.
fn progress(run: &SeedRun) -> String {
    let rpe = run
        .metrics
        .relative_pose_error
        .as_ref()
        .and_then(|rpe| rpe.trajectory)
        .and_then(|s| s.errors)
        .map(|e| format!("{:.3} m", e.translation_m.mean));
    let ate = run.metrics.ate_rmse_m.map(|m| format!("ATE {m:.3} m"));
    let error = rpe.or(ate).unwrap_or_else(|| "no score".to_owned());
    format!("{error} in {:.1} s", run.wall_s)
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
