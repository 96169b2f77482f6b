//! `landmarks.json`: the best particle's corners with their covariances, in a versioned
//! file that a later run can load (docs/CONVENTIONS.md, "Saved maps").
//!
//! ```json
//! {
//!   "format": "lidar-slam-landmarks",
//!   "version": 1,
//!   "frame": "map",
//!   "units": "m, rad",
//!   "grid": { "yaml": "map.yaml", "image": "map.pgm", "width": 960, "height": 600, "resolution": 0.05 },
//!   "corners": [
//!     { "x": 1.0, "y": 2.0, "heading": 0.78, "angle": 1.57,
//!       "covariance": [[1e-4, 0, 0, 0], [0, 1e-4, 0, 0], [0, 0, 1e-3, 0], [0, 0, 0, 1e-3]],
//!       "observations": 12 }
//!   ]
//! }
//! ```
//!
//! `frame: "map"` is the SLAM frame (the run's first pose at the origin, facing +x), the
//! frame of `trajectory.tum` and of `map.yaml`'s origin. A corner is as in
//! docs/CONVENTIONS.md: the walls' intersection, the heading of the bisector towards the
//! tip, the opening angle; `covariance` is the symmetric 4 x 4 over `(x, y, heading, angle)`
//! in m² and rad². `grid` names the occupancy grid written beside it and its size, so a
//! loader can tell that the three files belong together; it is `null` for a run that had
//! no scans to trace.

use serde::{Deserialize, Serialize};

use slam_geom::MapCorner;

/// The `format` name of the file.
pub const LANDMARKS_FORMAT: &str = "lidar-slam-landmarks";
/// The version this crate writes and reads.
pub const LANDMARKS_VERSION: u32 = 1;
/// The frame every position is in.
pub const LANDMARKS_FRAME: &str = "map";
/// The units of every number.
pub const LANDMARKS_UNITS: &str = "m, rad";

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Landmarks {
    pub format: String,
    pub version: u32,
    pub frame: String,
    pub units: String,
    pub grid: Option<GridReference>,
    pub corners: Vec<CornerLandmark>,
}

/// The occupancy grid the landmarks were written with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridReference {
    /// The map_server description, relative to this file's directory.
    pub yaml: String,
    /// The image it names.
    pub image: String,
    /// Pixels across and down.
    pub width: usize,
    pub height: usize,
    /// Metres per pixel.
    pub resolution: f64,
}

/// One corner landmark.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CornerLandmark {
    pub x: f64,
    pub y: f64,
    pub heading: f64,
    pub angle: f64,
    /// Rows of the symmetric covariance over `(x, y, heading, angle)`.
    pub covariance: [[f64; 4]; 4],
    /// Scans that saw the corner.
    pub observations: u32,
}

/// Why a text is not a landmarks file this crate can use.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LandmarksError {
    #[error("truncated: the JSON ends early (line {line})")]
    Truncated { line: usize },
    #[error("not a landmarks file: {0}")]
    Foreign(String),
    #[error(
        "version {found} of {LANDMARKS_FORMAT}; this program reads version {LANDMARKS_VERSION}"
    )]
    Version { found: u64 },
    #[error("{0}")]
    Malformed(String),
}

impl Landmarks {
    /// The file for a map's corners (and the grid written beside them, if any).
    pub fn new(corners: &[MapCorner], grid: Option<GridReference>) -> Self {
        Self {
            format: LANDMARKS_FORMAT.to_owned(),
            version: LANDMARKS_VERSION,
            frame: LANDMARKS_FRAME.to_owned(),
            units: LANDMARKS_UNITS.to_owned(),
            grid,
            corners: corners
                .iter()
                .map(|c| CornerLandmark {
                    x: c.x,
                    y: c.y,
                    heading: c.heading,
                    angle: c.angle,
                    covariance: std::array::from_fn(|r| {
                        std::array::from_fn(|k| c.covariance[(r, k)])
                    }),
                    observations: c.observations,
                })
                .collect(),
        }
    }

    /// The corners as the recorder holds them.
    pub fn map_corners(&self) -> Vec<MapCorner> {
        self.corners
            .iter()
            .map(|c| MapCorner {
                x: c.x,
                y: c.y,
                heading: c.heading,
                angle: c.angle,
                covariance: nalgebra::Matrix4::from_fn(|r, k| c.covariance[r][k]),
                observations: c.observations,
            })
            .collect()
    }

    /// Pretty JSON with a final newline; numbers in shortest round-trip form, so a corner
    /// reads back bit for bit.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }

