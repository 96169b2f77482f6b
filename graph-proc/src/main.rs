//! `graph-proc`: global SLAM (the `back-end` library) as a stage. It reads the front end's
//! motion from the features topic and, where the robot moved enough for a new node, the
//! scan's beams; it builds submaps, closes the loops the scans confirm and solves the pose
//! graph, and publishes the graph's path (and, for a recording, its occupancy grid) as they
//! stand every few seconds and, solved once more, both at the end of the stream (or when
//! stopped).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use back_end::{GlobalConfig, GlobalSlam, GlobalStats, ScanRanges};
use clap::Parser;
use ipc_types::prelude::*;
use nalgebra::Matrix3;
use scan_match::FrontEndConfig;
use stage_kit::held_scans::HeldScans;
use stage_kit::{say, say_err};

/// How often the path is published while the run goes on: a viewer, a recording and a run
/// stopped without a last word all have one at most this old.
const PATH_PERIOD: Duration = Duration::from_secs(2);
/// How often the grid is: laying out every submap costs a few tenths of a second on a
/// large building.
const GRID_PERIOD: Duration = Duration::from_secs(5);

/// Subscribes to the features (the front end's motion) and the scans, and publishes the
/// pose graph's path on `graph/path` and its grid on `graph/grid` as they go and at the end.
#[derive(Debug, Parser)]
#[command(name = "graph-proc", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// TOML file with the front end's settings (every field optional; see
    /// scan_match::FrontEndConfig): the back end thins and registers scans as it does.
    #[arg(long, value_name = "FILE")]
    front_end_config: Option<PathBuf>,
    /// Path subscribers to wait for before the first lockstep publish.
    #[arg(long, default_value_t = 1)]
    subscribers: usize,
    /// Publish the grid every few seconds too, not only at the end (for a recording).
    #[arg(long)]
    interim_grids: bool,
}

fn main() -> ExitCode {
    stage_kit::run_stage("graph-proc", run)
}

fn run(args: Args) -> Result<()> {
    let front_end: FrontEndConfig = stage_kit::settings::load(args.front_end_config.as_deref())?;
    front_end.validate().context("front-end configuration")?;
    let mut global =
        GlobalSlam::new(GlobalConfig::for_front_end(&front_end)).context("the pose graph")?;

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("graph-proc")?;
    // The path and grid go out in many pieces: lossless whatever the run's delivery. Made
    // first: map-sink and the recorder wait for them.
    let mut results = Results {
        path: Outlet::create(&domain, &node, topic::GRAPH_PATH, Delivery::Lossless, 0)?,
        grid: Outlet::create(&domain, &node, topic::GRAPH_GRID, Delivery::Lossless, 0)?,
        interim_grids: args.interim_grids,
        path_at: Instant::now(),
        grid_at: Instant::now(),
    };
    let features = Inlet::open(&node, topic::FEATURES)?;
    let scans = Inlet::open(&node, topic::SCAN)?;
    let delivery = features.delivery();
    say("ready");
    if delivery == Delivery::Lossless {
        results.path.wait_for_subscribers(args.subscribers, None)?;
    }

    let mut held = HeldScans::default();
    let mut counts = Counts::default();
    let mut last_stamp = 0;
    loop {
        if wait_any(&[&features, &scans], Duration::from_millis(100))? == Wake::Shutdown {
            break;
        }
        held.hold(&scans)?;
        while let Some(sample) = features.receive()? {
            if sample.header.is_end_of_stream() {
                results.publish_final(&mut global, sample.header.stamp_ns)?;
                say_err(&summary(&global.stats(), &counts));
                ipc_types::losses::report(&counts.losses());
                return Ok(());
            }
            let Some(motion) = sample.motion() else {
                counts.without_motion += 1;
                continue;
            };
            let odom_from_robot = motion.pose.into();
            let scan = if global.wants_scan(&odom_from_robot) {
                let scan = held.wait_for(&scans, sample.header.seq, delivery)?;
                if scan.is_none() {
                    counts.scans_lost += 1;
                }
                scan
            } else {
                None
            };
            global
                .add_scan(
                    sample.header.stamp_ns,
                    &odom_from_robot,
                    &motion.increment.into(),
                    &Matrix3::from_row_slice(&motion.increment_covariance),
                    scan.map(|s| ScanRanges {
                        geometry: &s.geometry,
                        ranges: &s.ranges,
                    }),
                )
                .context("the pose graph")?;
            last_stamp = sample.header.stamp_ns;
        }
        if last_stamp > 0 {
            results.publish_interim(&global, last_stamp)?;
        }
    }
    // Stopped by a signal: the path and grid as far as they got, solved once more.
    results.publish_final(&mut global, last_stamp)?;
    say_err("graph-proc: stopped");
    say_err(&summary(&global.stats(), &counts));
    ipc_types::losses::report(&counts.losses());
    Ok(())
}

