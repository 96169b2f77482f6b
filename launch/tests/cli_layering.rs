//! slam-launch's options over its config file: an option given replaces the file's key, a
//! key the file has replaces the default, and the file's errors are the file's.

use std::path::PathBuf;

use clap::Parser;
use launch::cli::Args;
use launch::config::{RunConfig, SourceKind};

/// A config file of its own for each test, removed when the test ends.
struct ConfigFile(PathBuf);

impl ConfigFile {
    fn new(name: &str, text: &str) -> Self {
        let path = std::env::temp_dir().join(format!(
            "slam-launch-cli-{}-{name}.toml",
            std::process::id()
        ));
        std::fs::write(&path, text).expect("temp file written");
        Self(path)
    }

    fn config(&self, options: &[&str]) -> RunConfig {
        let path = self.0.display().to_string();
        let argv = ["slam-launch", "--config", path.as_str()]
            .into_iter()
            .chain(options.iter().copied());
        Args::try_parse_from(argv)
            .expect("options parse")
            .run_config()
            .expect("configuration layers")
    }
}

impl Drop for ConfigFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

#[test]
fn an_option_overrides_the_file_and_the_file_overrides_the_default() {
    let file = ConfigFile::new(
        "layers",
        "stall_warning = 20\n[sim]\nworld = 'hall'\nframes = 300\nseed = 4\n\
         [sim.sensor]\nnoise_sigma = 0.02\n[slam]\nparticles = 50\nupdate_min_distance = 0.4\n\
         [grid]\nresolution = 0.1\n",
    );
    let config = file.config(&[
        "--world",
        "corridor",
        "--seed",
        "7",
        "--odometry",
        "--resolution",
        "0.02",
    ]);
    // Given as options: over the file.
    assert_eq!(config.sim.world, "corridor");
    assert_eq!(config.sim.seed, 7);
    assert_eq!(config.slam.seed, 7);
    assert!(config.sim.odometry);
    assert_eq!(config.grid.resolution, 0.02);
    // Only in the file: over the defaults, the keys the launcher passes on included.
    assert_eq!(config.sim.frames, 300);
    assert_eq!(config.slam.filter.particles, 50);
    assert_eq!(config.stall_warning, 20.0);
    assert_eq!(config.sim.settings.sensor.noise_sigma, 0.02);
    assert_eq!(config.slam.filter.update_min_distance, 0.4);
    // In neither: the defaults.
    let defaults = RunConfig::default();
    assert_eq!(config.stall_limit, defaults.stall_limit);
    assert_eq!(
        config.slam.filter.view_range,
        defaults.slam.filter.view_range
    );
    assert_eq!(config.front_end, defaults.front_end);
    assert_eq!(config.source, SourceKind::Sim);

    // Without options the file is the configuration as it was read.
    assert_eq!(
        file.config(&[]),
        RunConfig::load(&file.0).expect("file loads")
    );
}

#[test]
fn a_replayed_log_sets_the_source_and_an_mcap_its_format() {
    let file = ConfigFile::new("replay", "[replay]\nformat = 'seed-csv'\nrate = 2.0\n");
    let config = file.config(&["--replay", "run.mcap", "--frames", "12", "--no-odometry"]);
    assert_eq!(config.source, SourceKind::Replay);
    assert_eq!(config.replay.file, Some(PathBuf::from("run.mcap")));
    assert_eq!(config.replay.format, "mcap");
    assert_eq!(config.replay.frames, 12);
    assert_eq!(config.sim.frames, 12);
    assert!(!config.replay.odometry);
    assert_eq!(config.replay.rate, 2.0);
    // --source and --format over what --replay implies.
    let config = file.config(&[
        "--replay", "run.mcap", "--format", "carmen", "--source", "sim",
    ]);
    assert_eq!(config.source, SourceKind::Sim);
    assert_eq!(config.replay.format, "carmen");
    // A log that is no recording keeps the file's format.
    assert_eq!(
        file.config(&["--replay", "log.csv"]).replay.format,
        "seed-csv"
    );
}

