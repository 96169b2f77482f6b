//! `map-sink`: records a run (trajectory, map, picture, metrics) from the pipeline's topics.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use clap::Parser;
use ipc_types::Wakeable;
use ipc_types::prelude::*;
use map_sink::{
    FinishedRun, GridConfig, OccupancyGrid, PathAssembly, Recorder, RecorderOptions, StampedPose,
};
use slam_eval::{FrameCounts, METRICS_FILE, MapFit, RelationsFile};
use stage_kit::{say, say_err};

/// Subscribes to poses, maps, scans and (from a simulator) the ground truth and writes
/// trajectory.tum, ground_truth.tum, map_corners.csv, the saved map (map.yaml, map.pgm,
/// map.png, landmarks.json), map.svg and metrics.json into DIR; with --relations,
/// metrics.json and the picture also give the relative-pose error of each trajectory file.
#[derive(Debug, Parser)]
#[command(name = "map-sink", version)]
struct Args {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    domain: String,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Print `status key=value ...` progress lines on stdout (for slam-launch).
    #[arg(long)]
    status: bool,
    /// Title of the picture.
    #[arg(long, default_value = "lidar SLAM run")]
    title: String,
    /// Ground-truth relations (Kuemmerle et al. 2009: t1 t2 x y z roll pitch yaw) to score
    /// the trajectories against at the end; read and checked before anything else.
    #[arg(long, value_name = "FILE")]
    relations: Option<PathBuf>,
    /// Edge of the occupancy grid's cells, metres (0.005 to 5).
    #[arg(long, value_name = "METRES", default_value_t = GridConfig::default().resolution_m)]
    resolution: f64,
    /// Once the files are written, publish the final path of trajectory.tum on `map/path`
    /// and the grid of map.pgm on `map/grid`, then an end marker on `map/grid` (for a
    /// recording).
    #[arg(long)]
    publish_final: bool,
    /// Mapping on a saved map (a run's output directory): the grid starts from its grid,
    /// and this run's scans add to it.
    #[arg(long, value_name = "DIR")]
    map: Option<PathBuf>,
    /// The back end (graph-proc) runs: the final path is its `graph/path` and the grid its
    /// `graph/grid`, not the filter's path and a grid traced here. The run waits for them at
    /// its end and keeps no scan.
    #[arg(long)]
    back_end: bool,
}

/// How long a stopped run waits for the final path, which slam-proc or the back end sends
/// as it stops: without it the online estimate would stand in.
const PATH_WAIT_ON_STOP: Duration = Duration::from_secs(2);
/// How often that wait looks for the path (the wait on the inlets ends at once once a stop
/// was asked for).
const PATH_POLL: Duration = Duration::from_millis(20);

const STATUS_PERIOD: Duration = Duration::from_millis(500);

fn main() -> ExitCode {
    stage_kit::run_stage("map-sink", run)
}

/// What the status line shows, from the latest pose.
#[derive(Debug, Default)]
struct Progress {
    poses: u64,
    latency_ms: f64,
    neff: f64,
    particles: u32,
    map: u32,
    /// `PoseEstimate::localization` of the last pose.
    localization: u32,
    first_pose: Option<Instant>,
}

impl Progress {
    fn line(&self) -> String {
        let elapsed = self.first_pose.map_or(0.0, |t| t.elapsed().as_secs_f64());
        let rate = if elapsed > 0.0 {
            self.poses.saturating_sub(1) as f64 / elapsed
        } else {
            0.0
        };
        let mut line = format!(
            "status frames={} scans_per_s={rate:.1} latency_ms={:.2} neff={:.1} particles={} map={}",
            self.poses, self.latency_ms, self.neff, self.particles, self.map
        );
        match self.localization {
            PoseEstimate::SEARCHING => line.push_str(" localization=searching"),
            PoseEstimate::CONVERGED => line.push_str(" localization=converged"),
            _ => {}
        }
        line
    }
}

