//! A saved grid's likelihood field by the way a beam travels: a beam end is scored against
//! the wall faces a beam going its way can end on, not against every occupied cell.
//!
//! A plain likelihood field is blind to sides: a beam end that sank into a wall drawn
//! several cells thick (a door frame seen from both rooms, a corner seen from afar) scores
//! as well as one on the wall's face. A scanner that looks forward then scores better a
//! little ahead of its pose, where more of its ends sink into the walls in front of it, and
//! a localizer on such a field runs ahead of the path that drew the map, most along
//! corridors whose only walls across are far ahead.
//! Here a cell is a face for a beam when free space borders it on the side the beam comes
//! from, and so is the cell behind such a face (a wall a pass drew two cells thick is hit in
//! both); the map-sink's alignment of scans to walls holds returns to faces seen from their
//! side for the same reason.

use std::f64::consts::TAU;

use saved_map::{CellState, GridMap};
use slam_geom::Pose2;

use crate::localize::cell_frame::CellFrame;
use crate::localize::likelihood_field::{BeamModel, distance_transform_2d};

/// Directions of travel a beam is binned by, evenly around the circle; a power of two.
pub const DIRECTIONS: usize = 8;
const _: () = assert!(DIRECTIONS.is_power_of_two());

/// Distances are stored in steps this much finer than a cell (or coarser, when the field's
/// reach would not fit in a byte).
const STEPS_PER_CELL: f64 = 8.0;

/// The largest stored step; it stands for the field's reach and beyond.
const FAR_STEP: u8 = u8::MAX;

/// The grid's field, one table of distances to the faces per direction of travel.
#[derive(Debug, Clone)]
pub struct FacedField {
    frame: CellFrame,
    /// Per cell, the distance to the nearest face for each direction (`DIRECTIONS` bytes a
    /// cell, so one cell's directions share a cache line), in steps of `step` metres.
    steps: Vec<u8>,
    /// A beam end's log-likelihood at each step (boxed: a kilobyte).
    score_at_step: Box<[f32; 256]>,
}

impl FacedField {
    /// The field of `grid`, distances capped at `max_distance` metres.
    pub fn new(grid: &GridMap, max_distance: f64, model: BeamModel) -> Self {
        let (width, height) = (grid.width, grid.height);
        let resolution = grid.yaml.resolution;
        let step = (resolution / STEPS_PER_CELL).max(max_distance / f64::from(FAR_STEP));
        let far_cells = ((max_distance / resolution).ceil() + 1.0).powi(2);
        let mut steps = vec![FAR_STEP; width * height * DIRECTIONS];
        let mut squared = vec![0.0; width * height];
        for direction in 0..DIRECTIONS {
            let faces = faces(grid, direction);
            for (d2, face) in squared.iter_mut().zip(&faces) {
                *d2 = if *face { 0.0 } else { far_cells };
            }
            distance_transform_2d(&mut squared, width, height);
            for (cell, d2) in squared.iter().enumerate() {
                let metres = d2.sqrt() * resolution;
                if metres < max_distance {
                    steps[cell * DIRECTIONS + direction] =
                        ((metres / step).round() as u8).min(FAR_STEP - 1);
                }
            }
        }
        let mut score_at_step = Box::new([0.0; 256]);
        for (k, score) in score_at_step.iter_mut().enumerate() {
            let metres = (k as f64 * step).min(max_distance);
            *score = model.log_likelihood(metres) as f32;
        }
        score_at_step[usize::from(FAR_STEP)] = model.log_likelihood(max_distance) as f32;
        Self {
            frame: CellFrame::of(grid),
            steps,
            score_at_step,
        }
    }

    /// The log-likelihood of a beam travelling along world `bearing` (radians) that ends
    /// at `(x, y)` (map frame), at most 0.
    #[inline]
    pub fn score(&self, x: f64, y: f64, bearing: f64) -> f64 {
        self.score_towards(x, y, direction_of(bearing))
    }

