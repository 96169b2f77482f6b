//! Fixed capacities of the messages and the error for data that does not fit.

/// Beams a [`crate::LaserScan`] can carry (RPLIDAR drivers use 8192; a UTM-30LX has 1081).
pub const MAX_BEAMS: usize = 8192;
/// Lines a [`crate::Features`] message can carry.
pub const MAX_LINES: usize = 256;
/// Corners a [`crate::Features`] message can carry.
pub const MAX_FEATURE_CORNERS: usize = 128;
/// Corners a [`crate::MapSnapshot`] can carry.
pub const MAX_MAP_CORNERS: usize = 4096;
/// Poses a [`crate::PathChunk`] can carry (a path of any length travels as several).
pub const MAX_PATH_CHUNK_POSES: usize = 4096;
/// Particles a [`crate::ParticleCloud`] piece carries (a cloud of any size travels as
/// several): 64 KiB, a scan's size.
pub const MAX_CLOUD_CHUNK_PARTICLES: usize = 2048;
/// Cells a [`crate::GridCells`] piece carries (a grid of any size travels as several).
pub const MAX_GRID_CHUNK_CELLS: usize = 65536;
/// True corners a [`crate::WorldCorners`] message can carry.
pub const MAX_WORLD_CORNERS: usize = 4096;

/// More items than a fixed-capacity message holds.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what}: {len} items exceed the capacity of {capacity}")]
pub struct CapacityError {
    /// Which list overflowed.
    pub what: &'static str,
    /// How many items were offered.
    pub len: usize,
    /// How many fit.
    pub capacity: usize,
}

/// Copies `items` into the front of `slots`, or says which list overflowed.
pub(crate) fn fill<T: Copy>(
    what: &'static str,
    slots: &mut [T],
    items: &[T],
) -> Result<u32, CapacityError> {
    let capacity = slots.len();
    if items.len() > capacity {
        return Err(CapacityError {
            what,
            len: items.len(),
            capacity,
        });
    }
    slots[..items.len()].copy_from_slice(items);
    // Every capacity is far below u32::MAX, checked above.
    Ok(items.len() as u32)
}

/// The first `count` slots, clamped to the capacity so a corrupt count cannot index past it.
pub(crate) fn used<T>(slots: &[T], count: u32) -> &[T] {
    &slots[..(count as usize).min(slots.len())]
}