fn run(args: Args) -> Result<()> {
    // A bad relations file fails the run now, not after the whole log.
    let relations = args
        .relations
        .as_deref()
        .map(RelationsFile::read)
        .transpose()?;
    // Read before the recorder clears the output directory, which may be the map's own.
    let saved = saved_grid(args.map.as_deref())?;
    let mut recorder = Recorder::create(
        &args.out,
        RecorderOptions {
            title: args.title.clone(),
            relations,
            grid: GridConfig {
                resolution_m: args.resolution,
                ..GridConfig::default()
            },
            back_end: args.back_end,
            ..RecorderOptions::default()
        },
    )?;

    if let Some(saved) = &saved {
        recorder.map_on(saved)?;
    }

    let domain = Domain::new(&args.domain)?;
    let node = domain.node("map-sink")?;
    // Made now, before the recorder looks for them: it subscribes once the scans exist.
    let final_outlets = if args.publish_final {
        Some((
            Outlet::create(&domain, &node, topic::MAP_PATH, Delivery::Lossless, 0)?,
            Outlet::create(&domain, &node, topic::MAP_GRID, Delivery::Lossless, 0)?,
        ))
    } else {
        None
    };
    // The source creates its ground truth and world before the scans: once the scans exist,
    // so do they, if the source is a simulator.
    wait_for_topic(&node, topic::SCAN)?;
    let truth = Inlet::try_open(&node, topic::GROUND_TRUTH)?;
    let world = Inlet::try_open(&node, topic::WORLD_CORNERS)?;
    // The scans last: the source starts once its readers are subscribed, and in real time
    // slam-proc does not wait for its readers, so a pose sent before map-sink subscribed
    // to the poses would be lost.
    let maps = Inlet::open(&node, topic::MAP)?;
    let poses = Inlet::open(&node, topic::POSE)?;
    let path = Inlet::open(&node, topic::PATH)?;
    let graph = if args.back_end {
        Some(Graph {
            path: Inlet::open(&node, topic::GRAPH_PATH)?,
            grid: Inlet::open(&node, topic::GRAPH_GRID)?,
        })
    } else {
        None
    };
    let scans = Inlet::open(&node, topic::SCAN)?;
    say("ready");

    let mut wakeables: Vec<&dyn Wakeable> = vec![&poses, &scans, &maps, &path];
    if let Some(graph) = &graph {
        wakeables.push(&graph.path);
        wakeables.push(&graph.grid);
    }
    if let Some(truth) = &truth {
        wakeables.push(truth);
    }
    if let Some(world) = &world {
        wakeables.push(world);
    }

    let mut progress = Progress::default();
    let mut told = 0;
    let mut assembly = PathAssembly::new();
    // The filter's path is final only in a run without the back end's.
    let mut final_path = FinalPath::new(graph.is_some());
    let mut graph_pieces = GraphPieces::default();
    let mut published = None;
    let mut last_status = Instant::now();
    let mut finished = false;
    let mut stop_seen = None;
    while !finished {
        if wait_any(&wakeables, Duration::from_millis(100))? == Wake::Shutdown {
            let stopped = *stop_seen.get_or_insert_with(Instant::now);
            // The back end (or slam-proc, without it) sends its path as it stops: take it,
            // unless the run localizes on a saved map (no path comes) or never started.
            let mapping = progress.poses > 0 && progress.localization == PoseEstimate::MAPPING;
            if !mapping || final_path.complete || stopped.elapsed() >= PATH_WAIT_ON_STOP {
                break;
            }
            std::thread::sleep(PATH_POLL);
        }
        if let Some(world) = &world {
            while let Some(sample) = world.receive()? {
                recorder.set_true_corners(sample.corners().iter().map(|c| [c.x, c.y]).collect());
            }
        }
        if let Some(truth) = &truth {
            while let Some(sample) = truth.receive()? {
                if !sample.header.is_end_of_stream() {
                    let p = sample.pose;
                    recorder.record_truth(sample.header.stamp_ns, p.into())?;
                }
            }
        }
        drain_scans(&scans, &mut recorder, &mut published)?;
        while let Some(sample) = maps.receive()? {
            recorder.set_map(map_corners(&sample));
        }
        drain_path(&path, &mut assembly, &mut recorder, &mut final_path, false)?;
        if let Some(graph) = &graph {
            graph.drain(&mut graph_pieces, &mut recorder, &mut final_path)?;
        }
        while let Some(sample) = poses.receive()? {
            if sample.header.is_end_of_stream() {
                finished = true;
                // Everything sent before the end marker is already queued: take it.
                drain_scans(&scans, &mut recorder, &mut published)?;
                while let Some(sample) = maps.receive()? {
                    recorder.set_map(map_corners(&sample));
                }
                drain_path(&path, &mut assembly, &mut recorder, &mut final_path, false)?;
                break;
            }
            let latency = sample.header.sent_ns.checked_sub(sample.scan_sent_ns);
            recorder.record_pose(
                sample.header.seq,
                sample.header.stamp_ns,
                // The weighted mean is the filter's estimate of each pose; the best
                // particle (whose map is published) flickers as the weights change.
                sample.mean.into(),
                Some(sample.dead_reckoning.into()),
                latency,
            )?;
            progress.poses += 1;
            progress.first_pose.get_or_insert_with(Instant::now);
            progress.latency_ms = latency.unwrap_or(0) as f64 * 1e-6;
            progress.neff = sample.effective_particles;
            progress.particles = sample.particle_count;
            progress.map = sample.map_corners;
            progress.localization = sample.localization;
            if sample.localization != PoseEstimate::MAPPING {
                recorder.record_localization(
                    sample.header.seq,
                    sample.header.stamp_ns,
                    sample.localization == PoseEstimate::CONVERGED,
                );
            }
            // On a saved map, slam-proc judges how well it explains the scans.
            if sample.localization != PoseEstimate::MAPPING || saved.is_some() {
                recorder.set_map_fit(MapFit {
                    beams_judged: sample.map_beams_judged,
                    beams_explained: sample.map_beams_explained,
                });
            }
        }
        if finished
            && let Some(graph) = &graph
            && !final_path.complete
        {
            // The back end solves its graph once more at the end of the stream, then sends
            // its grid and path.
            finished = graph.wait_for_final(&mut graph_pieces, &mut recorder, &mut final_path)?;
        }
        tell_incomplete(&recorder, &mut told);
        if args.status && last_status.elapsed() >= STATUS_PERIOD {
            say(&progress.line());
            last_status = Instant::now();
        }
    }
    if args.status {
        say(&progress.line());
    }

    if let Some(published) = published {
        recorder.set_counts(FrameCounts {
            published,
            processed: progress.poses,
            dropped: published.saturating_sub(progress.poses),
        });
    }
    tell_incomplete(&recorder, &mut told);
    if recorder.saved_grid_set_aside() {
        say_err(&format!(
            "map-sink: the saved map in {} does not fit this run's scans: its grid is left \
             out, {} holds this run's map alone (metrics.json: map_fit)",
            args.map.as_deref().unwrap_or(Path::new("")).display(),
            args.out.display()
        ));
    }
    let finished = recorder.finish_run()?;
    if let Some((path_outlet, grid_outlet)) = &final_outlets {
        // The run's results are written; what cannot be passed on is said, not fatal.
        if let Err(e) = publish_final(path_outlet, grid_outlet, &finished) {
            say_err(&format!(
                "map-sink: cannot publish the final path and grid: {e:#}"
            ));
        }
    }
    let FinishedRun {
        metrics,
        report: grid,
        corners_left_out,
        ..
    } = finished;
    say_err(&format!(
        "map-sink: {} poses, {} map corners written to {}",
        metrics.frames_processed,
        metrics.map_corners,
        args.out.display()
    ));
    if corners_left_out > 0 {
        say_err(&format!(
            "map-sink: {corners_left_out} of the filter's corners lay off the grid's walls \
             once moved onto the final path and were left out"
        ));
    }
    if let Some(g) = grid.as_ref().filter(|_| args.back_end) {
        say_err(&format!(
            "map-sink: occupancy grid {} x {} cells of {} m from the back end, written in {:.2} s",
            g.width, g.height, g.resolution_m, g.build_s
        ));
    }
    if let Some(g) = grid.filter(|_| !args.back_end) {
        say_err(&format!(
            "map-sink: occupancy grid {} x {} cells of {} m from {} scans ({} beams kept, {:.1} MB) in {:.2} s, {:.1} MB of log-odds",
            g.width,
            g.height,
            g.resolution_m,
            g.scans_traced,
            g.beams_kept,
            g.scan_bytes as f64 / 1e6,
            g.build_s,
            g.grid_bytes as f64 / 1e6
        ));
        if g.revisits_left_out > 0 {
            say_err(&format!(
                "map-sink: {} scans left out of the grid: taken where kept scans had been, past the cap on the beams kept",
                g.revisits_left_out
            ));
        }
    }
    if let Some(peak) = peak_memory_kb() {
        say_err(&format!(
            "map-sink: peak memory {:.1} MB",
            peak as f64 / 1e3
        ));
    }
    let incomplete = &metrics.incomplete_outputs;
    if !incomplete.is_empty() {
        // A closing summary (slam-launch shows it on the console): the run went on, but
        // its results are not all there.
        let listed = if incomplete.iter().any(|o| o.file == METRICS_FILE) {
            String::new()
        } else {
            format!(" (also in {})", METRICS_FILE)
        };
        say_err(&format!(
            "map-sink: summary: {} of the run's files incomplete{listed}",
            incomplete.len()
        ));
        for output in incomplete {
            say_err(&format!("  {}", output.line()));
        }
        anyhow::bail!("the run's results are incomplete");
    }
    Ok(())
}

