//! One particle's corner map: corner estimates in a persistent array keyed by id, a
//! persistent spatial grid over them, and the list of tentative corners awaiting a second
//! sighting. Cloning a map copies three pointers; particles resampled from one parent share
//! everything until one of them writes.

use std::sync::Arc;

use nalgebra::{Matrix4, Vector4};

use slam_geom::MapCorner;

use crate::map::grid::SpatialGrid;
use crate::map::persistent::PersistentArray;

/// A corner's Gaussian estimate in the world, `(x, y, heading, angle)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CornerState {
    pub mean: Vector4<f64>,
    pub covariance: Matrix4<f64>,
    pub observations: u32,
}

impl CornerState {
    fn to_map_corner(self) -> MapCorner {
        MapCorner {
            x: self.mean.x,
            y: self.mean.y,
            heading: self.mean.z,
            angle: self.mean.w,
            covariance: self.covariance,
            observations: self.observations,
        }
    }
}

/// A corner seen fewer times than confirmation needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Tentative {
    id: u32,
    /// Scans in which it was in view and not observed.
    misses: u32,
}

#[derive(Debug, Clone)]
pub(crate) struct CornerMap {
    corners: PersistentArray<Option<CornerState>>,
    grid: SpatialGrid,
    tentative: Arc<Vec<Tentative>>,
    next_id: u32,
    confirmed: usize,
}

impl CornerMap {
    pub fn new(cell_size: f64) -> Self {
        Self {
            corners: PersistentArray::default(),
            grid: SpatialGrid::new(cell_size),
            tentative: Arc::new(Vec::new()),
            next_id: 0,
            confirmed: 0,
        }
    }

    pub fn get(&self, id: u32) -> Option<&CornerState> {
        self.corners.get(id as usize)?.as_ref()
    }

    /// Appends to `out` the ids of corners that may lie within `radius` of `(x, y)`.
    pub fn near(&self, x: f64, y: f64, radius: f64, out: &mut Vec<u32>) {
        self.grid.query(x, y, radius, out);
    }

    /// Adds a corner; it is tentative unless `state.observations >= confirm_at` already.
    pub fn insert(&mut self, state: CornerState, confirm_at: u32) -> u32 {
        let id = self.next_id;
        self.next_id += 1;
        *self.corners.get_mut(id as usize) = Some(state);
        self.grid.insert(id, state.mean.x, state.mean.y);
        if state.observations >= confirm_at {
            self.confirmed += 1;
        } else {
            Arc::make_mut(&mut self.tentative).push(Tentative { id, misses: 0 });
        }
        id
    }

    /// Replaces a corner's estimate by `estimate(old)` after one more observation. One walk
    /// down the tree, which copies the nodes this map still shares.
    pub fn update(
        &mut self,
        id: u32,
        confirm_at: u32,
        estimate: impl FnOnce(&CornerState) -> (Vector4<f64>, Matrix4<f64>),
    ) {
        let Some(state) = self.corners.get_mut(id as usize).as_mut() else {
            return;
        };
        let from = (state.mean.x, state.mean.y);
        (state.mean, state.covariance) = estimate(state);
        state.observations = state.observations.saturating_add(1);
        let confirmed_now = state.observations == confirm_at;
        let to = (state.mean.x, state.mean.y);
        self.grid.relocate(id, from, to);
        if confirmed_now {
            self.confirmed += 1;
            Arc::make_mut(&mut self.tentative).retain(|t| t.id != id);
        }
    }

