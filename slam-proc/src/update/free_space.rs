//! Whether two scans' walls can both be right: a wall of one where the other's beams passed
//! through to a wall behind it is a contradiction.
//!
//! A line fitted to a scan's returns says more than where the wall is: the beams that hit it
//! crossed the triangle between the sensor and the wall unobstructed. Placed by a loop
//! closure's pose, the scan now seen and the scans from where the closure ties the path
//! either agree (their walls lie on each other's, or where the other saw nothing) or one puts
//! a wall in the other's free space. Two corners can fit a wrong offset in a building of
//! repeated rooms; the walls around them then leave the old walls, or cut through what the
//! old scans saw as free. A closure is compared with staying put after each pose has been
//! settled onto the old walls ([`crate::update::wall_alignment`]).

use slam_geom::{Point2, Pose2};

use crate::update::wall_alignment::{OldWalls, settle};

/// How much worse than staying a landing may fit and still be taken, as a share of the
/// points: two poses settled into the same place differ by a point or two.
const SCORE_TOLERANCE: f64 = 0.1;
/// Spacing of the points sampled along a wall, metres.
const STEP_M: f64 = 0.2;
/// About the most points sampled along a scan's walls.
const MAX_POINTS: usize = 200;
/// A point this close to another scan's wall lies on it, metres.
const NEAR_M: f64 = 0.2;
/// A point this far or farther in front of the wall another scan's beams ended on is in
/// that scan's free space, metres.
const MARGIN_M: f64 = 0.4;

/// A stretch of wall in the sensor frame: the first and last point of a fitted line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WallSegment {
    pub start: Point2,
    pub end: Point2,
}

/// A scan's walls in the world, with the sensor they were seen from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PlacedWalls {
    pub sensor: Point2,
    pub walls: Vec<(Point2, Point2)>,
}

impl PlacedWalls {
    pub fn new(pose: &Pose2, walls: &[WallSegment]) -> Self {
        let (rotation, sensor) = (pose.rotation(), pose.position());
        Self {
            sensor,
            walls: walls
                .iter()
                .map(|w| (rotation * w.start + sensor, rotation * w.end + sensor))
                .collect(),
        }
    }
}

/// What the points along one set of walls found in the other set's scans.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct WallAgreement {
    /// Points within [`NEAR_M`] of a wall of the other scans.
    pub agree: usize,
    /// Points in the free space of one of the other scans, [`MARGIN_M`] or more in front of
    /// the wall its beams ended on.
    pub conflict: usize,
    /// Points sampled.
    pub points: usize,
}

impl WallAgreement {
    /// The share of the points that lie on the other scans' walls less the share that lie
    /// in their free space: 1 when every point is confirmed, below 0 when more contradict
    /// than confirm, 0 without points.
    pub fn score(&self) -> f64 {
        if self.points == 0 {
            return 0.0;
        }
        (self.agree as f64 - self.conflict as f64) / self.points as f64
    }
}

/// Whether the scan's walls (`walls`, sensor frame) fit the walls of the scans a loop
/// closure ties it to (`tied`, placed in the map) from `landed` about as well as from
/// `predicted`, where the particle was before the jump, or better. Each pose is first
/// settled onto the old walls ([`settle`]): a landing from two corners can be a few degrees
/// off, and the pose before the jump carries the drift. A jump that undoes real drift lands
/// the walls on the old ones; one onto corners that only look alike takes them off walls
/// that fitted where they were. Without walls on either side there is nothing to go by,
/// and the closure stands.
pub(crate) fn closure_fits(
    walls: &[WallSegment],
    tied: &[PlacedWalls],
    landed: &Pose2,
    predicted: &Pose2,
) -> bool {
    if walls.is_empty() || tied.iter().all(|t| t.walls.is_empty()) {
        return true;
    }
    let points = sample_points(walls);
    let old = OldWalls::new(tied);
    let fit = |pose: &Pose2| agreement(&points, &settle(&points, &old, *pose), tied).score();
    fit(landed) >= fit(predicted) - SCORE_TOLERANCE
}

/// Points along each of `walls` (sensor frame), each with its wall's unit direction: every
/// [`STEP_M`], or farther apart where that would make more than [`MAX_POINTS`], so that a
/// cluttered scan costs no more than a plain one.
pub(crate) fn sample_points(walls: &[WallSegment]) -> Vec<(Point2, Point2)> {
    let length = |wall: &WallSegment| (wall.end - wall.start).norm();
    let total: f64 = walls.iter().map(length).filter(|l| l.is_finite()).sum();
    let step = STEP_M.max(total / MAX_POINTS as f64);
    let mut points = Vec::new();
    for wall in walls {
        let along = wall.end - wall.start;
        let length = along.norm();
        if !length.is_finite() || length <= 0.0 {
            continue;
        }
        let direction = along / length;
        let n = (length / step).floor() as usize + 1;
        for k in 0..n {
            let t = if n == 1 {
                0.5
            } else {
                k as f64 / (n - 1) as f64
            };
            points.push((wall.start + along * t, direction));
        }
    }
    points
}