/// Publishes the final path and the grid as they were written, then the grid's end marker:
/// the recorder's cue that nothing more comes from map-sink.
fn publish_final(
    path_outlet: &Outlet<PathChunk>,
    grid_outlet: &Outlet<GridCells>,
    finished: &FinishedRun,
) -> Result<()> {
    let path = finished.final_path.as_deref().unwrap_or_default();
    let stamp_ns = path.last().map_or(0, |p| p.stamp_ns);
    if !path.is_empty() {
        let poses: Vec<ipc_types::StampedPose> = path.iter().map(|&p| p.into()).collect();
        path_outlet.publish_path(&poses, stamp_ns, Form::Final)?;
    }
    if let Some(grid) = &finished.grid {
        publish_grid(grid_outlet, grid, stamp_ns)?;
    }
    grid_outlet.publish_end_of_stream(u64::from(finished.grid.is_some()), stamp_ns)?;
    Ok(())
}

/// The grid's cells as map.pgm's trinary pixels, row by row from the lowest y, in pieces.
fn publish_grid(outlet: &Outlet<GridCells>, grid: &OccupancyGrid, stamp_ns: u64) -> Result<()> {
    let (width, height) = (grid.width(), grid.height());
    let (Ok(width), Ok(height)) = (u32::try_from(width), u32::try_from(height)) else {
        anyhow::bail!("the grid of {width} x {height} cells is too large to publish");
    };
    let geometry = GridGeometry {
        resolution: grid.resolution_m(),
        origin: grid.origin(),
        width,
        height,
    };
    outlet.publish_grid(geometry, &grid.pixels(), stamp_ns, Form::Final)?;
    Ok(())
}

