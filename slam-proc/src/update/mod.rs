//! The measurement update of one particle: the corner observation model, data association
//! and the Kalman update of matched corners.

pub(crate) mod corner_model;
pub(crate) mod jcbb;
pub(crate) mod kalman;
