//! The motion between scans: estimated from matched corners or lines, and sampled for each
//! particle.

pub(crate) mod estimator;
pub(crate) mod line_motion;
pub(crate) mod predict;
