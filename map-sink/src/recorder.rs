//! The recorder: takes a run's messages as they arrive and writes the run's files.

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::fs;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::atomic::write_atomic;
use crate::corner_shift::follow_final_path;
use crate::corners_csv::corners_csv;
use crate::error::SinkError;
use crate::map_writer::map_files;
use crate::prior_grid::prior_grid;
use crate::scan_keeper::ScanKeeper;
use crate::svg::{SvgInput, render_svg};
use crate::tum_stream::TumStream;
use back_end::compact_scan::CompactScan;
use back_end::global_grid::{self, Layer};
use back_end::occupancy_grid::{CellState, GridConfig, OccupancyGrid};
use saved_map::{GridMap, LANDMARKS_FILE, MAP_PGM_FILE, MAP_PNG_FILE, MAP_YAML_FILE};
use slam_eval::{
    AteStats, DEAD_RECKONING_FILE, FitVerdict, FrameCounts, GROUND_TRUTH_FILE, IncompleteOutput,
    METRICS_FILE, MapFit, Metrics, RelationsFile, RelativePoseErrors, SearchPhase, TRAJECTORY_FILE,
    TRAJECTORY_ONLINE_FILE, ate, distance, nearest_rmse, percentile, score_run,
};
use slam_geom::MapCorner;
use slam_geom::Point2;
use slam_geom::Pose2;
use slam_geom::Se2Alignment;
use slam_geom::StampedPose;
use slam_geom::format_tum_line;

/// The final map, written atomically by [`Recorder::finish`].
pub const MAP_CORNERS_FILE: &str = "map_corners.csv";
/// The picture, written atomically by [`Recorder::finish`].
pub const MAP_SVG_FILE: &str = "map.svg";

/// How a [`Recorder`] records.
#[derive(Debug, Clone, PartialEq)]
pub struct RecorderOptions {
    /// The first line of the picture.
    pub title: String,
    /// The occupancy grid (`map.pgm`, `map.yaml`, `map.png`, the picture's background).
    pub grid: GridConfig,
    /// Ground-truth relations to score the trajectory files against when the run finishes.
    pub relations: Option<RelationsFile>,
    /// How far a pose's stamp may be from a relation's, nanoseconds.
    pub relations_tolerance_ns: u64,
    /// The back end (graph-proc) runs: its path and grid are the run's
    /// ([`Recorder::set_back_end_path`], [`Recorder::set_back_end_grid`]), so no scan is
    /// kept and nothing is traced here.
    pub back_end: bool,
}

impl Default for RecorderOptions {
    fn default() -> Self {
        Self {
            title: "lidar SLAM run".to_owned(),
            grid: GridConfig::default(),
            relations: None,
            relations_tolerance_ns: slam_eval::DEFAULT_TOLERANCE_NS,
            back_end: false,
        }
    }
}

/// What the occupancy grid cost, for the run's log.
#[derive(Debug, Clone, PartialEq)]
pub struct GridReport {
    /// Cells across (x) and down (y).
    pub width: usize,
    pub height: usize,
    pub resolution_m: f64,
    /// Scans traced (kept and found on the final path).
    pub scans_traced: usize,
    /// Beams kept over the whole run, and the bytes the kept scans held until the end.
    pub beams_kept: usize,
    pub scan_bytes: usize,
    /// Scans left out because a kept scan had their viewpoint (a long run going round the
    /// same places, past [`ScanKeeper`]'s cap).
    pub revisits_left_out: usize,
    /// Bytes of the grid's log-odds (as much again was used while tracing).
    pub grid_bytes: usize,
    /// Laying or tracing the grid and writing the run's results, seconds.
    pub build_s: f64,
}

/// What a finished run wrote, for whoever passes it on (map-sink publishes it for a
/// recording).
#[derive(Debug)]
pub struct FinishedRun {
    pub metrics: Metrics,
    /// What the occupancy grid cost.
    pub report: Option<GridReport>,
    /// The poses of `trajectory.tum` (the final path, or the online estimate standing in),
    /// or `None` when the file was not written.
    pub final_path: Option<Vec<StampedPose>>,
    /// The grid of `map.pgm` and `map.yaml`, or `None` when there is none or it was not
    /// written.
    pub grid: Option<OccupancyGrid>,
    /// The filter's corners left out for lying where the back end's grid shows free space.
    pub corners_left_out: usize,
}

/// A pose whose trajectory lines wait for its scan (or a later one, if this stage lost it):
/// the scan says where the sensor sits and under which stamp the source knows it.
#[derive(Debug, Clone, Copy)]
struct Unwritten {
    seq: u64,
    stamp_ns: u64,
    online: Pose2,
    dead_reckoning: Option<Pose2>,
}

#[derive(Debug, Clone, Copy)]
struct Estimate {
    stamp_ns: u64,
    pose: Pose2,
    dead_reckoning: Option<Pose2>,
}

