//! `graph-proc`: global SLAM (the `back-end` library) as a stage. It reads the front end's
//! motion from the features topic and, where the robot moved enough for a new node, the
//! scan's beams; it builds submaps, closes the loops the scans confirm and solves the pose
//! graph, and publishes the graph's path as it stands every [`INTERIM_PERIOD`] and, solved
//! once more, at the end of the stream (or when stopped).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use back_end::{GlobalConfig, GlobalSlam, GlobalStats};
use clap::Parser;
use ipc_types::prelude::*;
use nalgebra::Matrix3;
use scan_match::FrontEndConfig;
use stage_kit::held_scans::HeldScans;
use stage_kit::{say, say_err};

/// How often the path is published while the run goes on: a viewer, a recording and a run
/// stopped without a last word all have one at most this old.
const INTERIM_PERIOD: Duration = Duration::from_secs(2);

/// Subscribes to the features (the front end's motion) and the scans, and publishes the
/// pose graph's path on `graph/path` as it goes and at the end.
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
    // The path goes out in many chunks: lossless whatever the run's delivery. Made first:
    // map-sink waits for it.
    let path = Outlet::create(&domain, &node, topic::GRAPH_PATH, Delivery::Lossless, 0)?;
    let features = Inlet::open(&node, topic::FEATURES)?;
    let scans = Inlet::open(&node, topic::SCAN)?;
    let delivery = features.delivery();
    say("ready");
    if delivery == Delivery::Lossless {
        path.wait_for_subscribers(args.subscribers, None)?;
    }

    let mut held = HeldScans::default();
    let mut counts = Counts::default();
    let mut last_stamp = 0;
    let mut interim_at = Instant::now();
    loop {
        if wait_any(&[&features, &scans], Duration::from_millis(100))? == Wake::Shutdown {
            break;
        }
        held.hold(&scans)?;
        while let Some(sample) = features.receive()? {
            if sample.header.is_end_of_stream() {
                publish_final(&path, &mut global, sample.header.stamp_ns)?;
                say_err(&summary(&global.stats(), &counts));
                ipc_types::losses::report(&counts.losses());
                return Ok(());
            }
            let Some(motion) = sample.motion() else {
                counts.without_motion += 1;
                continue;
            };
            let odom_from_robot = motion.pose.into();
            let points = if global.wants_node(&odom_from_robot) {
                let scan = held.wait_for(&scans, sample.header.seq, delivery)?;
                if scan.is_none() {
                    counts.nodes_without_scan += 1;
                }
                scan.map(|s| global.node_scan(&s.geometry, &s.ranges))
            } else {
                None
            };
            global
                .add_scan(
                    sample.header.stamp_ns,
                    &odom_from_robot,
                    &motion.increment.into(),
                    &Matrix3::from_row_slice(&motion.increment_covariance),
                    points,
                )
                .context("the pose graph")?;
            last_stamp = sample.header.stamp_ns;
        }
        if interim_at.elapsed() >= INTERIM_PERIOD && last_stamp > 0 {
            path.publish_path(&stamped(&global), last_stamp, PathForm::Interim)?;
            interim_at = Instant::now();
        }
    }
    // Stopped by a signal: the path as far as it got, solved once more.
    publish_final(&path, &mut global, last_stamp)?;
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

/// Solves the graph with everything in it and publishes its path as final.
fn publish_final(outlet: &Outlet<PathChunk>, global: &mut GlobalSlam, stamp_ns: u64) -> Result<()> {
    let started = Instant::now();
    global.finish().context("the pose graph's last solve")?;
    let path = stamped(global);
    outlet.publish_path(&path, stamp_ns, PathForm::Final)?;
    say_err(&format!(
        "graph-proc: path of {} poses solved and published in {:.2} s",
        path.len(),
        started.elapsed().as_secs_f64()
    ));
    Ok(())
}

/// What the run made do without.
#[derive(Debug, Default)]
struct Counts {
    /// Features without the front end's motion (a front end that did not run).
    without_motion: u64,
    /// Nodes whose scan never came (lost in real time).
    nodes_without_scan: u64,
}

impl Counts {
    /// What was lost, for the launcher (`ipc_types::losses`).
    fn losses(&self) -> [(&'static str, u64); 2] {
        [
            ("scans_without_motion", self.without_motion),
            ("nodes_without_scan", self.nodes_without_scan),
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
         nodes:           {} in {} submaps\n  \
         loop closures:   {} verified by the scans, of {} searched ({} refused: {} not found, \
         {} overlapping too little, {} contradicted, {} ambiguous, {} unconstrained)\n  \
         solves:          {}",
        stats.nodes,
        stats.submaps,
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
    if counts.nodes_without_scan > 0 {
        text.push_str(&format!(
            "\n  {} nodes whose scan was lost waited for the next",
            counts.nodes_without_scan
        ));
    }
    text
}
