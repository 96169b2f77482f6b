//! A run's output directory read back as a map: `landmarks.json`, the map_server
//! description it names (`map.yaml`) and that description's image (`map.pgm`).

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use stage_kit::{InputError, InputKind};

use crate::file_names::LANDMARKS_FILE;
use crate::landmarks::{Landmarks, LandmarksError};
use crate::map_load_error::MapLoadError;
use crate::map_yaml::{MapMode, MapYaml, YamlError};
use crate::pgm::{Pgm, PgmError};
use back_end::occupancy_grid::CellState;

/// An occupancy grid read by the map_server rules.
#[derive(Debug, Clone, PartialEq)]
pub struct GridMap {
    pub yaml: MapYaml,
    /// Cells across (x) and down (y).
    pub width: usize,
    pub height: usize,
    /// Row 0 is the lowest y (the image's last row), as in a ROS `OccupancyGrid`.
    pub cells: Vec<CellState>,
}

impl GridMap {
    /// Cell `(col, row)`, row 0 the lowest y.
    pub fn state(&self, col: usize, row: usize) -> CellState {
        self.cells[row * self.width + col]
    }

    /// The area the grid covers: lower-left and upper-right corners, map frame.
    pub fn extent(&self) -> ([f64; 2], [f64; 2]) {
        let [x, y, _] = self.yaml.origin;
        let res = self.yaml.resolution;
        (
            [x, y],
            [x + self.width as f64 * res, y + self.height as f64 * res],
        )
    }

    /// Checks that the grid lies within [`MAX_MAP_COORDINATE_M`] of the map frame's origin
    /// and, when the run knows where it starts (`start`, map frame), that it covers that
    /// place: a map far from where its run is would make the run's grid span both.
    pub fn check_extent(&self, start: Option<[f64; 2]>) -> Result<(), MapExtentError> {
        let (low, high) = self.extent();
        let within = |v: f64| v.abs() <= MAX_MAP_COORDINATE_M;
        if !low.into_iter().chain(high).all(within) {
            return Err(MapExtentError::Far { low, high });
        }
        if let Some(start) = start {
            let covers = (0..2).all(|a| (low[a]..=high[a]).contains(&start[a]));
            if !covers {
                return Err(MapExtentError::Elsewhere { low, high, start });
            }
        }
        Ok(())
    }
}

/// Farthest a saved grid may reach from its frame's origin, metres: a map of a city.
pub const MAX_MAP_COORDINATE_M: f64 = 100_000.0;

/// Why a saved grid's place does not fit the run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MapExtentError {
    #[error(
        "its grid spans x {:.2} to {:.2} m, y {:.2} to {:.2} m: beyond {MAX_MAP_COORDINATE_M} m \
         of its origin",
        low[0], high[0], low[1], high[1]
    )]
    Far { low: [f64; 2], high: [f64; 2] },
    #[error(
        "its grid spans x {:.2} to {:.2} m, y {:.2} to {:.2} m, which does not hold the run's \
         start ({:.2}, {:.2})",
        low[0], high[0], low[1], high[1], start[0], start[1]
    )]
    Elsewhere {
        low: [f64; 2],
        high: [f64; 2],
        start: [f64; 2],
    },
}

/// A saved map: the landmarks and, if the run traced one, the occupancy grid.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedMap {
    pub landmarks: Landmarks,
    pub grid: Option<GridMap>,
}

impl SavedMap {
    /// Reads the map in `dir`, refusing a missing, truncated or foreign file, and an image
    /// that does not match its description or the landmarks' record of it.
    pub fn load(dir: &Path) -> Result<Self, MapLoadError> {
        let landmarks_path = dir.join(LANDMARKS_FILE);
        let text = read(&landmarks_path, &LANDMARKS_INPUT)?;
        let text = String::from_utf8(text).map_err(|_| MapLoadError::Foreign {
            path: landmarks_path.clone(),
            reason: "not UTF-8 text".into(),
        })?;
        let landmarks = Landmarks::from_json(&text).map_err(|e| {
            let path = landmarks_path.clone();
            match e {
                LandmarksError::Truncated { .. } => MapLoadError::Truncated {
                    path,
                    reason: e.to_string(),
                },
                LandmarksError::Foreign(reason) => MapLoadError::Foreign { path, reason },
                LandmarksError::Version { .. } => MapLoadError::Version {
                    path,
                    reason: e.to_string(),
                },
                LandmarksError::Malformed(reason) => MapLoadError::Malformed { path, reason },
            }
        })?;
        let grid = match &landmarks.grid {
            Some(reference) => Some(load_grid(dir, reference)?),
            None => None,
        };
        Ok(Self { landmarks, grid })
    }
}

