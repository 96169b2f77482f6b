//! `slam-launch`: one command runs the whole pipeline and leaves its results in a directory.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Parser;
use ipc_types::{Domain, shutdown};
use launch::config::{RunConfig, SourceKind};
use launch::relations::relations_beside;
use launch::stall::StallLimits;
use launch::supervisor::{self, Display, Outcome, StagePlan};
use map_sink::write_atomic;
use slam_eval::{METRICS_FILE, Metrics, ScoreSummary};
use stage_kit::{say, say_err};

/// Runs a scan source (lidar-sim, lidar-replay or lidar-hokuyo) -> feature-proc -> slam-proc
/// -> map-sink as separate processes over iceoryx2 shared memory in a domain of their own,
/// and writes trajectory, map, picture and metrics into the output directory.
///
/// Every setting can also come from a TOML file (--config) with the keys `source`,
/// `relations`, `stall_warning`, `stall_limit`, `map`, `localize` and `initial_pose` and the
/// sections [sim], [replay], [hokuyo], [features], [front_end], [slam], [grid] and [record];
/// options given here override the file. Keys a section does not know are refused by the
/// process that reads it.
#[derive(Debug, Parser)]
#[command(name = "slam-launch", version)]
struct Args {
    /// TOML file with `source`, `relations`, `stall_warning`, `stall_limit`, `map`,
    /// `localize`, `initial_pose` and [sim], [replay], [hokuyo], [features], [front_end],
    /// [slam], [grid], [record] sections.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Where the scans come from (default: sim; --replay implies replay).
    #[arg(long, value_enum)]
    source: Option<SourceKind>,
    /// World to simulate: hall, office, corridor or a world file (JSON).
    #[arg(long)]
    world: Option<String>,
    /// Replay this recorded log instead of simulating.
    #[arg(long, value_name = "FILE")]
    replay: Option<PathBuf>,
    /// Format of the replayed log: seed-csv, carmen or mcap (a run.mcap of --record; the
    /// default for a file named *.mcap).
    #[arg(long)]
    format: Option<String>,
    /// HOST:PORT of a live Hokuyo scanner (with --source hokuyo).
    #[arg(long)]
    addr: Option<String>,
    /// Do not use the odometry of a replayed log.
    #[arg(long)]
    no_odometry: bool,
    /// Scans to simulate or replay (0 = the whole path of the world, the whole log).
    #[arg(long)]
    frames: Option<u64>,
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
    out: Option<PathBuf>,
    /// iceoryx2 domain of this run (default: a fresh one).
    #[arg(long)]
    domain: Option<String>,
    /// Directory with the pipeline's executables (default: this program's directory).
    #[arg(long, value_name = "DIR")]
    bin_dir: Option<PathBuf>,
    /// No progress output, only the final summary.
    #[arg(long)]
    quiet: bool,
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
    /// Record every topic into OUT/run.mcap (slam-record), for Foxglove; in lockstep the
    /// run stays lossless and deterministic.
    #[arg(long)]
    record: bool,
}

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            say_err(&format!("slam-launch: {e:#}"));
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<ExitCode> {
    let args = Args::parse();
    shutdown::install().context("cannot install the Ctrl-C handler")?;

    let mut config = match &args.config {
        Some(path) => RunConfig::load(path)?,
        None => RunConfig::default(),
    };
    apply_overrides(&mut config, &args);
    config.validate()?;
    // slam-proc refuses it too, but as a stage that dies once map-sink is up.
    slam_proc::memory::check(config.slam.particles).context("refusing to start")?;
    // A map that cannot be used would only fail once the stages are up.
    if let Some(dir) = &config.map {
        let saved = map_sink::SavedMap::load(dir).with_context(|| {
            format!("refusing to start: cannot use the map in {}", dir.display())
        })?;
        anyhow::ensure!(
            !config.localize || saved.grid.is_some(),
            "refusing to start: cannot localize on the map in {}: it has no occupancy grid",
            dir.display()
        );
        let yaw = saved.grid.as_ref().map_or(0.0, |g| g.yaml.origin[2]);
        anyhow::ensure!(
            !config.localize || yaw == 0.0,
            "refusing to start: cannot localize on the map in {}: its grid is rotated \
             (origin yaw {yaw}), which is not supported",
            dir.display()
        );
    }
    // An address that names nothing would be retried for ever by lidar-hokuyo.
    if config.source == SourceKind::Hokuyo {
        lidar_hokuyo::resolve(&config.hokuyo.addr)
            .context("refusing to start: the Hokuyo's address")?;
    }
    if config.relations.is_none()
        && config.source == SourceKind::Replay
        && let Some(found) = config.replay.file.as_deref().and_then(relations_beside)
    {
        if !args.quiet {
            say_err(&format!(
                "scoring against {} (beside the log)",
                found.display()
            ));
        }
        config.relations = Some(found);
    }
    // A bad relations file would only show once the whole log has run: check it now.
    if let Some(path) = &config.relations {
        let relations = slam_eval::read_relations(path)
            .context("refusing to start: the relations file cannot be used")?;
        if !args.quiet {
            say_err(&format!(
                "{} relations in {}",
                relations.len(),
                path.display()
            ));
        }
    }

    let bin_dir = match &args.bin_dir {
        Some(dir) => dir.clone(),
        None => std::env::current_exe()
            .context("cannot find this program's path")?
            .parent()
            .map(Path::to_path_buf)
            .context("this program has no directory")?,
    };
    let label = source_label(&config);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs").join(&label));
    let config_dir = out.join("config");
    let log_dir = out.join("logs");
    for dir in [&out, &config_dir, &log_dir] {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create directory {}", dir.display()))?;
    }
    let effective = toml::to_string(&config).context("cannot write the effective configuration")?;
    // Atomically, like every small result of a run: a full disk leaves no half file.
    write_atomic(&out.join("config.toml"), effective.as_bytes())?;

    let cleaned = Domain::sweep_abandoned();
    if !cleaned.is_empty() {
        say_err(&format!(
            "cleaned up shared memory of {} abandoned run(s): {}",
            cleaned.len(),
            cleaned.join(", ")
        ));
    }
    // After the sweep, which may have freed some: a stage that finds /dev/shm full dies of
    // SIGBUS wherever it is, so the run must fit before it starts.
    launch::shm_room::check(&config).context("refusing to start")?;
    let domain_name = args.domain.clone().unwrap_or_else(|| {
        format!(
            "run-{}-{}",
            std::process::id(),
            ipc_types::now_ns() % 1_000_000_000
        )
    });
    let domain = Domain::new(&domain_name)?;
    domain.cleanup_dead_nodes();
    // Two pipelines in one domain would each take the other's messages for their own.
    let alive = domain.alive_nodes();
    anyhow::ensure!(
        alive == 0,
        "refusing to start: domain '{domain_name}' has {alive} live node(s), another \
         pipeline's; give another --domain, or none for a fresh one"
    );
    // Held until this process ends, however it ends: if it is killed, the next start knows
    // at once that the domain's shared memory is abandoned (its stages die with it).
    let _claim = domain
        .claim()
        .context("refusing to start; give another --domain, or none for a fresh one")?;

    let plan = plan(&config, &domain, &bin_dir, &out, &config_dir)?;
    let display = Display {
        label,
        total_frames: match config.source {
            SourceKind::Sim => Some(config.sim.frames),
            SourceKind::Replay => Some(config.replay.frames),
            SourceKind::Hokuyo => None,
        }
        .filter(|&frames| frames > 0),
        quiet: args.quiet,
    };
    let (warning, limit) = config.stall_times();
    let stall = StallLimits {
        warning,
        limit,
        lockstep: config.lockstep(),
    };
    let supervisor::Ended {
        outcome,
        mut losses,
    } = supervisor::run(&plan, &domain, &log_dir, &display, &stall)?;
    // map-sink's count is in its metrics; it prints none of its own.
    if let Some(metrics) = read_metrics(&out) {
        losses.add("map-sink", "frames_dropped", metrics.frames_dropped);
    }
    // Even in quiet mode, like the stages' closing summaries: lost data is part of the result.
    for line in losses.lines() {
        say_err(&line);
    }

    domain.cleanup_dead_nodes();
    if let Err(e) = domain.remove_leftovers() {
        say_err(&format!("cannot remove the run's shared memory: {e}"));
    }

    match outcome {
        Outcome::Finished => {
            print_summary(&out)?;
            Ok(ExitCode::SUCCESS)
        }
        // A live sensor has no end: Ctrl-C is how its run finishes, but not a run that
        // never got a scan (a sensor that was never reached, or is no sensor).
        Outcome::Interrupted { source_failure } if config.source == SourceKind::Hokuyo => {
            // lidar-hokuyo knows whether it published; it fails a run that got no scan.
            if let Some(why) = source_failure {
                say_err(&format!(
                    "slam-launch: no scan arrived from the Hokuyo at {}: {why}",
                    config.hokuyo.addr
                ));
                say_err(&format!("logs in {}", log_dir.display()));
                return Ok(ExitCode::FAILURE);
            }
            print_summary(&out)?;
            Ok(ExitCode::SUCCESS)
        }
        Outcome::Interrupted { .. } => {
            say_err(&format!(
                "interrupted; partial results in {}",
                out.display()
            ));
            Ok(ExitCode::from(130))
        }
        Outcome::Failed(message) => {
            say_err(&format!("slam-launch: {message}"));
            say_err(&format!("logs in {}", log_dir.display()));
            Ok(ExitCode::FAILURE)
        }
    }
}

