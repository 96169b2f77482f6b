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

/// Cells per tile edge, a power of two.
const TILE_BITS: i32 = 5;
const TILE: i32 = 1 << TILE_BITS;

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
    /// Tile coordinates to the tile's place in `tiles`.
    index: HashMap<(i32, i32), usize>,
    tiles: Vec<Box<[Counts]>>,
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
            index: HashMap::new(),
            tiles: Vec::new(),
        }
    }

    /// The place of tile `key` in `tiles`, allocated if new.
    fn tile(&mut self, key: (i32, i32)) -> usize {
        let next = self.tiles.len();
        let index = *self.index.entry(key).or_insert(next);
        if index == next {
            self.tiles
                .push(vec![Counts::default(); (TILE * TILE) as usize].into());
        }
        index
    }

    fn counts(&self, (x, y): (i32, i32)) -> Counts {
        self.index
            .get(&(x >> TILE_BITS, y >> TILE_BITS))
            .map_or(Counts::default(), |&tile| self.tiles[tile][offset(x, y)])
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
        let last = self.cell_of(end);
        // Consecutive cells mostly share a tile: it is looked up when the beam enters one.
        let mut tile = ((i32::MAX, i32::MAX), 0);
        for c in Traversal::new(
            start / self.cell,
            end / self.cell,
            self.cell_of(start),
            last,
        ) {
            // Stop a cell short: a beam ending near a cell border grazes the wall's cell.
            if (c.0 - last.0).abs() <= 1 && (c.1 - last.1).abs() <= 1 {
                break;
            }
            let key = (c.0 >> TILE_BITS, c.1 >> TILE_BITS);
            if key != tile.0 {
                tile = (key, self.tile(key));
            }
            let counts = &mut self.tiles[tile.1][offset(c.0, c.1)];
            counts.passes = counts.passes.saturating_add(1);
        }
        let tile = self.tile((last.0 >> TILE_BITS, last.1 >> TILE_BITS));
        let counts = &mut self.tiles[tile][offset(last.0, last.1)];
        counts.hits = counts.hits.saturating_add(1);
    }

    /// What the submap says about `point`.
    pub fn seen(&self, point: Vector2<f64>) -> Seen {
        if is_free(self.counts(self.cell_of(point))) {
            Seen::Free
        } else {
            Seen::NotFree
        }
    }

    /// The free cells alone, a bit each: what a finished submap keeps.
    pub fn free_space(&self) -> FreeSpace {
        let mut free = FreeSpace {
            cell: self.cell,
            index: HashMap::new(),
            tiles: Vec::new(),
        };
        for (&key, &tile) in &self.index {
            let mut bits = [0u64; BIT_WORDS];
            for (i, counts) in self.tiles[tile].iter().enumerate() {
                if is_free(*counts) {
                    bits[i / 64] |= 1 << (i % 64);
                }
            }
            if bits.iter().any(|&w| w != 0) {
                free.index.insert(key, free.tiles.len());
                free.tiles.push(bits);
            }
        }
        free
    }
}

fn is_free(counts: Counts) -> bool {
    counts.hits == 0 && counts.passes >= FREE_PASSES
}

/// Words of a tile's bitmap.
const BIT_WORDS: usize = (TILE * TILE) as usize / 64;

/// A finished submap's free space: one bit per cell, tiles where any cell is free.
#[derive(Debug, Clone)]
pub struct FreeSpace {
    cell: f64,
    index: HashMap<(i32, i32), usize>,
    tiles: Vec<[u64; BIT_WORDS]>,
}

impl FreeSpace {
    /// Memory held, bytes (the index's entries counted at their size, not the table's).
    pub fn bytes(&self) -> usize {
        self.tiles.capacity() * std::mem::size_of::<[u64; BIT_WORDS]>()
            + self.index.capacity() * std::mem::size_of::<((i32, i32), usize)>()
    }

    /// What the submap says about `point`, as [`Coverage::seen`] said it.
    pub fn seen(&self, point: Vector2<f64>) -> Seen {
        let (x, y) = (
            (point.x / self.cell).floor() as i32,
            (point.y / self.cell).floor() as i32,
        );
        let free = self
            .index
            .get(&(x >> TILE_BITS, y >> TILE_BITS))
            .is_some_and(|&tile| {
                let i = offset(x, y);
                self.tiles[tile][i / 64] & (1 << (i % 64)) != 0
            });
        if free { Seen::Free } else { Seen::NotFree }
    }
}