/// Every scan's pose on the graph as it stands.
fn stamped(global: &GlobalSlam) -> Vec<StampedPose> {
    global
        .path()
        .into_iter()
        .map(|(stamp_ns, pose)| StampedPose {
            stamp_ns,
            pose: pose.into(),
        })
        .collect()
}

/// The back end's results on their topics.
struct Results {
    path: Outlet<PathChunk>,
    grid: Outlet<GridCells>,
    /// Whether the grid goes out while the run goes on (for a recording).
    interim_grids: bool,
    /// When each was last published.
    path_at: Instant,
    grid_at: Instant,
}

impl Results {
    /// The path and the grid as they stand, each when its period has passed.
    fn publish_interim(&mut self, global: &GlobalSlam, stamp_ns: u64) -> Result<()> {
        if self.path_at.elapsed() >= PATH_PERIOD {
            self.path
                .publish_path(&stamped(global), stamp_ns, Form::Interim)?;
            self.path_at = Instant::now();
        }
        if self.interim_grids && self.grid_at.elapsed() >= GRID_PERIOD {
            publish_grid(&self.grid, global, stamp_ns, Form::Interim)?;
            self.grid_at = Instant::now();
        }
        Ok(())
    }

    /// Solves the graph with everything in it and publishes its grid and path as final:
    /// the grid first, so that a reader holding the final path has the grid too.
    fn publish_final(&self, global: &mut GlobalSlam, stamp_ns: u64) -> Result<()> {
        let started = Instant::now();
        global.finish().context("the pose graph's last solve")?;
        publish_grid(&self.grid, global, stamp_ns, Form::Final)?;
        let path = stamped(global);
        self.path.publish_path(&path, stamp_ns, Form::Final)?;
        say_err(&format!(
            "graph-proc: path of {} poses solved and published in {:.2} s",
            path.len(),
            started.elapsed().as_secs_f64()
        ));
        Ok(())
    }
}

/// Lays the submaps out at their poses on the graph and publishes the grid (none before
/// any beam).
fn publish_grid(
    outlet: &Outlet<GridCells>,
    global: &GlobalSlam,
    stamp_ns: u64,
    form: Form,
) -> Result<()> {
    let Some(grid) = global.grid().context("the grid")? else {
        return Ok(());
    };
    let (Ok(width), Ok(height)) = (u32::try_from(grid.width()), u32::try_from(grid.height()))
    else {
        anyhow::bail!(
            "the grid of {} x {} cells is too large to publish",
            grid.width(),
            grid.height()
        );
    };
    let geometry = GridGeometry {
        resolution: grid.resolution_m(),
        origin: grid.origin(),
        width,
        height,
    };
    outlet.publish_grid(geometry, &grid.pixels(), stamp_ns, form)?;
    Ok(())
}

/// What the run made do without.
#[derive(Debug, Default)]
struct Counts {
    /// Features without the front end's motion (a front end that did not run).
    without_motion: u64,
    /// Scans wanted (for a node or the grid) that never came (lost in real time).
    scans_lost: u64,
}

impl Counts {
    /// What was lost, for the launcher (`ipc_types::losses`).
    fn losses(&self) -> [(&'static str, u64); 2] {
        [
            ("scans_without_motion", self.without_motion),
            ("scans_lost", self.scans_lost),
        ]
    }
}

/// The closing summary block.
fn summary(stats: &GlobalStats, counts: &Counts) -> String {
    let refused = stats.no_match
        + stats.unexplained
        + stats.contradicted
        + stats.ambiguous
        + stats.unconstrained;
    let mut text = format!(
        "graph-proc: summary of the back end\n  \
         nodes:           {} in {} submaps ({} retired: they repeated older ones)\n  \
         loop closures:   {} verified by the scans, of {} searched ({} refused: {} not found, \
         {} overlapping too little, {} contradicted, {} ambiguous, {} unconstrained)\n  \
         solves:          {}",
        stats.nodes,
        stats.submaps,
        stats.retired,
        stats.closures,
        stats.attempts,
        refused,
        stats.no_match,
        stats.unexplained,
        stats.contradicted,
        stats.ambiguous,
        stats.unconstrained,
        stats.optimizations,
    );
    if counts.without_motion > 0 {
        text.push_str(&format!(
            "\n  {} scans without the front end's motion left out",
            counts.without_motion
        ));
    }
    if counts.scans_lost > 0 {
        text.push_str(&format!(
            "\n  {} scans wanted were lost (a node waits for the next)",
            counts.scans_lost
        ));
    }
    text
}
