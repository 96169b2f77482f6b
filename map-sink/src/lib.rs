//! # map-sink
//!
//! Records a lidar SLAM run into a directory: the estimated trajectory (the final path, the
//! back end's or the filter's, or the online per-scan estimate when none came; the online
//! estimate beside it), the true and dead-reckoning trajectories in TUM format, the corner
//! map as CSV, a saved map (an occupancy grid as ROS map_server reads it and the landmarks,
//! in the saved-map crate's format; [`saved_map::SavedMap::load`] reads it back), a picture
//! of the run as SVG and a `metrics.json` with throughput, latency and, when the truth is
//! known, accuracy scores.
//!
//! This is the library half; the process shell receives the pipeline's messages and feeds
//! them to a [`Recorder`] as plain values, so nothing here depends on the transport.
//!
//! * Trajectories are appended and flushed line by line, so a killed run keeps what it had;
//!   whole-file results are written to `name.tmp` and renamed, so none is ever half written
//!   (see [`TumWriter`] and [`write_atomic`]).
//! * Accuracy is scored through slam-eval, as docs/CONVENTIONS.md says: the estimate is
//!   aligned to the truth by a least-squares rigid SE(2) fit before the absolute trajectory
//!   error ([`slam_eval::ate`]) is taken, and the map corners are moved by the same
//!   transform before they are scored; the summary is slam-eval's [`Metrics`](slam_eval::Metrics).
//! * The occupancy grid is the back end's where it runs ([`RecorderOptions::back_end`]);
//!   without it, it is traced at the end of the run along the final path
//!   ([`OccupancyGrid`]), so the scans are kept until then, compactly ([`CompactScan`],
//!   [`ScanKeeper`]). Mapping on a saved map, the run's grid is laid over the saved one
//!   ([`prior_grid`]) unless slam-proc found that the saved map does not explain the run's
//!   scans ([`slam_eval::MapFit`], [`Recorder::set_map_fit`]).
//! * Localizing on a saved map, the scores count from the first converged pose on, the
//!   search before it scored apart ([`Recorder::record_localization`]).
//! * Given ground-truth relations ([`RecorderOptions::relations`]), the trajectory files are
//!   scored with the relative-pose error of Kuemmerle et al. 2009 through slam-eval
//!   ([`slam_eval::score_run`]; why here and not in slam-launch is said there).
//!
//! ```
//! use map_sink::{Pose2, Recorder, RecorderOptions};
//!
//! # fn main() -> Result<(), map_sink::SinkError> {
//! let dir = std::env::temp_dir().join(format!("map-sink-doc-{}", std::process::id()));
//! let mut recorder = Recorder::create(&dir, RecorderOptions::default())?;
//! for seq in 0..10_u64 {
//!     let stamp_ns = seq * 100_000_000;
//!     let truth = Pose2::new(0.1 * seq as f64, 0.0, 0.0);
//!     recorder.record_truth(stamp_ns, truth)?;
//!     recorder.record_scan(seq, -1.0, 0.5, 0.1, 30.0, &[2.0, 2.1, f32::NAN, 2.3, 2.2]);
//!     recorder.record_pose(seq, stamp_ns, truth, None, Some(3_000_000))?;
//! }
//! let metrics = recorder.finish()?;
//! assert_eq!(metrics.frames_processed, 10);
//! assert!(metrics.ate_rmse_m.is_some_and(|e| e < 1e-9));
//! # std::fs::remove_dir_all(&dir).ok();
//! # Ok(())
//! # }
//! ```

mod atomic;
mod corner_shift;
mod corners_csv;
mod error;
mod grid_image;
mod line_file;
mod map_writer;
mod path_assembly;
mod prior_grid;
mod recorder;
mod scan_keeper;
mod svg;
mod tum;
mod tum_stream;

pub use atomic::{tmp_path, write_atomic};
pub use back_end::compact_scan::{Beam, CompactScan};
pub use back_end::occupancy_grid::{
    CellState, FREE_PROBABILITY, GridCell, GridConfig, GridError, OCCUPIED_PROBABILITY,
    OccupancyGrid, RESOLUTION_RANGE_M,
};
pub use corners_csv::{corners_csv, corners_csv_header};
pub use error::SinkError;
pub use grid_image::{encode_png, grid_pixels};
pub use line_file::LineFile;
pub use map_writer::{map_files, write_map};
pub use path_assembly::{ChunkError, PathAssembly};
pub use prior_grid::{PRIOR_FREE_LOG_ODDS, PRIOR_OCCUPIED_LOG_ODDS, PriorGridError, prior_grid};
pub use recorder::{
    FinishedRun, GridReport, MAP_CORNERS_FILE, MAP_SVG_FILE, Recorder, RecorderOptions,
};
pub use scan_keeper::ScanKeeper;
pub use slam_geom::MapCorner;
pub use slam_geom::Pose2;
pub use slam_geom::StampedPose;
pub use svg::{SvgInput, render_svg};
pub use tum::TumWriter;
pub use tum_stream::TumStream;
