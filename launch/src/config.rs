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
// With `flatten`, serde refuses the keys neither this struct nor the flattened one takes
// (the flattened one alone cannot: it sees only its own).
#[serde(default, deny_unknown_fields)]
pub struct SimSection {
    /// `hall`, `office`, `corridor` or a world file (JSON).
    pub world: String,
    /// Scans to publish (0 = until the end of the path's last lap).
    pub frames: u64,
    /// Times to drive the world's route in a row (`--laps`, 1 to [`lidar_sim::MAX_LAPS`]).
    pub laps: u32,
    /// Scans per second; 0 = lockstep (lossless and deterministic).
    pub rate: f64,
    /// Noise seed.
    pub seed: u64,
    /// Publish noisy wheel odometry too.
    pub odometry: bool,
    /// The sensor and the vehicle (`[sim.sensor]`, `[sim.vehicle]`): `lidar-sim --config`.
    #[serde(flatten)]
    pub settings: lidar_sim::SimSettings,
}

impl Default for SimSection {
    fn default() -> Self {
        Self {
            world: "office".into(),
            frames: 0,
            laps: 1,
            rate: 0.0,
            seed: 1,
            odometry: false,
            settings: lidar_sim::SimSettings::default(),
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
    /// Publish every N-th scan of the log (`--replay-every`, lidar-replay's `--every`);
    /// unset = every scan.
    pub every: Option<u64>,
    /// Ranges beyond this many metres become no-returns (`--replay-max-range`,
    /// lidar-replay's `--max-range`).
    pub max_range: Option<f64>,
    /// `seed-csv`, `carmen`, `mcap` or `rosbag2`.
    pub format: String,
    /// Scans per second relative to the log's timing (1 = as recorded); 0 = lockstep.
    pub rate: f64,
    /// Publish the log's odometry (when it has any).
    pub odometry: bool,
    /// Scans to publish; 0 = the whole log.
    pub frames: u64,
    /// Seconds of log time lidar-replay waits for lines written out of time order
    /// (`--reorder-window`); unset = its default.
    pub reorder_window: Option<f64>,
    /// The log's scan to start at, from 0 (`--replay-start`, lidar-replay's `--skip`).
    pub start: u64,
    /// A ROS 2 bag's LaserScan topic (`--scan-topic`); unset = the bag's only one.
    pub scan_topic: Option<String>,
    /// A ROS 2 bag's odometry: `auto`, `odom` (nav_msgs/msg/Odometry) or `tf`
    /// (`--odom-source`).
    pub odom_source: String,
    /// A ROS 2 bag's Odometry topic (`--odom-topic`); unset = the bag's only one.
    pub odom_topic: Option<String>,
    /// A ROS 2 bag's robot frame, REP 105 (`--base-frame`).
    pub base_frame: String,
    /// A ROS 2 bag's odometry frame, for odometry from /tf (`--odom-frame`).
    pub odom_frame: String,
}

impl ReplaySection {
    /// What lidar-replay is asked to replay of a ROS 2 bag.
    pub fn bag_options(&self) -> Result<lidar_replay::rosbag::BagOptions, ConfigError> {
        let odometry = self.odom_source.parse().map_err(|e| {
            ConfigError::Invalid(format!("[replay] odom_source (--odom-source): {e}"))
        })?;
        Ok(lidar_replay::rosbag::BagOptions {
            scan_topic: self.scan_topic.clone(),
            odometry,
            odometry_topic: self.odom_topic.clone(),
            base_frame: self.base_frame.clone(),
            odom_frame: self.odom_frame.clone(),
            ..lidar_replay::rosbag::BagOptions::default()
        })
    }
}

impl Default for ReplaySection {
    fn default() -> Self {
        Self {
            file: None,
            every: None,
            max_range: None,
            format: "carmen".into(),
            rate: 0.0,
            odometry: true,
            frames: 0,
            reorder_window: None,
            start: 0,
            scan_topic: None,
            odom_source: "auto".into(),
            odom_topic: None,
            base_frame: "base_link".into(),
            odom_frame: "odom".into(),
        }
    }
}

/// A live Hokuyo scanner: what lidar-hokuyo is asked for, passed on as its options.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
// With `flatten`, serde refuses the keys neither this struct nor the flattened one takes
// (the flattened one alone cannot: it sees only its own).
#[serde(default, deny_unknown_fields)]
pub struct HokuyoSection {
    /// `HOST:PORT` of the scanner.
    pub addr: String,
    /// Scans to publish before stopping; 0 = until stopped.
    pub frames: u64,
    /// frame_id of the scans.
    pub frame_id: String,
    /// The bearings, the clustering and the intensities wanted.
    #[serde(flatten)]
    pub request: lidar_hokuyo::ScanRequest,
}

impl Default for HokuyoSection {
    fn default() -> Self {
        Self {
            addr: "192.168.0.10:10940".into(),
            frames: 0,
            frame_id: "laser".into(),
            request: lidar_hokuyo::ScanRequest::default(),
        }
    }
}

impl HokuyoSection {
    /// lidar-hokuyo's options: `--addr`, and each setting that is not its default.
    pub fn args(&self) -> Vec<String> {
        let defaults = Self::default();
        let given = |differs: bool, option: &str, value: String| {
            differs.then(|| [option.to_owned(), value])
        };
        let request = &self.request;
        let options = [
            Some(["--addr".to_owned(), self.addr.clone()]),
            request
                .min_angle
                .map(|a| ["--min-angle".to_owned(), a.to_string()]),
            request
                .max_angle
                .map(|a| ["--max-angle".to_owned(), a.to_string()]),
            given(
                request.cluster != defaults.request.cluster,
                "--cluster",
                request.cluster.to_string(),
            ),
            given(
                request.intensities != defaults.request.intensities,
                "--intensities",
                request.intensities.to_string(),
            ),
            given(
                self.frames != defaults.frames,
                "--frames",
                self.frames.to_string(),
            ),
            given(
                self.frame_id != defaults.frame_id,
                "--frame-id",
                self.frame_id.clone(),
            ),
        ];
        options.into_iter().flatten().flatten().collect()
    }
}

/// The filter: `particles` and every other setting of slam-proc's [`slam_proc::SlamConfig`]
/// (handed to `slam-proc --config`), with the run's seed.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
// With `flatten`, serde refuses the keys neither this struct nor the flattened one takes
// (the flattened one alone cannot: it sees only its own).
#[serde(default, deny_unknown_fields)]
pub struct SlamSection {
    pub seed: u64,
    #[serde(flatten)]
    pub filter: slam_proc::SlamConfig,
}

impl Default for SlamSection {
    fn default() -> Self {
        Self {
            seed: 1,
            filter: slam_proc::SlamConfig::default(),
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

/// The whole run. Every section is the settings of the process that reads it, so a typo or
/// a value out of range is refused here, before anything starts, naming the key.
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
    /// feature-proc's extractor.
    pub features: feature_proc::FeatureConfig,
    /// The scan-matching front end, run by feature-proc.
    pub front_end: scan_match::FrontEndConfig,
    pub slam: SlamSection,
    pub grid: GridSection,
    pub record: crate::record::RecordSection,
    /// The live view (`--foxglove`).
    pub foxglove: crate::view::ViewSection,
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
            features: feature_proc::FeatureConfig::default(),
            front_end: scan_match::FrontEndConfig::default(),
            slam: SlamSection::default(),
            grid: GridSection::default(),
            record: crate::record::RecordSection::default(),
            foxglove: crate::view::ViewSection::default(),
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
        if let Err(e) = lidar_sim::Laps::new(i64::from(self.sim.laps)) {
            return Err(ConfigError::Invalid(format!("[sim] laps (--laps) {e}")));
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
            self.replay.bag_options()?;
            if let Err(e) = lidar_replay::Degradation::new(
                self.replay.every.unwrap_or(1),
                self.replay.max_range,
            ) {
                return Err(ConfigError::Invalid(format!(
                    "[replay] every / max_range (--replay-every, --replay-max-range): {e}"
                )));
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
        if self.slam.filter.particles == 0 {
            return Err(ConfigError::Invalid("particles must be at least 1".into()));
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
        self.validate_sections()?;
        if let Err(e) = self.foxglove.address() {
            return Err(ConfigError::Invalid(format!(
                "[foxglove] addr (--foxglove): {e}"
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

    /// The processes' own checks of their sections, each error prefixed with its section.
    fn validate_sections(&self) -> Result<(), ConfigError> {
        let checks: [(&str, Result<(), stage_kit::SettingError>); 5] = [
            ("[sim.sensor]", self.sim.settings.sensor.validate()),
            ("[sim.vehicle]", self.sim.settings.vehicle.validate()),
            ("[features]", self.features.validate()),
            ("[front_end]", self.front_end.validate()),
            ("[slam]", self.slam.filter.validate()),
        ];
        for (section, check) in checks {
            check.map_err(|e| ConfigError::Invalid(format!("{section} {e}")))?;
        }
        let cluster = self.hokuyo.request.cluster;
        if !(1..=lidar_hokuyo::scip::MAX_CLUSTER).contains(&cluster) {
            return Err(ConfigError::Invalid(format!(
                "[hokuyo] cluster must be from 1 to {}, not {cluster}",
                lidar_hokuyo::scip::MAX_CLUSTER
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

    /// A section as the TOML text its process reads with `--config`; `None` when it holds
    /// the defaults, which the process has without a file.
    pub fn section_text<T: Serialize + Default + PartialEq>(
        settings: &T,
    ) -> Result<Option<String>, toml::ser::Error> {
        if *settings == T::default() {
            return Ok(None);
        }
        toml::to_string(settings).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_full_file_parses_into_the_processes_settings() {
        let config: RunConfig = toml::from_str(
            r#"
            [sim]
            world = "hall"
            frames = 300
            [sim.sensor]
            noise_sigma = 0.02
            [sim.vehicle]
            max_accel = 2
            [features]
            min_line_points = 5
            [front_end]
            voxel_size = 0.1
            [slam]
            particles = 50
            update_min_distance = 0.4
            [slam.localize]
            max_particles = 5000
            [hokuyo]
            cluster = 2
            min_angle = -1.5
            "#,
        )
        .unwrap();
        assert_eq!(config.sim.world, "hall");
        assert_eq!(config.sim.frames, 300);
        assert_eq!(config.sim.settings.sensor.noise_sigma, 0.02);
        assert_eq!(config.sim.settings.vehicle.max_accel, 2.0);
        assert_eq!(config.features.min_line_points, 5);
        assert_eq!(config.front_end.voxel_size, 0.1);
        assert_eq!(config.slam.filter.particles, 50);
        assert_eq!(config.slam.filter.update_min_distance, 0.4);
        assert_eq!(config.slam.filter.localize.max_particles, 5000);
        assert_eq!(
            config.hokuyo.args(),
            [
                "--addr",
                "192.168.0.10:10940",
                "--min-angle",
                "-1.5",
                "--cluster",
                "2"
            ]
        );
        config.validate().unwrap();
    }

    #[test]
    fn a_typo_in_any_section_is_refused_with_its_key() {
        for (text, key) in [
            ("[slam]\npartcles = 10", "partcles"),
            ("[slam.localize]\nmax_partcles = 10", "max_partcles"),
            ("[sim]\nrange_noise = 0.02", "range_noise"),
            ("[sim.sensor]\nrange_noise = 0.02", "range_noise"),
            ("[features]\nmin_points = 5", "min_points"),
            // Constants now, no longer settings.
            ("[features]\nsplit_threshold = 0.05", "split_threshold"),
            ("[front_end]\nmax_keyframes = 50", "max_keyframes"),
            ("[slam]\nresample_threshold = 0.4", "resample_threshold"),
            ("[slam]\nmap_every = 20", "map_every"),
            ("[slam.localize]\nkld_z = 2.3", "kld_z"),
            ("[front_end]\nvoxel = 0.1", "voxel"),
            ("[hokuyo]\nclustr = 2", "clustr"),
        ] {
            let error = RunConfig::parse(text, Path::new("run.toml")).unwrap_err();
            let shown = format!("{:#}", anyhow::Error::new(error));
            assert!(
                shown.starts_with("config file run.toml: ")
                    && shown.contains(&format!("unknown field `{key}`")),
                "{text}: {shown}"
            );
        }
    }

    #[test]
    fn values_out_of_range_are_refused_with_their_section() {
        for (text, start) in [
            (
                "[slam]\nupdate_min_distance = -1",
                "[slam] update_min_distance = -1",
            ),
            ("[features]\nmax_range = -1", "[features] max_range = -1"),
            ("[front_end]\nvoxel_size = 0", "[front_end] voxel_size = 0"),
            ("[sim.sensor]\nbeams = 0", "[sim.sensor] beams = 0"),
            (
                "[sim.vehicle]\nmax_accel = 0",
                "[sim.vehicle] max_accel = 0",
            ),
            (
                "[hokuyo]\ncluster = 100",
                "[hokuyo] cluster must be from 1 to 99",
            ),
        ] {
            let config: RunConfig = toml::from_str(text).unwrap();
            let message = config.validate().unwrap_err().to_string();
            assert!(message.starts_with(start), "{text}: {message}");
        }
    }

    #[test]
    fn a_section_goes_to_its_process_as_it_was_read() {
        let config: RunConfig = toml::from_str(
            "[slam]\nparticles = 7\nview_range = 9.5\n[slam.localize]\nmax_particles = 500\n\
             [sim.vehicle]\nmax_accel = 2\n[front_end]\nkeyframe_angle = 0.1",
        )
        .unwrap();
        let slam = RunConfig::section_text(&config.slam.filter)
            .unwrap()
            .unwrap();
        assert_eq!(
            stage_kit::settings::parse::<slam_proc::SlamConfig>(&slam, Path::new("slam.toml"))
                .unwrap(),
            config.slam.filter
        );
        let sim = RunConfig::section_text(&config.sim.settings)
            .unwrap()
            .unwrap();
        assert_eq!(
            toml::from_str::<lidar_sim::SimSettings>(&sim).unwrap(),
            config.sim.settings
        );
        let front_end = RunConfig::section_text(&config.front_end).unwrap().unwrap();
        assert_eq!(
            toml::from_str::<scan_match::FrontEndConfig>(&front_end).unwrap(),
            config.front_end
        );
        // The defaults need no file: the process has them.
        assert_eq!(RunConfig::section_text(&config.features).unwrap(), None);
        // The effective configuration, written beside the run, reads back as itself.
        let effective = toml::to_string(&config).unwrap();
        assert_eq!(toml::from_str::<RunConfig>(&effective).unwrap(), config);
    }

    #[test]
    fn a_harder_replay_is_checked_before_anything_starts() {
        let config: RunConfig = toml::from_str(
            "source = 'replay'\n[replay]\nfile = 'aces.clf'\nevery = 3\nmax_range = 5.0",
        )
        .unwrap();
        config.validate().unwrap();
        for (key, value) in [("every", "0"), ("max_range", "-1.0"), ("max_range", "0.0")] {
            let bad: RunConfig = toml::from_str(&format!(
                "source = 'replay'\n[replay]\nfile = 'aces.clf'\n{key} = {value}"
            ))
            .unwrap();
            let error = bad.validate().unwrap_err().to_string();
            assert!(
                error.contains("--replay-every, --replay-max-range"),
                "{error}"
            );
        }
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
        assert_eq!(config.slam.filter.localize.max_particles, 5000);
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
        config.slam.filter.particles = 0;
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