/// Records one run into a directory.
///
/// The online estimate (`trajectory_online.tum`) and the other per-scan trajectories are
/// appended and flushed line by line as poses arrive (once their scan has), so a killed run
/// keeps every pose it had but those still waiting for their scan ([`crate::TumWriter`] explains why they are not written atomically); the map, the
/// picture and the metrics are whole-file results written atomically by
/// [`finish`](Self::finish), so a crash never leaves one half-written.
///
/// A file that cannot be written (a full disk) does not stop the run: a trajectory file
/// stops at its last whole line, a whole-file result is left out, and each is listed in
/// [`incomplete_outputs`](Self::incomplete_outputs) and in metrics.json, which is written
/// last.
///
/// Poses, truth and scans are matched by sequence number (the scan's), in any arrival order.
/// Without the back end, the occupancy grid is traced at the end from the final path, so
/// scans are kept until then: compactly, and only those taken from a new viewpoint
/// ([`ScanKeeper`]). With it, the grid is the back end's.
#[derive(Debug)]
pub struct Recorder {
    dir: PathBuf,
    options: RecorderOptions,
    online: TumStream,
    ground_truth: TumStream,
    dead_reckoning: TumStream,
    incomplete: Vec<IncompleteOutput>,
    estimates: BTreeMap<u64, Estimate>,
    /// The simulator's true poses by stamp: the final path carries stamps only.
    truth: BTreeMap<u64, Pose2>,
    final_path: Option<Vec<StampedPose>>,
    scans: ScanKeeper,
    /// Mapping on a saved map: its grid on this run's cells ([`Self::map_on`]).
    prior: Option<OccupancyGrid>,
    /// The back end's latest grid, in its frame.
    back_end_grid: Option<OccupancyGrid>,
    /// On a saved map, the motion from the back end's frame to the map's.
    map_from_graph: Option<Pose2>,
    /// The back end's grid laid in the run's frame, at the end ([`Self::lay_back_end_grid`]).
    laid_grid: Option<OccupancyGrid>,
    /// Corners left out for lying off the walls of the grid written.
    corners_left_out: usize,
    /// Whether the run maps on a saved map (whose frame the filter's estimate is in).
    on_saved_map: bool,
    latencies_ns: Vec<u64>,
    map: Vec<MapCorner>,
    true_corners: Vec<[f64; 2]>,
    counts: Option<FrameCounts>,
    scans_seen: u64,
    /// Where the sensor sits on the robot, from the first scan: the pipeline estimates the
    /// sensor's poses, the trajectories written are the robot's.
    robot_from_sensor: Option<Pose2>,
    first_message: Option<Instant>,
    last_message: Option<Instant>,
    wall_s: Option<f64>,
    /// Earliest and latest pose stamps, for the duration the run covers.
    stamps_ns: Option<(u64, u64)>,
    /// Localizing: the first converged pose's sequence number and stamp.
    converged_at: Option<(u64, u64)>,
    /// Whether the run localizes on a saved map (its scores count from convergence).
    localizing: bool,
    /// On a saved map: how well it explained the scans, as slam-proc last counted.
    map_fit: Option<MapFit>,
    /// The source's own stamps of the scans it re-stamped (a log's scans stamped late), by
    /// the stamp the pipeline knows them by: what the run writes carries the source's.
    source_stamps: HashMap<u64, u64>,
    /// Poses whose lines wait for their scan, in the order they came.
    unwritten: VecDeque<Unwritten>,
    /// The highest sequence number of the scans recorded.
    scans_through: Option<u64>,
}

