//! `slam-launch`: one command runs the whole pipeline and leaves its results in a directory.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Parser;
use ipc_types::Domain;
use launch::cli::{Args, PrintFormat};
use launch::config::{RunConfig, SourceKind};
use launch::relations::relations_beside;
use launch::stall::StallLimits;
use launch::supervisor::{self, Display, Outcome, StagePlan};
use launch::topology::{self, Role, RunKind};
use map_sink::write_atomic;
use slam_eval::{FitVerdict, METRICS_FILE, Metrics, ScoreSummary};
use stage_kit::{say, say_err, shutdown};

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            say_err(&format!("slam-launch: {e:#}"));
            ExitCode::from(2)
        }
    }
}

/// `--print-config`: the configuration as a commented TOML file, or the reference.
fn print_config(config: &RunConfig, format: PrintFormat) -> Result<()> {
    use std::io::Write;
    let text = match format {
        PrintFormat::Toml => launch::reference::toml_file(config),
        PrintFormat::Markdown => launch::reference::markdown(),
    }
    .context("cannot write the configuration as TOML")?;
    std::io::stdout()
        .lock()
        .write_all(text.as_bytes())
        .context("cannot print the configuration")
}

fn run() -> Result<ExitCode> {
    let args = Args::parse();
    // Started by slam-bench: a killed slam-bench takes this run with it.
    stage_kit::launcher_watch::stop_with_launcher()?;
    shutdown::install().context("cannot install the Ctrl-C handler")?;

    let mut config = args.run_config()?;
    config.validate()?;
    if let Some(format) = args.print_config {
        print_config(&config, format)?;
        return Ok(ExitCode::SUCCESS);
    }
    check_source_input(&config).context("refusing to start")?;
    // slam-proc refuses it too, but as a stage that dies once map-sink is up.
    slam_proc::memory::check(config.slam.filter.particles).context("refusing to start")?;
    // A map that cannot be used would only fail once the stages are up.
    if let Some(dir) = &config.map {
        let saved = saved_map::SavedMap::load(dir).with_context(|| {
            format!("refusing to start: cannot use the map in {}", dir.display())
        })?;
        anyhow::ensure!(
            !config.localize || saved.grid.is_some(),
            "refusing to start: cannot localize on the map in {}: it has no occupancy grid",
            dir.display()
        );
        // Mapping on it, map-sink starts its grid from the saved one (a localizing run's
        // slam-proc needs the same of it): the check map-sink makes, made now.
        if let Some(grid) = &saved.grid {
            grid.check_extent(run_start(&config)?).with_context(|| {
                format!("refusing to start: cannot use the map in {}", dir.display())
            })?;
            map_sink::prior_grid(grid, config.grid.resolution).with_context(|| {
                format!("refusing to start: cannot use the map in {}", dir.display())
            })?;
        }
    }
    // A port in use would only fail the view once the run has started.
    config
        .foxglove
        .check()
        .context("refusing to start: --foxglove")?;
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
        let read = slam_eval::read_relations_noted(path)
            .context("refusing to start: the relations file cannot be used")?;
        for note in read.notes(path) {
            say_err(&note);
        }
        let relations = read.relations;
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
    // The run clears its directory's map files as it starts, while slam-proc and map-sink
    // read the saved map: it would be gone before they had it.
    if let Some(map) = &config.map {
        let same = |a: &Path, b: &Path| matches!((a.canonicalize(), b.canonicalize()), (Ok(a), Ok(b)) if a == b);
        anyhow::ensure!(
            !same(map, &out),
            "refusing to start: --out {} is the saved map's directory (--map), which the run \
             would clear while reading it; write the extended map to another directory",
            out.display()
        );
    }
    let config_dir = out.join("config");
    let log_dir = out.join("logs");
    for dir in [&out, &config_dir, &log_dir] {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create directory {}", dir.display()))?;
    }
    let effective = toml::to_string(&config).context("cannot write the effective configuration")?;
    // Atomically, like every small result of a run: a full disk leaves no half file.
    write_atomic(&out.join("config.toml"), effective.as_bytes())?;

    let ipc_types::Sweep { cleaned, foreign } = Domain::sweep_abandoned();
    for file in &foreign {
        say_err(&format!("slam-launch: {file}"));
    }
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
        peak_memory_kib,
    } = supervisor::run(&plan, &domain, &log_dir, &display, &stall)?;
    write_memory(&out, peak_memory_kib);
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
            let metrics = print_summary(&out)?;
            Ok(judge_map_fit(&config, &out, &metrics))
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
            let metrics = print_summary(&out)?;
            Ok(judge_map_fit(&config, &out, &metrics))
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

