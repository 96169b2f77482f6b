//! The likelihood field of a saved occupancy grid (Thrun et al., "Probabilistic Robotics",
//! 6.4; AMCL's `likelihood_field` model): the distance from every cell to the nearest
//! occupied one, so that weighting a beam end costs one lookup.

use saved_map::{CellState, GridMap};

use crate::localize::cell_frame::{CellFrame, SeenCells};

/// A beam end far from every wall still scores this (relative to one on a wall at 1):
/// unmapped things and people in the way cost a bounded amount, as AMCL's `z_rand` does.
pub(crate) const BEAM_FLOOR: f64 = 0.1;

/// Distance at which the field stops growing, metres: beyond a metre from every wall a
/// beam end is equally wrong, and the floor above scores it anyway.
pub(crate) const MAX_DISTANCE_M: f64 = 1.0;

/// A beam end's likelihood by its distance `d` to the nearest wall: a Gaussian hit plus a
/// floor for what the map does not hold, `exp(-d^2 / (2 sigma^2)) + floor`, scaled so that
/// a beam on a wall scores 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamModel {
    pub sigma_hit: f64,
    pub floor: f64,
}

impl BeamModel {
    /// The log-likelihood of a beam end `distance` metres from the nearest wall.
    pub fn log_likelihood(&self, distance: f64) -> f64 {
        let hit = (-0.5 * (distance / self.sigma_hit).powi(2)).exp();
        ((hit + self.floor) / (1.0 + self.floor)).ln()
    }
}

/// Distances to the nearest occupied cell over a grid, capped, and the grid's free cells.
#[derive(Debug, Clone)]
pub struct LikelihoodField {
    frame: CellFrame,
    /// Metres to the nearest occupied cell's centre, at most `max_distance`; row 0 the
    /// lowest y.
    distance: Vec<f32>,
    max_distance: f64,
    /// A beam end's log-likelihood in each cell, by [`BeamModel`]; at most 0.
    score: Vec<f32>,
    /// The score off the grid (and beyond `max_distance`).
    far_score: f64,
    /// Indices of the free cells, where a robot may stand.
    free: Vec<u32>,
    /// Which cells were seen (free or occupied).
    seen: SeenCells,
}

impl LikelihoodField {
    /// The field of `grid`, distances capped at `max_distance` metres (beyond it every
    /// beam end is equally wrong).
    pub fn new(grid: &GridMap, max_distance: f64, model: BeamModel) -> Self {
        let (width, height) = (grid.width, grid.height);
        let resolution = grid.yaml.resolution;
        // Squared distances in cells, by the exact Euclidean transform.
        let far = ((max_distance / resolution).ceil() + 1.0).powi(2);
        let mut squared: Vec<f64> = grid
            .cells
            .iter()
            .map(|c| if *c == CellState::Occupied { 0.0 } else { far })
            .collect();
        distance_transform_2d(&mut squared, width, height);
        let distance: Vec<f32> = squared
            .iter()
            .map(|d2| (d2.sqrt() * resolution).min(max_distance) as f32)
            .collect();
        let score = distance
            .iter()
            .map(|&d| model.log_likelihood(f64::from(d)) as f32)
            .collect();
        let free = grid
            .cells
            .iter()
            .enumerate()
            .filter(|(_, c)| **c == CellState::Free)
            .filter_map(|(i, _)| u32::try_from(i).ok())
            .collect();
        Self {
            frame: CellFrame::of(grid),
            distance,
            max_distance,
            score,
            far_score: model.log_likelihood(max_distance),
            free,
            seen: SeenCells::of(grid),
        }
    }

    /// Whether `(x, y)` (map frame) lies in a cell the grid saw, free or occupied: a beam
    /// ending there can be judged by the field, one ending in unknown space cannot.
    #[inline]
    pub fn is_known(&self, x: f64, y: f64) -> bool {
        self.seen.contains(x, y)
    }

    /// Metres from `(x, y)` (map frame) to the nearest occupied cell; `max_distance` off
    /// the grid.
    #[inline]
    pub fn distance(&self, x: f64, y: f64) -> f64 {
        match self.frame.index(x, y) {
            Some(i) => f64::from(self.distance[i]),
            None => self.max_distance,
        }
    }

    /// The log-likelihood of a beam ending at `(x, y)` (map frame), at most 0.
    #[inline]
    pub fn score(&self, x: f64, y: f64) -> f64 {
        match self.frame.index(x, y) {
            Some(i) => f64::from(self.score[i]),
            None => self.far_score,
        }
    }

    /// How many free cells the grid has.
    pub fn free_cells(&self) -> usize {
        self.free.len()
    }

