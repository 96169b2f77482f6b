//! From what the user asks for (an angular window, a cluster size, intensities or not) and
//! what the sensor reports (`PP`) to the ranging command and the `LaserScan` geometry.
//!
//! Step `s` looks at bearing `(s - AFRT) * 2 pi / ARES` (x forward, counter-clockwise, as in
//! the project's conventions: Hokuyos turn counter-clockwise seen from above). With a cluster
//! of `K` steps, beam `i` covers steps `start + i K ..= start + i K + K - 1`; its bearing and
//! time are those of the cluster's middle, the best single guess for the step whose range the
//! sensor reports (the shortest of the group). The window is cut to whole clusters.

use slam_geom::{ScanGeometry, wrap_angle};
use std::f64::consts::TAU;

use crate::scip::{DataKind, MAX_CLUSTER, Ranging, SensorParams};

/// What the user asks the sensor for (the options of `lidar-hokuyo`, and the keys of
/// slam-launch's `[hokuyo]` section).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScanRequest {
    /// First bearing wanted, radians; `None` = the sensor's first step.
    pub min_angle: Option<f64>,
    /// Last bearing wanted, radians; `None` = the sensor's last step.
    pub max_angle: Option<f64>,
    /// Adjacent steps merged into one beam (1 = none).
    pub cluster: u8,
    /// Ask for intensities (`ME`) as well as ranges (`MD`).
    pub intensities: bool,
}

impl ScanRequest {
    /// Every step of the sensor's field of view, one beam each, ranges only.
    pub const WHOLE_FIELD: Self = Self {
        min_angle: None,
        max_angle: None,
        cluster: 1,
        intensities: false,
    };
}

/// What the options and the `[hokuyo]` keys leave out: [`ScanRequest::WHOLE_FIELD`].
impl Default for ScanRequest {
    fn default() -> Self {
        Self::WHOLE_FIELD
    }
}

/// Why a request does not fit the sensor.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    #[error("{which} angle {angle} rad is outside the sensor's {first:.4} .. {last:.4} rad")]
    AngleOutOfRange {
        which: &'static str,
        angle: f64,
        first: f64,
        last: f64,
    },
    #[error("angle {0} is not a number")]
    NotANumber(f64),
    #[error("the window {min} .. {max} rad holds no whole cluster of {cluster} steps")]
    Empty { min: f64, max: f64, cluster: u8 },
    #[error("cluster must be 1 to {MAX_CLUSTER}, not {0}")]
    BadCluster(u8),
    #[error("{0} beams are more than a LaserScan holds ({max})", max = ipc_types::MAX_BEAMS)]
    TooManyBeams(usize),
    #[error("the sensor's parameters make no ranging command: {0}")]
    Command(#[from] crate::scip::ScipError),
}

/// The ranging command for a request, and the geometry and timing of its scans.
#[derive(Debug, Clone, PartialEq)]
pub struct RangingPlan {
    pub command: Ranging,
    /// Beams per scan.
    pub beams: usize,
    /// The `LaserScan` angles (the first bearing wrapped to [-pi, pi)), timing and range
    /// limits.
    pub geometry: ScanGeometry,
    /// `DMIN` in millimetres: smaller values are error codes.
    pub dmin_mm: u32,
    /// Time from the sensor's time stamp (taken at step 0) to the first beam, seconds.
    pub first_beam_delay: f64,
}

