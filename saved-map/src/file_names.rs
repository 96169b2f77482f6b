//! The names of a saved map's files in a run's output directory.

/// The map_server description of the grid.
pub const MAP_YAML_FILE: &str = "map.yaml";
/// The grid's trinary image, named by `map.yaml`.
pub const MAP_PGM_FILE: &str = "map.pgm";
/// The same image as PNG, for people.
pub const MAP_PNG_FILE: &str = "map.png";
/// The landmark map, which names the grid files.
pub const LANDMARKS_FILE: &str = "landmarks.json";
