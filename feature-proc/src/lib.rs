//! Line and corner features from planar lidar scans, the library half of the
//! `feature-proc` process.
//!
//! Pipeline per scan ([`Extractor::extract`]):
//! 1. valid readings become sensor-frame points (REP 117 validity plus a range cap);
//! 2. the adaptive breakpoint detector cuts them into segments, with a break distance that
//!    grows with range and beam spacing;
//! 3. split-and-merge turns segments into straight runs, merges collinear neighbours, moves
//!    the points at each shared boundary to the line they lie on and hands stubs left
//!    around a corner to its two walls;
//! 4. each run gets a total-least-squares line `(rho, theta)` with its covariance
//!    propagated from the range and bearing noise (scaled up when the residuals say the
//!    wall is rougher than that noise);
//! 5. neighbouring lines whose ends meet at their intersection form a corner
//!    `(x, y, heading, angle)` with a covariance propagated from both lines.
//!
//! Conventions (frames, corner heading and angle) are those of docs/CONVENTIONS.md; the
//! scanner's settings are in [`FeatureConfig`], the thresholds that describe walls and
//! corners are constants beside the code that uses them. The process pairs each scan with the odometry at its
//! stamp (`stage_kit::odometry_buffer`), so the features carry it downstream.

#![forbid(unsafe_code)]

mod config;
mod corner;
mod extractor;
mod features;
mod line_fit;
mod motion_message;
mod scan;
mod segment;
mod split_merge;

pub use config::{FeatureConfig, WALL_SIGMA_FACTOR};
pub use corner::{CORNER_MAX_ANGLE, CORNER_MIN_ANGLE, MIN_LINE_LENGTH};
pub use extractor::Extractor;
pub use features::FeatureSet;
pub use motion_message::scan_motion;
pub use scan::{MAX_BEAMS, ScanError, ScanInput};
pub use stage_kit::SettingError;
