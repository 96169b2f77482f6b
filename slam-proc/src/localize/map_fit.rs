//! How well a saved grid explains a run's scans ([`slam_eval::MapFit`], the rule is there):
//! each beam is judged from the estimate by the cells it crosses and the cell it ends in.
//! A fraction of beams, not a likelihood, so that it means the same whatever the scanner's
//! beam count or range and the localizer's beam model.

use saved_map::{CellState, GridMap};
use slam_eval::MapFit;
use slam_geom::Pose2;

use crate::localize::cell_frame::CellFrame;
use crate::localize::likelihood_field::distance_transform_2d;

/// The cell is unknown and away from every wall: a beam ending there is not judged (the
/// map says nothing of a room it never saw, or of the far side of a wall).
const UNKNOWN: u8 = 0;
/// Seen free, away from every wall: a beam ending there contradicts the map.
const FREE: u8 = 1;
/// Within the distance of a mapped wall, seen or not (an end a little behind a wall's
/// face lies in the unknown cell behind it): a beam ending there is explained.
const NEAR_WALL: u8 = 2;
/// A mapped wall (and near one): a beam passing through it, out beyond its reach well
/// short of its end, contradicts the map.
const WALL: u8 = 3;

/// Each cell of a saved grid classed once, so that judging a beam costs a walk along it.
#[derive(Debug, Clone)]
pub struct FitField {
    frame: CellFrame,
    class: Vec<u8>,
    /// A beam explained by its end passes through its own wall's cells within this of the
    /// end, metres: only a wall crossed before that contradicts the map.
    through_before_m: f64,
}

impl FitField {
    /// The field of `grid`; a beam is explained when it ends within `within_m` of an
    /// occupied cell's centre.
    pub fn new(grid: &GridMap, within_m: f64) -> Self {
        let (width, height) = (grid.width, grid.height);
        let resolution = grid.yaml.resolution;
        let reach = within_m / resolution;
        let far = (reach.ceil() + 1.0).powi(2);
        let mut squared: Vec<f64> = grid
            .cells
            .iter()
            .map(|c| if *c == CellState::Occupied { 0.0 } else { far })
            .collect();
        distance_transform_2d(&mut squared, width, height);
        let class = squared
            .iter()
            .zip(&grid.cells)
            .map(|(d2, cell)| match cell {
                CellState::Occupied => WALL,
                _ if *d2 <= reach * reach => NEAR_WALL,
                CellState::Unknown => UNKNOWN,
                CellState::Free => FREE,
            })
            .collect();
        Self {
            frame: CellFrame::of(grid),
            class,
            // A wall's cell reaches half a diagonal beyond its centre.
            through_before_m: within_m + resolution,
        }
    }

    /// The class of the cell at `(col, row)` in cell units from the grid's origin (the
    /// cell's lower-left corner at whole numbers); off the grid, unknown.
    #[inline]
    fn class_in_cells(&self, col: f64, row: f64) -> u8 {
        // Written so that NaN fails every comparison.
        if col >= 0.0
            && row >= 0.0
            && col < self.frame.width as f64
            && row < self.frame.height as f64
        {
            self.class[row as usize * self.frame.width + col as usize]
        } else {
            UNKNOWN
        }
    }

