//! The measurement update of one particle: the corner observation model, data association,
//! the Kalman update of matched corners, and the uncertainty a revisit allows for.

pub(crate) mod corner_model;
pub(crate) mod drift;
pub(crate) mod free_space;
pub(crate) mod jcbb;
pub(crate) mod kalman;
pub(crate) mod wall_alignment;