    /// The centre of the `k`-th free cell and the cell's edge, for spreading particles.
    pub fn free_cell(&self, k: usize) -> Option<([f64; 2], f64)> {
        let index = *self.free.get(k)? as usize;
        Some((self.frame.centre(index), self.frame.resolution))
    }
}

/// Squared Euclidean distance transform in place (Felzenszwalb and Huttenlocher 2012):
/// `f` holds 0 at the sites and a large value elsewhere; columns, then rows.
pub(crate) fn distance_transform_2d(f: &mut [f64], width: usize, height: usize) {
    let n = width.max(height);
    let mut line = vec![0.0; n];
    let mut out = vec![0.0; n];
    let mut work = Work::new(n);
    for col in 0..width {
        for row in 0..height {
            line[row] = f[row * width + col];
        }
        transform_1d(&line[..height], &mut out[..height], &mut work);
        for row in 0..height {
            f[row * width + col] = out[row];
        }
    }
    for row in 0..height {
        line[..width].copy_from_slice(&f[row * width..(row + 1) * width]);
        transform_1d(&line[..width], &mut out[..width], &mut work);
        f[row * width..(row + 1) * width].copy_from_slice(&out[..width]);
    }
}

/// The 1-D transform's buffers: the parabolas' vertices and the boundaries between them.
struct Work {
    vertices: Vec<usize>,
    boundaries: Vec<f64>,
}

impl Work {
    fn new(n: usize) -> Self {
        Self {
            vertices: vec![0; n],
            boundaries: vec![0.0; n + 1],
        }
    }
}

/// The lower envelope of the parabolas `(q - p)^2 + f[p]`, sampled at every `q`.
fn transform_1d(f: &[f64], out: &mut [f64], work: &mut Work) {
    let n = f.len();
    if n == 0 {
        return;
    }
    let (v, z) = (&mut work.vertices, &mut work.boundaries);
    let mut k = 0;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let intersection = |p: usize| {
            ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
        };
        let mut s = intersection(v[k]);
        while s <= z[k] {
            // The new parabola hides the last one entirely.
            k -= 1;
            s = intersection(v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, value) in out.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let d = q as f64 - v[k] as f64;
        *value = d * d + f[v[k]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use saved_map::MapYaml;

    fn grid(width: usize, height: usize, occupied: &[(usize, usize)]) -> GridMap {
        let mut cells = vec![CellState::Free; width * height];
        for &(col, row) in occupied {
            cells[row * width + col] = CellState::Occupied;
        }
        GridMap {
            yaml: MapYaml::trinary("map.pgm", 0.1, [-1.0, -2.0]),
            width,
            height,
            cells,
        }
    }

    #[test]
    fn distances_are_euclidean_to_the_nearest_occupied_cell_and_capped() {
        let g = grid(40, 30, &[(10, 10), (30, 20)]);
        let model = BeamModel {
            sigma_hit: 0.1,
            floor: 0.1,
        };
        let field = LikelihoodField::new(&g, 1.5, model);
        // Brute force over every cell.
        for row in 0..30 {
            for col in 0..40 {
                let brute = [(10.0, 10.0), (30.0, 20.0)]
                    .iter()
                    .map(|&(c, r): &(f64, f64)| (col as f64 - c).hypot(row as f64 - r) * 0.1)
                    .fold(f64::INFINITY, f64::min)
                    .min(1.5);
                let x = -1.0 + (col as f64 + 0.5) * 0.1;
                let y = -2.0 + (row as f64 + 0.5) * 0.1;
                assert!((field.distance(x, y) - brute).abs() < 1e-5, "{col},{row}");
            }
        }
        assert_eq!(field.distance(-5.0, 0.0), 1.5);
        assert_eq!(field.distance(f64::NAN, 0.0), 1.5);
        // On a wall 0, far from every wall ln(0.1 / 1.1).
        assert!(field.score(0.05, -0.95).abs() < 1e-6);
        assert!((field.score(-5.0, 0.0) - (0.1f64 / 1.1).ln()).abs() < 1e-6);
        assert_eq!(field.free_cells(), 40 * 30 - 2);
        let (centre, edge) = field.free_cell(0).unwrap();
        assert!((centre[0] + 0.95).abs() < 1e-12 && (centre[1] + 1.95).abs() < 1e-12);
        assert_eq!(edge, 0.1);
    }

    #[test]
    fn a_grid_without_walls_is_far_everywhere() {
        let model = BeamModel {
            sigma_hit: 0.1,
            floor: 0.1,
        };
        let field = LikelihoodField::new(&grid(5, 5, &[]), 2.0, model);
        assert_eq!(field.distance(0.0, 0.0), 2.0);
    }
}