    /// Reads and checks a landmarks file: the format name first (another file is refused as
    /// foreign, whatever else is wrong with it), then the version, then every field.
    pub fn from_json(text: &str) -> Result<Self, LandmarksError> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| {
            if e.is_eof() {
                LandmarksError::Truncated { line: e.line() }
            } else if text.trim_start().starts_with('{') {
                LandmarksError::Malformed(format!("not valid JSON: {e}"))
            } else {
                LandmarksError::Foreign("not a JSON object".into())
            }
        })?;
        let format = value.get("format").and_then(serde_json::Value::as_str);
        if format != Some(LANDMARKS_FORMAT) {
            return Err(LandmarksError::Foreign(match format {
                Some(other) => format!("format `{other}`, expected `{LANDMARKS_FORMAT}`"),
                None => format!("no `format: \"{LANDMARKS_FORMAT}\"`"),
            }));
        }
        match value.get("version").and_then(serde_json::Value::as_u64) {
            Some(v) if v == u64::from(LANDMARKS_VERSION) => {}
            Some(found) => return Err(LandmarksError::Version { found }),
            None => {
                return Err(LandmarksError::Malformed(
                    "no whole-number `version`".into(),
                ));
            }
        }
        let landmarks: Self =
            serde_json::from_value(value).map_err(|e| LandmarksError::Malformed(e.to_string()))?;
        landmarks.check()?;
        Ok(landmarks)
    }

    fn check(&self) -> Result<(), LandmarksError> {
        if self.frame != LANDMARKS_FRAME {
            return Err(LandmarksError::Malformed(format!(
                "frame `{}`, expected `{LANDMARKS_FRAME}`",
                self.frame
            )));
        }
        if self.units != LANDMARKS_UNITS {
            return Err(LandmarksError::Malformed(format!(
                "units `{}`, expected `{LANDMARKS_UNITS}`",
                self.units
            )));
        }
        if let Some(grid) = &self.grid
            && !(grid.resolution.is_finite() && grid.resolution > 0.0)
        {
            return Err(LandmarksError::Malformed(format!(
                "grid resolution {} is not a positive number",
                grid.resolution
            )));
        }
        for (i, c) in self.corners.iter().enumerate() {
            let numbers = [c.x, c.y, c.heading, c.angle];
            if !numbers
                .iter()
                .chain(c.covariance.iter().flatten())
                .all(|v| v.is_finite())
            {
                return Err(LandmarksError::Malformed(format!(
                    "corner {i} holds a number that is not finite"
                )));
            }
            for r in 0..4 {
                for k in 0..r {
                    let (a, b) = (c.covariance[r][k], c.covariance[k][r]);
                    if (a - b).abs() > 1e-9 * a.abs().max(b.abs()).max(1e-12) {
                        return Err(LandmarksError::Malformed(format!(
                            "corner {i}: covariance is not symmetric ({r},{k}) {a} vs {b}"
                        )));
                    }
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corner(x: f64) -> MapCorner {
        let mut covariance =
            nalgebra::Matrix4::from_diagonal(&nalgebra::Vector4::new(1e-4, 2e-4, 3e-3, 4e-3));
        covariance[(0, 1)] = 1.5e-5;
        covariance[(1, 0)] = 1.5e-5;
        MapCorner {
            x,
            y: -x / 3.0,
            heading: 0.1 * x,
            angle: std::f64::consts::FRAC_PI_2,
            covariance,
            observations: 7,
        }
    }

    #[test]
    fn corners_and_grid_round_trip_bit_for_bit() -> Result<(), Box<dyn std::error::Error>> {
        let corners = [corner(1.0), corner(-2.7), corner(1e-7)];
        let grid = GridReference {
            yaml: "map.yaml".into(),
            image: "map.pgm".into(),
            width: 30,
            height: 20,
            resolution: 0.05,
        };
        let text = Landmarks::new(&corners, Some(grid.clone())).to_json()?;
        let back = Landmarks::from_json(&text)?;
        assert_eq!(back.map_corners(), corners);
        assert_eq!(back.grid, Some(grid));
        assert_eq!(back.corners[0].covariance[0][1], 1.5e-5);
        Ok(())
    }

    #[test]
    fn other_files_versions_and_broken_ones_are_refused_by_name()
    -> Result<(), Box<dyn std::error::Error>> {
        let good = Landmarks::new(&[corner(1.0)], None).to_json()?;
        assert!(matches!(
            Landmarks::from_json(&good[..good.len() / 2]),
            Err(LandmarksError::Truncated { .. })
        ));
        assert!(matches!(
            Landmarks::from_json("x,y,heading\n1,2,3\n"),
            Err(LandmarksError::Foreign(_))
        ));
        assert_eq!(
            Landmarks::from_json(r#"{"format": "geojson", "version": 1}"#),
            Err(LandmarksError::Foreign(
                "format `geojson`, expected `lidar-slam-landmarks`".into()
            ))
        );
        let future = good.replace("\"version\": 1", "\"version\": 2");
        assert_eq!(
            Landmarks::from_json(&future),
            Err(LandmarksError::Version { found: 2 })
        );
        let asymmetric = good.replacen("0.000015", "0.000025", 1);
        assert_ne!(asymmetric, good);
        assert!(matches!(
            Landmarks::from_json(&asymmetric),
            Err(LandmarksError::Malformed(m)) if m.contains("not symmetric")
        ));
        let unknown = good.replace("\"frame\"", "\"colour\": 1, \"frame\"");
        assert!(matches!(
            Landmarks::from_json(&unknown),
            Err(LandmarksError::Malformed(m)) if m.contains("colour")
        ));
        Ok(())
    }
}
