//! A scan's walls laid onto other scans' walls: the pose near a start that puts the points
//! along the scan's walls on the walls the other scans saw (point to line, Gauss-Newton with
//! a Cauchy loss, the gate narrowing pass by pass).
//!
//! A loop closure's landing comes from two or three corners, whose headings can leave it a
//! few degrees off, and the pose before the jump carries the drift: neither lays the walls
//! where they fit best. Compared as they are, a landing a few degrees off looks no better
//! than the drift it undoes. Each is first settled onto the old walls, then compared.

use std::collections::HashMap;

use nalgebra::{Matrix3, Vector3};
use slam_geom::{Point2, Pose2, wrap_angle};

use crate::math::linalg::spd_solve3;
use crate::update::free_space::PlacedWalls;

/// The gate of each pass, metres: a point is paired with a wall this close or not at all.
const GATES_M: [f64; 8] = [1.0, 1.0, 0.6, 0.6, 0.4, 0.3, 0.3, 0.3];
/// The scale of the Cauchy loss, metres.
const LOSS_SCALE_M: f64 = 0.1;
/// A point pairs only with a wall within this angle of its own wall's direction.
const MAX_ANGLE_RAD: f64 = 0.5;
/// Fewer paired points than this leave the pose where it is.
const MIN_PAIRED: usize = 6;
/// The weight that holds the pose to the start, as a share of the pairs' total weight, per
/// unit of each coordinate: along a corridor the walls fix nothing, and the pose stays.
const HOLD: f64 = 1e-3;
/// Side of the cells the old walls are indexed by, metres.
const CELL_M: f64 = 1.0;

/// An old wall ready for pairing: its ends and the unit normal towards the sensor that saw
/// it.
struct OldWall {
    a: Point2,
    b: Point2,
    normal: Point2,
}

/// The old walls, indexed by the cells within the widest gate of them.
pub(crate) struct OldWalls {
    walls: Vec<OldWall>,
    cells: HashMap<(i64, i64), Vec<u32>>,
}

fn cell(p: Point2) -> (i64, i64) {
    ((p.x / CELL_M).floor() as i64, (p.y / CELL_M).floor() as i64)
}

impl OldWalls {
    pub fn new(tied: &[PlacedWalls]) -> Self {
        let mut walls = Vec::new();
        let mut cells: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
        let reach = GATES_M[0];
        for scan in tied {
            for &(a, b) in &scan.walls {
                let along = b - a;
                let length = along.norm();
                if length < 1e-6 {
                    continue;
                }
                let mut normal = Point2::new(-along.y, along.x) / length;
                if normal.dot(&(scan.sensor - a)) < 0.0 {
                    normal = -normal;
                }
                let index = walls.len() as u32;
                let (lo, hi) = (
                    cell(Point2::new(a.x.min(b.x) - reach, a.y.min(b.y) - reach)),
                    cell(Point2::new(a.x.max(b.x) + reach, a.y.max(b.y) + reach)),
                );
                for i in lo.0..=hi.0 {
                    for j in lo.1..=hi.1 {
                        cells.entry((i, j)).or_default().push(index);
                    }
                }
                walls.push(OldWall { a, b, normal });
            }
        }
        Self { walls, cells }
    }

