//! A lookup raster over the local map: for every cell of a fine grid near a map surface,
//! the map point nearest to the cell's centre in each of four normal directions. A
//! registration query then costs one table lookup and a few candidates instead of a
//! search through the neighbouring grid cells, and the raster changes only where a
//! keyframe adds points (the map changes every few scans, the queries thousands of times
//! per scan).
//!
//! Points leave the map by dying in the [`crate::local_map`]'s slab (their generation
//! moves on); a raster slot that still names a dead point is stale, and the query falls
//! back to the exact search. New points overwrite the stale slots they come near, so the
//! raster heals where the robot is, and stays stale only where it has left.

use nalgebra::Vector2;

use crate::cell_hash::{CellMap, floor_i32, pack};
use crate::points::SurfacePoint;

/// Raster cells per tile edge (a power of two): tiles are allocated only near the map's
/// surfaces, and consecutive scan points mostly fall in one.
const TILE_BITS: i32 = 4;
const TILE: i32 = 1 << TILE_BITS;

/// Normal directions are told apart in four sectors of 90 degrees centred on the axes:
/// a query normal is compatible (60 degrees, see [`crate::local_map`]) with normals in its
/// own sector and the two beside it, never with the opposite one, so a thin wall's two
/// faces or a corner's two walls keep their own candidates in every cell.
const SECTORS: usize = 4;

/// A raster slot: a point of the slab, the generation it had when it was stamped, and
/// its distance from the cell's centre (single precision: it only ranks candidates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Slot {
    pub id: u32,
    pub generation: u32,
    pub distance_squared: f32,
}

impl Slot {
    const EMPTY: Slot = Slot {
        id: u32::MAX,
        generation: 0,
        distance_squared: f32::INFINITY,
    };
}

/// A map point as the slab keeps it: its generation moves on when it dies, so slots that
/// named it can tell.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SlabPoint {
    pub point: SurfacePoint,
    pub generation: u32,
    pub alive: bool,
}

/// What the raster says about a query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Lookup {
    /// The nearest compatible candidate within the gate: `(slab id, distance squared)`.
    Found(u32, f64),
    /// No compatible map point within the gate.
    Nothing,
    /// A candidate the query needs has left the map: ask the exact search.
    Stale,
}

type Cell = [Slot; SECTORS];

#[derive(Debug, Clone)]
struct Tile {
    key: u64,
    /// The newest keyframe that stamped it: once that one has left the map, every slot
    /// of the tile is stale and the tile goes.
    last_keyframe: u64,
    cells: Box<[Cell]>,
}

#[derive(Debug, Clone)]
pub(crate) struct NearestField {
    /// Edge of a raster cell, metres.
    resolution: f64,
    inverse: f64,
    /// Points stamp the cells whose centres are within this of them, metres.
    reach: f64,
    /// Tile key to index in `tiles`.
    index: CellMap<u32>,
    tiles: Vec<Tile>,
}

/// The sector of a unit normal.
#[inline]
fn sector(normal: &Vector2<f64>) -> usize {
    if normal.x.abs() >= normal.y.abs() {
        if normal.x >= 0.0 { 0 } else { 2 }
    } else if normal.y >= 0.0 {
        1
    } else {
        3
    }
}

/// Whether two normals share a raster sector (and so the raster slots one is stamped in).
pub(crate) fn same_sector(a: &Vector2<f64>, b: &Vector2<f64>) -> bool {
    sector(a) == sector(b)
}

impl NearestField {
    /// A raster of cells `resolution` wide that answers queries with gates up to `reach`
    /// less half a cell diagonal ([`NearestField::max_gate`]).
    pub fn new(resolution: f64, reach: f64) -> Self {
        Self {
            resolution,
            inverse: 1.0 / resolution,
            reach,
            index: CellMap::default(),
            tiles: Vec::new(),
        }
    }

    /// The widest gate the raster answers exactly (within its resolution): a point within
    /// the gate of a query is within `reach` of the query's cell centre.
    pub fn max_gate(&self) -> f64 {
        self.reach - std::f64::consts::FRAC_1_SQRT_2 * self.resolution
    }

    fn tile_mut(&mut self, tx: i32, ty: i32, keyframe: u64) -> &mut [Cell] {
        let key = pack(tx, ty);
        let next = self.tiles.len() as u32;
        let index = *self.index.entry(key).or_insert(next);
        if index == next {
            self.tiles.push(Tile {
                key,
                last_keyframe: keyframe,
                cells: vec![[Slot::EMPTY; SECTORS]; (TILE * TILE) as usize].into_boxed_slice(),
            });
        }
        let tile = &mut self.tiles[index as usize];
        tile.last_keyframe = tile.last_keyframe.max(keyframe);
        &mut tile.cells
    }

    /// Marks the tiles a point at `point` reaches as used by `keyframe`, without stamping:
    /// for a point that took over a slab place (and its slots) from its voxel's previous
    /// point.
    pub fn touch(&mut self, point: Vector2<f64>, keyframe: u64) {
        let x0 = floor_i32((point.x - self.reach) * self.inverse) >> TILE_BITS;
        let x1 = floor_i32((point.x + self.reach) * self.inverse) >> TILE_BITS;
        let y0 = floor_i32((point.y - self.reach) * self.inverse) >> TILE_BITS;
        let y1 = floor_i32((point.y + self.reach) * self.inverse) >> TILE_BITS;
        for ty in y0..=y1 {
            for tx in x0..=x1 {
                if let Some(&index) = self.index.get(&pack(tx, ty))
                    && let Some(tile) = self.tiles.get_mut(index as usize)
                {
                    tile.last_keyframe = tile.last_keyframe.max(keyframe);
                }
            }
        }
    }