impl Recorder {
    /// Creates `dir` if needed and starts `trajectory_online.tum`. Files of an earlier run in the
    /// same directory are removed, so none can be mistaken for this run's.
    pub fn create(dir: &Path, options: RecorderOptions) -> Result<Self, SinkError> {
        options.grid.validate().map_err(SinkError::InvalidOption)?;
        let resolution = options.grid.resolution_m;
        fs::create_dir_all(dir).map_err(|e| SinkError::io("create directory", dir, e))?;
        for stale in [
            GROUND_TRUTH_FILE,
            TRAJECTORY_FILE,
            DEAD_RECKONING_FILE,
            MAP_CORNERS_FILE,
            MAP_SVG_FILE,
            METRICS_FILE,
            MAP_PGM_FILE,
            MAP_YAML_FILE,
            MAP_PNG_FILE,
            LANDMARKS_FILE,
        ] {
            let path = dir.join(stale);
            match fs::remove_file(&path) {
                Err(e) if e.kind() != ErrorKind::NotFound => {
                    return Err(SinkError::io("remove stale", path, e));
                }
                _ => {}
            }
        }
        let online = TumStream::start(&dir.join(TRAJECTORY_ONLINE_FILE))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            scans: ScanKeeper::new(resolution),
            prior: None,
            back_end_grid: None,
            map_from_graph: None,
            laid_grid: None,
            corners_left_out: 0,
            on_saved_map: false,
            options,
            online,
            ground_truth: TumStream::lazy(&dir.join(GROUND_TRUTH_FILE)),
            dead_reckoning: TumStream::lazy(&dir.join(DEAD_RECKONING_FILE)),
            incomplete: Vec::new(),
            estimates: BTreeMap::new(),
            truth: BTreeMap::new(),
            final_path: None,
            latencies_ns: Vec::new(),
            map: Vec::new(),
            true_corners: Vec::new(),
            counts: None,
            scans_seen: 0,
            robot_from_sensor: None,
            first_message: None,
            last_message: None,
            wall_s: None,
            stamps_ns: None,
            converged_at: None,
            localizing: false,
            map_fit: None,
            source_stamps: HashMap::new(),
            unwritten: VecDeque::new(),
            scans_through: None,
        })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The files that stopped short or were not written so far, in the order it happened.
    pub fn incomplete_outputs(&self) -> &[IncompleteOutput] {
        &self.incomplete
    }

    /// Records the estimate for scan `seq`, stamped with the scan's `stamp_ns`, with the
    /// dead-reckoning pose and the scan-to-pose latency when known. Its trajectory lines are
    /// appended once the scan (or a later one) has been recorded, which says where the
    /// sensor sits and the source's own stamp of the scan.
    pub fn record_pose(
        &mut self,
        seq: u64,
        stamp_ns: u64,
        est: Pose2,
        dead_reckoning: Option<Pose2>,
        latency_ns: Option<u64>,
    ) -> Result<(), SinkError> {
        self.touch();
        self.stamps_ns = Some(match self.stamps_ns {
            Some((first, last)) => (first.min(stamp_ns), last.max(stamp_ns)),
            None => (stamp_ns, stamp_ns),
        });
        self.unwritten.push_back(Unwritten {
            seq,
            stamp_ns,
            online: est,
            dead_reckoning,
        });
        self.write_lines(false);
        self.estimates.insert(
            seq,
            Estimate {
                stamp_ns,
                pose: est,
                dead_reckoning,
            },
        );
        self.latencies_ns.extend(latency_ns);
        self.scans.add_pose(seq, stamp_ns, est);
        Ok(())
    }

    /// Appends the trajectory lines of the poses whose scan (or a later one) has come, or
    /// of every pose held (`all`, at the end).
    fn write_lines(&mut self, all: bool) {
        while let Some(next) = self.unwritten.front().copied() {
            if !all && self.scans_through.is_none_or(|through| next.seq > through) {
                return;
            }
            self.unwritten.pop_front();
            let written_ns = self.source_stamp(next.stamp_ns);
            let online = self.robot_pose(&next.online);
            self.incomplete
                .extend(self.online.append(written_ns, online));
            if let Some(dr) = next.dead_reckoning {
                let dr = self.robot_pose(&dr);
                self.incomplete
                    .extend(self.dead_reckoning.append(written_ns, dr));
            }
        }
    }

    /// The scan the pipeline knows by `stamp_ns` has `source_stamp_ns` as the source's own
    /// stamp: the files written say that one. Record it before [`Self::record_scan`] of
    /// that scan.
    pub fn record_source_stamp(&mut self, stamp_ns: u64, source_stamp_ns: u64) {
        if source_stamp_ns != stamp_ns {
            self.source_stamps.insert(stamp_ns, source_stamp_ns);
        }
    }

    /// The source's own stamp of the scan the pipeline stamped `stamp_ns`.
    fn source_stamp(&self, stamp_ns: u64) -> u64 {
        self.source_stamps
            .get(&stamp_ns)
            .copied()
            .unwrap_or(stamp_ns)
    }

    /// The sensor's mount on the robot, as the scans give it; the first one holds for the run.
    pub fn set_mount(&mut self, robot_from_sensor: Pose2) {
        self.robot_from_sensor.get_or_insert(robot_from_sensor);
    }

    /// The robot's pose where the sensor's is `world_from_sensor`.
    fn robot_pose(&self, world_from_sensor: &Pose2) -> Pose2 {
        match &self.robot_from_sensor {
            Some(mount) => world_from_sensor.compose(&mount.inverse()),
            None => *world_from_sensor,
        }
    }

    /// `path` as the robot's poses, for `trajectory.tum`.
    fn robot_path(&self, path: &[StampedPose]) -> String {
        let robot: Vec<StampedPose> = path
            .iter()
            .map(|p| StampedPose {
                stamp_ns: self.source_stamp(p.stamp_ns),
                pose: self.robot_pose(&p.pose),
            })
            .collect();
        tum_text(&robot)
    }

    /// Records the simulator's true pose at `stamp_ns` (its scan's).
    pub fn record_truth(&mut self, stamp_ns: u64, pose: Pose2) -> Result<(), SinkError> {
        self.touch();
        self.incomplete
            .extend(self.ground_truth.append(stamp_ns, pose));
        self.truth.insert(stamp_ns, pose);
        Ok(())
    }

    /// Records scan `seq` for the occupancy grid: kept (compactly) if it was taken from a
    /// new viewpoint, which its online estimate decides, now if known, else when it comes.
    pub fn record_scan(
        &mut self,
        seq: u64,
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
        ranges: &[f32],
    ) {
        self.touch();
        self.scans_seen += 1;
        self.scans_through = Some(self.scans_through.map_or(seq, |through| through.max(seq)));
        if self.options.back_end {
            self.write_lines(false);
            return;
        }
        let grid = &self.options.grid;
        let scan = CompactScan::new(
            angle_min,
            angle_increment,
            range_min,
            range_max,
            ranges,
            grid.resolution_m,
            grid.no_return_reach_m,
        );
        let estimate = self.estimates.get(&seq).map(|e| (e.stamp_ns, e.pose));
        self.scans.add_scan(seq, scan, estimate);
        self.write_lines(false);
    }

    /// Mapping on a saved map: the run's grid starts from `saved` (its scans add to it, or
    /// the back end's grid is laid over it: [`crate::prior_grid`]).
    pub fn map_on(&mut self, saved: &GridMap) -> Result<(), SinkError> {
        self.prior = prior_grid(saved, self.options.grid.resolution_m)?;
        self.on_saved_map = true;
        Ok(())
    }

    /// The back end's path, which becomes `trajectory.tum` (the latest path wins). Its
    /// graph starts at the run's first scan; on a saved map the filter's estimate is in the
    /// map's frame, so the path is moved there whole: by the rigid motion that best lays it
    /// on that estimate (from convergence, where the run reports one).
    pub fn set_back_end_path(&mut self, path: Vec<StampedPose>) {
        self.map_from_graph = self
            .on_saved_map
            .then(|| self.map_from_graph(&path))
            .flatten();
        let path = match self.map_from_graph {
            Some(map_from_graph) => path
                .into_iter()
                .map(|p| StampedPose {
                    stamp_ns: p.stamp_ns,
                    pose: map_from_graph.compose(&p.pose),
                })
                .collect(),
            None => path,
        };
        self.final_path = Some(path);
    }

    /// The motion from the back end's frame to the filter's, fitted over the poses both have.
    fn map_from_graph(&self, path: &[StampedPose]) -> Option<Pose2> {
        let from = self.converged_at.map_or(0, |(seq, _)| seq);
        let online: HashMap<u64, Pose2> = self
            .estimates
            .range(from..)
            .map(|(_, e)| (e.stamp_ns, e.pose))
            .collect();
        let pairs: Vec<(Pose2, Pose2)> = path
            .iter()
            .filter_map(|p| Some((p.pose, *online.get(&p.stamp_ns)?)))
            .collect();
        Pose2::fit(&pairs)
    }

    /// The corners, placed by the filter, moved as the back end's final path moved the
    /// filter's estimate of the poses near them: they lie on the grid traced from that path.
    /// A corner the robot passed more than once moves by the mean of the passes'
    /// corrections, which need not be its own: one that lands off the walls of the grid
    /// written is left out, lest a run on the saved map hold on to it.
    fn corners_onto_final_path(&mut self) {
        let Some(path) = &self.final_path else {
            return;
        };
        let online: HashMap<u64, Pose2> = self
            .estimates
            .values()
            .map(|e| (e.stamp_ns, e.pose))
            .collect();
        let (filter, last): (Vec<StampedPose>, Vec<StampedPose>) = path
            .iter()
            .filter_map(|p| {
                let pose = *online.get(&p.stamp_ns)?;
                let stamp_ns = p.stamp_ns;
                Some((StampedPose { stamp_ns, pose }, *p))
            })
            .unzip();
        if let Some(moved) = follow_final_path(&self.map, &filter, &last) {
            self.map = moved;
        }
        let Some(grid) = &self.laid_grid else {
            return;
        };
        let before = self.map.len();
        self.map
            .retain(|corner| wall_near(grid, Point2::new(corner.x, corner.y), CORNER_WALL_REACH_M));
        self.corners_left_out = before - self.map.len();
    }

    /// The back end's grid (in its frame; the latest wins), which becomes `map.pgm`: on a
    /// saved map laid over the saved grid where the back end's path was laid.
    pub fn set_back_end_grid(&mut self, grid: OccupancyGrid) {
        self.back_end_grid = Some(grid);
    }

    /// The filter's final path, which becomes `trajectory.tum` (the latest path wins).
    pub fn set_final_path(&mut self, path: Vec<StampedPose>) {
        self.final_path = Some(path);
    }

    /// Replaces the map (the latest snapshot wins), in the SLAM frame.
    pub fn set_map(&mut self, corners: Vec<MapCorner>) {
        self.map = corners;
    }

    /// The world's true corner positions, for scoring the map.
    pub fn set_true_corners(&mut self, corners: Vec<[f64; 2]>) {
        self.true_corners = corners;
    }

    /// The pipeline's own frame counts. Without them, `processed` is the number of poses
    /// recorded, `published` the larger of that and the scans recorded, and `dropped` the
    /// difference.
    pub fn set_counts(&mut self, counts: FrameCounts) {
        self.counts = Some(counts);
    }

    /// Localizing on a saved map: the pose of scan `seq` is the localizer's, `converged` or
    /// still searching. The scores count from the first converged pose on.
    pub fn record_localization(&mut self, seq: u64, stamp_ns: u64, converged: bool) {
        self.localizing = true;
        if converged {
            self.converged_at.get_or_insert((seq, stamp_ns));
        }
    }

    /// On a saved map: how well it explains the scans so far (the latest counts win). A
    /// run mapping on its grid ([`Self::map_on`]) whose counts say it does not fit leaves
    /// the saved grid out: slam-proc set the map aside, and the run's map is its own.
    pub fn set_map_fit(&mut self, fit: MapFit) {
        self.map_fit = Some(fit);
    }

    /// Whether the run mapped on a saved grid that did not fit its scans (and so was left
    /// out of the run's map).
    pub fn saved_grid_set_aside(&self) -> bool {
        self.prior.is_some() && self.misfit()
    }

    /// The saved map's fit says it does not explain the scans.
    fn misfit(&self) -> bool {
        self.map_fit
            .is_some_and(|fit| fit.verdict() == FitVerdict::DoesNotFit)
    }

    /// Overrides the measured wall time (first to last message recorded), seconds.
    pub fn set_wall_time(&mut self, wall_s: f64) {
        self.wall_s = Some(wall_s);
    }

    /// Syncs the trajectories, scores the run (against the relations too, if given: every
    /// trajectory file is complete by then), traces the occupancy grid from the final path
    /// and writes `map_corners.csv`, the map (`map.pgm`, `map.yaml`, `map.png`,
    /// `landmarks.json`), `map.svg` and finally `metrics.json`, each atomically. A file
    /// that cannot be written is left out and listed in the metrics' `incomplete_outputs`
    /// (metrics.json itself only in those returned). Returns the metrics.
    pub fn finish(self) -> Result<Metrics, SinkError> {
        self.finish_with_report().map(|(metrics, _)| metrics)
    }

    /// [`finish`](Self::finish), also saying what the occupancy grid cost.
    pub fn finish_with_report(self) -> Result<(Metrics, Option<GridReport>), SinkError> {
        self.finish_run().map(|run| (run.metrics, run.report))
    }

    /// [`finish`](Self::finish), also handing on what the occupancy grid cost, the final
    /// path and the grid as they were written. Each file is written atomically, so a kill
    /// at any moment leaves whole files: `trajectory.tum`, `map_corners.csv`,
    /// `landmarks.json` and `metrics.json` first (cheap), then the grid (`map.pgm`,
    /// `map.png`, `map.yaml`, `landmarks.json` naming them), `map.svg` and `metrics.json`
    /// again, last.
    pub fn finish_run(mut self) -> Result<FinishedRun, SinkError> {
        self.write_lines(true);
        for stream in [&self.online, &self.ground_truth, &self.dead_reckoning] {
            self.incomplete.extend(stream.sync());
        }
        if self.misfit() {
            // Another building's grid: the run's map is its own.
            self.prior = None;
        }
        let started = Instant::now();
        if self.options.back_end {
            self.laid_grid = self.lay_back_end_grid()?;
            self.corners_onto_final_path();
        }
        let path = match &self.final_path {
            Some(path) => path.clone(),
            // No final path came: the online estimate stands in.
            None => self
                .estimates
                .values()
                .map(|e| StampedPose {
                    stamp_ns: e.stamp_ns,
                    pose: e.pose,
                })
                .collect(),
        };
        let written = self.write_results(&path)?;
        let report = written.grid.as_ref().map(|(grid, traced)| GridReport {
            width: grid.width(),
            height: grid.height(),
            resolution_m: self.options.grid.resolution_m,
            scans_traced: *traced,
            beams_kept: self.scans.beams(),
            scan_bytes: self.scans.bytes(),
            revisits_left_out: self.scans.revisits(),
            grid_bytes: grid.bytes(),
            build_s: started.elapsed().as_secs_f64(),
        });
        Ok(FinishedRun {
            metrics: written.metrics,
            report,
            final_path: written.path_written.then_some(path),
            grid: written
                .grid
                .filter(|_| written.map_written)
                .map(|(grid, _)| grid),
            corners_left_out: self.corners_left_out,
        })
    }

    /// Every result of `path`, each file written atomically in turn.
    fn write_results(&mut self, path: &[StampedPose]) -> Result<Written, SinkError> {
        let unwritten = self.incomplete.len();
        self.write_result(TRAJECTORY_FILE, self.robot_path(path).as_bytes());
        let path_written = self.incomplete.len() == unwritten;
        let relative_pose_error = self
            .scored_relations()
            .map(|truth| score_run(&self.dir, &truth, self.options.relations_tolerance_ns))
            .transpose()?;
        let scored = self.scored(path, relative_pose_error);
        self.write_result(MAP_CORNERS_FILE, corners_csv(&self.map).as_bytes());
        // The landmarks and the metrics before the grid, which takes long on a long run: a
        // run killed while tracing it keeps a landmark map (without a grid) and its numbers.
        let landmarks = map_files(None, &self.map);
        self.write_map_files(landmarks);
        self.write_metrics(&scored.metrics);
        let grid = self.grid(path)?;
        let map_written =
            self.write_map_files(map_files(grid.as_ref().map(|(grid, _)| grid), &self.map));
        let svg = self.picture(
            &scored.trajectory,
            scored.stats,
            &scored.metrics,
            grid.as_ref().map(|(grid, _)| grid),
        );
        self.write_result(MAP_SVG_FILE, svg.as_bytes());
        let metrics = self.write_metrics(&scored.metrics);
        Ok(Written {
            metrics,
            path_written,
            grid,
            map_written,
        })
    }

    /// Writes `metrics` as metrics.json, atomically, with the run's incomplete files; a
    /// metrics.json that cannot be written is listed in what is returned (for the closing
    /// summary), not in the file.
    fn write_metrics(&self, metrics: &Metrics) -> Metrics {
        let mut metrics = metrics.clone();
        metrics.incomplete_outputs = self.incomplete.clone();
        let written = serde_json::to_string_pretty(&metrics)
            .map_err(SinkError::from)
            .and_then(|mut json| {
                json.push('\n');
                write_atomic(&self.dir.join(METRICS_FILE), json.as_bytes())
            });
        if let Err(e) = written {
            metrics
                .incomplete_outputs
                .push(IncompleteOutput::new(METRICS_FILE, "not written", &e));
        }
        metrics
    }

    /// Writes the map's files (`files` as [`map_files`] made them) atomically in their
    /// order; true when all were written.
    fn write_map_files(&mut self, files: Result<Vec<(&'static str, Vec<u8>)>, SinkError>) -> bool {
        let written = files.and_then(|files| {
            files
                .into_iter()
                .try_for_each(|(name, contents)| write_atomic(&self.dir.join(name), &contents))
        });
        match written {
            Ok(()) => {
                self.incomplete.retain(|o| o.file != map_files_label());
                true
            }
            Err(e) => {
                // The map's files name each other: they are written in an order that leaves
                // none naming a file that is not there, and the first failure ends them.
                let label = map_files_label();
                if !self.incomplete.iter().any(|o| o.file == label) {
                    self.incomplete
                        .push(IncompleteOutput::new(&label, "not all written", &e));
                }
                false
            }
        }
    }

    /// The metrics of `path` as the run's trajectory, with the trajectory's positions and
    /// its alignment to the truth for the picture.
    fn scored(
        &self,
        path: &[StampedPose],
        relative_pose_error: Option<RelativePoseErrors>,
    ) -> Scored {
        let trajectory: Vec<[f64; 2]> = path.iter().map(|p| p.pose.position().into()).collect();
        let stats = self.score_path(path);
        let online_stats = self.score(|e| Some(e.pose));
        let dead_reckoning_stats = self.score(|e| e.dead_reckoning);
        let map_corner_rmse_m = stats.and_then(|s| {
            let aligned: Vec<[f64; 2]> = self
                .map
                .iter()
                .map(|c| s.alignment.apply([c.x, c.y]))
                .collect();
            nearest_rmse(&aligned, &self.true_corners)
        });
        let mut metrics = self.metrics(&trajectory, stats, dead_reckoning_stats, map_corner_rmse_m);
        metrics.search_phase = self.search_phase(stats.as_ref());
        metrics.relative_pose_error = relative_pose_error;
        metrics.online_ate_rmse_m = online_stats.map(|s| s.rmse_m);
        Scored {
            metrics,
            trajectory,
            stats,
        }
    }

    /// The run's grid: the back end's where it runs ([`Self::lay_back_end_grid`]), else
    /// traced here.
    fn grid(&self, path: &[StampedPose]) -> Result<Option<(OccupancyGrid, usize)>, SinkError> {
        if self.options.back_end {
            Ok(self.laid_grid.clone().map(|g| (g, 0)))
        } else {
            self.traced_grid(path)
        }
    }

    /// The back end's grid in the run's frame: on a saved map, laid over the saved grid
    /// where the back end's path was laid.
    fn lay_back_end_grid(&self) -> Result<Option<OccupancyGrid>, SinkError> {
        Ok(match (&self.back_end_grid, &self.prior) {
            (Some(run), Some(prior)) => {
                let map_from_graph = self.map_from_graph.unwrap_or(Pose2::IDENTITY);
                let layers: [(Pose2, &dyn Layer); 2] =
                    [(Pose2::IDENTITY, prior), (map_from_graph, run)];
                global_grid::render(&layers, self.options.grid.resolution_m)?
            }
            (run, prior) => run.as_ref().or(prior.as_ref()).cloned(),
        })
    }

    /// The occupancy grid of the scans kept, each traced from its pose on `path` (matched by
    /// stamp; a scan the path does not hold is left out), with the number traced.
    fn traced_grid(
        &self,
        path: &[StampedPose],
    ) -> Result<Option<(OccupancyGrid, usize)>, SinkError> {
        let poses: HashMap<u64, Pose2> = path.iter().map(|p| (p.stamp_ns, p.pose)).collect();
        let scans: Vec<(Pose2, &CompactScan)> = self
            .scans
            .kept()
            .iter()
            .filter_map(|(stamp, scan)| Some((*poses.get(stamp)?, scan)))
            .collect();
        let grid = OccupancyGrid::build_on(&self.options.grid, self.prior.as_ref(), &scans)?;
        Ok(grid.map(|g| (g, scans.len())))
    }

    /// Writes a whole-file result atomically; one that cannot be written is listed as
    /// incomplete and the run's other results still go on.
    fn write_result(&mut self, name: &str, contents: &[u8]) {
        if let Err(e) = write_atomic(&self.dir.join(name), contents) {
            self.incomplete
                .push(IncompleteOutput::new(name, "not written", &e));
        }
    }

    fn touch(&mut self) {
        let now = Instant::now();
        self.first_message.get_or_insert(now);
        self.last_message = Some(now);
    }

    /// The sequence number and stamp of the first pose the scores count: every pose of a
    /// mapping run, a localization's from its first converged one; `None` for a
    /// localization that never converged (it has nothing to score but its search).
    fn scored_from(&self) -> Option<(u64, u64)> {
        if self.localizing {
            self.converged_at
        } else {
            Some((0, 0))
        }
    }

    /// The relations to score the trajectories against: those whose two stamps are both
    /// from [`Self::scored_from`] on.
    fn scored_relations(&self) -> Option<RelationsFile> {
        let truth = self.options.relations.as_ref()?;
        let (_, from_ns) = self.scored_from()?;
        Some(RelationsFile {
            path: truth.path.clone(),
            relations: truth
                .relations
                .iter()
                .filter(|r| r.t1_ns.min(r.t2_ns) >= from_ns)
                .cloned()
                .collect(),
        })
    }

    /// ATE of the final path over the poses whose stamps have truth (from
    /// [`Self::scored_from`]).
    fn score_path(&self, path: &[StampedPose]) -> Option<AteStats> {
        let (_, from_ns) = self.scored_from()?;
        let (est, truth): (Vec<[f64; 2]>, Vec<[f64; 2]>) = path
            .iter()
            .filter(|p| p.stamp_ns >= from_ns)
            .filter_map(|p| {
                let truth = self.truth.get(&p.stamp_ns)?;
                Some((xy(&p.pose), xy(truth)))
            })
            .unzip();
        ate(&est, &truth)
    }

    /// ATE of the trajectory `pick` takes from each estimate, over the scans with truth
    /// (from [`Self::scored_from`]).
    fn score(&self, pick: impl Fn(&Estimate) -> Option<Pose2>) -> Option<AteStats> {
        let (from, _) = self.scored_from()?;
        let (est, truth) = self.paired(from.., pick);
        ate(&est, &truth)
    }

    /// The positions `pick` takes from the estimates of the scans in `seqs` that have
    /// truth, with the truth's.
    fn paired(
        &self,
        seqs: impl std::ops::RangeBounds<u64>,
        pick: impl Fn(&Estimate) -> Option<Pose2>,
    ) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        self.estimates
            .range(seqs)
            .filter_map(|(_, e)| {
                let (estimate, truth) = (pick(e)?, self.truth.get(&e.stamp_ns)?);
                Some((xy(&estimate), xy(truth)))
            })
            .unzip()
    }

    /// A localization's search before convergence, its positions scored by `converged`'s
    /// alignment (the converged poses'), or by their own when it never converged.
    fn search_phase(&self, converged: Option<&AteStats>) -> Option<SearchPhase> {
        if !self.localizing {
            return None;
        }
        let until = self.converged_at.map_or(u64::MAX, |(seq, _)| seq);
        let scans = self.estimates.range(..until).count() as u64;
        let (est, truth) = self.paired(..until, |e| Some(e.pose));
        let ate_rmse_m = match (converged, self.converged_at) {
            (Some(stats), Some(_)) => {
                let squares: Vec<f64> = est
                    .iter()
                    .zip(&truth)
                    .map(|(e, t)| distance(stats.alignment.apply(*e), *t).powi(2))
                    .collect();
                (!squares.is_empty())
                    .then(|| (squares.iter().sum::<f64>() / squares.len() as f64).sqrt())
            }
            (None, None) => ate(&est, &truth).map(|s| s.rmse_m),
            // Converged, without truth to align by.
            _ => None,
        };
        Some(SearchPhase { scans, ate_rmse_m })
    }

    fn metrics(
        &self,
        trajectory: &[[f64; 2]],
        stats: Option<AteStats>,
        dead_reckoning: Option<AteStats>,
        map_corner_rmse_m: Option<f64>,
    ) -> Metrics {
        let counts = self.counts.unwrap_or_else(|| {
            let processed = self.estimates.len() as u64;
            let published = processed.max(self.scans_seen);
            FrameCounts {
                published,
                processed,
                dropped: published - processed,
            }
        });
        let measured = match (self.first_message, self.last_message) {
            (Some(first), Some(last)) => last.duration_since(first).as_secs_f64(),
            _ => 0.0,
        };
        let wall_s = self.wall_s.unwrap_or(measured);
        let latencies_ms: Vec<f64> = self
            .latencies_ns
            .iter()
            .map(|&ns| ns as f64 / 1e6)
            .collect();
        Metrics {
            frames_published: counts.published,
            frames_processed: counts.processed,
            frames_dropped: counts.dropped,
            path_length_m: trajectory.windows(2).map(|w| distance(w[0], w[1])).sum(),
            map_corners: self.map.len(),
            wall_s,
            duration_s: self
                .stamps_ns
                .map(|(first, last)| (last - first) as f64 * 1e-9),
            scans_per_s: (wall_s > 0.0).then(|| counts.processed as f64 / wall_s),
            latency_ms_p50: percentile(&latencies_ms, 50.0),
            latency_ms_p99: percentile(&latencies_ms, 99.0),
            ate_rmse_m: stats.map(|s| s.rmse_m),
            ate_max_m: stats.map(|s| s.max_m),
            final_error_m: stats.map(|s| s.final_error_m),
            map_corner_rmse_m,
            dead_reckoning_ate_rmse_m: dead_reckoning.map(|s| s.rmse_m),
            online_ate_rmse_m: None,
            relative_pose_error: None,
            converged_at_scan: self.converged_at.map(|(seq, _)| seq),
            converged_at_stamp: self
                .converged_at
                .map(|(_, stamp_ns)| slam_geom::format_stamp(self.source_stamp(stamp_ns))),
            search_phase: None,
            map_fit: self.map_fit.map(|fit| fit.summary()),
            incomplete_outputs: Vec::new(),
        }
    }

    /// The picture is drawn in the world frame when there is an alignment: the estimate,
    /// its map, the dead reckoning (which shares the SLAM frame) and the occupancy grid are moved
    /// by the trajectory alignment onto the truth. Without one (no truth, or no scan with
    /// both an estimate and truth) it is drawn in the SLAM frame and the truth is left out.
    fn picture(
        &self,
        trajectory: &[[f64; 2]],
        stats: Option<AteStats>,
        metrics: &Metrics,
        grid: Option<&OccupancyGrid>,
    ) -> String {
        let placement = stats.map_or(Se2Alignment::IDENTITY, |s| s.alignment);
        let trajectory: Vec<[f64; 2]> = trajectory.iter().map(|p| placement.apply(*p)).collect();
        let dead_reckoning: Vec<[f64; 2]> = self
            .estimates
            .values()
            .filter_map(|e| {
                e.dead_reckoning
                    .map(|p| placement.apply(p.position().into()))
            })
            .collect();
        let map_corners: Vec<MapCorner> =
            self.map.iter().map(|c| placement.apply_corner(c)).collect();
        let (ground_truth, true_corners): (Vec<[f64; 2]>, &[[f64; 2]]) = if stats.is_some() {
            (self.truth.values().map(xy).collect(), &self.true_corners)
        } else {
            (Vec::new(), &[])
        };
        let note = if stats.is_some() {
            "World frame: the estimate, its map, its occupancy grid and the dead reckoning are moved onto the truth by the least-squares SE(2) fit of the estimated to the true positions."
        } else {
            "SLAM frame: the first pose is the origin, facing +x."
        };
        let cells = grid.map(OccupancyGrid::known_cells).unwrap_or_default();
        let subtitle = subtitle(metrics);
        render_svg(&SvgInput {
            title: &self.options.title,
            subtitle: &subtitle,
            note,
            cell_m: self.options.grid.resolution_m,
            cells: &cells,
            cells_placement: placement,
            trajectory: &trajectory,
            ground_truth: &ground_truth,
            dead_reckoning: &dead_reckoning,
            map_corners: &map_corners,
            true_corners,
        })
    }
}