    /// [`score`](Self::score) for a beam in the bin `direction`.
    #[inline]
    fn score_towards(&self, x: f64, y: f64, direction: usize) -> f64 {
        let step = match self.frame.index(x, y) {
            Some(cell) => self.steps[cell * DIRECTIONS + direction],
            None => FAR_STEP,
        };
        f64::from(self.score_at_step[usize::from(step)])
    }
}

/// The log-likelihood of beam ends `points` (sensor frame), whose beams left the sensor at
/// `bearings` (sensor frame, radians), seen from `pose`.
pub fn faced_scan_score(
    field: &FacedField,
    points: &[[f64; 2]],
    bearings: &[f64],
    pose: &Pose2,
) -> f64 {
    let (s, c) = pose.yaw.sin_cos();
    // Bins counted from half a bin below the first, so that flooring rounds to the nearest.
    let yaw_bins = pose.yaw * BINS_PER_RADIAN + 0.5;
    points
        .iter()
        .zip(bearings)
        .map(|([px, py], bearing)| {
            field.score_towards(
                pose.x + c * px - s * py,
                pose.y + s * px + c * py,
                bin_of_bins(yaw_bins + bearing * BINS_PER_RADIAN),
            )
        })
        .sum()
}

/// Direction bins per radian.
const BINS_PER_RADIAN: f64 = DIRECTIONS as f64 / TAU;

/// The bin of a direction of travel: the nearest of `DIRECTIONS` evenly spaced ones.
#[inline]
fn direction_of(bearing: f64) -> usize {
    bin_of_bins(bearing * BINS_PER_RADIAN + 0.5)
}

/// The bin of a direction given in bins, offset by half a bin: its floor around the circle
/// (`DIRECTIONS` is a power of two, so the mask wraps negative ones too; NaN casts to 0).
#[inline]
fn bin_of_bins(bins: f64) -> usize {
    (bins.floor() as i64 & (DIRECTIONS as i64 - 1)) as usize
}

