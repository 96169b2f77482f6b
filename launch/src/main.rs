//! `slam-launch`: one command runs the whole pipeline and leaves its results in a directory.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Parser;
use ipc_types::{Domain, shutdown};
use launch::config::{RunConfig, SourceKind};
use launch::supervisor::{self, Display, Outcome, StagePlan};

/// Runs a scan source (lidar-sim, lidar-replay or lidar-hokuyo) -> feature-proc -> slam-proc
/// -> map-sink as separate processes over iceoryx2 shared memory in a domain of their own,
/// and writes trajectory, map, picture and metrics into the output directory.
///
/// Every setting can also come from a TOML file (--config) with the key `source` and the
/// sections [sim], [replay], [hokuyo], [features] and [slam]; options given here override
/// the file. Keys a section does not know are refused by the process that reads it.
#[derive(Debug, Parser)]
#[command(name = "slam-launch", version)]
struct Args {
    /// TOML file with `source` and [sim], [replay], [hokuyo], [features], [slam] sections.
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
    /// Format of the replayed log: seed-csv or carmen.
    #[arg(long)]
    format: Option<String>,
    /// HOST:PORT of a live Hokuyo scanner (with --source hokuyo).
    #[arg(long)]
    addr: Option<String>,
    /// Do not use the odometry of a replayed log.
    #[arg(long)]
    no_odometry: bool,
    /// Scans to simulate (0 = the whole path of the world).
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
    /// Let the simulator publish noisy wheel odometry, which slam-proc then uses as a prior.
    #[arg(long)]
    odometry: bool,
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
}

fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("slam-launch: {e:#}");
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
    std::fs::write(
        out.join("config.toml"),
        toml::to_string(&config).context("cannot write the effective configuration")?,
    )?;

    let cleaned = Domain::sweep_abandoned();
    if !cleaned.is_empty() {
        eprintln!(
            "cleaned up shared memory of {} abandoned run(s): {}",
            cleaned.len(),
            cleaned.join(", ")
        );
    }
    let domain_name = args.domain.clone().unwrap_or_else(|| {
        format!(
            "run-{}-{}",
            std::process::id(),
            ipc_types::now_ns() % 1_000_000_000
        )
    });
    let domain = Domain::new(&domain_name)?;
    domain.cleanup_dead_nodes();

    let plan = plan(&config, &domain, &bin_dir, &out, &config_dir)?;
    let display = Display {
        label,
        total_frames: (config.source == SourceKind::Sim && config.sim.frames > 0)
            .then_some(config.sim.frames),
        quiet: args.quiet,
    };
    let outcome = supervisor::run(&plan, &domain, &log_dir, &display)?;

    domain.cleanup_dead_nodes();
    if let Err(e) = domain.remove_leftovers() {
        eprintln!("cannot remove the run's shared memory: {e}");
    }

    match outcome {
        Outcome::Finished => {
            print_summary(&out)?;
            Ok(ExitCode::SUCCESS)
        }
        // A live sensor has no end: Ctrl-C is how its run finishes.
        Outcome::Interrupted if config.source == SourceKind::Hokuyo => {
            print_summary(&out)?;
            Ok(ExitCode::SUCCESS)
        }
        Outcome::Interrupted => {
            eprintln!("interrupted; partial results in {}", out.display());
            Ok(ExitCode::from(130))
        }
        Outcome::Failed(message) => {
            eprintln!("slam-launch: {message}");
            eprintln!("logs in {}", log_dir.display());
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
    let section = |name: &str, table: &toml::Table| -> Result<Vec<String>> {
        if table.is_empty() {
            return Ok(Vec::new());
        }
        let path = config_dir.join(format!("{name}.toml"));
        std::fs::write(&path, RunConfig::section_text(table))
            .with_context(|| format!("cannot write {}", path.display()))?;
        Ok(vec!["--config".into(), path.display().to_string()])
    };
    let d = domain.name().to_owned();

    let sink = vec![
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
    let mut slam = vec![
        "--domain".into(),
        d.clone(),
        "--particles".into(),
        config.slam.particles.to_string(),
        "--seed".into(),
        config.slam.seed.to_string(),
        "--map-every".into(),
        config.slam.map_every.to_string(),
    ];
    slam.extend(section("slam", &config.slam.extra)?);
    let mut features = vec!["--domain".into(), d.clone()];
    features.extend(section("features", &config.features)?);
    let source = match config.source {
        SourceKind::Sim => sim_stage(config, &d, &section, &program)?,
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
                "2".into(),
            ];
            if !config.replay.odometry {
                args.push("--no-odometry".into());
            }
            if let Some(window) = config.replay.reorder_window {
                args.push(format!("--reorder-window={window}"));
            }
            StagePlan {
                name: "lidar-replay".into(),
                program: program("lidar-replay")?,
                args,
            }
        }
        SourceKind::Hokuyo => {
            let mut args = vec![
                "--addr".into(),
                config.hokuyo.addr.clone(),
                "--domain".into(),
                d.clone(),
                "--subscribers".into(),
                "2".into(),
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
            }
        }
    };

    Ok(vec![
        StagePlan {
            name: "map-sink".into(),
            program: program("map-sink")?,
            args: sink,
        },
        StagePlan {
            name: "slam-proc".into(),
            program: program("slam-proc")?,
            args: slam,
        },
        StagePlan {
            name: "feature-proc".into(),
            program: program("feature-proc")?,
            args: features,
        },
        source,
    ])
}

/// The simulator's stage.
fn sim_stage(
    config: &RunConfig,
    domain: &str,
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
        // feature-proc and map-sink take the scans.
        "--subscribers".into(),
        "2".into(),
    ];
    if config.sim.odometry {
        sim.push("--odometry".into());
    }
    sim.extend(section("sim", &config.sim.extra)?);
    Ok(StagePlan {
        name: "lidar-sim".into(),
        program: program("lidar-sim")?,
        args: sim,
    })
}

/// Prints the key numbers of metrics.json.
fn print_summary(out: &Path) -> Result<()> {
    let path = out.join("metrics.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("the run finished but {} is missing", path.display()))?;
    let metrics: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let number = |key: &str| metrics.get(key).and_then(serde_json::Value::as_f64);
    let mut line = format!("results in {}", out.display());
    for (key, label, unit) in [
        ("frames_processed", "scans", ""),
        ("scans_per_s", "rate", " scans/s"),
        ("ate_rmse_m", "ATE RMSE", " m"),
        ("map_corner_rmse_m", "map RMSE", " m"),
        ("map_corners", "map", " corners"),
    ] {
        if let Some(value) = number(key) {
            line.push_str(&format!(" | {label} {}{unit}", trim(value)));
        }
    }
    println!("{line}");
    Ok(())
}

fn trim(value: f64) -> String {
    if value.fract() == 0.0 && value.abs() < 1e12 {
        format!("{value:.0}")
    } else {
        format!("{value:.3}")
    }
}