impl RangingPlan {
    /// The geometry of `request` on the sensor `params` describes.
    pub fn new(params: &SensorParams, request: &ScanRequest) -> Result<Self, GeometryError> {
        if request.cluster == 0 || request.cluster > MAX_CLUSTER {
            return Err(GeometryError::BadCluster(request.cluster));
        }
        let first = params.step_angle(f64::from(params.amin));
        let last = params.step_angle(f64::from(params.amax));
        let steps_per_radian = f64::from(params.ares) / TAU;
        // Bearings are compared in steps; a millionth of a step absorbs rounding.
        let slack = 1e-6;
        let to_step = |which, angle: Option<f64>, default: u32| match angle {
            None => Ok(f64::from(default)),
            Some(a) if a.is_nan() => Err(GeometryError::NotANumber(a)),
            Some(a) => {
                let step = f64::from(params.afrt) + a * steps_per_radian;
                if step < f64::from(params.amin) - slack || step > f64::from(params.amax) + slack {
                    Err(GeometryError::AngleOutOfRange {
                        which,
                        angle: a,
                        first,
                        last,
                    })
                } else {
                    Ok(step)
                }
            }
        };
        let min_step = to_step("minimum", request.min_angle, params.amin)?;
        let max_step = to_step("maximum", request.max_angle, params.amax)?;
        // The first step at or after the minimum, the last at or before the maximum.
        let start = (min_step - slack).ceil().max(f64::from(params.amin));
        let end = (max_step + slack).floor().min(f64::from(params.amax));
        let cluster = usize::from(request.cluster);
        let steps = if end >= start {
            // Both are whole steps within 0 ..= AMAX (at most 9999): exact as usize.
            (end - start) as usize + 1
        } else {
            0
        };
        let beams = steps / cluster;
        if beams == 0 {
            return Err(GeometryError::Empty {
                min: params.step_angle(min_step),
                max: params.step_angle(max_step),
                cluster: request.cluster,
            });
        }
        if beams > ipc_types::MAX_BEAMS {
            return Err(GeometryError::TooManyBeams(beams));
        }
        // Whole steps of at most AMAX <= 9999, checked by SensorParams: they fit u16.
        let start_step = start as u16;
        let end_step = start_step + (beams * cluster - 1) as u16;
        let kind = if request.intensities {
            DataKind::RangesIntensities
        } else {
            DataKind::Ranges3
        };
        let command = Ranging::new(kind, start_step, end_step, request.cluster, 0, 0)?;
        let first_beam_step = f64::from(start_step) + (cluster as f64 - 1.0) / 2.0;
        Ok(Self {
            command,
            beams,
            geometry: ScanGeometry {
                angle_min: wrap_angle(params.step_angle(first_beam_step)),
                angle_increment: cluster as f64 * TAU / f64::from(params.ares),
                time_increment: cluster as f64 * params.step_time(),
                scan_time: params.scan_time(),
                range_min: f64::from(params.dmin_mm) / 1000.0,
                range_max: f64::from(params.dmax_mm) / 1000.0,
            },
            dmin_mm: params.dmin_mm,
            first_beam_delay: first_beam_step * params.step_time(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const STEP: f64 = TAU / 1440.0;

    fn utm(request: ScanRequest) -> Result<RangingPlan, GeometryError> {
        RangingPlan::new(&SensorParams::utm_30lx(), &request)
    }

    #[test]
    fn the_whole_field_of_a_utm_30lx() {
        let g = utm(ScanRequest::default()).unwrap();
        assert_eq!((g.command.start, g.command.end), (0, 1080));
        assert_eq!(g.command.kind, DataKind::Ranges3);
        assert_eq!(g.beams, 1081);
        assert!((g.geometry.angle_min + 0.75 * PI).abs() < 1e-12);
        assert!((g.geometry.angle_increment - PI / 720.0).abs() < 1e-15);
        assert!((g.geometry.scan_time - 0.025).abs() < 1e-12);
        assert!((g.geometry.time_increment - 0.025 / 1440.0).abs() < 1e-15);
        assert_eq!((g.geometry.range_min, g.geometry.range_max), (0.023, 60.0));
        assert_eq!(g.first_beam_delay, 0.0);
    }

    #[test]
    fn a_window_picks_the_steps_inside_it() {
        let g = utm(ScanRequest {
            min_angle: Some(-1.0),
            max_angle: Some(1.0),
            ..Default::default()
        })
        .unwrap();
        // 1 rad = 229.18 steps: from step 540 - 229 = 311 to 540 + 229 = 769.
        assert_eq!((g.command.start, g.command.end), (311, 769));
        assert_eq!(g.beams, 459);
        assert!((g.geometry.angle_min - (-229.0 * STEP)).abs() < 1e-12);
        assert!(g.geometry.angle_min >= -1.0);
        assert!((g.first_beam_delay - 311.0 * 0.025 / 1440.0).abs() < 1e-15);
        // Exact step bearings are kept despite rounding.
        let g = utm(ScanRequest {
            min_angle: Some(-0.75 * PI),
            max_angle: Some(0.0),
            ..Default::default()
        })
        .unwrap();
        assert_eq!((g.command.start, g.command.end), (0, 540));
    }

    #[test]
    fn clusters_are_whole_and_centred() {
        let g = utm(ScanRequest {
            cluster: 3,
            intensities: true,
            ..Default::default()
        })
        .unwrap();
        // 1081 steps make 360 whole clusters of 3; the last step is dropped.
        assert_eq!(g.beams, 360);
        assert_eq!((g.command.start, g.command.end), (0, 1079));
        assert_eq!(g.command.cluster, 3);
        assert_eq!(g.command.beams(), 360);
        assert_eq!(g.command.kind, DataKind::RangesIntensities);
        // The first beam sits at the middle step of 0, 1, 2.
        assert!((g.geometry.angle_min - (1.0 - 540.0) * STEP).abs() < 1e-12);
        assert!((g.geometry.angle_increment - 3.0 * STEP).abs() < 1e-15);
        assert!((g.geometry.time_increment - 3.0 * 0.025 / 1440.0).abs() < 1e-15);
        let g = utm(ScanRequest {
            cluster: 2,
            ..Default::default()
        })
        .unwrap();
        assert!((g.geometry.angle_min - (0.5 - 540.0) * STEP).abs() < 1e-12);
    }

    #[test]
    fn impossible_requests_are_refused() {
        let out = ScanRequest {
            min_angle: Some(-2.5),
            ..Default::default()
        };
        assert!(matches!(
            utm(out),
            Err(GeometryError::AngleOutOfRange {
                which: "minimum",
                ..
            })
        ));
        let out = ScanRequest {
            max_angle: Some(3.0),
            ..Default::default()
        };
        assert!(matches!(
            utm(out),
            Err(GeometryError::AngleOutOfRange { .. })
        ));
        let empty = ScanRequest {
            min_angle: Some(0.5),
            max_angle: Some(0.4),
            ..Default::default()
        };
        assert!(matches!(utm(empty), Err(GeometryError::Empty { .. })));
        let narrow = ScanRequest {
            min_angle: Some(0.0),
            max_angle: Some(STEP),
            cluster: 3,
            ..Default::default()
        };
        assert!(matches!(utm(narrow), Err(GeometryError::Empty { .. })));
        for cluster in [0, 100] {
            let bad = ScanRequest {
                cluster,
                ..Default::default()
            };
            assert_eq!(utm(bad), Err(GeometryError::BadCluster(cluster)));
        }
        let nan = ScanRequest {
            min_angle: Some(f64::NAN),
            ..Default::default()
        };
        assert!(matches!(utm(nan), Err(GeometryError::NotANumber(_))));
    }

    #[test]
    fn angles_wrap_into_minus_pi_to_pi() {
        assert!((wrap_angle(PI) + PI).abs() < 1e-12);
        assert!((wrap_angle(-PI) + PI).abs() < 1e-12);
        assert!((wrap_angle(1.5 * PI) + 0.5 * PI).abs() < 1e-12);
        assert_eq!(wrap_angle(0.25), 0.25);
    }
}