    /// Judges the beams ending at `points` (sensor frame), cast from `pose`, into `fit`.
    pub fn judge(&self, points: &[[f64; 2]], pose: &Pose2, fit: &mut MapFit) {
        let (s, c) = pose.yaw.sin_cos();
        let resolution = self.frame.resolution;
        // The sensor in cell units, and steps of half a cell along the beam: a wall one
        // cell thick is not stepped over.
        let col0 = (pose.x - self.frame.origin[0]) / resolution;
        let row0 = (pose.y - self.frame.origin[1]) / resolution;
        for [px, py] in points {
            let range = px.hypot(*py);
            if range.is_nan() || range <= 0.0 {
                continue;
            }
            let (dx, dy) = ((c * px - s * py) / range, (s * px + c * py) / range);
            let (step_col, step_row) = (0.5 * dx, 0.5 * dy);
            let steps = ((range - self.through_before_m) / (0.5 * resolution)).ceil();
            // Through a wall: into one of its cells and out beyond its reach. A beam that
            // grazes the wall it ends on stays within reach of it up to its end.
            let mut in_wall = false;
            let mut crossed = false;
            let mut k = 1.0;
            while k < steps {
                match self.class_in_cells(col0 + k * step_col, row0 + k * step_row) {
                    WALL => in_wall = true,
                    NEAR_WALL => {}
                    _ if in_wall => {
                        crossed = true;
                        break;
                    }
                    _ => {}
                }
                k += 1.0;
            }
            let reach = range / resolution;
            let end = self.class_in_cells(col0 + reach * dx, row0 + reach * dy);
            let (judged, explained) = match end {
                _ if crossed => (true, false),
                NEAR_WALL | WALL => (true, true),
                FREE => (true, false),
                _ => (false, false),
            };
            fit.beams_judged += u64::from(judged);
            fit.beams_explained += u64::from(explained);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use saved_map::MapYaml;

    /// A 10 m x 6 m room of 0.05 m cells: walls on its border and across it at x = 5 m
    /// (y from 0 to 3 m), seen inside, unknown beyond x = 8 m.
    fn room() -> GridMap {
        let (width, height) = (200, 120);
        let mut cells = vec![CellState::Free; width * height];
        for row in 0..height {
            for col in 0..width {
                let border = row == 0 || col == 0 || row == height - 1 || col == width - 1;
                let across = col == 100 && row < 60;
                cells[row * width + col] = if border || across {
                    CellState::Occupied
                } else if col >= 160 {
                    CellState::Unknown
                } else {
                    CellState::Free
                };
            }
        }
        GridMap {
            yaml: MapYaml::trinary("map.pgm", 0.05, [0.0, 0.0]),
            width,
            height,
            cells,
        }
    }

    fn judged(points: &[[f64; 2]], pose: Pose2) -> MapFit {
        let field = FitField::new(&room(), 0.2);
        let mut fit = MapFit::default();
        field.judge(points, &pose, &mut fit);
        fit
    }

    #[test]
    fn a_beam_is_explained_on_a_wall_and_contradicts_the_map_in_free_space_or_through_a_wall() {
        let pose = Pose2::new(2.0, 1.5, 0.0);
        // Ends on the wall across (x = 5.0-5.05 m), a little short or past its face.
        for range in [2.9, 3.02, 3.15] {
            assert_eq!(
                judged(&[[range, 0.0]], pose),
                MapFit {
                    beams_judged: 1,
                    beams_explained: 1
                },
                "{range}"
            );
        }
        // Ends in the room's free space.
        assert_eq!(
            judged(&[[1.5, 0.0]], pose),
            MapFit {
                beams_judged: 1,
                beams_explained: 0
            }
        );
        // Passes through the wall across and ends in free space, or on the far wall.
        for range in [4.5, 7.9] {
            assert_eq!(
                judged(&[[range, 0.0]], pose),
                MapFit {
                    beams_judged: 1,
                    beams_explained: 0
                },
                "{range}"
            );
        }
    }

    #[test]
    fn a_beam_ending_where_the_map_never_saw_is_not_judged() {
        // From above the wall across, facing +x: into the unknown part.
        let pose = Pose2::new(6.0, 4.5, 0.0);
        assert_eq!(judged(&[[3.0, 0.0]], pose), MapFit::default());
        // Off the grid without crossing a wall: neither.
        let outside = Pose2::new(20.0, 4.5, 0.0);
        assert_eq!(judged(&[[3.0, 0.0]], outside), MapFit::default());
        // The same beam facing -x ends in seen free space.
        let back = Pose2::new(6.0, 4.5, std::f64::consts::PI);
        assert_eq!(judged(&[[3.0, 0.0]], back).beams_judged, 1);
    }
}