/// A short name of the source, for the progress line and the default output directory.
fn source_label(config: &RunConfig) -> String {
    let stem = |path: &Path| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into())
    };
    match config.source {
        SourceKind::Sim => stem(Path::new(&config.sim.world)),
        SourceKind::Replay => config
            .replay
            .file
            .as_deref()
            .map(stem)
            .unwrap_or_else(|| "replay".into()),
        SourceKind::Hokuyo => "hokuyo".into(),
    }
}

fn apply_overrides(config: &mut RunConfig, args: &Args) {
    if let Some(source) = args.source {
        config.source = source;
    } else if args.replay.is_some() {
        config.source = SourceKind::Replay;
    }
    if let Some(file) = &args.replay {
        config.replay.file = Some(file.clone());
    }
    if let Some(format) = &args.format {
        config.replay.format = format.clone();
    } else if let Some(file) = &args.replay
        && file.extension().is_some_and(|e| e == "mcap")
    {
        config.replay.format = lidar_replay::LogFormat::Mcap.name().into();
    }
    if let Some(addr) = &args.addr {
        config.hokuyo.addr = addr.clone();
    }
    if args.no_odometry {
        config.replay.odometry = false;
    }
    if let Some(rate) = args.rate {
        config.replay.rate = rate;
    }
    if let Some(world) = &args.world {
        config.sim.world = world.clone();
    }
    if let Some(frames) = args.frames {
        config.sim.frames = frames;
        config.replay.frames = frames;
    }
    if let Some(relations) = &args.relations {
        config.relations = Some(relations.clone());
    }
    if let Some(rate) = args.rate {
        config.sim.rate = rate;
    }
    if let Some(seed) = args.seed {
        config.sim.seed = seed;
        config.slam.seed = seed;
    }
    if let Some(particles) = args.particles {
        config.slam.particles = particles;
    }
    if args.odometry {
        config.sim.odometry = true;
    }
    if let Some(seconds) = args.stall_warning {
        config.stall_warning = seconds;
    }
    if let Some(seconds) = args.stall_limit {
        config.stall_limit = seconds;
    }
    if let Some(resolution) = args.resolution {
        config.grid.resolution = resolution;
    }
    if args.record {
        config.record.enabled = true;
    }
    if let Some(dir) = &args.map {
        config.map = Some(dir.clone());
    }
    if args.localize {
        config.localize = true;
    }
    if let Some(pose) = &args.initial_pose {
        config.initial_pose = Some(pose.clone());
    }
    if let Some(start) = args.replay_start {
        config.replay.start = start;
    }
}

