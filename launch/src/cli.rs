//! slam-launch's command line, and its options layered over the config file: an option
//! given replaces the file's key, a key the file has replaces the default.

use std::path::{Path, PathBuf};

use clap::Parser;
use figment::Figment;
use figment::providers::Serialized;
use figment::value::Value;
use serde::Serialize;

use crate::config::{ConfigError, RunConfig, SourceKind};

/// Runs a scan source (lidar-sim, lidar-replay or lidar-hokuyo) -> feature-proc -> slam-proc
/// -> map-sink as separate processes over iceoryx2 shared memory in a domain of their own,
/// and writes trajectory, map, picture and metrics into the output directory.
///
/// Every setting can also come from a TOML file (--config) with the keys `source`,
/// `relations`, `stall_warning`, `stall_limit`, `map`, `localize` and `initial_pose` and the
/// sections [sim], [replay], [hokuyo], [features], [front_end], [slam], [grid], [record] and
/// [foxglove];
/// options given here override the file. A key a section does not know, or a value out of
/// its range, is refused before anything starts.
#[derive(Debug, Parser)]
#[command(name = "slam-launch", version)]
pub struct Args {
    /// TOML file with `source`, `relations`, `stall_warning`, `stall_limit`, `map`,
    /// `localize`, `initial_pose` and [sim], [replay], [hokuyo], [features], [front_end],
    /// [slam], [grid], [record], [foxglove] sections.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Where the scans come from (default: sim; --replay implies replay).
    #[arg(long, value_enum)]
    source: Option<SourceKind>,
    /// World to simulate: hall, office, corridor or a world file (JSON).
    #[arg(long)]
    world: Option<String>,
    /// Replay this recorded log instead of simulating: a CARMEN log, a run.mcap of
    /// --record, or a ROS 2 bag (its directory, or a bare .mcap or .db3).
    #[arg(long, value_name = "FILE")]
    replay: Option<PathBuf>,
    /// Format of the replayed log: seed-csv, carmen, mcap (a run.mcap of --record) or
    /// rosbag2 (a ROS 2 bag). Default: rosbag2 for a directory, a .db3 or a .mcap of ROS 2
    /// messages, mcap for another .mcap, else carmen.
    #[arg(long)]
    format: Option<String>,
    /// A ROS 2 bag's sensor_msgs/msg/LaserScan topic (default: the bag's only one).
    #[arg(long, value_name = "TOPIC")]
    scan_topic: Option<String>,
    /// A ROS 2 bag's odometry: odom (nav_msgs/msg/Odometry), tf (/tf, odom to base_link)
    /// or auto (Odometry if the bag has it, else /tf).
    #[arg(long, value_name = "SOURCE")]
    odom_source: Option<String>,
    /// A ROS 2 bag's nav_msgs/msg/Odometry topic (default: the bag's only one).
    #[arg(long, value_name = "TOPIC")]
    odom_topic: Option<String>,
    /// A ROS 2 bag's robot frame (REP 105; default base_link): the odometry's child frame
    /// and the parent of the laser's mount on /tf_static.
    #[arg(long, value_name = "FRAME")]
    base_frame: Option<String>,
    /// A ROS 2 bag's odometry frame, for --odom-source tf (default odom).
    #[arg(long, value_name = "FRAME")]
    odom_frame: Option<String>,
    /// HOST:PORT of a live Hokuyo scanner (with --source hokuyo).
    #[arg(long)]
    addr: Option<String>,
    /// Do not use the odometry of a replayed log.
    #[arg(long)]
    no_odometry: bool,
    /// Scans to simulate or replay (0 = the whole path of the world, the whole log).
    #[arg(long)]
    frames: Option<u64>,
    /// Drive the simulated world's route N times in a row (1 to 1000): round again when it
    /// ends where it starts, else back and forth along it. Only with the simulator.
    #[arg(long, value_name = "N", value_parser = lidar_sim::parse_laps)]
    laps: Option<lidar_sim::Laps>,
    /// Scans per second (a replay: times the log's own speed); 0 = lockstep: nothing is lost
    /// and a run repeats exactly.
    #[arg(long)]
    rate: Option<f64>,
    /// Seed of the simulator's noise and of the particle filter.
    #[arg(long)]
    seed: Option<u64>,
    /// Particles of the filter.
    #[arg(long)]
    particles: Option<usize>,
    /// Edge of the occupancy grid's cells (map.pgm), metres; default 0.05.
    #[arg(long, value_name = "METRES")]
    resolution: Option<f64>,
    /// Let the simulator publish noisy wheel odometry, which slam-proc then uses as a prior.
    #[arg(long)]
    odometry: bool,
    /// Ground-truth relations (t1 t2 x y z roll pitch yaw, Kuemmerle et al. 2009) to score
    /// the run against: trajectory.tum, dead_reckoning.tum and trajectory_online.tum, where
    /// written. A replay of DIR/NAME.clf is scored against DIR/NAME.relations without this
    /// option if that file exists.
    #[arg(long, value_name = "FILE")]
    relations: Option<PathBuf>,
    /// Seconds a stage may make no progress before the console names it (default 10).
    #[arg(long, value_name = "SECONDS")]
    stall_warning: Option<f64>,
    /// Seconds a stage may make no progress before the run fails with its name (default
    /// 120; at least --stall-warning).
    #[arg(long, value_name = "SECONDS")]
    stall_limit: Option<f64>,
    /// Output directory (default: runs/<world or log name>).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// iceoryx2 domain of this run (default: a fresh one).
    #[arg(long)]
    pub domain: Option<String>,
    /// Directory with the pipeline's executables (default: this program's directory).
    #[arg(long, value_name = "DIR")]
    pub bin_dir: Option<PathBuf>,
    /// No progress output, only the final summary.
    #[arg(long)]
    pub quiet: bool,
    /// A saved map (a run's output directory): the run maps on top of it, extending its
    /// landmarks, or with --localize localizes on it.
    #[arg(long, value_name = "DIR")]
    map: Option<PathBuf>,
    /// Localize on --map without changing it; the status line says whether the pose has
    /// converged.
    #[arg(long)]
    localize: bool,
    /// Where the robot starts in --map's frame, `x,y,yaw` (metres, radians); localizing
    /// without it searches the whole map.
    #[arg(long, value_name = "X,Y,YAW", allow_hyphen_values = true)]
    initial_pose: Option<String>,
    /// Start the replay at this scan of the log (from 0).
    #[arg(long, value_name = "SCAN")]
    replay_start: Option<u64>,
    /// Replay every N-th scan of the log (all its odometry): a harder version of the log.
    #[arg(long, value_name = "N")]
    replay_every: Option<u64>,
    /// Replay the log's ranges beyond this many metres as no-returns: a shorter sensor.
    #[arg(long, value_name = "METRES")]
    replay_max_range: Option<f64>,
    /// Record every topic into OUT/run.mcap (slam-record), for Foxglove; in lockstep the
    /// run stays lossless and deterministic.
    #[arg(long)]
    record: bool,
    /// Serve the run live to Foxglove over its WebSocket protocol (slam-view) on HOST:PORT,
    /// default 127.0.0.1:8765: open Foxglove, Open connection, ws://HOST:PORT. The view
    /// reads lossy: nothing about the run changes with it, and a slow client loses view
    /// messages, never the pipeline's.
    #[arg(long, value_name = "HOST:PORT", num_args = 0..=1)]
    foxglove: Option<Option<String>>,
    /// Print the configuration and exit: every setting with its value (the defaults, with
    /// --config and the options given over them) and a comment line saying what it means,
    /// its unit and its range, as a TOML file to start a --config file from; `markdown`
    /// prints the reference of the defaults (docs/CONFIG.md).
    #[arg(long, value_enum, value_name = "FORMAT", num_args = 0..=1, default_missing_value = "toml")]
    pub print_config: Option<PrintFormat>,
}