fn load_grid(
    dir: &Path,
    reference: &crate::landmarks::GridReference,
) -> Result<GridMap, MapLoadError> {
    let yaml_path = dir.join(&reference.yaml);
    let bytes = read(&yaml_path, &MAP_YAML_INPUT)?;
    let text = String::from_utf8(bytes).map_err(|_| MapLoadError::Foreign {
        path: yaml_path.clone(),
        reason: "not UTF-8 text".into(),
    })?;
    let yaml = MapYaml::parse(&text).map_err(|e| match e {
        YamlError::MissingKey(_) => MapLoadError::Foreign {
            path: yaml_path.clone(),
            reason: e.to_string(),
        },
        YamlError::Line { .. } => MapLoadError::Malformed {
            path: yaml_path.clone(),
            reason: e.to_string(),
        },
    })?;
    if yaml.mode == MapMode::Raw {
        return Err(MapLoadError::Malformed {
            path: yaml_path,
            reason: "mode `raw` holds occupancy values, not a trinary or scaled image".into(),
        });
    }
    let image_path = resolve(dir, &yaml.image);
    if yaml.image != reference.image {
        return Err(MapLoadError::ImageMismatch {
            path: image_path,
            reason: format!(
                "{} names image `{}`, {LANDMARKS_FILE} `{}`",
                yaml_path.display(),
                yaml.image,
                reference.image
            ),
        });
    }
    let pgm = Pgm::decode(&read(&image_path, &MAP_IMAGE_INPUT)?).map_err(|e| match e {
        PgmError::Foreign(reason) => MapLoadError::Foreign {
            path: image_path.clone(),
            reason,
        },
        PgmError::Truncated { .. } | PgmError::TruncatedHeader => MapLoadError::Truncated {
            path: image_path.clone(),
            reason: e.to_string(),
        },
    })?;
    if (pgm.width, pgm.height) != (reference.width, reference.height) {
        return Err(MapLoadError::ImageMismatch {
            path: image_path,
            reason: format!(
                "it is {} x {} pixels, {LANDMARKS_FILE} records {} x {}",
                pgm.width, pgm.height, reference.width, reference.height
            ),
        });
    }
    if (yaml.resolution - reference.resolution).abs() > 1e-9 * reference.resolution {
        return Err(MapLoadError::ImageMismatch {
            path: yaml_path,
            reason: format!(
                "resolution {} m, {LANDMARKS_FILE} records {} m",
                yaml.resolution, reference.resolution
            ),
        });
    }
    let (width, height) = (pgm.width, pgm.height);
    let mut cells = Vec::with_capacity(width * height);
    // Image rows run from the top (largest y); grid rows from the bottom.
    for row in (0..height).rev() {
        let line = &pgm.pixels[row * width..(row + 1) * width];
        cells.extend(line.iter().map(|&p| yaml.cell_state(p)));
    }
    Ok(GridMap {
        yaml,
        width,
        height,
        cells,
    })
}

/// A path from a map file: relative to the map's directory unless absolute.
fn resolve(dir: &Path, name: &str) -> PathBuf {
    let path = Path::new(name);
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        dir.join(path)
    }
}

/// A saved map's landmarks: a few hundred bytes a corner.
pub const LANDMARKS_INPUT: InputKind = InputKind {
    what: "landmarks file",
    limit_name: "saved_map::LANDMARKS_INPUT",
    max_bytes: 64 << 20,
};

/// A map_server description: a dozen lines.
pub const MAP_YAML_INPUT: InputKind = InputKind {
    what: "map description",
    limit_name: "saved_map::MAP_YAML_INPUT",
    max_bytes: 1 << 20,
};

/// A map image: one byte a cell, so 8192 x 8192 cells (410 m square at 5 cm).
pub const MAP_IMAGE_INPUT: InputKind = InputKind {
    what: "map image",
    limit_name: "saved_map::MAP_IMAGE_INPUT",
    max_bytes: 64 << 20,
};

fn read(path: &Path, kind: &InputKind) -> Result<Vec<u8>, MapLoadError> {
    kind.read(path).map_err(|e| match e {
        InputError::Open { source, .. } if source.kind() == ErrorKind::NotFound => {
            MapLoadError::Missing {
                path: path.to_path_buf(),
            }
        }
        other => other.into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 5 x 5 m grid whose lower-left corner is at `origin`.
    fn grid(origin: [f64; 2]) -> GridMap {
        GridMap {
            yaml: MapYaml::trinary("map.pgm", 0.05, origin),
            width: 100,
            height: 100,
            cells: vec![CellState::Unknown; 100 * 100],
        }
    }

    #[test]
    fn a_grid_far_away_or_not_where_the_run_starts_is_refused() {
        assert_eq!(grid([-1.0, -2.0]).check_extent(Some([0.0, 0.0])), Ok(()));
        assert_eq!(grid([1000.0, 1000.0]).check_extent(None), Ok(()));
        let elsewhere = grid([1000.0, 1000.0]).check_extent(Some([0.0, 0.0]));
        assert!(
            matches!(elsewhere, Err(MapExtentError::Elsewhere { .. })),
            "{elsewhere:?}"
        );
        let far = grid([1e300, -1e300]).check_extent(None).unwrap_err();
        assert!(far.to_string().contains("beyond 100000 m"), "{far}");
    }
}
