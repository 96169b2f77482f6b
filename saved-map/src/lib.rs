//! # saved-map
//!
//! The map a run writes and a later run loads: a run's output directory read as a map. It
//! holds `landmarks.json` (the corners with their covariances, [`Landmarks`]), the
//! occupancy grid as ROS map_server and nav2's map_io read it (`map.yaml`, [`MapYaml`], and
//! the binary PGM it names, [`Pgm`]) and, for people, `map.png`; docs/CONVENTIONS.md,
//! "Saved maps", has the rules.
//!
//! This crate is the format alone, both ways: the file names, the encoders map-sink writes
//! the files with ([`MapYaml::to_text`], [`encode_pgm`], [`Landmarks::to_json`]) and the
//! reader, [`SavedMap::load`], which refuses a missing, truncated or foreign file and files
//! of different runs put together ([`MapLoadError`]). map-sink writes a map; slam-proc
//! (localization, mapping on a saved map) and slam-launch (the checks before a run) read
//! one, without depending on map-sink.
//!
//! A grid's cells are the back end's [`CellState`]s, row 0 the lowest y ([`GridMap`]).

mod file_names;
mod landmarks;
mod map_load_error;
mod map_yaml;
mod pgm;
mod saved_map;

pub use file_names::{LANDMARKS_FILE, MAP_PGM_FILE, MAP_PNG_FILE, MAP_YAML_FILE};
pub use landmarks::{
    CornerLandmark, GridReference, LANDMARKS_FORMAT, LANDMARKS_FRAME, LANDMARKS_UNITS,
    LANDMARKS_VERSION, Landmarks, LandmarksError,
};
pub use map_load_error::MapLoadError;
pub use map_yaml::{
    CellState, FREE_PIXEL, FREE_THRESH, MapMode, MapYaml, OCCUPIED_PIXEL, OCCUPIED_THRESH,
    UNKNOWN_PIXEL, YamlError, trinary_pixel,
};
pub use pgm::{Pgm, PgmError, encode_pgm};
pub use saved_map::{
    GridMap, LANDMARKS_INPUT, MAP_IMAGE_INPUT, MAP_YAML_INPUT, MAX_MAP_COORDINATE_M,
    MapExtentError, SavedMap,
};