/// The map's files written from a grid, in their order.
const MAP_NAMES: [&str; 4] = [MAP_PGM_FILE, MAP_PNG_FILE, MAP_YAML_FILE, LANDMARKS_FILE];

/// The map's files as one output in the list of incomplete ones.
fn map_files_label() -> String {
    MAP_NAMES.join(", ")
}

/// A TUM file of `path`.
fn tum_text(path: &[StampedPose]) -> String {
    path.iter()
        .map(|p| format_tum_line(p.stamp_ns, &p.pose))
        .collect()
}

/// How far from a corner the back end's grid must show a wall for it to stay, metres: the
/// cell the corner lies in and the next, whichever way the two walls' cells were cut.
const CORNER_WALL_REACH_M: f64 = 0.1;

/// Whether `grid` holds an occupied cell within `reach` of `at`.
fn wall_near(grid: &OccupancyGrid, at: Point2, reach: f64) -> bool {
    let res = grid.resolution_m();
    let [x0, y0] = grid.origin();
    let span = (reach / res).ceil() as i64;
    let col = ((at.x - x0) / res).floor() as i64;
    let row = ((at.y - y0) / res).floor() as i64;
    for r in row - span..=row + span {
        for c in col - span..=col + span {
            let (Ok(c), Ok(r)) = (usize::try_from(c), usize::try_from(r)) else {
                continue;
            };
            if c >= grid.width() || r >= grid.height() {
                continue;
            }
            let centre = Point2::new(x0 + (c as f64 + 0.5) * res, y0 + (r as f64 + 0.5) * res);
            if (centre - at).norm() > reach + 0.5 * res {
                continue;
            }
            if grid.state(c, r) == CellState::Occupied {
                return true;
            }
        }
    }
    false
}