    /// Counts a miss for every tentative corner not in `observed` that `in_view` says the
    /// robot should have seen, and drops those that reach `max_misses`: a corner seen once
    /// and never again was noise, and must not clutter the map or the association.
    pub fn age_tentative(
        &mut self,
        observed: &[u32],
        in_view: impl Fn(&CornerState) -> bool,
        max_misses: u32,
    ) {
        let missed =
            |t: &Tentative| !observed.contains(&t.id) && self.get(t.id).is_some_and(&in_view);
        // Most scans change nothing for most particles: look before copying the list.
        let Some(first) = self.tentative.iter().position(missed) else {
            return;
        };
        let flags: Vec<bool> = self.tentative[first..].iter().map(missed).collect();
        let tentative = Arc::make_mut(&mut self.tentative);
        let mut dropped = Vec::new();
        for (t, missed) in tentative[first..].iter_mut().zip(flags) {
            if missed {
                t.misses += 1;
                if t.misses >= max_misses {
                    dropped.push(t.id);
                }
            }
        }
        if dropped.is_empty() {
            return;
        }
        tentative.retain(|t| !dropped.contains(&t.id));
        for id in dropped {
            if let Some(state) = self.corners.get_mut(id as usize).take() {
                self.grid.remove(id, state.mean.x, state.mean.y);
            }
        }
    }

    /// Removes a corner, confirmed or tentative.
    pub fn remove(&mut self, id: u32, confirm_at: u32) {
        let Some(state) = self.get(id).copied() else {
            return;
        };
        *self.corners.get_mut(id as usize) = None;
        self.grid.remove(id, state.mean.x, state.mean.y);
        if state.observations >= confirm_at {
            self.confirmed -= 1;
        } else {
            Arc::make_mut(&mut self.tentative).retain(|t| t.id != id);
        }
    }

    /// Number of confirmed corners.
    pub fn confirmed_count(&self) -> usize {
        self.confirmed
    }

    /// Number of tentative corners.
    #[cfg(test)]
    pub fn tentative_count(&self) -> usize {
        self.tentative.len()
    }

    /// Every confirmed corner, by id.
    pub fn confirmed(&self, confirm_at: u32) -> Vec<MapCorner> {
        let mut out = Vec::with_capacity(self.confirmed);
        self.corners.for_each(|_, slot| {
            if let Some(state) = slot
                && state.observations >= confirm_at
            {
                out.push(state.to_map_corner());
            }
        });
        out
    }

    /// Whether both maps are one structure (a clone neither has written to since).
    #[cfg(test)]
    pub fn shares_corners_with(&self, other: &Self) -> bool {
        self.corners.shares_root_with(&other.corners)
    }

    /// How many maps hold this map's corner tree.
    #[cfg(test)]
    pub fn corner_tree_holders(&self) -> usize {
        self.corners.root_strong_count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(x: f64, y: f64) -> CornerState {
        CornerState {
            mean: Vector4::new(x, y, 0.0, 1.5),
            covariance: Matrix4::identity() * 1e-4,
            observations: 1,
        }
    }

    #[test]
    fn tentative_corners_confirm_or_drop() {
        let mut map = CornerMap::new(2.0);
        let kept = map.insert(state(1.0, 0.0), 2);
        let noise = map.insert(state(3.0, 0.0), 2);
        let unseen = map.insert(state(50.0, 0.0), 2);
        assert_eq!((map.confirmed_count(), map.tentative_count()), (0, 3));
        let near = |s: &CornerState| s.mean.x < 10.0;
        map.age_tentative(&[kept], near, 2);
        let updated = (
            Vector4::new(1.01, 0.0, 0.0, 1.5),
            Matrix4::identity() * 5e-5,
        );
        map.update(kept, 2, |_| updated);
        assert_eq!((map.confirmed_count(), map.tentative_count()), (1, 2));
        map.age_tentative(&[], near, 2);
        // Two misses in view: gone. Out of view: kept, however long.
        assert!(map.get(noise).is_none());
        assert!(map.get(unseen).is_some());
        let mut out = Vec::new();
        map.near(3.0, 0.0, 1.0, &mut out);
        assert!(out.is_empty());
        let confirmed = map.confirmed(2);
        assert_eq!(confirmed.len(), 1);
        assert_eq!((confirmed[0].x, confirmed[0].observations), (1.01, 2));

        // Removing works for both kinds, and is gone from the grid.
        map.remove(kept, 2);
        map.remove(unseen, 2);
        assert_eq!((map.confirmed_count(), map.tentative_count()), (0, 0));
        assert!(map.get(kept).is_none());
        map.near(1.0, 0.0, 1.0, &mut out);
        assert!(out.is_empty());
    }
}
