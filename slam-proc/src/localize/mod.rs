//! Localization on a saved map: Monte Carlo localization over its likelihood field, and the
//! start pose given on the command line.

pub(crate) mod cell_frame;
pub(crate) mod faced_field;
pub(crate) mod hill_climb;
pub(crate) mod kld;
pub(crate) mod likelihood_field;
pub(crate) mod localizer;
pub(crate) mod map_fit;
pub(crate) mod pose_arg;
pub(crate) mod tracking_field;
