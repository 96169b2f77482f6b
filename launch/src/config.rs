//! The run configuration: one TOML file for every process, command-line options on top.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use stage_kit::SettingsFileError;

/// Why a configuration file was refused.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error(transparent)]
    File(#[from] SettingsFileError),
    #[error("{0}")]
    Invalid(String),
}

/// Where the scans come from.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
// No deny_unknown_fields: serde cannot combine it with `flatten`; the keys left over go to
// the process, which refuses what it does not know.
#[serde(default)]
pub struct SimSection {
    /// `hall`, `office`, `corridor` or a world file (JSON).
    pub world: String,
    /// Scans to publish (0 = until the end of the path).
    pub frames: u64,
    /// Scans per second; 0 = lockstep (lossless and deterministic).
    pub rate: f64,
    /// Noise seed.
    pub seed: u64,
    /// Publish noisy wheel odometry too.
    pub odometry: bool,
    /// Anything else `lidar-sim --config` takes (sensor and vehicle settings).
    #[serde(flatten)]
    pub extra: toml::Table,
}

impl Default for SimSection {
    fn default() -> Self {
        Self {
            world: "office".into(),
            frames: 0,
            rate: 0.0,
            seed: 1,
            odometry: false,
            extra: toml::Table::new(),
        }
    }
}

/// Which publisher feeds the pipeline.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq, Eq, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum SourceKind {
    /// `lidar-sim` in a simulated world, with ground truth.
    #[default]
    Sim,
    /// `lidar-replay` of a recorded log.
    Replay,
    /// `lidar-hokuyo`, a live Hokuyo scanner over Ethernet (SCIP 2.0).
    Hokuyo,
}

/// A recorded log to replay.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ReplaySection {
    /// The log file.
    pub file: Option<PathBuf>,
    /// `seed-csv`, `carmen` or `mcap`.
    pub format: String,
    /// Scans per second relative to the log's timing (1 = as recorded); 0 = lockstep.
    pub rate: f64,
    /// Publish the log's odometry (when it has any).
    pub odometry: bool,
    /// Scans to publish; 0 = the whole log.
    pub frames: u64,
    /// The log's scan to start at, from 0 (`--replay-start`, lidar-replay's `--skip`).
    pub start: u64,
    /// Seconds of log time lidar-replay waits for lines written out of time order
    /// (`--reorder-window`); unset = its default.
    pub reorder_window: Option<f64>,
}

impl Default for ReplaySection {
    fn default() -> Self {
        Self {
            file: None,
            format: "carmen".into(),
            rate: 0.0,
            odometry: true,
            frames: 0,
            start: 0,
            reorder_window: None,
        }
    }
}

/// A live Hokuyo scanner.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
// No deny_unknown_fields: serde cannot combine it with `flatten`; the keys left over go to
// the process, which refuses what it does not know.
#[serde(default)]
pub struct HokuyoSection {
    /// `HOST:PORT` of the scanner.
    pub addr: String,
    /// Anything else `lidar-hokuyo` takes, as `--key value` (e.g. `cluster = 2`).
    #[serde(flatten)]
    pub extra: toml::Table,
}

impl Default for HokuyoSection {
    fn default() -> Self {
        Self {
            addr: "192.168.0.10:10940".into(),
            extra: toml::Table::new(),
        }
    }
}

/// SLAM settings; `extra` goes to `slam-proc --config` as is.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
// No deny_unknown_fields: serde cannot combine it with `flatten`; the keys left over go to
// the process, which refuses what it does not know.
#[serde(default)]
pub struct SlamSection {
    pub particles: usize,
    pub seed: u64,
    /// Publish the map every this many scans (and at the end).
    pub map_every: u64,
    #[serde(flatten)]
    pub extra: toml::Table,
}

impl Default for SlamSection {
    fn default() -> Self {
        Self {
            particles: 100,
            seed: 1,
            map_every: 20,
            extra: toml::Table::new(),
        }
    }
}