/// The place of cell `(x, y)` in its tile.
fn offset(x: i32, y: i32) -> usize {
    (((y & (TILE - 1)) << TILE_BITS) | (x & (TILE - 1))) as usize
}

/// The cells a segment crosses, in order from its first (Amanatides and Woo's walk): at each
/// step it moves into the neighbour across the cell border it meets first.
struct Traversal {
    cell: (i32, i32),
    step: (i32, i32),
    /// Where along the segment (0 to 1) it next crosses a border in x, and in y...
    next: (f64, f64),
    /// ...and how far along it the borders of each axis are apart.
    delta: (f64, f64),
    /// Cells still to give: the segment crosses one border per step.
    left: u32,
}

impl Traversal {
    /// The cells from `first` to `last` crossed by the segment between `a` and `b`, both in
    /// cells.
    fn new(a: Vector2<f64>, b: Vector2<f64>, first: (i32, i32), last: (i32, i32)) -> Self {
        let d = b - a;
        let axis = |from: f64, cell: i32, d: f64| -> (i32, f64, f64) {
            if d > 0.0 {
                (1, (f64::from(cell) + 1.0 - from) / d, 1.0 / d)
            } else if d < 0.0 {
                (-1, (f64::from(cell) - from) / d, -1.0 / d)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (sx, nx, dx) = axis(a.x, first.0, d.x);
        let (sy, ny, dy) = axis(a.y, first.1, d.y);
        Self {
            cell: first,
            step: (sx, sy),
            next: (nx, ny),
            delta: (dx, dy),
            left: (last.0 - first.0).unsigned_abs() + (last.1 - first.1).unsigned_abs() + 1,
        }
    }
}

impl Iterator for Traversal {
    type Item = (i32, i32);

    fn next(&mut self) -> Option<(i32, i32)> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let cell = self.cell;
        if self.next.0 < self.next.1 {
            self.cell.0 += self.step.0;
            self.next.0 += self.delta.0;
        } else {
            self.cell.1 += self.step.1;
            self.next.1 += self.delta.1;
        }
        Some(cell)
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

    #[test]
    fn the_free_space_kept_says_what_the_counts_said() {
        let mut coverage = Coverage::new(0.1);
        for i in 0..40 {
            let angle = f64::from(i) * 0.15;
            let end = Vector2::new(angle.cos(), angle.sin()) * (3.0 + 0.05 * f64::from(i % 7));
            coverage.add_beam(Vector2::new(0.3, -0.2), end);
            coverage.add_beam(Vector2::new(-0.2, 0.3), end);
        }
        let free = coverage.free_space();
        let mut free_cells = 0;
        for x in -45..45 {
            for y in -45..45 {
                let p = Vector2::new(f64::from(x) * 0.1 + 0.05, f64::from(y) * 0.1 + 0.05);
                assert_eq!(free.seen(p), coverage.seen(p), "{p:?}");
                free_cells += usize::from(free.seen(p) == Seen::Free);
            }
        }
        assert!(free_cells > 100, "{free_cells}");
    }

    #[test]
    fn the_walk_gives_every_cell_the_segment_crosses_and_only_those() {
        let mut state = 7_u64;
        let mut uniform = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 20.0 - 10.0
        };
        let cell = |p: Vector2<f64>| (p.x.floor() as i32, p.y.floor() as i32);
        for _ in 0..200 {
            let (a, b) = (
                Vector2::new(uniform(), uniform()),
                Vector2::new(uniform(), uniform()),
            );
            let walk: Vec<(i32, i32)> = Traversal::new(a, b, cell(a), cell(b)).collect();
            assert_eq!(walk.first(), Some(&cell(a)));
            assert_eq!(walk.last(), Some(&cell(b)), "{a:?} {b:?}");
            for pair in walk.windows(2) {
                let step = (pair[1].0 - pair[0].0).abs() + (pair[1].1 - pair[0].1).abs();
                assert_eq!(step, 1, "{a:?} {b:?}");
            }
            for i in 0..=1000 {
                let p = a + (b - a) * (f64::from(i) / 1000.0);
                assert!(walk.contains(&cell(p)), "{a:?} {b:?} {p:?}");
            }
        }
    }
}