    /// The nearest wall within `gate` of `p` that runs within [`MAX_ANGLE_RAD`] of
    /// `direction` and faces `sensor`, with the signed distance of `p` from its line.
    fn pair(
        &self,
        p: Point2,
        direction: Point2,
        sensor: Point2,
        gate: f64,
    ) -> Option<(usize, f64)> {
        let max_cross = MAX_ANGLE_RAD.sin();
        let mut best: Option<(usize, f64, f64)> = None;
        for &k in self.cells.get(&cell(p))? {
            let wall = &self.walls[k as usize];
            if wall.normal.dot(&direction).abs() > max_cross
                || wall.normal.dot(&(sensor - wall.a)) <= 0.0
            {
                continue;
            }
            let ab = wall.b - wall.a;
            let t = ((p - wall.a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
            let distance = (p - (wall.a + ab * t)).norm();
            if distance <= gate && best.is_none_or(|(_, d, _)| distance < d) {
                best = Some((k as usize, distance, wall.normal.dot(&(p - wall.a))));
            }
        }
        best.map(|(k, _, signed)| (k, signed))
    }
}

/// The pose near `start` that lays `points` (along a scan's walls, sensor frame, with their
/// walls' directions: [`crate::update::free_space::sample_points`]) on the old walls best;
/// `start` itself when too few of them pair with those walls.
pub(crate) fn settle(points: &[(Point2, Point2)], index: &OldWalls, start: Pose2) -> Pose2 {
    let mut pose = start;
    for gate in GATES_M {
        let (rotation, sensor) = (pose.rotation(), pose.position());
        let mut h = Matrix3::zeros();
        let mut g = Vector3::zeros();
        let mut paired = 0;
        let mut total = 0.0;
        for (p, d) in points {
            let world = rotation * p + sensor;
            let direction = rotation * d;
            let Some((k, r)) = index.pair(world, direction, sensor, gate) else {
                continue;
            };
            let n = index.walls[k].normal;
            let j = Vector3::new(
                n.x,
                n.y,
                n.x * -(world.y - pose.y) + n.y * (world.x - pose.x),
            );
            let w = 1.0 / (1.0 + (r / LOSS_SCALE_M).powi(2));
            h += j * j.transpose() * w;
            g += j * (w * r);
            total += w;
            paired += 1;
        }
        if paired < MIN_PAIRED {
            break;
        }
        // Held weakly to where it is: the directions the walls leave open do not move.
        let held = h + Matrix3::identity() * (HOLD * total);
        let Some(step) = spd_solve3(&held, &(-g)) else {
            break;
        };
        pose = Pose2::new(
            pose.x + step.x,
            pose.y + step.y,
            wrap_angle(pose.yaw + step.z),
        );
    }
    pose
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::update::free_space::sample_points;
    use crate::update::free_space::tests::wall;

    #[test]
    fn walls_a_few_degrees_and_decimetres_off_settle_onto_the_old_ones() {
        // A room 6 m x 4 m seen from its middle, and seen again from 1 m along x.
        let room = |x0: f64| {
            vec![
                wall(-3.0 - x0, 2.0, 3.0 - x0, 2.0),
                wall(3.0 - x0, 2.0, 3.0 - x0, -2.0),
                wall(3.0 - x0, -2.0, -3.0 - x0, -2.0),
                wall(-3.0 - x0, -2.0, -3.0 - x0, 2.0),
            ]
        };
        let tied = [PlacedWalls::new(&Pose2::IDENTITY, &room(0.0))];
        let truth = Pose2::new(1.0, 0.0, 0.0);
        let start = Pose2::new(1.3, -0.25, 6f64.to_radians());
        let settled = settle(&sample_points(&room(1.0)), &OldWalls::new(&tied), start);
        let error = truth.between(&settled);
        assert!(
            error.translation_norm() < 0.01 && error.yaw.abs() < 0.002,
            "{settled:?}"
        );
        // With nothing to pair with, the pose stays.
        assert_eq!(
            settle(&sample_points(&room(1.0)), &OldWalls::new(&[]), start),
            start
        );
    }

    #[test]
    fn along_a_corridor_only_the_walls_directions_move() {
        // Two long parallel walls: across them and in heading the pose settles, along them
        // it stays where it started.
        let corridor = [wall(-10.0, 1.0, 10.0, 1.0), wall(10.0, -1.0, -10.0, -1.0)];
        let tied = [PlacedWalls::new(&Pose2::IDENTITY, &corridor)];
        let seen = [wall(-5.0, 1.0, 5.0, 1.0), wall(5.0, -1.0, -5.0, -1.0)];
        let start = Pose2::new(0.4, 0.2, 2f64.to_radians());
        let settled = settle(&sample_points(&seen), &OldWalls::new(&tied), start);
        assert!((settled.x - 0.4).abs() < 0.01, "{settled:?}");
        assert!(
            settled.y.abs() < 0.01 && settled.yaw.abs() < 0.002,
            "{settled:?}"
        );
    }
}