    /// Drops the tiles no keyframe from `oldest` on has stamped: all their points are gone.
    pub fn evict_before(&mut self, oldest: u64) {
        let mut i = 0;
        while i < self.tiles.len() {
            if self.tiles[i].last_keyframe >= oldest {
                i += 1;
                continue;
            }
            let gone = self.tiles.swap_remove(i);
            self.index.remove(&gone.key);
            if let Some(moved) = self.tiles.get(i) {
                self.index.insert(moved.key, i as u32);
            }
        }
    }

    /// Memory held by the raster's tiles, bytes.
    pub fn bytes(&self) -> usize {
        self.tiles() * (TILE * TILE) as usize * std::mem::size_of::<Cell>()
    }

    /// Tiles allocated.
    pub fn tiles(&self) -> usize {
        self.tiles.len()
    }

    /// Stamps the point `id` of `slab`, of keyframe `keyframe`, into every cell whose
    /// centre is within the reach, where it is nearer than the cell's candidate of its
    /// sector or that one is gone.
    pub fn stamp(&mut self, slab: &[SlabPoint], id: u32, keyframe: u64) {
        let Some(new) = slab.get(id as usize) else {
            return;
        };
        let p = new.point.point;
        let s = sector(&new.point.normal);
        let r2 = self.reach * self.reach;
        let h = self.resolution;
        let y0 = floor_i32((p.y - self.reach) * self.inverse);
        let y1 = floor_i32((p.y + self.reach) * self.inverse);
        for iy in y0..=y1 {
            let dy = (f64::from(iy) + 0.5) * h - p.y;
            let rest = r2 - dy * dy;
            if rest < 0.0 {
                continue;
            }
            // The cells of this row whose centres lie inside the circle.
            let half = rest.sqrt();
            let x0 = floor_i32((p.x - half) * self.inverse + 0.5);
            let x1 = floor_i32((p.x + half) * self.inverse - 0.5);
            let mut ix = x0;
            while ix <= x1 {
                let tx = ix >> TILE_BITS;
                let end = x1.min((tx << TILE_BITS) + TILE - 1);
                let row = ((iy & (TILE - 1)) << TILE_BITS) as usize;
                let cells = self.tile_mut(tx, iy >> TILE_BITS, keyframe);
                let span = row + (ix & (TILE - 1)) as usize..=row + (end & (TILE - 1)) as usize;
                let Some(span) = cells.get_mut(span) else {
                    break;
                };
                let mut dx = (f64::from(ix) + 0.5) * h - p.x;
                for cell in span {
                    let d2 = (dx * dx + dy * dy) as f32;
                    dx += h;
                    let cell = &mut cell[s];
                    let live = slab
                        .get(cell.id as usize)
                        .is_some_and(|c| c.generation == cell.generation && c.alive);
                    if !live || d2 <= cell.distance_squared {
                        *cell = Slot {
                            id,
                            generation: new.generation,
                            distance_squared: d2,
                        };
                    }
                }
                ix = end + 1;
            }
        }
    }

    /// The candidate for `query` with unit normal `normal` within `gate` (at most
    /// [`NearestField::max_gate`]) whose normal's cosine with the query's is at least
    /// `min_cosine`.
    #[inline]
    pub fn lookup(
        &self,
        slab: &[SlabPoint],
        query: Vector2<f64>,
        normal: Vector2<f64>,
        gate: f64,
        min_cosine: f64,
    ) -> Lookup {
        let ix = floor_i32(query.x * self.inverse);
        let iy = floor_i32(query.y * self.inverse);
        let Some(&tile) = self.index.get(&pack(ix >> TILE_BITS, iy >> TILE_BITS)) else {
            return Lookup::Nothing;
        };
        let local = (((iy & (TILE - 1)) << TILE_BITS) | (ix & (TILE - 1))) as usize;
        let cell = &self.tiles[tile as usize].cells[local];
        let own = sector(&normal);
        let g2 = gate * gate;
        let mut best = Lookup::Nothing;
        let mut best_d2 = f64::INFINITY;
        for s in [own, (own + 1) % SECTORS, (own + SECTORS - 1) % SECTORS] {
            let slot = cell[s];
            if slot.id == u32::MAX {
                continue;
            }
            let Some(candidate) = slab.get(slot.id as usize) else {
                return Lookup::Stale;
            };
            if candidate.generation != slot.generation || !candidate.alive {
                return Lookup::Stale;
            }
            let c = &candidate.point;
            let d2 = (c.point - query).norm_squared();
            if d2 > g2 || d2 >= best_d2 || c.normal.dot(&normal) < min_cosine {
                continue;
            }
            best = Lookup::Found(slot.id, d2);
            best_d2 = d2;
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sectors_are_centred_on_the_axes() {
        assert_eq!(sector(&Vector2::new(1.0, 0.9)), 0);
        assert_eq!(sector(&Vector2::new(0.1, 1.0)), 1);
        assert_eq!(sector(&Vector2::new(-1.0, 0.2)), 2);
        assert_eq!(sector(&Vector2::new(0.3, -1.0)), 3);
    }
}