/// The processes of a simulated run, consumers first and the source last.
fn plan(
    config: &RunConfig,
    domain: &Domain,
    bin_dir: &Path,
    out: &Path,
    config_dir: &Path,
) -> Result<Vec<StagePlan>> {
    let program = |name: &str| -> Result<PathBuf> {
        let path = bin_dir.join(name);
        if !path.is_file() {
            bail!(
                "{} not found; build the workspace first (cargo build --release)",
                path.display()
            );
        }
        Ok(path)
    };
    let section_as = |name: &str, table: &toml::Table, flag: &str| -> Result<Vec<String>> {
        if table.is_empty() {
            return Ok(Vec::new());
        }
        let path = config_dir.join(format!("{name}.toml"));
        write_atomic(&path, RunConfig::section_text(table).as_bytes())?;
        Ok(vec![flag.into(), path.display().to_string()])
    };
    let section = |name: &str, table: &toml::Table| section_as(name, table, "--config");
    let d = domain.name().to_owned();
    // The recorder subscribes to every topic: each publisher waits for it too.
    let recorder = config.record.extra_subscribers();
    // feature-proc and map-sink take the scans; slam-proc too when its beams weight the
    // particles on a saved map.
    let scan_subscribers = (2 + usize::from(config.localize) + recorder).to_string();

    let mut sink: Vec<String> = vec![
        "--domain".into(),
        d.clone(),
        "--out".into(),
        out.display().to_string(),
        "--status".into(),
        "--title".into(),
        format!(
            "{}: {} particles, seed {}",
            source_label(config),
            config.slam.particles,
            config.slam.seed
        ),
    ];
    sink.push(format!("--resolution={}", config.grid.resolution));
    // map-sink scores: it writes metrics.json and map.svg once, at the end, and the score
    // belongs in both (see slam_eval::score_run).
    if let Some(relations) = &config.relations {
        sink.push("--relations".into());
        sink.push(relations.display().to_string());
    }
    let mut slam = vec![
        "--domain".into(),
        d.clone(),
        "--particles".into(),
        config.slam.particles.to_string(),
        "--seed".into(),
        config.slam.seed.to_string(),
        "--map-every".into(),
        config.slam.map_every.to_string(),
        // map-sink takes the poses.
        "--subscribers".into(),
        (1 + recorder).to_string(),
    ];
    if let Some(dir) = &config.map {
        slam.push("--map".into());
        slam.push(dir.display().to_string());
    }
    if config.localize {
        slam.push("--localize".into());
    }
    if let Some(pose) = &config.initial_pose {
        slam.push(format!("--initial-pose={pose}"));
    }
    slam.extend(section("slam", &config.slam.extra)?);
    // slam-proc takes the features.
    let mut features = vec![
        "--domain".into(),
        d.clone(),
        "--subscribers".into(),
        (1 + recorder).to_string(),
    ];
    features.extend(section("features", &config.features)?);
    features.extend(section_as(
        "front_end",
        &config.front_end,
        "--front-end-config",
    )?);
    let source = match config.source {
        SourceKind::Sim => sim_stage(config, &d, &scan_subscribers, &section, &program)?,
        SourceKind::Replay => {
            let mut args = vec![
                "--format".into(),
                config.replay.format.clone(),
                "--file".into(),
                config
                    .replay
                    .file
                    .as_deref()
                    .map(|f| f.display().to_string())
                    .unwrap_or_default(),
                "--rate".into(),
                config.replay.rate.to_string(),
                "--domain".into(),
                d.clone(),
                "--subscribers".into(),
                scan_subscribers.clone(),
                "--frames".into(),
                config.replay.frames.to_string(),
            ];
            if !config.replay.odometry {
                args.push("--no-odometry".into());
            }
            if config.replay.start > 0 {
                args.push(format!("--skip={}", config.replay.start));
            }
            if let Some(window) = config.replay.reorder_window {
                args.push(format!("--reorder-window={window}"));
            }
            StagePlan {
                name: "lidar-replay".into(),
                program: program("lidar-replay")?,
                args,
                expendable: false,
            }
        }
        SourceKind::Hokuyo => {
            let mut args = vec![
                "--addr".into(),
                config.hokuyo.addr.clone(),
                "--domain".into(),
                d.clone(),
                "--subscribers".into(),
                scan_subscribers.clone(),
            ];
            for (key, value) in &config.hokuyo.extra {
                args.push(format!("--{}", key.replace('_', "-")));
                args.push(match value {
                    toml::Value::String(s) => s.clone(),
                    other => other.to_string(),
                });
            }
            StagePlan {
                name: "lidar-hokuyo".into(),
                program: program("lidar-hokuyo")?,
                args,
                expendable: false,
            }
        }
    };

    let mut stages = Vec::new();
    if config.record.enabled {
        stages.push(StagePlan {
            name: "slam-record".into(),
            program: program("slam-record")?,
            args: vec![
                "--domain".into(),
                d.clone(),
                "--out".into(),
                out.display().to_string(),
            ],
            expendable: true,
        });
    }
    stages.extend([
        StagePlan {
            name: "map-sink".into(),
            program: program("map-sink")?,
            args: sink,
            expendable: false,
        },
        StagePlan {
            name: "slam-proc".into(),
            program: program("slam-proc")?,
            args: slam,
            expendable: false,
        },
        StagePlan {
            name: "feature-proc".into(),
            program: program("feature-proc")?,
            args: features,
            expendable: false,
        },
        source,
    ]);
    Ok(stages)
}

