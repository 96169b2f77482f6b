//! Writes a run's map: the occupancy grid as map_server reads it (`map.yaml`, `map.pgm`),
//! a PNG of it for people (`map.png`) and the landmarks (`landmarks.json`), each atomically.

use std::path::Path;

use crate::atomic::write_atomic;
use crate::error::SinkError;
use crate::grid_image::{encode_png, grid_pixels};
use back_end::occupancy_grid::OccupancyGrid;
use saved_map::{
    GridReference, LANDMARKS_FILE, Landmarks, MAP_PGM_FILE, MAP_PNG_FILE, MAP_YAML_FILE, MapYaml,
    encode_pgm,
};
use slam_geom::MapCorner;

/// Writes the map files into `dir` ([`map_files`]), each atomically, in their order; the
/// first failure ends them.
pub fn write_map(
    dir: &Path,
    grid: Option<&OccupancyGrid>,
    corners: &[MapCorner],
) -> Result<(), SinkError> {
    for (name, contents) in map_files(grid, corners)? {
        write_atomic(&dir.join(name), &contents)?;
    }
    Ok(())
}

/// The map's files by name, in the order they are to be written: the image before the
/// description that names it, and `landmarks.json`, which names both, last, so whoever
/// finds a file finds what it names.
pub fn map_files(
    grid: Option<&OccupancyGrid>,
    corners: &[MapCorner],
) -> Result<Vec<(&'static str, Vec<u8>)>, SinkError> {
    let mut files = Vec::with_capacity(4);
    let reference = match grid {
        Some(grid) => {
            let (width, height) = (grid.width(), grid.height());
            let pixels = grid_pixels(grid);
            files.push((MAP_PGM_FILE, encode_pgm(width, height, &pixels)));
            files.push((MAP_PNG_FILE, encode_png(width, height, &pixels)?));
            let yaml = MapYaml::trinary(MAP_PGM_FILE, grid.resolution_m(), grid.origin());
            files.push((MAP_YAML_FILE, yaml.to_text().into_bytes()));
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
    files.push((LANDMARKS_FILE, json.into_bytes()));
    Ok(files)
}
