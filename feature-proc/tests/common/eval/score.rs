//! Precision and recall of detected corners against true ones.

use feature_proc::{Extractor, ScanInput};
use slam_geom::MeasuredCorner;

use super::world::{TrueCorner, View, World};

/// Counts for precision (detections near a true corner) and recall (true corners in view
/// with a detection near them). Add the scores of many scans to pool them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CornerScore {
    pub detected: usize,
    /// Detections within the tolerance of some true corner.
    pub correct: usize,
    pub in_view: usize,
    /// True corners in view with a detection within the tolerance.
    pub found: usize,
}

impl CornerScore {
    /// Share of detections that are real; 1 with no detections.
    pub fn precision(&self) -> f64 {
        ratio(self.correct, self.detected)
    }

    /// Share of the true corners in view that were detected; 1 with none in view.
    pub fn recall(&self) -> f64 {
        ratio(self.found, self.in_view)
    }
}

impl std::ops::AddAssign for CornerScore {
    fn add_assign(&mut self, other: Self) {
        self.detected += other.detected;
        self.correct += other.correct;
        self.in_view += other.in_view;
        self.found += other.found;
    }
}

fn ratio(part: usize, whole: usize) -> f64 {
    if whole == 0 {
        1.0
    } else {
        part as f64 / whole as f64
    }
}

/// Scores `detected` (sensor frame, sensor at `pose` = `[x, y, yaw]`, world from sensor)
/// against the world's corners. A detection is correct near any true corner, so one that
/// is real but narrowly outside `in_view` is not held against the detector.
pub fn score_corners(
    detected: &[MeasuredCorner],
    pose: [f64; 3],
    true_corners: &[TrueCorner],
    in_view: &[TrueCorner],
    tolerance: f64,
) -> CornerScore {
    let (sin, cos) = pose[2].sin_cos();
    let world = |c: &MeasuredCorner| {
        [
            pose[0] + cos * c.x - sin * c.y,
            pose[1] + sin * c.x + cos * c.y,
        ]
    };
    let near = |p: [f64; 2], t: &TrueCorner| (p[0] - t.x).hypot(p[1] - t.y) <= tolerance;
    let correct = detected
        .iter()
        .filter(|c| true_corners.iter().any(|t| near(world(c), t)))
        .count();
    let found = in_view
        .iter()
        .filter(|t| detected.iter().any(|c| near(world(c), t)))
        .count();
    CornerScore {
        detected: detected.len(),
        correct,
        in_view: in_view.len(),
        found,
    }
}

/// Extracts corners from every `(pose, scan)` of a run through `world` and pools their
/// scores: precision against all true corners, recall of those in `view`, each within
/// `tolerance`. Scans the extractor refuses count as scans without corners.
pub fn score_run<'a>(
    extractor: &mut Extractor,
    world: &World,
    view: &View,
    tolerance: f64,
    scans: impl IntoIterator<Item = ([f64; 3], ScanInput<'a>)>,
) -> CornerScore {
    let mut total = CornerScore::default();
    for (pose, scan) in scans {
        let detected = extractor.extract(&scan).map_or(&[][..], |f| &f.corners[..]);
        total += world.score(detected, pose, view, tolerance);
    }
    total
}