/// Which cells of `grid` a beam travelling in bin `direction` can end on: occupied cells
/// with a free neighbour on the side the beam comes from, and the occupied cells right
/// behind those.
fn faces(grid: &GridMap, direction: usize) -> Vec<bool> {
    let (width, height) = (grid.width, grid.height);
    let angle = TAU * direction as f64 / DIRECTIONS as f64;
    let (dy, dx) = angle.sin_cos();
    // The neighbours on the sensor's side: against the direction of travel.
    let behind: Vec<(i64, i64)> = (-1..=1)
        .flat_map(|r| (-1..=1).map(move |c| (c, r)))
        .filter(|&(c, r)| c as f64 * dx + r as f64 * dy < -1e-9)
        .collect();
    let neighbour = |cell: usize, (c, r): (i64, i64)| -> Option<usize> {
        let (col, row) = ((cell % width) as i64 + c, (cell / width) as i64 + r);
        (col >= 0 && row >= 0 && col < width as i64 && row < height as i64)
            .then(|| row as usize * width + col as usize)
    };
    let occupied = |cell: usize| grid.cells[cell] == CellState::Occupied;
    let front: Vec<bool> = (0..width * height)
        .map(|cell| {
            occupied(cell)
                && behind.iter().any(|&offset| {
                    neighbour(cell, offset).is_some_and(|n| grid.cells[n] == CellState::Free)
                })
        })
        .collect();
    (0..width * height)
        .map(|cell| {
            front[cell]
                || (occupied(cell)
                    && behind
                        .iter()
                        .any(|&offset| neighbour(cell, offset).is_some_and(|n| front[n])))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LikelihoodField;
    use saved_map::MapYaml;

    const MODEL: BeamModel = BeamModel {
        sigma_hit: 0.1,
        floor: 0.1,
    };

    /// A 4 m x 3 m room of 0.1 m cells, free, with a wall four cells thick across it at
    /// columns 20-23 (x 2.0-2.4 m).
    fn room_with_a_thick_wall() -> GridMap {
        let (width, height) = (40, 30);
        let mut cells = vec![CellState::Free; width * height];
        for row in 0..height {
            for col in 20..24 {
                cells[row * width + col] = CellState::Occupied;
            }
        }
        GridMap {
            yaml: MapYaml::trinary("map.pgm", 0.1, [0.0, 0.0]),
            width,
            height,
            cells,
        }
    }

    #[test]
    fn a_beam_scores_on_the_faces_it_can_reach_and_not_inside_the_wall() {
        let grid = room_with_a_thick_wall();
        let faced = FacedField::new(&grid, 1.0, MODEL);
        let plain = LikelihoodField::new(&grid, 1.0, MODEL);
        let (east, west) = (0.0, std::f64::consts::PI);
        // Travelling east, a beam ends on the wall's west face or the cell behind it ...
        assert!(faced.score(2.05, 1.5, east).abs() < 1e-6);
        assert!(faced.score(2.15, 1.5, east).abs() < 1e-6);
        // ... and sinking deeper is 0.1 m past the faces, where the plain field sees a wall.
        let sunk = faced.score(2.25, 1.5, east);
        assert!((sunk - MODEL.log_likelihood(0.1)).abs() < 0.01, "{sunk}");
        assert!(plain.score(2.25, 1.5).abs() < 1e-6);
        // Travelling west, the faces are the east ones.
        assert!(faced.score(2.35, 1.5, west).abs() < 1e-6);
        assert!((faced.score(2.05, 1.5, west) - MODEL.log_likelihood(0.2)).abs() < 0.01);
        // Short of the face, both fields agree.
        for x in [1.55, 1.75, 1.95] {
            let (a, b) = (faced.score(x, 1.5, east), plain.score(x, 1.5));
            assert!((a - b).abs() < 0.01, "{x}: {a} against {b}");
        }
        // Off the grid and far from every face, the floor.
        let far = MODEL.log_likelihood(1.0);
        assert!((faced.score(-3.0, 1.5, east) - far).abs() < 1e-6);
        assert!((faced.score(0.05, 1.5, east) - far).abs() < 1e-6);
    }

    #[test]
    fn a_scan_scores_best_at_its_own_pose_not_pushed_into_the_wall() {
        // A scanner 1.55 m west of the thick wall, looking east: its beams end in the
        // wall's first cells. The plain field scores it as well 0.25 m ahead, its ends deep
        // in the wall; the faced field scores it best where it is.
        let grid = room_with_a_thick_wall();
        let faced = FacedField::new(&grid, 1.0, MODEL);
        let plain = LikelihoodField::new(&grid, 1.0, MODEL);
        let pose = Pose2::new(0.5, 1.5, 0.0);
        let bearings: Vec<f64> = (-6..=6).map(|k| f64::from(k) * 0.1).collect();
        let points: Vec<[f64; 2]> = bearings
            .iter()
            .map(|b| {
                let range = (2.05 - pose.x) / b.cos();
                [range * b.cos(), range * b.sin()]
            })
            .collect();
        let moved = |dx: f64| Pose2::new(pose.x + dx, pose.y, pose.yaw);
        let at = |dx: f64| faced_scan_score(&faced, &points, &bearings, &moved(dx));
        let plain_at = |dx: f64| crate::scan_score(&plain, &points, &moved(dx));
        assert_eq!(plain_at(0.0), plain_at(0.25));
        assert!(at(0.0) > at(0.25) + 1.0, "{} against {}", at(0.0), at(0.25));
        assert!(at(0.0) > at(-0.1) + 1.0);
    }

    #[test]
    fn directions_wrap_around_the_circle() {
        assert_eq!(direction_of(0.0), 0);
        assert_eq!(direction_of(TAU), 0);
        assert_eq!(direction_of(-TAU / 8.0), 7);
        assert_eq!(direction_of(TAU / 8.0 * 3.4), 3);
        assert_eq!(direction_of(f64::NAN), 0);
    }
}
