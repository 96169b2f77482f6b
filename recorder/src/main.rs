//! `slam-record`: records the pipeline's topics into DIR/run.mcap as the run goes.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Parser;
use iceoryx2::prelude::{Node, ipc};
use ipc_types::prelude::*;
use ipc_types::{Topic, Wakeable, wait_loop};
use recorder::Recording;
use stage_kit::{say, say_err};

/// Subscribes to every topic of the pipeline (scans, odometry, features, pose estimates, map
/// snapshots, the final path and, from a simulator, the ground truth and the world's
/// corners) and writes them into DIR/run.mcap, in zstd-compressed chunks that reach the disk
/// as each is complete. In lockstep the publishers wait for it like for any subscriber, so
/// nothing is lost.
#[derive(Debug, Parser)]
#[command(name = "slam-record", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// slam-proc publishes its particle cloud every few scans: record it.
    #[arg(long)]
    particles: bool,
    /// map-sink publishes the final path and grid it wrote once it has: record them, and end
    /// only after its end marker (or on a signal: slam-launch stops the run when map-sink
    /// dies).
    #[arg(long)]
    final_map: bool,
    /// graph-proc publishes the back end's path and grid as they stand every few seconds
    /// and at the end of the stream: record them.
    #[arg(long)]
    back_end: bool,
    /// Output directory; the recording is DIR/run.mcap.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

fn main() -> ExitCode {
    stage_kit::run_stage("slam-record", run)
}

/// Longest sleep without a notification: a wake-up missed under load costs at most this.
const WAIT: Duration = Duration::from_millis(100);

/// Every inlet of the recorder; the optional ones exist when their source publishes them.
struct Inlets {
    truth: Option<Inlet<GroundTruthPose>>,
    world: Option<Inlet<WorldCorners>>,
    odometry: Option<Inlet<Odometry>>,
    features: Inlet<Features>,
    poses: Inlet<PoseEstimate>,
    maps: Inlet<MapSnapshot>,
    path: Inlet<PathChunk>,
    scans: Inlet<LaserScan>,
    particles: Option<Inlet<ParticleCloud>>,
    map_path: Option<Inlet<PathChunk>>,
    map_grid: Option<Inlet<GridCells>>,
    graph_path: Option<Inlet<PathChunk>>,
    graph_grid: Option<Inlet<GridCells>>,
}

impl Inlets {
    /// Subscribes to everything, the scans last: the source starts once it counts us among
    /// its scan subscribers, and by then we listen to every other topic too.
    fn open(node: &Node<ipc::Service>, args: &Args) -> Result<Self> {
        // The source creates its ground truth, world and odometry before its scans: once
        // the scans exist, so do they, if the source publishes them.
        wait_for_topic(node, topic::SCAN)?;
        let truth = Inlet::try_open(node, topic::GROUND_TRUTH)?;
        let world = Inlet::try_open(node, topic::WORLD_CORNERS)?;
        let odometry = Inlet::try_open(node, topic::ODOMETRY)?;
        let features = Inlet::open(node, topic::FEATURES)?;
        let poses = Inlet::open(node, topic::POSE)?;
        let maps = Inlet::open(node, topic::MAP)?;
        let path = Inlet::open(node, topic::PATH)?;
        let particles = open_if(args.particles, node, topic::PARTICLES)?;
        let map_path = open_if(args.final_map, node, topic::MAP_PATH)?;
        let map_grid = open_if(args.final_map, node, topic::MAP_GRID)?;
        // The grid before the path: graph-proc publishes it once it counts its path's
        // readers, and by then we read the grid too.
        let graph_grid = open_if(args.back_end, node, topic::GRAPH_GRID)?;
        let graph_path = open_if(args.back_end, node, topic::GRAPH_PATH)?;
        let scans = Inlet::open(node, topic::SCAN)?;
        Ok(Self {
            graph_path,
            graph_grid,
            particles,
            map_path,
            map_grid,
            truth,
            world,
            odometry,
            features,
            poses,
            maps,
            path,
            scans,
        })
    }

    fn wakeables(&self) -> Vec<&dyn Wakeable> {
        let mut all: Vec<&dyn Wakeable> = vec![
            &self.scans,
            &self.features,
            &self.poses,
            &self.maps,
            &self.path,
        ];
        if let Some(truth) = &self.truth {
            all.push(truth);
        }
        if let Some(world) = &self.world {
            all.push(world);
        }
        if let Some(odometry) = &self.odometry {
            all.push(odometry);
        }
        all.extend(self.particles.as_ref().map(|i| i as &dyn Wakeable));
        all.extend(self.map_path.as_ref().map(|i| i as &dyn Wakeable));
        all.extend(self.map_grid.as_ref().map(|i| i as &dyn Wakeable));
        all.extend(self.graph_path.as_ref().map(|i| i as &dyn Wakeable));
        all.extend(self.graph_grid.as_ref().map(|i| i as &dyn Wakeable));
        all
    }

