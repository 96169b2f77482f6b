//! Evaluation helpers shared by tests and benchmarks (here and in other crates): ray-cast
//! worlds with known corners, precision and recall of detected corners against them, and
//! a corner-matching motion estimate for checking that corners of real scans recur.
//!
//! Not used on the extraction path.

mod motion;
mod score;
mod world;

pub use motion::{MatchParams, Motion, estimate_motion, redetected};
pub use score::{CornerScore, score_corners, score_run};
pub use world::{ScanGeometry, TrueCorner, View, World};