/// What `--print-config` prints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PrintFormat {
    /// A config file with a comment line per setting.
    Toml,
    /// The reference as Markdown tables, as docs/CONFIG.md has it.
    Markdown,
}

impl Args {
    /// The run's configuration: the defaults, the config file's keys over them and the
    /// options given over both (merged by figment, key by key). Not yet validated.
    pub fn run_config(&self) -> Result<RunConfig, ConfigError> {
        let file = match &self.config {
            Some(path) => RunConfig::load(path)?,
            None => RunConfig::default(),
        };
        let config: RunConfig = self
            .options()?
            .into_iter()
            .fold(
                Figment::from(Serialized::defaults(file)),
                |figment, (key, value)| figment.merge(Serialized::default(key, value)),
            )
            .extract()
            .map_err(|e| ConfigError::Invalid(format!("the options over the config file: {e}")))?;
        self.check_laps(&config)?;
        Ok(config)
    }

    /// `--laps` asks the simulator for its route again: another source would silently
    /// give one pass over its scans instead.
    fn check_laps(&self, config: &RunConfig) -> Result<(), ConfigError> {
        let source = match config.source {
            _ if self.laps.is_none() => return Ok(()),
            SourceKind::Sim => return Ok(()),
            SourceKind::Replay => "a replayed log (--replay)",
            SourceKind::Hokuyo => "a live Hokuyo (--source hokuyo)",
        };
        Err(ConfigError::Invalid(format!(
            "--laps drives the simulator's route again, but this run's scans come from \
             {source}; leave --laps out, or simulate a world (--world)"
        )))
    }

