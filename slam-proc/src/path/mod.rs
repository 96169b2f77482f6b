//! Each particle's path.

pub(crate) mod particle_path;