/// `OUT/memory.json`: the stages' peak memory and slam-launch's own. A run whose file
/// cannot be written says so and goes on: it is a measurement, not a result.
fn write_memory(out: &Path, stages: Vec<(String, u64)>) {
    use launch::memory::{MEMORY_FILE, RunMemory, peak_resident_kib};
    let mut memory = RunMemory {
        sampled_every_ms: supervisor::POLL.as_millis() as u64,
        peak_resident_kib: stages.into_iter().collect(),
    };
    if let Some(own) = peak_resident_kib(None) {
        memory
            .peak_resident_kib
            .insert("slam-launch".to_owned(), own);
    }
    // Whole lines, as every text file of a run.
    let written = serde_json::to_string_pretty(&memory)
        .map_err(anyhow::Error::from)
        .and_then(|json| {
            Ok(write_atomic(
                &out.join(MEMORY_FILE),
                format!("{json}\n").as_bytes(),
            )?)
        });
    if let Err(e) = written {
        say_err(&format!("slam-launch: cannot write {MEMORY_FILE}: {e:#}"));
    }
}

/// Where the run starts in a saved map's frame, when it is known: the initial pose, or the
/// map's origin for a run that maps on it (a global localization searches).
fn run_start(config: &RunConfig) -> Result<Option<[f64; 2]>> {
    Ok(match &config.initial_pose {
        Some(pose) => {
            let pose = slam_proc::parse_pose(pose)?;
            Some([pose.x, pose.y])
        }
        None => (!config.localize).then_some([0.0, 0.0]),
    })
}