/// A path's metrics, positions and alignment to the truth.
struct Scored {
    metrics: Metrics,
    trajectory: Vec<[f64; 2]>,
    stats: Option<AteStats>,
}

/// What the end of the run wrote.
struct Written {
    /// As written in metrics.json (with the files that could not be written).
    metrics: Metrics,
    path_written: bool,
    /// The grid and the scans traced into it.
    grid: Option<(OccupancyGrid, usize)>,
    map_written: bool,
}

/// The picture's metric lines.
fn subtitle(m: &Metrics) -> Vec<String> {
    let optional = |v: Option<f64>, unit: &str| {
        v.map_or_else(|| "n/a".to_owned(), |v| format!("{v:.2} {unit}"))
    };
    let first = format!(
        "{} scans processed, {} dropped  ·  path {:.1} m  ·  {} map corners  ·  {}  ·  latency p50 {}, p99 {}",
        m.frames_processed,
        m.frames_dropped,
        m.path_length_m,
        m.map_corners,
        optional(m.scans_per_s, "scans/s"),
        optional(m.latency_ms_p50, "ms"),
        optional(m.latency_ms_p99, "ms"),
    );
    let mut lines = vec![first];
    match (m.ate_rmse_m, m.ate_max_m, m.final_error_m) {
        (Some(rmse), Some(max), Some(last)) => {
            let mut line = format!("ATE RMSE {rmse:.3} m, max {max:.3} m, final {last:.3} m");
            if let Some(v) = m.map_corner_rmse_m {
                line.push_str(&format!("  ·  map corner RMSE {v:.3} m"));
            }
            if let Some(v) = m.dead_reckoning_ate_rmse_m {
                line.push_str(&format!("  ·  dead reckoning ATE RMSE {v:.3} m"));
            }
            lines.push(line);
        }
        // A replay has no true poses, but its relations are ground truth all the same.
        _ if m.relative_pose_error.is_some() => {}
        _ => lines.push("no ground truth".to_owned()),
    }
    lines.extend(m.relative_pose_error.as_ref().map(rpe_line));
    lines
}

