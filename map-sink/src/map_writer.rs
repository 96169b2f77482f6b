//! Writes a run's map: the occupancy grid as map_server reads it (`map.yaml`, `map.pgm`),
//! a PNG of it for people (`map.png`) and the landmarks (`landmarks.json`), each atomically.

use std::path::Path;

use crate::atomic::write_atomic;
use crate::error::SinkError;
use crate::grid_image::{encode_png, grid_pixels};
use crate::landmarks::{GridReference, Landmarks};
use crate::map_yaml::MapYaml;
use crate::occupancy_grid::OccupancyGrid;
use crate::pgm::encode_pgm;
use slam_geom::MapCorner;

/// The map_server description of the grid.
pub const MAP_YAML_FILE: &str = "map.yaml";
/// The grid's trinary image, named by `map.yaml`.
pub const MAP_PGM_FILE: &str = "map.pgm";
/// The same image as PNG, for people.
pub const MAP_PNG_FILE: &str = "map.png";
/// The landmark map, which names the grid files.
pub const LANDMARKS_FILE: &str = "landmarks.json";

/// Writes the map files into `dir`: the image before the description that names it, and
/// `landmarks.json`, which names both, last, so whoever finds a file finds what it names.
pub fn write_map(
    dir: &Path,
    grid: Option<&OccupancyGrid>,
    corners: &[MapCorner],
) -> Result<(), SinkError> {
    let reference = match grid {
        Some(grid) => {
            let (width, height) = (grid.width(), grid.height());
            let pixels = grid_pixels(grid);
            write_atomic(&dir.join(MAP_PGM_FILE), &encode_pgm(width, height, &pixels))?;
            write_atomic(
                &dir.join(MAP_PNG_FILE),
                &encode_png(width, height, &pixels)?,
            )?;
            let yaml = MapYaml::trinary(MAP_PGM_FILE, grid.resolution_m(), grid.origin());
            write_atomic(&dir.join(MAP_YAML_FILE), yaml.to_text().as_bytes())?;
            Some(GridReference {
                yaml: MAP_YAML_FILE.to_owned(),
                image: MAP_PGM_FILE.to_owned(),
                width,
                height,
                resolution: grid.resolution_m(),
            })
        }
        None => None,
    };
    let json = Landmarks::new(corners, reference).to_json()?;
    write_atomic(&dir.join(LANDMARKS_FILE), json.as_bytes())
}
