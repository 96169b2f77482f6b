//! The motion between two scans from their corners alone, for showing that corners recur:
//! hypotheses from one or two corner matches of similar opening angle, the one that
//! explains most corners wins, refined by a least-squares rigid fit of its matches.

use slam_geom::MeasuredCorner;
use slam_geom::{Point2, WeightedPair, align_se2, wrap_angle};

/// The pose of the later scan in the earlier scan's frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Motion {
    pub x: f64,
    pub y: f64,
    pub yaw: f64,
}

impl Motion {
    /// A point of the later scan in the earlier scan's frame.
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (sin, cos) = self.yaw.sin_cos();
        [
            self.x + cos * p[0] - sin * p[1],
            self.y + sin * p[0] + cos * p[1],
        ]
    }
}

/// When two corners of consecutive scans are the same.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchParams {
    /// Largest distance between matched corners after the motion, metres.
    pub tolerance: f64,
    /// Largest difference of opening angles, radians, unless three standard deviations of
    /// the difference (from the corners' covariances) are larger.
    pub angle_tolerance: f64,
    /// Largest difference of headings after the motion, radians; widened like the angle's.
    pub heading_tolerance: f64,
    /// Largest motion between the scans.
    pub max_translation: f64,
    pub max_rotation: f64,
}

impl Default for MatchParams {
    /// For consecutive seed-hall scans: about 0.11 m and up to 0.2 rad apart.
    fn default() -> Self {
        Self {
            tolerance: 0.3,
            angle_tolerance: 0.2,
            heading_tolerance: 0.3,
            max_translation: 0.5,
            max_rotation: 0.4,
        }
    }
}

/// Corners of `earlier` that have a match in `later` after `motion`.
pub fn redetected(
    earlier: &[MeasuredCorner],
    later: &[MeasuredCorner],
    motion: &Motion,
    params: &MatchParams,
) -> usize {
    earlier
        .iter()
        .filter(|e| later.iter().any(|l| matches(e, l, motion, params)))
        .count()
}

fn matches(e: &MeasuredCorner, l: &MeasuredCorner, motion: &Motion, params: &MatchParams) -> bool {
    let p = motion.apply([l.x, l.y]);
    (p[0] - e.x).hypot(p[1] - e.y) <= params.tolerance
        && similar_angle(e, l, params)
        && wrap_angle(l.heading + motion.yaw - e.heading).abs()
            <= params.heading_tolerance.max(three_sigma(e, l, 2))
}

fn similar_angle(e: &MeasuredCorner, l: &MeasuredCorner, params: &MatchParams) -> bool {
    (e.angle - l.angle).abs() <= params.angle_tolerance.max(three_sigma(e, l, 3))
}

/// Three standard deviations of the difference of element `k` of two corners: a far corner
/// with short arms has a loose angle, and its covariance says how loose.
fn three_sigma(e: &MeasuredCorner, l: &MeasuredCorner, k: usize) -> f64 {
    3.0 * (e.covariance[(k, k)] + l.covariance[(k, k)]).sqrt()
}

/// The motion under which most corners of `earlier` recur in `later`, or `None` when no
/// plausible motion matches any corner.
pub fn estimate_motion(
    earlier: &[MeasuredCorner],
    later: &[MeasuredCorner],
    params: &MatchParams,
) -> Option<Motion> {
    // Candidate matches: similar angle, and a range change the motion can explain.
    let mut candidates = Vec::new();
    for (i, e) in earlier.iter().enumerate() {
        for (j, l) in later.iter().enumerate() {
            let range_change = (e.x.hypot(e.y) - l.x.hypot(l.y)).abs();
            if similar_angle(e, l, params)
                && range_change <= params.max_translation + params.tolerance
            {
                candidates.push((i, j));
            }
        }
    }
    let plausible =
        |m: &Motion| m.x.hypot(m.y) <= params.max_translation && m.yaw.abs() <= params.max_rotation;
    let mut best: Option<(usize, Motion)> = None;
    let mut consider = |m: Motion| {
        if plausible(&m) {
            let score = redetected(earlier, later, &m, params);
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, m));
            }
        }
    };
    for &(i, j) in &candidates {
        // One match fixes the motion through the corner's heading.
        let yaw = wrap_angle(earlier[i].heading - later[j].heading);
        consider(rigid(&[(point(&earlier[i]), point(&later[j]))], Some(yaw)));
    }
    for (k, &(i1, j1)) in candidates.iter().enumerate() {
        for &(i2, j2) in &candidates[k + 1..] {
            if i1 == i2 || j1 == j2 {
                continue;
            }
            let (e1, e2, l1, l2) = (
                point(&earlier[i1]),
                point(&earlier[i2]),
                point(&later[j1]),
                point(&later[j2]),
            );
            let (de, dl) = (dist(e1, e2), dist(l1, l2));
            if de < 0.5 || (de - dl).abs() > 2.0 * params.tolerance {
                continue;
            }
            consider(rigid(&[(e1, l1), (e2, l2)], None));
        }
    }
    let (score, motion) = best?;
    if score == 0 {
        return None;
    }
    // Refine on every match of the winner; keep the refinement only if it explains as much.
    let pairs: Vec<_> = earlier
        .iter()
        .filter_map(|e| {
            later
                .iter()
                .find(|l| matches(e, l, &motion, params))
                .map(|l| (point(e), point(l)))
        })
        .collect();
    let refined = rigid(&pairs, (pairs.len() < 2).then_some(motion.yaw));
    Some(
        if plausible(&refined) && redetected(earlier, later, &refined, params) >= score {
            refined
        } else {
            motion
        },
    )
}

/// Least-squares rigid motion taking the second point of each pair onto the first
/// (`slam_geom::align_se2`), or with the rotation given (none when the points fix none).
fn rigid(pairs: &[([f64; 2], [f64; 2])], yaw: Option<f64>) -> Motion {
    if yaw.is_none() {
        let weighted: Vec<WeightedPair> = pairs
            .iter()
            .map(|(e, l)| (Point2::from(*l), Point2::from(*e), 1.0))
            .collect();
        if let Some(fit) = align_se2(&weighted) {
            return Motion {
                x: fit.translation[0],
                y: fit.translation[1],
                yaw: fit.rotation,
            };
        }
    }
    let n = pairs.len().max(1) as f64;
    let (mut ce, mut cl) = ([0.0; 2], [0.0; 2]);
    for (e, l) in pairs {
        ce = [ce[0] + e[0] / n, ce[1] + e[1] / n];
        cl = [cl[0] + l[0] / n, cl[1] + l[1] / n];
    }
    let yaw = yaw.unwrap_or(0.0);
    let (sin, cos) = yaw.sin_cos();
    Motion {
        x: ce[0] - (cos * cl[0] - sin * cl[1]),
        y: ce[1] - (sin * cl[0] + cos * cl[1]),
        yaw,
    }
}

fn point(c: &MeasuredCorner) -> [f64; 2] {
    [c.x, c.y]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}
