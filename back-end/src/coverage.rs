//! What a submap saw: per cell, how many of its beams passed through and how many ended
//! there. A scan point that lands where the submap's beams passed freely is a contradiction;
//! one that lands where the submap never looked says nothing either way. A closure is then
//! judged on the points the submap can speak for, not on how much of the scan it happens to
//! cover.
//!
//! Cells live in square tiles allocated where beams go, so a submap costs memory by the
//! area it saw.

use std::collections::HashMap;

use nalgebra::Vector2;

/// Cells per tile edge.
const TILE: i32 = 32;

/// A cell's counts: beams through, beams ending.
#[derive(Debug, Clone, Copy, Default)]
struct Counts {
    passes: u8,
    hits: u8,
}

/// The submap's passes and hits on a grid of `cell` metres.
#[derive(Debug, Clone)]
pub struct Coverage {
    cell: f64,
    tiles: HashMap<(i32, i32), Box<[Counts]>>,
}

/// What the submap says about a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seen {
    /// Its beams passed through here and none ended: free space.
    Free,
    /// A beam ended here, or the cell was never crossed enough to tell.
    NotFree,
}

/// Metres of each beam traced back from its end.
const TRACED_M: f64 = 4.0;

/// Beams through a cell with none ending in it before it counts as free: one beam can graze
/// a wall's cell.
const FREE_PASSES: u8 = 2;

impl Coverage {
    pub fn new(cell: f64) -> Self {
        Self {
            cell,
            tiles: HashMap::new(),
        }
    }

    fn counts_mut(&mut self, x: i32, y: i32) -> &mut Counts {
        let key = (x.div_euclid(TILE), y.div_euclid(TILE));
        let tile = self
            .tiles
            .entry(key)
            .or_insert_with(|| vec![Counts::default(); (TILE * TILE) as usize].into());
        &mut tile[(y.rem_euclid(TILE) * TILE + x.rem_euclid(TILE)) as usize]
    }

    fn counts(&self, x: i32, y: i32) -> Counts {
        let key = (x.div_euclid(TILE), y.div_euclid(TILE));
        self.tiles.get(&key).map_or(Counts::default(), |tile| {
            tile[(y.rem_euclid(TILE) * TILE + x.rem_euclid(TILE)) as usize]
        })
    }

    fn cell_of(&self, p: Vector2<f64>) -> (i32, i32) {
        (
            (p.x / self.cell).floor() as i32,
            (p.y / self.cell).floor() as i32,
        )
    }

    /// A beam from `origin` ending at `end`: the cells it crossed short of its last cell
    /// are passed, its end is hit.
    pub fn add_beam(&mut self, origin: Vector2<f64>, end: Vector2<f64>) {
        let length = (end - origin).norm();
        // Only the stretch near the end is traced: a contradiction is judged where the
        // scan's points are, and these are near walls the submap's beams reached.
        let start = if length > TRACED_M {
            end + (origin - end) * (TRACED_M / length)
        } else {
            origin
        };
        let (origin, length) = (start, length.min(TRACED_M));
        let last = self.cell_of(end);
        let steps = (length / (0.5 * self.cell)).floor() as usize;
        let mut previous = None;
        for i in 0..steps {
            let p = origin + (end - origin) * (i as f64 * 0.5 * self.cell / length);
            let c = self.cell_of(p);
            // Stop a cell short: a beam ending near a cell border grazes the wall's cell.
            if (c.0 - last.0).abs() <= 1 && (c.1 - last.1).abs() <= 1 {
                break;
            }
            if previous != Some(c) {
                let counts = self.counts_mut(c.0, c.1);
                counts.passes = counts.passes.saturating_add(1);
                previous = Some(c);
            }
        }
        let counts = self.counts_mut(last.0, last.1);
        counts.hits = counts.hits.saturating_add(1);
    }

    /// What the submap says about `point`.
    pub fn seen(&self, point: Vector2<f64>) -> Seen {
        let c = self.cell_of(point);
        let counts = self.counts(c.0, c.1);
        if counts.hits == 0 && counts.passes >= FREE_PASSES {
            Seen::Free
        } else {
            Seen::NotFree
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn space_crossed_by_beams_is_free_and_their_ends_are_not() {
        let mut coverage = Coverage::new(0.1);
        for i in 0..10 {
            let end = Vector2::new(5.0, -0.5 + 0.1 * f64::from(i));
            coverage.add_beam(Vector2::zeros(), end);
        }
        assert_eq!(coverage.seen(Vector2::new(2.5, 0.0)), Seen::Free);
        assert_eq!(coverage.seen(Vector2::new(5.0, 0.0)), Seen::NotFree);
        // Never crossed: unknown, not free.
        assert_eq!(coverage.seen(Vector2::new(-2.0, 0.0)), Seen::NotFree);
        assert_eq!(coverage.seen(Vector2::new(7.0, 0.0)), Seen::NotFree);
    }
}
