//! The extraction pipeline, with buffers kept between scans so the hot path does not
//! allocate once they have grown to the scan size.

use std::ops::Range;

use crate::config::FeatureConfig;
use crate::corner::{MIN_LINE_LENGTH, corner_between};
use crate::features::FeatureSet;
use crate::line_fit::covariance;
use crate::scan::{BeamDirections, ScanError, ScanInput, ScanPoint, to_points};
use crate::segment::segment;
use crate::split_merge::{Piece, absorb_stubs, merge, refine_boundaries, split};
use slam_geom::MeasuredLine;
use stage_kit::SettingError;

/// Extracts lines and corners from scans: segments (adaptive breakpoints), split-and-merge,
/// total-least-squares lines with covariances, corners at the intersections of neighbouring
/// lines.
#[derive(Debug, Clone)]
pub struct Extractor {
    config: FeatureConfig,
    config_error: Option<SettingError>,
    directions: BeamDirections,
    points: Vec<ScanPoint>,
    segments: Vec<Range<usize>>,
    stack: Vec<Range<usize>>,
    pieces: Vec<Piece>,
    merged: Vec<Piece>,
    features: FeatureSet,
}

impl Extractor {
    /// An extractor with `config`. An invalid configuration is reported by every
    /// [`Extractor::extract`] call; check it up front with [`FeatureConfig::validate`].
    pub fn new(config: FeatureConfig) -> Self {
        Self {
            config_error: config.validate().err(),
            config,
            directions: BeamDirections::default(),
            points: Vec::new(),
            segments: Vec::new(),
            stack: Vec::new(),
            pieces: Vec::new(),
            merged: Vec::new(),
            features: FeatureSet::default(),
        }
    }

    pub fn config(&self) -> &FeatureConfig {
        &self.config
    }

    /// The lines and corners of `scan`, valid until the next call.
    pub fn extract(&mut self, scan: &ScanInput<'_>) -> Result<&FeatureSet, ScanError> {
        self.features.lines.clear();
        self.features.corners.clear();
        if let Some(error) = &self.config_error {
            return Err(error.clone().into());
        }
        let config = &self.config;
        let geometry = to_points(scan, config, &mut self.directions, &mut self.points)?;
        segment(&mut self.points, geometry, config, &mut self.segments);

        self.pieces.clear();
        for run in &self.segments {
            split(
                &self.points,
                run.clone(),
                config,
                &mut self.stack,
                &mut self.pieces,
            );
        }
        merge(&self.points, &self.pieces, &mut self.merged);
        refine_boundaries(&self.points, &mut self.merged, config.min_line_points);
        let tolerance = 3.0 * config.wall_sigma();
        absorb_stubs(&self.points, &mut self.merged, MIN_LINE_LENGTH, tolerance);

        for piece in &self.merged {
            let points = &self.points[piece.start..piece.end];
            let (Some(first), Some(last)) = (points.first(), points.last()) else {
                continue;
            };
            let fit = &piece.fit;
            self.features.lines.push(MeasuredLine {
                rho: fit.rho,
                theta: fit.theta(),
                covariance: covariance(points, fit, config.wall_sigma(), config.bearing_sigma),
                start: fit.project(first.x, first.y).into(),
                end: fit.project(last.x, last.y).into(),
                point_count: points.len(),
            });
        }

        let lines = &self.features.lines;
        for pair in lines.windows(2) {
            if let Some(corner) = corner_between(&pair[0], &pair[1]) {
                self.features.corners.push(corner);
            }
        }
        // In a 360-degree scan the last line is followed by the first.
        if geometry.cyclic
            && lines.len() > 2
            && let (Some(last), Some(first)) = (lines.last(), lines.first())
            && let Some(corner) = corner_between(last, first)
        {
            self.features.corners.push(corner);
        }
        Ok(&self.features)
    }
}
