//! Evaluation of the detector, for this crate's tests only: worlds of walls with known
//! corners (ray cast by lidar-sim's caster), precision and recall of detected corners
//! against them, and a corner-matching motion estimate for checking that corners of real
//! scans recur.

// Each test binary uses a part of this support.
#![allow(unused_imports)]

mod motion;
mod score;
mod world;

pub use motion::{MatchParams, Motion, estimate_motion, redetected};
pub use score::{CornerScore, score_corners, score_run};
pub use world::{ScanGeometry, TrueCorner, View, World};