/// The simulator's stage.
fn sim_stage(
    config: &RunConfig,
    domain: &str,
    scan_subscribers: &str,
    section: &dyn Fn(&str, &toml::Table) -> Result<Vec<String>>,
    program: &dyn Fn(&str) -> Result<PathBuf>,
) -> Result<StagePlan> {
    let mut sim = vec![
        "--world".into(),
        config.sim.world.clone(),
        "--frames".into(),
        config.sim.frames.to_string(),
        "--rate".into(),
        config.sim.rate.to_string(),
        "--seed".into(),
        config.sim.seed.to_string(),
        "--domain".into(),
        domain.to_owned(),
        "--subscribers".into(),
        scan_subscribers.to_owned(),
    ];
    if config.sim.odometry {
        sim.push("--odometry".into());
    }
    sim.extend(section("sim", &config.sim.extra)?);
    Ok(StagePlan {
        name: "lidar-sim".into(),
        program: program("lidar-sim")?,
        args: sim,
        expendable: false,
    })
}

/// metrics.json, if the run wrote a readable one.
fn read_metrics(out: &Path) -> Option<Metrics> {
    let text = std::fs::read_to_string(out.join(METRICS_FILE)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Prints the key numbers of metrics.json.
fn print_summary(out: &Path) -> Result<()> {
    let path = out.join(METRICS_FILE);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("the run finished but {} is missing", path.display()))?;
    let metrics: Metrics = serde_json::from_str(&text)
        .with_context(|| format!("{} is not the metrics map-sink writes", path.display()))?;
    say(&summary(out, &metrics));
    Ok(())
}

/// One line: where the results are and the numbers that matter.
fn summary(out: &Path, m: &Metrics) -> String {
    let mut parts = vec![
        format!("results in {}", out.display()),
        format!("scans {}", m.frames_processed),
    ];
    if let Some(rate) = m.scans_per_s {
        parts.push(format!("rate {rate:.0} scans/s"));
    }
    if let Some(duration) = m.duration_s.filter(|_| m.wall_s > 0.0) {
        parts.push(format!("{:.0} x real time", duration / m.wall_s));
    }
    if let Some(ate) = m.ate_rmse_m {
        parts.push(format!("ATE RMSE {ate:.3} m"));
    }
    if let Some(rmse) = m.map_corner_rmse_m {
        parts.push(format!("map RMSE {rmse:.3} m"));
    }
    parts.push(format!("map {} corners", m.map_corners));
    if let Some(rpe) = &m.relative_pose_error {
        for (name, summary) in [
            ("RPE", &rpe.trajectory),
            ("online RPE", &rpe.trajectory_online),
            ("front end RPE", &rpe.dead_reckoning),
        ] {
            if let Some(summary) = summary {
                parts.push(format!("{name} {}", rpe_text(summary)));
            }
        }
    }
    parts.join(" | ")
}

/// `0.580 +- 1.782 m, 2.60 +- 6.04 deg over 1172/1172 relations`.
fn rpe_text(s: &ScoreSummary) -> String {
    let errors = match (s.translation_m, s.rotation_deg) {
        (Some(t), Some(r)) => format!(
            "{:.3} +- {:.3} m, {:.2} +- {:.2} deg",
            t.mean, t.std, r.mean, r.std
        ),
        _ => "none: no relation has both poses".to_owned(),
    };
    format!("{errors} over {}/{} relations", s.used, s.relations)
}