/// Says on stderr which files stopped since the last call, as it happens.
fn tell_incomplete(recorder: &Recorder, told: &mut usize) {
    for output in recorder.incomplete_outputs().iter().skip(*told) {
        say_err(&format!("map-sink: {}; the run goes on", output.line()));
    }
    *told = recorder.incomplete_outputs().len();
}

/// Which path is the run's final one, and whether it has come whole.
struct FinalPath {
    from_graph: bool,
    complete: bool,
}

impl FinalPath {
    fn new(from_graph: bool) -> Self {
        Self {
            from_graph,
            complete: false,
        }
    }
}

/// Takes a path's chunks; a complete path goes to the recorder when it is the one the run
/// keeps (`from_graph` says whose it is; the other is not assembled), and the path is done
/// once the final form came. A chunk that does not fit is reported and the path left
/// incomplete (the online estimate stands in).
fn drain_path(
    inlet: &Inlet<PathChunk>,
    assembly: &mut PathAssembly,
    recorder: &mut Recorder,
    final_path: &mut FinalPath,
    from_graph: bool,
) -> Result<()> {
    while let Some(chunk) = inlet.receive()? {
        if from_graph != final_path.from_graph {
            continue;
        }
        let poses: Vec<StampedPose> = chunk
            .poses()
            .iter()
            .map(|&p| StampedPose::from(p))
            .collect();
        if let Err(e) = assembly.add(chunk.first, chunk.total, &poses) {
            say_err(&format!("map-sink: {e}; the final path is incomplete"));
            continue;
        }
        if let Some(path) = assembly.take_complete() {
            // A path as it stands is kept too: a run stopped before the last one came
            // still has it.
            if from_graph {
                recorder.set_back_end_path(path);
            } else {
                recorder.set_final_path(path);
            }
            final_path.complete = chunk.header.is_final();
        }
    }
    Ok(())
}

