//! One particle's corner map and the persistent structures it shares with its ancestors.

pub(crate) mod corner_map;
pub(crate) mod grid;
pub(crate) mod persistent;
