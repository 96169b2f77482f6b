//! The input scan, its validation and its conversion to sensor-frame points.

use std::f64::consts::TAU;

use slam_geom::{ScanGeometry, ScanGeometryError};
use stage_kit::SettingError;

use crate::config::FeatureConfig;

/// Most beams a scan may have (the `LaserScan` message's capacity).
pub const MAX_BEAMS: usize = 8192;

/// One sweep, as in ROS `sensor_msgs/LaserScan`: the ranges of the beams `geometry` places.
/// A range that is non-finite or outside `[range_min, range_max]` is invalid (REP 117).
#[derive(Debug, Clone, Copy)]
pub struct ScanInput<'a> {
    pub geometry: ScanGeometry,
    pub ranges: &'a [f32],
}

/// Why a scan yields no features. The caller counts it and moves on to the next scan.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScanError {
    #[error("the scan has no beams")]
    Empty,
    #[error("{count} beams exceed the limit of {max}")]
    TooManyBeams { count: usize, max: usize },
    /// The bearings are not defined, or no range could be valid.
    #[error(transparent)]
    Geometry(#[from] ScanGeometryError),
    #[error("{count} beams of {angle_increment} rad span more than a full turn")]
    SpanTooWide { count: usize, angle_increment: f64 },
    #[error("{valid} valid readings, at least {needed} needed")]
    TooFewValid { valid: usize, needed: usize },
    #[error(transparent)]
    Config(#[from] SettingError),
}

/// A valid reading in the sensor frame.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScanPoint {
    pub x: f64,
    pub y: f64,
    pub range: f64,
    /// Unit vector of the beam, for the point's noise along and across it.
    pub cos: f64,
    pub sin: f64,
    /// Index of the beam in the scan.
    pub beam: usize,
}

impl ScanPoint {
    pub fn distance(&self, other: &ScanPoint) -> f64 {
        // Plain square root: `hypot`'s overflow care is not needed for ranges and is slow.
        let (dx, dy) = (self.x - other.x, self.y - other.y);
        (dx * dx + dy * dy).sqrt()
    }
}

/// The beam pattern of a validated scan.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BeamPattern {
    pub count: usize,
    /// Angle between neighbouring beams, radians, > 0.
    pub spacing: f64,
    /// The last beam is the first one's neighbour (a 360-degree scan).
    pub cyclic: bool,
}

/// Unit vectors of the beams, kept while the beam pattern stays the same: a sensor's
/// pattern never changes, and a thousand `sin_cos` calls would be a third of the work.
#[derive(Debug, Clone, Default)]
pub(crate) struct BeamDirections {
    /// `angle_min` and `angle_increment` bits and the beam count they were made for.
    key: Option<(u64, u64, usize)>,
    unit: Vec<(f64, f64)>,
}

impl BeamDirections {
    fn update(&mut self, angle_min: f64, increment: f64, count: usize) -> &[(f64, f64)] {
        let key = Some((angle_min.to_bits(), increment.to_bits(), count));
        if self.key != key {
            self.unit.clear();
            self.unit.extend((0..count).map(|i| {
                let (sin, cos) = (angle_min + i as f64 * increment).sin_cos();
                (cos, sin)
            }));
            self.key = key;
        }
        &self.unit
    }
}

/// Validates `scan` and fills `points` with its valid readings in beam order.
pub(crate) fn to_points(
    scan: &ScanInput<'_>,
    config: &FeatureConfig,
    directions: &mut BeamDirections,
    points: &mut Vec<ScanPoint>,
) -> Result<BeamPattern, ScanError> {
    points.clear();
    let count = scan.ranges.len();
    if count == 0 {
        return Err(ScanError::Empty);
    }
    if count > MAX_BEAMS {
        return Err(ScanError::TooManyBeams {
            count,
            max: MAX_BEAMS,
        });
    }
    scan.geometry.check()?;
    let (angle_min, increment) = (scan.geometry.angle_min, scan.geometry.angle_increment);
    let spacing = increment.abs();
    let span = spacing * (count - 1) as f64;
    // A scan whose last beam repeats its first spans exactly a full turn; allow for rounding.
    if span > TAU * (1.0 + 1e-6) {
        return Err(ScanError::SpanTooWide {
            count,
            angle_increment: increment,
        });
    }
    let (range_min, range_max) = (scan.geometry.range_min, scan.geometry.range_max);
    let upper = range_max.min(config.max_range);
    let unit = directions.update(angle_min, increment, count);
    for (beam, (&reading, &(cos, sin))) in scan.ranges.iter().zip(unit).enumerate() {
        let range = f64::from(reading);
        // Also false for NaN.
        if range > 0.0 && range >= range_min && range <= upper {
            points.push(ScanPoint {
                x: range * cos,
                y: range * sin,
                range,
                cos,
                sin,
                beam,
            });
        }
    }
    if points.len() < config.min_line_points {
        return Err(ScanError::TooFewValid {
            valid: points.len(),
            needed: config.min_line_points,
        });
    }
    Ok(BeamPattern {
        count,
        spacing,
        // The wrap from the last beam to the first is no wider than one and a half steps.
        cyclic: count > 2 && TAU - span < 1.5 * spacing,
    })
}