#[test]
fn the_file_s_errors_are_still_the_file_s() {
    let file = ConfigFile::new("typo", "[sim]\nworld = 'hall'\n[simulation]\nframes = 3\n");
    let path = file.0.display().to_string();
    let refusal = Args::try_parse_from(["slam-launch", "--config", path.as_str(), "--seed", "3"])
        .expect("options parse")
        .run_config()
        .expect_err("unknown section refused");
    // As slam-launch shows it ({:#}): the error and its sources.
    let mut error = refusal.to_string();
    let mut source = std::error::Error::source(&refusal);
    while let Some(cause) = source {
        error.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    assert!(
        error.contains(&path) && error.contains("simulation"),
        "{error}"
    );
}

#[test]
fn a_typo_in_a_process_s_section_is_the_file_s_error() {
    let file = ConfigFile::new("nested-typo", "[slam]\nparticles = 20\npartcles = 10\n");
    let path = file.0.display().to_string();
    let refusal = Args::try_parse_from(["slam-launch", "--config", path.as_str()])
        .expect("options parse")
        .run_config()
        .expect_err("unknown key refused");
    let shown = format!("{:#}", anyhow::Error::new(refusal));
    assert!(
        shown.starts_with(&format!("config file {path}: "))
            && shown.contains("unknown field `partcles`"),
        "{shown}"
    );
    // An option over a section the launcher hands on lands in the process's settings.
    let file = ConfigFile::new("nested", "[slam]\nparticles = 20\nview_range = 9.5\n");
    let config = file.config(&["--particles", "30"]);
    assert_eq!(config.slam.filter.particles, 30);
    assert_eq!(config.slam.filter.view_range, 9.5);
}

#[test]
fn laps_go_to_the_simulator_and_are_refused_for_any_other_source() {
    let file = ConfigFile::new("laps", "[sim]\nlaps = 2\n");
    assert_eq!(file.config(&[]).sim.laps, 2);
    assert_eq!(file.config(&["--laps", "3"]).sim.laps, 3);
    assert_eq!(RunConfig::default().sim.laps, 1);
    // Out of range: refused as the option is read, naming it and the range.
    for laps in ["0", "1001", "-1", "x"] {
        let refusal = Args::try_parse_from(["slam-launch", &format!("--laps={laps}")])
            .expect_err("refused")
            .to_string();
        assert!(
            refusal.contains(&format!("invalid value '{laps}' for '--laps <N>'")),
            "{refusal}"
        );
    }
    // A replay or a live sensor has no route to drive again.
    for source in [
        &["--replay", "log.clf"][..],
        &["--source", "hokuyo"],
        &["--source", "replay", "--replay", "run.mcap"],
    ] {
        let argv = ["slam-launch", "--laps", "3"].iter().chain(source);
        let refusal = Args::try_parse_from(argv)
            .expect("options parse")
            .run_config()
            .expect_err("refused")
            .to_string();
        assert!(
            refusal.starts_with("--laps drives the simulator's route again"),
            "{refusal}"
        );
    }
    // A value out of range in the file is the file's, named with its key.
    let file = ConfigFile::new("laps-zero", "[sim]\nlaps = 0\n");
    let error = file
        .config(&[])
        .validate()
        .expect_err("refused")
        .to_string();
    assert_eq!(
        error,
        "[sim] laps (--laps) must be from 1 to 1000 laps, not 0"
    );
}

#[test]
fn a_bag_directory_is_a_rosbag2_replay_with_its_topics_and_frames() {
    let file = ConfigFile::new("bag", "[replay]\nbase_frame = 'base_footprint'\n");
    let dir = std::env::temp_dir().join(format!("slam-launch-cli-bag-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("bag directory");
    let bag = dir.display().to_string();
    let config = file.config(&[
        "--replay",
        &bag,
        "--scan-topic",
        "/front/scan",
        "--odom-source",
        "tf",
    ]);
    assert_eq!(config.source, SourceKind::Replay);
    assert_eq!(config.replay.format, "rosbag2");
    assert_eq!(config.replay.scan_topic.as_deref(), Some("/front/scan"));
    let options = config.replay.bag_options().expect("valid bag options");
    assert_eq!(options.odometry, lidar_replay::rosbag::OdometryFrom::Tf);
    // The file's frame, the default's other.
    assert_eq!(options.base_frame, "base_footprint");
    assert_eq!(options.odom_frame, "odom");
    // A bag's SQLite3 storage alone is a bag too; a text log stays what the file says.
    assert_eq!(
        file.config(&["--replay", "bag_0.db3"]).replay.format,
        "rosbag2"
    );
    assert_eq!(
        file.config(&["--replay", "log.clf"]).replay.format,
        "carmen"
    );
    // An odometry source that is none is refused before anything starts, by its name.
    let error = file
        .config(&["--replay", &bag, "--odom-source", "wheels"])
        .validate()
        .expect_err("unknown odometry source refused")
        .to_string();
    assert!(
        error.contains("[replay] odom_source (--odom-source): unknown odometry source 'wheels'"),
        "{error}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn foxglove_with_or_without_an_address_layers_over_the_file() {
    let plain = ConfigFile::new("foxglove-plain", "");
    assert!(!plain.config(&[]).foxglove.enabled);
    let default = plain.config(&["--foxglove", "--world", "office"]);
    assert!(
        default.foxglove.enabled,
        "a bare --foxglove takes no other option as its address"
    );
    assert_eq!(default.foxglove.addr, "127.0.0.1:8765");
    assert_eq!(default.sim.world, "office");
    let given = plain.config(&["--foxglove", "0.0.0.0:9000"]);
    assert_eq!(given.foxglove.addr, "0.0.0.0:9000");
    let equals = plain.config(&["--foxglove=[::1]:9001"]);
    assert_eq!(equals.foxglove.addr, "[::1]:9001");

    let file = ConfigFile::new("foxglove-file", "[foxglove]\naddr = '127.0.0.1:9100'\n");
    assert!(
        !file.config(&[]).foxglove.enabled,
        "an address alone turns nothing on"
    );
    // A bare --foxglove keeps the file's address; one given replaces it.
    assert_eq!(file.config(&["--foxglove"]).foxglove.addr, "127.0.0.1:9100");
    assert_eq!(
        file.config(&["--foxglove", "127.0.0.1:9200"]).foxglove.addr,
        "127.0.0.1:9200"
    );
    let bad = file.config(&["--foxglove", "nowhere"]);
    let error = bad.validate().expect_err("not HOST:PORT").to_string();
    assert!(error.contains("[foxglove] addr (--foxglove)"), "{error}");
    assert!(error.contains("'nowhere'"), "{error}");
}