/// Checks `points` (sensor frame, from [`sample_points`]) placed at `pose` against
/// `others`.
pub(crate) fn agreement(
    points: &[(Point2, Point2)],
    pose: &Pose2,
    others: &[PlacedWalls],
) -> WallAgreement {
    let (rotation, position) = (pose.rotation(), pose.position());
    let mut result = WallAgreement::default();
    for (p, _) in points {
        let p = rotation * p + position;
        result.points += 1;
        if others.iter().any(|o| {
            o.walls
                .iter()
                .any(|&(c, d)| segment_distance(p, c, d) <= NEAR_M)
        }) {
            result.agree += 1;
        } else if others.iter().any(|o| {
            o.walls
                .iter()
                .any(|&(c, d)| in_free_space(p, o.sensor, c, d))
        }) {
            result.conflict += 1;
        }
    }
    result
}

fn segment_distance(p: Point2, a: Point2, b: Point2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(1e-12)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

fn cross(u: Point2, v: Point2) -> f64 {
    u.x * v.y - u.y * v.x
}

/// Whether `p` is inside the triangle the beams from `o` to the wall `a`-`b` swept, at
/// least [`MARGIN_M`] in front of the wall.
fn in_free_space(p: Point2, o: Point2, a: Point2, b: Point2) -> bool {
    let (oa, ob, op) = (a - o, b - o, p - o);
    let turn = cross(oa, ob);
    if turn.abs() < 1e-12 {
        return false;
    }
    // Between the rays to a and to b.
    if cross(oa, op) * turn < 0.0 || cross(op, ob) * turn < 0.0 {
        return false;
    }
    // On the sensor's side of the wall by the margin: the wall's normal towards o.
    let ab = b - a;
    let length = ab.norm();
    if length < 1e-9 {
        return false;
    }
    let normal = Point2::new(-ab.y, ab.x) / length;
    let sensor_side = normal.dot(&(o - a));
    let side = normal.dot(&(p - a));
    sensor_side.signum() == side.signum()
        && side.abs() >= MARGIN_M
        && side.abs() < sensor_side.abs()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The wall from `(ax, ay)` to `(bx, by)`.
    pub(crate) fn wall(ax: f64, ay: f64, bx: f64, by: f64) -> WallSegment {
        WallSegment {
            start: Point2::new(ax, ay),
            end: Point2::new(bx, by),
        }
    }

    /// A scan from the origin facing +x that saw a wall across its view 4 m ahead.
    fn old_scan() -> PlacedWalls {
        PlacedWalls::new(&Pose2::IDENTITY, &[wall(4.0, -2.0, 4.0, 2.0)])
    }

    #[test]
    fn points_on_a_wall_agree_and_points_in_its_free_space_conflict() {
        let seen_from = |x: f64, walls: &[WallSegment]| {
            agreement(
                &sample_points(walls),
                &Pose2::new(x, 0.0, 0.0),
                &[old_scan()],
            )
        };
        // The same wall, seen from a metre closer: every point on it.
        let same = seen_from(1.0, &[wall(3.0, -1.0, 3.0, 1.0)]);
        assert_eq!((same.agree, same.conflict), (same.points, 0));
        assert_eq!(same.score(), 1.0);
        // A wall 2 m ahead of the origin, where the old scan's beams passed: all conflict.
        let through = seen_from(0.0, &[wall(2.0, -1.0, 2.0, 1.0)]);
        assert_eq!((through.agree, through.conflict), (0, through.points));
        assert_eq!(through.score(), -1.0);
        // Behind the old wall, or beside the old scan's view, nothing is known.
        for unknown in [
            seen_from(0.0, &[wall(6.0, -1.0, 6.0, 1.0)]),
            seen_from(0.0, &[wall(1.0, 3.0, 3.0, 3.0)]),
        ] {
            assert_eq!((unknown.agree, unknown.conflict), (0, 0), "{unknown:?}");
            assert!(unknown.points > 0);
        }
        // Just in front of the old wall (within the margin) is the wall's noise, not free.
        let close = seen_from(0.0, &[wall(3.7, -1.0, 3.7, 1.0)]);
        assert_eq!(close.conflict, 0, "{close:?}");
    }

    #[test]
    fn a_landing_that_takes_the_walls_off_the_old_ones_is_refused() {
        // A corridor 2 m wide and 8 m long along x, seen from its start.
        let corridor = [
            wall(0.5, 1.0, 8.0, 1.0),
            wall(8.0, 1.0, 8.0, -1.0),
            wall(8.0, -1.0, 0.5, -1.0),
        ];
        let old = [PlacedWalls::new(&Pose2::IDENTITY, &corridor)];
        // The same corridor seen again from 1 m along it: at the right pose its walls lie
        // on the old ones.
        let truth = Pose2::new(1.0, 0.0, 0.0);
        let now: Vec<WallSegment> = corridor
            .iter()
            .map(|w| wall(w.start.x - 1.0, w.start.y, w.end.x - 1.0, w.end.y))
            .collect();
        // The particle was there; the corners pulled it 1.5 m sideways and 15 degrees,
        // beyond where the walls could settle back: refused.
        let off = Pose2::new(1.0, 1.5, 15f64.to_radians());
        assert!(!closure_fits(&now, &old, &off, &truth));
        // The particle had drifted there and the corners bring it back: taken, and so is a
        // landing a few degrees and decimetres off, which settles onto the old walls.
        assert!(closure_fits(&now, &old, &truth, &off));
        let near = Pose2::new(1.3, 0.2, 5f64.to_radians());
        assert!(closure_fits(&now, &old, &near, &off));
        // A small correction of a particle that was in place: both settle into one place.
        assert!(closure_fits(&now, &old, &near, &truth));
        // Without walls on either side there is no evidence against the corners.
        assert!(closure_fits(&[], &old, &off, &truth));
        assert!(closure_fits(&now, &[], &off, &truth));
    }
}
