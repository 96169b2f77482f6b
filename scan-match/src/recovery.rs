//! Recovery after a gap in the data or a fast turn: when the prior is far too uncertain for
//! the correlative search's window (seconds without scans, a turn of a radian or more in
//! them; without odometry, a turn that reverses between two slow scans) and the match from
//! that window is weak, a wide coarse search (up to a full turn, or over turns only)
//! proposes a few distinct poses, each is refined (fine search, then registration), and
//! the registered fits are ranked by how much of the scan they explain and how tightly,
//! not by the coarse score alone: a coarse grid scores a wrong but symmetric pose about
//! as well as the right one.

use slam_geom::Pose2;

use crate::local_map::LocalMap;
use crate::points::SurfacePoint;
use crate::registration::{Registration, RegistrationParams, register};
use crate::search::{Window, search_candidates, search_sample};

/// Coarse candidates refined at most: a wrong basin that scores best on the coarse grid
/// is usually among the first few, the right one with it.
const CANDIDATES: usize = 4;

/// Yaw steps of the wide search at most: two degrees each over a full turn.
const MAX_YAW_STEPS: usize = 181;

/// Where and how wide to look, and how the candidates are refined.
#[derive(Debug, Clone, Copy)]
pub struct RecoveryWindow {
    /// The prior's prediction.
    pub seed: Pose2,
    /// Half-widths of the wide search.
    pub window: Window,
    /// The coarse scoring distance and translation step, metres.
    pub coarse_radius: f64,
    /// The fine search's, metres.
    pub fine_radius: f64,
}

/// The best registered fit among the wide search's candidates, if any registers.
pub fn recover(
    map: &LocalMap,
    points: &[SurfacePoint],
    sample: &[SurfacePoint],
    how: &RecoveryWindow,
    params: &RegistrationParams,
) -> Option<Registration> {
    let candidates = search_candidates(
        map,
        sample,
        &how.seed,
        how.window,
        how.coarse_radius,
        CANDIDATES,
        MAX_YAW_STEPS,
    );
    let spread = (sample.iter().map(|p| p.point.norm_squared()).sum::<f64>()
        / sample.len().max(1) as f64)
        .sqrt()
        .max(1.0);
    let around = Window {
        translation: how.coarse_radius,
        yaw: (how.window.yaw / (MAX_YAW_STEPS / 2) as f64).max(how.coarse_radius / spread),
    };
    candidates
        .iter()
        .map(|(pose, _)| {
            let (seed, _) = search_sample(map, sample, pose, around, how.fine_radius);
            register(map, points, seed, how.coarse_radius, params)
        })
        .filter(|r| !r.constraint.is_void())
        .max_by(|a, b| rank(a, params).total_cmp(&rank(b, params)))
}

/// How well a fit explains the scan: its inliers, discounted by the fit's residual spread
/// in voxels (a loose fit of many points to the wrong walls loses to a tight one).
pub fn rank(found: &Registration, params: &RegistrationParams) -> f64 {
    found.inliers as f64 / (1.0 + found.variance.sqrt() / params.voxel)
}
