//! A run's output directory read back as a map: `landmarks.json`, the map_server
//! description it names (`map.yaml`) and that description's image (`map.pgm`).

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

use crate::landmarks::{Landmarks, LandmarksError};
use crate::map_load_error::MapLoadError;
use crate::map_writer::LANDMARKS_FILE;
use crate::map_yaml::{MapMode, MapYaml, YamlError};
use crate::occupancy_grid::CellState;
use crate::pgm::{Pgm, PgmError};

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
        let text = read(&landmarks_path)?;
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
    let bytes = read(&yaml_path)?;
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
    let pgm = Pgm::decode(&read(&image_path)?).map_err(|e| match e {
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

fn read(path: &Path) -> Result<Vec<u8>, MapLoadError> {
    std::fs::read(path).map_err(|source| match source.kind() {
        ErrorKind::NotFound => MapLoadError::Missing {
            path: path.to_path_buf(),
        },
        _ => MapLoadError::Io {
            path: path.to_path_buf(),
            source,
        },
    })
}