/// How long the end of a run waits for the back end's path after the filter's last pose:
/// its last solve, bounded all the same (a back end that died must not hang the end).
const GRAPH_PATH_WAIT: Duration = Duration::from_secs(30);

/// The back end's results, as they come.
struct Graph {
    path: Inlet<PathChunk>,
    grid: Inlet<GridCells>,
}

/// The back end's path and grid, as far as their pieces have come.
#[derive(Default)]
struct GraphPieces {
    path: PathAssembly,
    grid: GridPieces,
}

impl Graph {
    /// Takes what has come of the back end's grid and path. The back end sends its grid
    /// before its path: once the final path is whole, so is the grid before it.
    fn drain(
        &self,
        pieces: &mut GraphPieces,
        recorder: &mut Recorder,
        final_path: &mut FinalPath,
    ) -> Result<()> {
        self.drain_grid(&mut pieces.grid, recorder)?;
        drain_path(&self.path, &mut pieces.path, recorder, final_path, true)?;
        self.drain_grid(&mut pieces.grid, recorder)
    }

    fn drain_grid(&self, pieces: &mut GridPieces, recorder: &mut Recorder) -> Result<()> {
        while let Some(piece) = self.grid.receive()? {
            let Some(whole) = pieces.add(&piece) else {
                continue;
            };
            let g = whole.geometry;
            let grid =
                OccupancyGrid::from_pixels(g.resolution, g.origin, g.width as usize, &whole.cells)
                    .context("the back end's grid")?;
            recorder.set_back_end_grid(grid);
        }
        Ok(())
    }

    /// Waits for the back end's final path at the end of the stream; false when stopped
    /// first.
    fn wait_for_final(
        &self,
        pieces: &mut GraphPieces,
        recorder: &mut Recorder,
        final_path: &mut FinalPath,
    ) -> Result<bool> {
        let since = Instant::now();
        while !final_path.complete && since.elapsed() < GRAPH_PATH_WAIT {
            if wait_any(&[&self.path, &self.grid], PATH_POLL)? == Wake::Shutdown {
                return Ok(false);
            }
            self.drain(pieces, recorder, final_path)?;
        }
        if !final_path.complete {
            say_err("map-sink: the back end's path did not come; the filter's estimate stands in");
        }
        if pieces.grid.out_of_place > 0 {
            say_err(&format!(
                "map-sink: {} pieces of the back end's grid did not fit it and were dropped",
                pieces.grid.out_of_place
            ));
        }
        Ok(true)
    }
}

fn drain_scans(
    scans: &Inlet<LaserScan>,
    recorder: &mut Recorder,
    published: &mut Option<u64>,
) -> Result<()> {
    while let Some(scan) = scans.receive()? {
        if scan.header.is_end_of_stream() {
            // The end marker's sequence number is the number of scans the source sent.
            *published = Some(scan.header.seq);
            continue;
        }
        recorder.set_mount(scan.robot_from_sensor.into());
        recorder.record_source_stamp(scan.header.stamp_ns, scan.source_stamp_ns());
        recorder.record_scan(
            scan.header.seq,
            f64::from(scan.angle_min),
            f64::from(scan.angle_increment),
            f64::from(scan.range_min),
            f64::from(scan.range_max),
            scan.ranges(),
        );
    }
    Ok(())
}

fn map_corners(snapshot: &MapSnapshot) -> Vec<map_sink::MapCorner> {
    snapshot.corners().iter().map(|&c| c.into()).collect()
}

/// The grid of the saved map in `dir`, if there is one and it has a grid.
fn saved_grid(dir: Option<&std::path::Path>) -> Result<Option<saved_map::GridMap>> {
    let Some(dir) = dir else { return Ok(None) };
    let saved = saved_map::SavedMap::load(dir)
        .with_context(|| format!("cannot use the map in {}", dir.display()))?;
    Ok(saved.grid)
}

/// This process's peak resident memory (Linux `VmHWM`), kilobytes; `None` elsewhere.
fn peak_memory_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}
