//! Each particle's path and the loop closures on it, smoothed as a pose graph.

pub(crate) mod particle_path;
pub(crate) mod pose_graph;
