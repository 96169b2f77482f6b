//! The filter itself: what it is given each scan, its particles, their weights and
//! resampling, and what it reports.

pub(crate) mod estimate;
pub(crate) mod fast_slam;
pub mod memory;
pub(crate) mod observation;
pub(crate) mod particle;
pub(crate) mod resample;
pub(crate) mod rng;
pub(crate) mod saved_grid;
