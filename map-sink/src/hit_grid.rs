//! A sparse grid counting scan hits per cell: the occupancy-ish cloud of the picture.

use std::collections::HashMap;

/// One grid cell that was hit. Cell `[i, j]` covers `[i * cell, (i + 1) * cell)` in x and
/// likewise in y.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HitCell {
    pub index: [i64; 2],
    pub hits: u32,
}

/// Counts points per square cell. Memory grows with the area seen, not with the length of
/// the run, so a long run can be drawn from a bounded amount of state.
#[derive(Debug, Clone)]
pub struct HitGrid {
    cell_m: f64,
    hits: HashMap<[i64; 2], u32>,
}

impl HitGrid {
    /// `cell_m` must be positive and finite (the recorder checks its options).
    pub fn new(cell_m: f64) -> Self {
        Self {
            cell_m,
            hits: HashMap::new(),
        }
    }

    pub fn cell_m(&self) -> f64 {
        self.cell_m
    }

    /// Counts a point; non-finite points are ignored.
    pub fn add(&mut self, p: [f64; 2]) {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return;
        }
        // `as` saturates, so a point absurdly far away lands in an edge cell instead of
        // wrapping around.
        let index = [
            (p[0] / self.cell_m).floor() as i64,
            (p[1] / self.cell_m).floor() as i64,
        ];
        *self.hits.entry(index).or_insert(0) += 1;
    }

    pub fn len(&self) -> usize {
        self.hits.len()
    }

    pub fn is_empty(&self) -> bool {
        self.hits.is_empty()
    }

    /// The hit cells ordered by row then column, so output built from them is deterministic.
    pub fn cells(&self) -> Vec<HitCell> {
        let mut cells: Vec<HitCell> = self
            .hits
            .iter()
            .map(|(&index, &hits)| HitCell { index, hits })
            .collect();
        cells.sort_by_key(|c| (c.index[1], c.index[0]));
        cells
    }
}
