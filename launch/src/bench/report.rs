//! What a benchmark found, per log: ours over the seeds, and the published figures beside.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use slam_eval::{Metrics, PoseErrors, RelativePoseErrors, ScoreSummary};

use super::published::{Published, SOURCES};

/// One run of slam-launch: a log with one seed.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SeedRun {
    pub seed: u64,
    /// The run's output directory.
    pub out: PathBuf,
    /// The whole slam-launch command, start to exit, seconds.
    pub wall_s: f64,
    /// The run's metrics.json.
    pub metrics: Metrics,
    /// Peak resident memory per process, KiB (slam-launch's memory.json; empty when the
    /// run did not write one).
    #[serde(default)]
    pub peak_memory_kib: BTreeMap<String, u64>,
}

/// The smallest, median and largest of some values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    /// `None` for no values; the median of an even count is the mean of the middle two.
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = match n {
            0 => return None,
            _ if n % 2 == 1 => sorted[n / 2],
            _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
        };
        Some(Self {
            min: sorted[0],
            median,
            max: sorted[n - 1],
        })
    }
}

/// One log over all its seeds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LogResult {
    /// The log's name (file stem), as the published figures know it.
    pub log: String,
    /// The figures published for the log, if it is one of the benchmark's.
    pub published: Option<Published>,
    pub file: PathBuf,
    pub relations: PathBuf,
    /// `trajectory.tum`'s errors over the relations of all seeds together.
    pub estimate: Option<PoseErrors>,
    /// The spread of the seeds' mean translational errors.
    pub seed_means_m: Option<Spread>,
    /// `dead_reckoning.tum` (the front end alone), over all seeds' relations.
    pub front_end: Option<PoseErrors>,
    /// Scans processed (the most of any seed; every seed processes the whole log).
    pub scans: u64,
    /// Mean wall time of a run, seconds.
    pub wall_s: f64,
    /// How long the log took to record, seconds (its scans' stamps, first to last).
    pub duration_s: Option<f64>,
    /// `duration_s / wall_s`: how many times faster than the log was recorded.
    pub real_time: Option<f64>,
    pub runs: Vec<SeedRun>,
}

impl LogResult {
    /// Sums up the runs of one log.
    pub fn new(log: String, file: PathBuf, relations: PathBuf, runs: Vec<SeedRun>) -> Self {
        let summaries = |pick: fn(&RelativePoseErrors) -> Option<ScoreSummary>| {
            runs.iter()
                .filter_map(|run| run.metrics.relative_pose_error.as_ref().and_then(pick))
                .collect::<Vec<_>>()
        };
        let estimate = summaries(|rpe| rpe.trajectory);
        let front_end = summaries(|rpe| rpe.dead_reckoning);
        let pool = |summaries: &[ScoreSummary]| {
            let parts: Vec<(usize, PoseErrors)> = summaries
                .iter()
                .filter_map(|s| Some((s.used, s.errors?)))
                .collect();
            PoseErrors::pooled(&parts)
        };
        let seed_means: Vec<f64> = estimate
            .iter()
            .filter_map(|s| s.errors.map(|e| e.translation_m.mean))
            .collect();
        let wall_s = if runs.is_empty() {
            0.0
        } else {
            runs.iter().map(|r| r.wall_s).sum::<f64>() / runs.len() as f64
        };
        let duration_s = runs.iter().find_map(|r| r.metrics.duration_s);
        Self {
            published: super::published::published(&log),
            log,
            file,
            relations,
            estimate: pool(&estimate),
            seed_means_m: Spread::of(&seed_means),
            front_end: pool(&front_end),
            scans: runs
                .iter()
                .map(|r| r.metrics.frames_processed)
                .max()
                .unwrap_or(0),
            wall_s,
            duration_s,
            real_time: duration_s.filter(|_| wall_s > 0.0).map(|d| d / wall_s),
            runs,
        }
    }
}

/// The whole benchmark, as bench.json.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchReport {
    pub particles: usize,
    pub seeds: Vec<u64>,
    /// The configuration file passed through to slam-launch, if any.
    pub config: Option<PathBuf>,
    /// Scans per log, if limited.
    pub frames: Option<u64>,
    /// Every how many scans of a log were replayed, if not all (`--every`).
    pub every: Option<u64>,
    /// Ranges beyond this were replayed as no-returns, metres (`--max-range`).
    pub max_range_m: Option<f64>,
    /// Where the published figures come from.
    pub published_sources: String,
    pub logs: Vec<LogResult>,
    /// The simulated worlds run beside the logs (`--worlds`), each over the seeds.
    #[serde(default)]
    pub worlds: Vec<WorldResult>,
    /// The workspace's commit when the benchmark ran (`git describe --always --dirty`).
    #[serde(default)]
    pub commit: Option<String>,
    /// When the benchmark started, UTC, `YYYY-MM-DD HH:MM`.
    #[serde(default)]
    pub started_utc: Option<String>,
    /// The machine's logical processors, as the runs had them.
    #[serde(default)]
    pub processors: Option<usize>,
    /// The runs that failed; they are in none of the figures.
    #[serde(default)]
    pub failures: Vec<FailedRun>,
}

/// A run of slam-launch that failed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailedRun {
    /// The log's name, or `world-NAME`.
    pub run: String,
    pub seed: u64,
    /// Why, on one line: the last line slam-launch gave (what it names as the failure).
    pub error: String,
}

impl FailedRun {
    /// The failure of `run` with `seed`, `error` cut to its last line that says anything.
    pub fn new(run: &str, seed: u64, error: &str) -> Self {
        let last = error
            .lines()
            .map(str::trim)
            .rfind(|line| !line.is_empty() && !line.starts_with("logs in "))
            .unwrap_or_default();
        Self {
            run: run.to_owned(),
            seed,
            error: last.to_owned(),
        }
    }
}

/// One simulated world over the seeds.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WorldResult {
    pub world: String,
    pub runs: Vec<SeedRun>,
}

impl BenchReport {
    pub fn new(
        particles: usize,
        seeds: Vec<u64>,
        config: Option<PathBuf>,
        frames: Option<u64>,
        logs: Vec<LogResult>,
    ) -> Self {
        Self {
            particles,
            seeds,
            config,
            frames,
            every: None,
            max_range_m: None,
            published_sources: SOURCES.to_owned(),
            logs,
            worlds: Vec::new(),
            commit: None,
            started_utc: None,
            processors: None,
            failures: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failure_keeps_the_line_that_names_it() {
        let error = "slam-launch failed (exit status: 1): slam-proc: summary of the filter\n  \
                     scans: 13631\nslam-launch: no progress for 120 s after the source \
                     finished (still running: map-sink)\nlogs in runs/intel/seed-3/logs\n";
        let failure = FailedRun::new("intel", 3, error);
        assert_eq!(
            failure.error,
            "slam-launch: no progress for 120 s after the source finished (still running: \
             map-sink)"
        );
        assert_eq!(FailedRun::new("aces", 1, "").error, "");
    }

    #[test]
    fn spread_of_odd_and_even_counts() {
        assert_eq!(Spread::of(&[]), None);
        let odd = Spread::of(&[0.3, 0.1, 0.2]).unwrap();
        assert_eq!((odd.min, odd.median, odd.max), (0.1, 0.2, 0.3));
        let even = Spread::of(&[0.4, 0.1, 0.2, 0.3]).unwrap();
        assert!((even.median - 0.25).abs() < 1e-12);
    }
}