/// Default of [`RunConfig::stall_warning`], seconds.
pub const STALL_WARNING_S: f64 = 10.0;
/// Default of [`RunConfig::stall_limit`], seconds.
pub const STALL_LIMIT_S: f64 = 120.0;
/// The range of both stall times, seconds: shorter than a stage's progress report period
/// (0.2 s) would name stages that are moving; a day is beyond any run's quiet spell.
const STALL_RANGE_S: std::ops::RangeInclusive<f64> = 0.5..=86_400.0;

/// map-sink's occupancy grid.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct GridSection {
    /// Edge of a cell, metres (`map-sink --resolution`).
    pub resolution: f64,
}

impl Default for GridSection {
    fn default() -> Self {
        Self {
            resolution: map_sink::GridConfig::default().resolution_m,
        }
    }
}

/// The whole run. Sections the launcher does not interpret (`features`, `front_end`) are
/// handed to the process that reads them (feature-proc), which validates them and names any
/// mistake.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RunConfig {
    pub source: SourceKind,
    /// Ground-truth relations (Kuemmerle et al. 2009) to score the run against; for a replay
    /// of `DIR/NAME.clf` without one, `DIR/NAME.relations` if it exists.
    pub relations: Option<PathBuf>,
    /// Seconds a stage may make no progress before the console names it (`--stall-warning`).
    pub stall_warning: f64,
    /// Seconds a stage may make no progress before the run fails (`--stall-limit`); at least
    /// `stall_warning`.
    pub stall_limit: f64,
    /// A saved map (a run's output directory) to map on top of, or with `localize` to
    /// localize on (`--map`).
    pub map: Option<PathBuf>,
    /// Localize on `map` without changing it (`--localize`).
    pub localize: bool,
    /// Where the robot starts in the map, `x,y,yaw` (`--initial-pose`); localizing without
    /// it searches the whole map.
    pub initial_pose: Option<String>,
    pub sim: SimSection,
    pub replay: ReplaySection,
    pub hokuyo: HokuyoSection,
    pub features: toml::Table,
    /// The scan-matching front end's settings (scan_match::FrontEndConfig).
    pub front_end: toml::Table,
    pub slam: SlamSection,
    pub grid: GridSection,
    pub record: crate::record::RecordSection,
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            source: SourceKind::default(),
            relations: None,
            stall_warning: STALL_WARNING_S,
            stall_limit: STALL_LIMIT_S,
            map: None,
            localize: false,
            initial_pose: None,
            sim: SimSection::default(),
            replay: ReplaySection::default(),
            hokuyo: HokuyoSection::default(),
            features: toml::Table::new(),
            front_end: toml::Table::new(),
            slam: SlamSection::default(),
            grid: GridSection::default(),
            record: crate::record::RecordSection::default(),
        }
    }
}

