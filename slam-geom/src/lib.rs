//! # slam-geom
//!
//! Planar geometry every algorithm crate of the pipeline needs, in one place and free of
//! the shared-memory transport, so the libraries stay testable on their own.

mod angle;

pub use angle::wrap_angle;