    /// The config keys the options given set, each with its value. One option may set
    /// several keys (`--seed` seeds the simulator and the filter).
    fn options(&self) -> Result<Vec<(&'static str, Value)>, ConfigError> {
        // What can be told apart by looking (a bag, a recording); a text log stays what the
        // config file or the default says.
        let detected = self
            .replay
            .as_deref()
            .and_then(lidar_replay::LogFormat::detect)
            .filter(|format| !format.is_text())
            .map(|format| format.name().to_owned());
        let given: [(&'static str, Option<Value>); 33] = [
            (
                "source",
                value(
                    self.source
                        .or(self.replay.as_ref().map(|_| SourceKind::Replay)),
                )?,
            ),
            (
                "replay.file",
                value(self.replay.as_deref().map(Path::to_path_buf))?,
            ),
            ("replay.format", value(self.format.clone().or(detected))?),
            ("replay.scan_topic", value(self.scan_topic.clone())?),
            ("replay.odom_source", value(self.odom_source.clone())?),
            ("replay.odom_topic", value(self.odom_topic.clone())?),
            ("replay.base_frame", value(self.base_frame.clone())?),
            ("replay.odom_frame", value(self.odom_frame.clone())?),
            ("hokuyo.addr", value(self.addr.clone())?),
            ("replay.odometry", value(self.no_odometry.then_some(false))?),
            ("replay.rate", value(self.rate)?),
            ("sim.rate", value(self.rate)?),
            ("sim.world", value(self.world.clone())?),
            ("sim.frames", value(self.frames)?),
            ("sim.laps", value(self.laps.map(lidar_sim::Laps::get))?),
            ("replay.frames", value(self.frames)?),
            ("relations", value(self.relations.clone())?),
            ("sim.seed", value(self.seed)?),
            ("slam.seed", value(self.seed)?),
            ("slam.particles", value(self.particles)?),
            ("sim.odometry", value(self.odometry.then_some(true))?),
            ("stall_warning", value(self.stall_warning)?),
            ("stall_limit", value(self.stall_limit)?),
            ("grid.resolution", value(self.resolution)?),
            ("record.enabled", value(self.record.then_some(true))?),
            (
                "foxglove.enabled",
                value(self.foxglove.as_ref().map(|_| true))?,
            ),
            // Without a value, the config file's address or the default.
            ("foxglove.addr", value(self.foxglove.clone().flatten())?),
            ("map", value(self.map.clone())?),
            ("localize", value(self.localize.then_some(true))?),
            ("initial_pose", value(self.initial_pose.clone())?),
            ("replay.start", value(self.replay_start)?),
            ("replay.every", value(self.replay_every)?),
            ("replay.max_range", value(self.replay_max_range)?),
        ];
        Ok(given
            .into_iter()
            .filter_map(|(key, value)| Some((key, value?)))
            .collect())
    }
}

/// An option's value as figment holds it, if the option was given.
fn value<T: Serialize>(given: Option<T>) -> Result<Option<Value>, ConfigError> {
    given
        .map(|v| Value::serialize(v).map_err(|e| ConfigError::Invalid(format!("{e}"))))
        .transpose()
}