    /// Records everything queued except the poses; returns what it took.
    fn drain_all_but_poses(&self, recording: &mut Recording) -> Result<u64> {
        let mut taken = 0;
        if let Some(world) = &self.world {
            taken += drain(world, |m| recording.world_corners(m))?;
        }
        if let Some(truth) = &self.truth {
            taken += drain(truth, |m| recording.ground_truth(m))?;
        }
        if let Some(odometry) = &self.odometry {
            taken += drain(odometry, |m| recording.odometry(m))?;
        }
        taken += drain(&self.scans, |m| recording.scan(m))?;
        taken += drain(&self.features, |m| recording.features(m))?;
        taken += drain(&self.maps, |m| recording.map(m))?;
        taken += drain(&self.path, |m| recording.path_chunk(m))?;
        if let Some(particles) = &self.particles {
            taken += drain(particles, |m| recording.particles(m))?;
        }
        if let Some(map_path) = &self.map_path {
            taken += drain(map_path, |m| recording.map_path_chunk(m))?;
        }
        if let Some(graph_path) = &self.graph_path {
            taken += drain(graph_path, |m| recording.graph_path_chunk(m))?;
        }
        if let Some(graph_grid) = &self.graph_grid {
            taken += drain(graph_grid, |m| recording.graph_grid_cells(m))?;
        }
        Ok(taken)
    }

    /// Records the pieces of map-sink's grid queued; true once its end marker has come
    /// (map-sink's last word, after its path and grid).
    fn drain_grid(&self, recording: &mut Recording) -> Result<bool> {
        let Some(grid) = &self.map_grid else {
            return Ok(true);
        };
        while let Some(sample) = grid.receive()? {
            if sample.header.is_end_of_stream() {
                return Ok(true);
            }
            recording.grid_cells(&sample)?;
        }
        Ok(false)
    }
}

/// Subscribes to `topic` when `wanted` (its publisher runs in this pipeline).
fn open_if<T: Message>(
    wanted: bool,
    node: &Node<ipc::Service>,
    topic: Topic<T>,
) -> Result<Option<Inlet<T>>> {
    Ok(if wanted {
        Some(Inlet::open(node, topic)?)
    } else {
        None
    })
}

/// Records every message queued on `inlet` with `record`; returns how many.
fn drain<T: Message>(
    inlet: &Inlet<T>,
    mut record: impl FnMut(&T) -> Result<(), recorder::RecordError>,
) -> Result<u64> {
    let mut taken = 0;
    while let Some(sample) = inlet.receive()? {
        record(&sample)?;
        taken += 1;
    }
    Ok(taken)
}

fn run(args: Args) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create directory {}", args.out.display()))?;
    let mut recording = Recording::create(&args.out)?;

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("slam-record")?;
    let inlets = Inlets::open(&node, &args)?;
    say("ready");
    let wakeables = inlets.wakeables();

    // The poses end with slam-proc's marker; map-sink's path and grid come after it, once
    // map-sink has written its files.
    let mut finished = false;
    let mut final_map_done = inlets.map_grid.is_none();
    wait_loop(&wakeables, WAIT, || -> Result<bool> {
        inlets.drain_all_but_poses(&mut recording)?;
        final_map_done = final_map_done || inlets.drain_grid(&mut recording)?;
        while let Some(sample) = inlets.poses.receive()? {
            if sample.header.is_end_of_stream() {
                // slam-proc's last word: what every stage sent before it is queued (each
                // lossless send waited for our room), or comes right behind it.
                finished = true;
                break;
            }
            recording.pose(&sample)?;
        }
        Ok(!(finished && final_map_done))
    })?;
    // Whatever is still queued belongs in the file; a few rounds take what was in flight.
    for _ in 0..3 {
        if inlets.drain_all_but_poses(&mut recording)? == 0 {
            break;
        }
    }

    let summary = recording.finish()?;
    let total: u64 = summary.channels.iter().map(|c| c.messages).sum();
    say_err(&format!(
        "slam-record: {total} messages on {} channels written to {}",
        summary.channels.len(),
        summary.path.display()
    ));
    for channel in &summary.channels {
        say_err(&format!(
            "slam-record:   {} ({}): {}",
            channel.topic, channel.schema, channel.messages
        ));
    }
    if summary.maps_left_out > 0 {
        say_err(&format!(
            "slam-record: {} map snapshots left out (one each {} s of data, and the last)",
            summary.maps_left_out,
            recorder::MAP_PERIOD_NS / 1_000_000_000
        ));
    }
    if summary.path_chunks_out_of_place > 0 {
        say_err(&format!(
            "slam-record: {} chunks of the final path came out of place; the path is not \
             recorded",
            summary.path_chunks_out_of_place
        ));
    }
    if summary.particle_clouds_incomplete > 0 {
        say_err(&format!(
            "slam-record: {} particle clouds left out (a piece of each was lost)",
            summary.particle_clouds_incomplete
        ));
    }
    ipc_types::losses::report(&[
        (
            "particle_clouds_incomplete",
            summary.particle_clouds_incomplete,
        ),
        ("path_chunks_out_of_place", summary.path_chunks_out_of_place),
        (
            "final_map_pieces_out_of_place",
            summary.final_map_pieces_out_of_place,
        ),
    ]);
    Ok(())
}