impl RunConfig {
    /// Reads a config file; unknown keys are errors so a typo never passes silently.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        Ok(stage_kit::settings::load_file(path)?)
    }

    /// Parses the text of the config file at `path` (named in errors).
    pub fn parse(text: &str, path: &Path) -> Result<Self, ConfigError> {
        Ok(stage_kit::settings::parse(text, path)?)
    }

    /// Checks what the launcher itself relies on.
    pub fn validate(&self) -> Result<(), ConfigError> {
        // The sources' own checks, so a rate is refused here, before any process starts,
        // exactly when the source would refuse it.
        if let Err(e) = lidar_sim::check_rate(self.sim.rate) {
            return Err(ConfigError::Invalid(format!("[sim] rate (--rate) {e}")));
        }
        if self.source == SourceKind::Replay {
            if self.replay.file.is_none() {
                return Err(ConfigError::Invalid(
                    "a replay needs a log file (--replay FILE)".into(),
                ));
            }
            if let Err(e) = self.replay.format.parse::<lidar_replay::LogFormat>() {
                return Err(ConfigError::Invalid(format!(
                    "[replay] format (--format): {e}"
                )));
            }
            if let Err(e) = lidar_replay::check_rate(self.replay.rate) {
                return Err(ConfigError::Invalid(format!("[replay] rate (--rate) {e}")));
            }
        }
        if self.map.is_none() && (self.localize || self.initial_pose.is_some()) {
            return Err(ConfigError::Invalid(
                "--localize and --initial-pose need a saved map (--map DIR)".into(),
            ));
        }
        if let Some(pose) = &self.initial_pose
            && let Err(e) = slam_proc::parse_pose(pose)
        {
            return Err(ConfigError::Invalid(format!("--initial-pose: {e}")));
        }
        if self.slam.particles == 0 {
            return Err(ConfigError::Invalid("particles must be at least 1".into()));
        }
        if self.slam.map_every == 0 {
            return Err(ConfigError::Invalid("map_every must be at least 1".into()));
        }
        for (key, value) in [
            ("stall_warning (--stall-warning)", self.stall_warning),
            ("stall_limit (--stall-limit)", self.stall_limit),
        ] {
            if !STALL_RANGE_S.contains(&value) {
                return Err(ConfigError::Invalid(format!(
                    "{key} must be from {} to {} seconds, not {value}",
                    STALL_RANGE_S.start(),
                    STALL_RANGE_S.end()
                )));
            }
        }
        if self.stall_limit < self.stall_warning {
            return Err(ConfigError::Invalid(format!(
                "stall_limit (--stall-limit) {} s is shorter than stall_warning \
                 (--stall-warning) {} s: a stall would fail the run before it is reported",
                self.stall_limit, self.stall_warning
            )));
        }
        let grid = map_sink::GridConfig {
            resolution_m: self.grid.resolution,
            ..map_sink::GridConfig::default()
        };
        if let Err(e) = grid.validate() {
            return Err(ConfigError::Invalid(format!(
                "[grid] resolution (--resolution): {e}"
            )));
        }
        Ok(())
    }

    /// Whether the run is in lockstep (lossless: every publisher waits for its
    /// subscribers), as the source will choose it.
    pub fn lockstep(&self) -> bool {
        match self.source {
            SourceKind::Sim => self.sim.rate == 0.0,
            SourceKind::Replay => self.replay.rate == 0.0,
            SourceKind::Hokuyo => false,
        }
    }

    /// The stall times as durations (after [`RunConfig::validate`]: within range).
    pub fn stall_times(&self) -> (std::time::Duration, std::time::Duration) {
        let duration =
            |s: f64| std::time::Duration::try_from_secs_f64(s).unwrap_or(std::time::Duration::MAX);
        (duration(self.stall_warning), duration(self.stall_limit))
    }

    /// A section as the TOML text its process reads with `--config`.
    pub fn section_text(table: &toml::Table) -> String {
        toml::to_string(table).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_full_file_parses_and_extra_keys_reach_the_process() {
        let config: RunConfig = toml::from_str(
            r#"
            [sim]
            world = "hall"
            frames = 300
            range_noise = 0.02
            [features]
            split_threshold = 0.05
            [slam]
            particles = 50
            resample_threshold = 0.4
            "#,
        )
        .unwrap();
        assert_eq!(config.sim.world, "hall");
        assert_eq!(config.sim.frames, 300);
        assert_eq!(config.sim.extra["range_noise"].as_float(), Some(0.02));
        assert_eq!(config.features["split_threshold"].as_float(), Some(0.05));
        assert_eq!(config.slam.particles, 50);
        assert!(config.slam.extra.contains_key("resample_threshold"));
        config.validate().unwrap();
    }

    #[test]
    fn localizing_needs_a_map_and_a_pose_that_reads() {
        let config: RunConfig = toml::from_str(
            "map = 'runs/office'\nlocalize = true\ninitial_pose = '1,-2,0.5'\n\
             [replay]\nstart = 300\n[slam.localize]\nmax_particles = 5000",
        )
        .unwrap();
        config.validate().unwrap();
        assert_eq!(config.replay.start, 300);
        assert!(config.slam.extra.contains_key("localize"));
        let mut bad = config.clone();
        bad.map = None;
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("--map DIR")
        );
        let mut bad = config;
        bad.initial_pose = Some("1,2".into());
        let message = bad.validate().unwrap_err().to_string();
        assert!(
            message.contains("--initial-pose") && message.contains("three"),
            "{message}"
        );
    }

    #[test]
    fn unknown_sections_are_refused() {
        assert!(toml::from_str::<RunConfig>("[simulation]\nworld = 'x'").is_err());
    }

    #[test]
    fn the_grid_resolution_is_read_and_checked() {
        let config: RunConfig = toml::from_str("[grid]\nresolution = 0.1").unwrap();
        assert_eq!(config.grid.resolution, 0.1);
        config.validate().unwrap();
        assert_eq!(RunConfig::default().grid.resolution, 0.05);
        for bad in [0.0, -0.05, 6.0, f64::NAN] {
            let mut config = RunConfig::default();
            config.grid.resolution = bad;
            let message = config.validate().unwrap_err().to_string();
            assert!(
                message.starts_with("[grid] resolution (--resolution)"),
                "{message}"
            );
        }
        assert!(toml::from_str::<RunConfig>("[grid]\ncell = 0.1").is_err());
    }

    #[test]
    fn bad_numbers_are_named() {
        let mut config = RunConfig::default();
        config.sim.rate = -1.0;
        assert!(config.validate().unwrap_err().to_string().contains("rate"));
        // Too slow for a Duration: refused with the range, not a panic in lidar-sim.
        config.sim.rate = 1e-20;
        assert_eq!(
            config.validate().unwrap_err().to_string(),
            "[sim] rate (--rate) must be 0 (lockstep) or from 0.001 to 1000 scans per \
             second, not 1e-20"
        );
        config.sim.rate = 0.0;
        config.source = SourceKind::Replay;
        config.replay.file = Some("log.clf".into());
        config.replay.rate = 1e-20;
        assert!(
            config
                .validate()
                .unwrap_err()
                .to_string()
                .starts_with("[replay] rate (--rate) must be 0 (lockstep) or a speed factor")
        );
        config.replay.rate = 0.001;
        config.validate().unwrap();
        config.slam.particles = 0;
        assert!(
            config
                .validate()
                .unwrap_err()
                .to_string()
                .contains("particles")
        );
    }

    #[test]
    fn stall_times_are_read_and_checked() {
        let config: RunConfig = toml::from_str("stall_warning = 2\nstall_limit = 5.5").unwrap();
        config.validate().unwrap();
        assert_eq!(
            config.stall_times(),
            (Duration::from_secs(2), Duration::from_millis(5500))
        );
        let defaults = RunConfig::default();
        assert_eq!(
            defaults.stall_times(),
            (Duration::from_secs(10), Duration::from_secs(120))
        );
        let mut config = RunConfig {
            stall_limit: 5.0,
            ..RunConfig::default()
        };
        assert_eq!(
            config.validate().unwrap_err().to_string(),
            "stall_limit (--stall-limit) 5 s is shorter than stall_warning (--stall-warning) \
             10 s: a stall would fail the run before it is reported"
        );
        for bad in [0.0, 0.1, -3.0, f64::NAN, f64::INFINITY, 1e9] {
            config.stall_warning = bad;
            config.stall_limit = 10.0;
            assert!(
                config
                    .validate()
                    .unwrap_err()
                    .to_string()
                    .starts_with("stall_warning (--stall-warning) must be from 0.5 to 86400"),
                "{bad}"
            );
        }
    }
}