/// The relative-pose errors in one line, e.g. `relative pose error: estimate 0.580 +- 1.782
/// m, 2.60 +- 6.04 deg (1172/1172 relations)  ·  front end ...`.
fn rpe_line(rpe: &RelativePoseErrors) -> String {
    let mut parts = Vec::new();
    for (name, summary) in [
        ("estimate", &rpe.trajectory),
        ("online", &rpe.trajectory_online),
        ("front end", &rpe.dead_reckoning),
    ] {
        let Some(summary) = summary else { continue };
        let errors = summary.errors.map_or_else(
            || "no relation with both poses".to_owned(),
            |errors| errors.to_string(),
        );
        parts.push(format!(
            "{name} {errors} ({}/{} relations)",
            summary.used, summary.relations
        ));
    }
    if parts.is_empty() {
        return "relative pose error: no trajectory to score".to_owned();
    }
    format!("relative pose error: {}", parts.join("  ·  "))
}

/// A pose's position as the scoring and drawing code takes it.
fn xy(pose: &Pose2) -> [f64; 2] {
    pose.position().into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_restamped_scans_pose_is_written_under_the_sources_stamp() -> Result<(), SinkError> {
        let dir =
            std::env::temp_dir().join(format!("map-sink-unit-restamped-{}", std::process::id()));
        let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
        // The source stamped the second scan late (at 40, after the third at 30) and
        // re-stamped it 20 for the pipeline.
        let mut path = Vec::new();
        for (seq, stamp, own) in [(0, 10, 10), (1, 20, 40), (2, 30, 30)] {
            recorder.record_source_stamp(stamp, own);
            let pose = Pose2::new(seq as f64, 0.0, 0.0);
            recorder.record_pose(seq, stamp, pose, Some(pose), None)?;
            path.push(StampedPose {
                stamp_ns: stamp,
                pose,
            });
        }
        recorder.set_final_path(path.clone());
        recorder.finish()?;
        for file in [TRAJECTORY_ONLINE_FILE, DEAD_RECKONING_FILE, TRAJECTORY_FILE] {
            let text = std::fs::read_to_string(dir.join(file)).unwrap_or_default();
            let written: Vec<u64> = slam_geom::parse_tum(&text)
                .unwrap_or_default()
                .iter()
                .map(|(_, p)| p.stamp_ns)
                .collect();
            assert_eq!(written, [10, 40, 30], "{file}");
        }
        let _ = std::fs::remove_dir_all(&dir);
        Ok(())
    }

    #[test]
    fn a_pose_waits_for_its_scan_to_be_written_under_the_sources_stamp() -> Result<(), SinkError> {
        let dir = std::env::temp_dir().join(format!("map-sink-unit-waits-{}", std::process::id()));
        let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
        let read = |dir: &Path| -> Vec<u64> {
            let text = std::fs::read_to_string(dir.join(DEAD_RECKONING_FILE)).unwrap_or_default();
            slam_geom::parse_tum(&text)
                .unwrap_or_default()
                .iter()
                .map(|(_, p)| p.stamp_ns)
                .collect()
        };
        let ranges = [1.0_f32, 2.0, 3.0];
        recorder.record_source_stamp(10, 10);
        recorder.record_scan(0, 0.0, 0.5, 0.1, 10.0, &ranges);
        recorder.record_pose(0, 10, Pose2::default(), Some(Pose2::default()), None)?;
        // The pose of a scan re-stamped 20 (its own stamp 40) comes before the scan.
        recorder.record_pose(1, 20, Pose2::default(), Some(Pose2::default()), None)?;
        assert_eq!(read(&dir), [10]);
        recorder.record_source_stamp(20, 40);
        recorder.record_scan(1, 0.0, 0.5, 0.1, 10.0, &ranges);
        assert_eq!(read(&dir), [10, 40]);
        // A scan this stage lost: the next one lets its pose out, under the pipeline's stamp.
        recorder.record_pose(2, 30, Pose2::default(), Some(Pose2::default()), None)?;
        recorder.record_source_stamp(45, 45);
        recorder.record_scan(3, 0.0, 0.5, 0.1, 10.0, &ranges);
        assert_eq!(read(&dir), [10, 40, 30]);
        let _ = std::fs::remove_dir_all(&dir);
        Ok(())
    }

    #[test]
    fn scans_meet_their_pose_in_either_order() -> Result<(), SinkError> {
        let dir = std::env::temp_dir().join(format!("map-sink-unit-order-{}", std::process::id()));
        let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
        let ranges = [1.0_f32, 2.0, 3.0];
        recorder.record_scan(0, 0.0, 0.5, 0.1, 10.0, &ranges);
        assert!(recorder.scans.kept().is_empty(), "no pose yet");
        recorder.record_pose(0, 7, Pose2::default(), None, None)?;
        recorder.record_pose(1, 8, Pose2::new(50.0, 0.0, 0.0), None, None)?;
        recorder.record_scan(1, 0.0, 0.5, 0.1, 10.0, &ranges);
        let stamps: Vec<u64> = recorder.scans.kept().iter().map(|(s, _)| *s).collect();
        assert_eq!(stamps, [7, 8]);
        assert_eq!(recorder.scans.pending(), 0);
        let _ = std::fs::remove_dir_all(&dir);
        Ok(())
    }
}
