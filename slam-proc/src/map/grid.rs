//! A persistent spatial hash grid of corner ids, so association looks only at the map
//! corners near an observation instead of the whole map.
//!
//! Cells of a fixed size are hashed into a fixed number of buckets held in a
//! [`PersistentArray`]; a bucket is an immutable shared slice of `(cell, id)` entries,
//! replaced whole when a corner is added, removed or moves to another cell. Clones share
//! every bucket, as the corner store does.

use std::sync::Arc;

use crate::map::persistent::PersistentArray;

/// Buckets of the hash. Maps of up to tens of thousands of corners keep a few entries per
/// bucket; distant cells sharing a bucket only cost a comparison.
const BUCKETS: usize = 4096;

type Cell = (i32, i32);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Entry {
    cell: Cell,
    id: u32,
}

#[derive(Debug, Clone)]
pub(crate) struct SpatialGrid {
    cell_size: f64,
    buckets: PersistentArray<Option<Arc<[Entry]>>>,
}

impl SpatialGrid {
    pub fn new(cell_size: f64) -> Self {
        Self {
            cell_size,
            buckets: PersistentArray::default(),
        }
    }

    fn cell(&self, x: f64, y: f64) -> Cell {
        (
            floor_index(x / self.cell_size),
            floor_index(y / self.cell_size),
        )
    }

    fn bucket(cell: Cell) -> usize {
        // The classic spatial hash (Teschner et al. 2003) of the two cell indices.
        let h = (cell.0 as u32).wrapping_mul(73_856_093) ^ (cell.1 as u32).wrapping_mul(19_349_663);
        h as usize % BUCKETS
    }

    pub fn insert(&mut self, id: u32, x: f64, y: f64) {
        let cell = self.cell(x, y);
        let slot = self.buckets.get_mut(Self::bucket(cell));
        let mut entries: Vec<Entry> = slot.as_deref().unwrap_or_default().to_vec();
        entries.push(Entry { cell, id });
        *slot = Some(entries.into());
    }

    pub fn remove(&mut self, id: u32, x: f64, y: f64) {
        let cell = self.cell(x, y);
        let slot = self.buckets.get_mut(Self::bucket(cell));
        let entries: Vec<Entry> = slot
            .as_deref()
            .unwrap_or_default()
            .iter()
            .copied()
            .filter(|e| e.id != id)
            .collect();
        *slot = (!entries.is_empty()).then(|| entries.into());
    }

    /// Re-files a corner that moved from `from` to `to`; nothing to do within one cell.
    pub fn relocate(&mut self, id: u32, from: (f64, f64), to: (f64, f64)) {
        if self.cell(from.0, from.1) != self.cell(to.0, to.1) {
            self.remove(id, from.0, from.1);
            self.insert(id, to.0, to.1);
        }
    }

    /// Appends to `out` the ids filed in cells overlapping the square of half-width
    /// `radius` around `(x, y)`: a superset of the corners within `radius`.
    pub fn query(&self, x: f64, y: f64, radius: f64, out: &mut Vec<u32>) {
        let (low, high) = (
            self.cell(x - radius, y - radius),
            self.cell(x + radius, y + radius),
        );
        for cx in low.0..=high.0 {
            for cy in low.1..=high.1 {
                let cell = (cx, cy);
                if let Some(Some(entries)) = self.buckets.get(Self::bucket(cell)) {
                    out.extend(entries.iter().filter(|e| e.cell == cell).map(|e| e.id));
                }
            }
        }
    }
}

/// `floor(v)` as an `i32`. Truncation then a correction below zero: `f64::floor` is a
/// library call on baseline x86-64. `as` saturates, so a corner a billion cells away still
/// lands in some cell.
fn floor_index(v: f64) -> i32 {
    let t = v as i32;
    if f64::from(t) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_index_matches_floor() {
        for v in [-2.5, -2.0, -0.1, -0.0, 0.0, 0.3, 1.0, 7.9, 1e12, -1e12] {
            assert_eq!(floor_index(v), (v.floor() as i32), "{v}");
        }
    }

    #[test]
    fn finds_near_ids_and_follows_moves() {
        let mut grid = SpatialGrid::new(2.0);
        grid.insert(1, 0.5, 0.5);
        grid.insert(2, 10.0, -3.0);
        grid.insert(3, -0.5, 1.9);
        let mut out = Vec::new();
        grid.query(0.0, 0.0, 1.0, &mut out);
        out.sort_unstable();
        assert_eq!(out, vec![1, 3]);
        let shared = grid.clone();
        grid.relocate(1, (0.5, 0.5), (10.5, -3.5));
        out.clear();
        grid.query(10.0, -3.0, 1.0, &mut out);
        out.sort_unstable();
        assert_eq!(out, vec![1, 2]);
        // The clone taken before the move still has the corner where it was.
        out.clear();
        shared.query(0.0, 0.0, 1.0, &mut out);
        out.sort_unstable();
        assert_eq!(out, vec![1, 3]);
        grid.remove(3, -0.5, 1.9);
        out.clear();
        grid.query(0.0, 0.0, 1.0, &mut out);
        assert!(out.is_empty());
    }
}