/// The world or log the source will read, checked as the source reads it: a device, a
/// FIFO or a file too large would otherwise only fail (or hang) a started stage.
fn check_source_input(config: &RunConfig) -> Result<()> {
    match config.source {
        SourceKind::Sim => {
            lidar_sim::World::resolve(&config.sim.world)
                .with_context(|| format!("world '{}'", config.sim.world))?;
        }
        SourceKind::Replay => {
            if let (Some(file), Ok(format)) = (&config.replay.file, config.replay.format.parse()) {
                // A bag is surveyed as lidar-replay will: its files there, its topics
                // chosen, its first scan read, its laser's mount found.
                if format == lidar_replay::LogFormat::Rosbag {
                    lidar_replay::rosbag::check_bag(file, &config.replay.bag_options()?)?;
                    return Ok(());
                }
                let opened =
                    lidar_replay::input_kind(format).open(file, stage_kit::input::Links::Follow)?;
                // A text log is also read up to its first scan, as lidar-replay will.
                if format.is_text() {
                    lidar_replay::check_format(format, std::io::BufReader::new(opened))
                        .with_context(|| format!("{}", file.display()))?;
                }
            }
        }
        SourceKind::Hokuyo => {}
    }
    Ok(())
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

/// The processes of the run, in the topology's start order (consumers first, the source
/// last): each with the run's domain, the subscribers it waits for as the topology counts
/// them, and its own settings.
fn plan(
    config: &RunConfig,
    domain: &Domain,
    bin_dir: &Path,
    out: &Path,
    config_dir: &Path,
) -> Result<Vec<StagePlan>> {
    let run = RunKind::of(config);
    topology::stages(&run)
        .map(|stage| {
            let program = bin_dir.join(stage.binary);
            if !program.is_file() {
                bail!(
                    "{} not found; build the workspace first (cargo build --release)",
                    program.display()
                );
            }
            let mut args = vec!["--domain".to_owned(), domain.name().to_owned()];
            for (option, subscribers) in topology::waits_for_subscribers(stage, &run) {
                args.extend([option.to_owned(), subscribers.to_string()]);
            }
            if let Some(dir) = &config.map
                && topology::takes_saved_map(stage, &run)
            {
                args.extend(["--map".to_owned(), dir.display().to_string()]);
            }
            args.extend(settings_args(stage.role, config, out, config_dir)?);
            Ok(StagePlan {
                name: stage.binary.into(),
                program,
                args,
                // The recording and the view are by-products: the run goes on without them.
                expendable: matches!(stage.role, Role::Recorder | Role::View),
                // The view has no end of its own (it may miss any end-of-stream marker).
                ends_with_run: stage.role == Role::View,
            })
        })
        .collect()
}

/// A recorded or viewed run's particle cloud every this many scans: each cloud holds every particle,
/// so it is kept rare for the recording's size, while a cloud every few seconds of a log
/// still shows how it spreads and collapses.
const PARTICLE_CLOUD_EVERY: u64 = 40;

/// A stage's arguments besides its topics: the settings of its config section, those the
/// launcher interprets as options and the process's own settings as a file of their own
/// (none when they are the defaults).
fn settings_args(
    role: Role,
    config: &RunConfig,
    out: &Path,
    config_dir: &Path,
) -> Result<Vec<String>> {
    let section_file = |name: &str, text: Option<String>, flag: &str| -> Result<Vec<String>> {
        let Some(text) = text else {
            return Ok(Vec::new());
        };
        let path = config_dir.join(format!("{name}.toml"));
        write_atomic(&path, text.as_bytes())?;
        Ok(vec![flag.into(), path.display().to_string()])
    };
    let text = |name: &str, text: Result<Option<String>, toml::ser::Error>| {
        text.with_context(|| format!("cannot write the [{name}] section"))
    };
    let out = out.display().to_string();
    let path = |p: &Path| p.display().to_string();
    // The topics published only for the recorder, when the run records them.
    let run = RunKind::of(config);
    let particles = topology::published(&run, ipc_types::topic::PARTICLES.name());
    let final_map = topology::published(&run, ipc_types::topic::MAP_GRID.name());
    let back_end = topology::published(&run, ipc_types::topic::GRAPH_PATH.name());
    let switch = |on: bool, flag: &str| on.then(|| flag.to_owned());
    Ok(match role {
        Role::View => {
            let mut args = vec![format!("--addr={}", config.foxglove.addr)];
            args.extend(switch(particles, "--particles"));
            args.extend(switch(back_end, "--back-end"));
            args
        }
        Role::Recorder => {
            let mut args = flag_values([("--out", Some(out))]);
            args.extend(switch(particles, "--particles"));
            args.extend(switch(final_map, "--final-map"));
            args.extend(switch(back_end, "--back-end"));
            args
        }
        Role::Sink => {
            let title = format!(
                "{}: {} particles, seed {}",
                source_label(config),
                config.slam.filter.particles,
                config.slam.seed
            );
            let mut args = flag_values([
                ("--out", Some(out)),
                ("--title", Some(title)),
                // map-sink scores: it writes metrics.json and map.svg once, at the end, and
                // the score belongs in both (see slam_eval::score_run).
                ("--relations", config.relations.as_deref().map(path)),
            ]);
            args.push("--status".into());
            args.push(format!("--resolution={}", config.grid.resolution));
            args.extend(switch(final_map, "--publish-final"));
            args.extend(switch(back_end, "--back-end"));
            args
        }
        Role::Filter => {
            let mut args = flag_values([
                (
                    "--particles",
                    Some(config.slam.filter.particles.to_string()),
                ),
                ("--seed", Some(config.slam.seed.to_string())),
            ]);
            if config.localize {
                args.push("--localize".into());
            }
            if particles {
                args.push(format!("--particles-every={PARTICLE_CLOUD_EVERY}"));
            }
            if let Some(pose) = &config.initial_pose {
                args.push(format!("--initial-pose={pose}"));
            }
            let slam = text("slam", RunConfig::section_text(&config.slam.filter))?;
            args.extend(section_file("slam", slam, "--config")?);
            args
        }
        Role::Graph => {
            let front_end = text("front_end", RunConfig::section_text(&config.front_end))?;
            let mut args = section_file("front_end", front_end, "--front-end-config")?;
            // The grid as it grows is for the recording and the view; map-sink needs only
            // the last.
            args.extend(switch(run.recorded || run.viewed, "--interim-grids"));
            args
        }
        Role::Perception => {
            let features = text("features", RunConfig::section_text(&config.features))?;
            let front_end = text("front_end", RunConfig::section_text(&config.front_end))?;
            let mut args = section_file("features", features, "--config")?;
            args.extend(section_file("front_end", front_end, "--front-end-config")?);
            args
        }
        Role::Source => match config.source {
            SourceKind::Sim => {
                let mut args = flag_values([
                    ("--world", Some(config.sim.world.clone())),
                    ("--frames", Some(config.sim.frames.to_string())),
                    ("--laps", Some(config.sim.laps.to_string())),
                    ("--rate", Some(config.sim.rate.to_string())),
                    ("--seed", Some(config.sim.seed.to_string())),
                ]);
                if config.sim.odometry {
                    args.push("--odometry".into());
                }
                let sim = text("sim", RunConfig::section_text(&config.sim.settings))?;
                args.extend(section_file("sim", sim, "--config")?);
                args
            }
            SourceKind::Replay => {
                let mut args = flag_values([
                    ("--format", Some(config.replay.format.clone())),
                    (
                        "--file",
                        Some(config.replay.file.as_deref().map(path).unwrap_or_default()),
                    ),
                    ("--rate", Some(config.replay.rate.to_string())),
                    ("--frames", Some(config.replay.frames.to_string())),
                ]);
                if !config.replay.odometry {
                    args.push("--no-odometry".into());
                }
                if config.replay.start > 0 {
                    args.push(format!("--skip={}", config.replay.start));
                }
                if let Some(every) = config.replay.every {
                    args.push(format!("--every={every}"));
                }
                if let Some(metres) = config.replay.max_range {
                    args.push(format!("--max-range={metres}"));
                }
                if let Some(window) = config.replay.reorder_window {
                    args.push(format!("--reorder-window={window}"));
                }
                if config.replay.format == lidar_replay::LogFormat::Rosbag.name() {
                    let replay = &config.replay;
                    args.extend(flag_values([
                        ("--scan-topic", replay.scan_topic.clone()),
                        ("--odom-source", Some(replay.odom_source.clone())),
                        ("--odom-topic", replay.odom_topic.clone()),
                        ("--base-frame", Some(replay.base_frame.clone())),
                        ("--odom-frame", Some(replay.odom_frame.clone())),
                    ]));
                }
                args
            }
            SourceKind::Hokuyo => config.hokuyo.args(),
        },
    })
}

/// `--flag value` for each flag that has a value, in order.
fn flag_values<const N: usize>(flags: [(&str, Option<String>); N]) -> Vec<String> {
    flags
        .into_iter()
        .filter_map(|(flag, value)| Some([flag.to_owned(), value?]))
        .flatten()
        .collect()
}

/// metrics.json, if the run wrote a readable one.
fn read_metrics(out: &Path) -> Option<Metrics> {
    let text = std::fs::read_to_string(out.join(METRICS_FILE)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Prints the key numbers of metrics.json, and returns them.
fn print_summary(out: &Path) -> Result<Metrics> {
    let path = out.join(METRICS_FILE);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("the run finished but {} is missing", path.display()))?;
    let metrics: Metrics = serde_json::from_str(&text)
        .with_context(|| format!("{} is not the metrics map-sink writes", path.display()))?;
    say(&summary(out, &metrics));
    Ok(metrics)
}

/// The exit status of a finished run on a saved map whose scans the map does not explain:
/// a localization on it fails (its poses are wherever another building's walls fitted
/// best); mapping on it was done without it, which is said.
fn judge_map_fit(config: &RunConfig, out: &Path, metrics: &Metrics) -> ExitCode {
    let (Some(dir), Some(fit)) = (&config.map, &metrics.map_fit) else {
        return ExitCode::SUCCESS;
    };
    if fit.verdict != FitVerdict::DoesNotFit {
        return ExitCode::SUCCESS;
    }
    let how = format!(
        "it explains {:.1} % of the {} beams it could judge, and a map is believed from {:.0} % \
         (metrics.json: map_fit)",
        100.0 * fit.explained_share.unwrap_or(0.0),
        fit.beams_judged,
        100.0 * fit.floor
    );
    if config.localize {
        say_err(&format!(
            "slam-launch: the map in {} does not fit this run's scans: once converged, {how}; \
             the localization is not to be trusted",
            dir.display()
        ));
        ExitCode::FAILURE
    } else {
        say_err(&format!(
            "slam-launch: warning: the saved map in {} does not fit this run's scans: {how}; \
             it was not merged, {} holds this run's map alone",
            dir.display(),
            out.display()
        ));
        ExitCode::SUCCESS
    }
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
    if let Some(search) = &m.search_phase {
        parts.push(match m.converged_at_scan {
            Some(scan) => format!("converged at scan {scan}, scored from there"),
            None => format!("never converged in {} scans", search.scans),
        });
    }
    if let Some(ate) = m.ate_rmse_m {
        parts.push(format!("ATE RMSE {ate:.3} m"));
    }
    if let Some(rmse) = m.map_corner_rmse_m {
        parts.push(format!("map RMSE {rmse:.3} m"));
    }
    parts.push(format!("map {} corners", m.map_corners));
    if let Some(share) = m.map_fit.as_ref().and_then(|fit| fit.explained_share) {
        parts.push(format!(
            "saved map explains {:.1} % of beams",
            100.0 * share
        ));
    }
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
    let errors = s.errors.map_or_else(
        || "none: no relation has both poses".to_owned(),
        |errors| errors.to_string(),
    );
    format!("{errors} over {}/{} relations", s.used, s.relations)
}
