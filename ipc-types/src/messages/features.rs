//! The lines and corners found in one scan.

use std::borrow::Cow;

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

use super::corner::Corner;
use super::line::Line;
use super::pose::Pose2;
use super::scan_motion::ScanMotion;
use crate::capacity::{CapacityError, MAX_FEATURE_CORNERS, MAX_LINES, fill, used};
use crate::header::Header;

/// The features of one scan, in the sensor frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, FromZeros)]
#[type_name("slam::Features::v4")]
pub struct Features {
    /// The source scan's header (sequence, stamp, frame); `sent_ns` is this message's.
    pub header: Header,
    /// When the source scan was published (its `header.sent_ns`), for end-to-end latency.
    pub scan_sent_ns: u64,
    /// Time spent extracting the features, nanoseconds.
    pub processing_ns: u64,
    pub line_count: u32,
    pub corner_count: u32,
    /// The odometry at the scan's stamp (`odom_from_robot`, interpolated between the readings
    /// around it: docs/CONVENTIONS.md, "Joining streams"); meaningful when `has_odometry` is 1.
    pub odometry: Pose2,
    /// Row-major 3x3 covariance of `odometry`, the integrated pose's.
    pub odometry_covariance: [f64; 9],
    /// 1 when the scan has an odometry pose, 0 when the run has no odometry.
    pub has_odometry: u32,
    /// 1 when `motion` holds the front end's estimate, 0 when no front end ran.
    pub has_motion: u32,
    /// The front end's motion estimate for this scan; meaningful when `has_motion` is 1.
    pub motion: ScanMotion,
    pub lines: [Line; MAX_LINES],
    pub corners: [Corner; MAX_FEATURE_CORNERS],
}

impl Features {
    pub fn lines(&self) -> &[Line] {
        used(&self.lines, self.line_count)
    }

    pub fn corners(&self) -> &[Corner] {
        used(&self.corners, self.corner_count)
    }

    /// The odometry pose at the scan's stamp and its covariance, if the run has odometry.
    pub fn odometry(&self) -> Option<OdometryAtScan> {
        (self.has_odometry == 1).then_some(OdometryAtScan {
            pose: self.odometry,
            covariance: self.odometry_covariance,
        })
    }

    /// Sets (or clears) the odometry pose at the scan's stamp.
    pub fn set_odometry(&mut self, odometry: Option<OdometryAtScan>) {
        let value = odometry.unwrap_or(OdometryAtScan {
            pose: Pose2::default(),
            covariance: [0.0; 9],
        });
        self.odometry = value.pose;
        self.odometry_covariance = value.covariance;
        self.has_odometry = u32::from(odometry.is_some());
    }

    /// The front end's motion estimate, if one ran.
    pub fn motion(&self) -> Option<ScanMotion> {
        (self.has_motion == 1).then_some(self.motion)
    }

    /// Sets (or clears) the front end's motion estimate.
    pub fn set_motion(&mut self, motion: Option<ScanMotion>) {
        self.motion = motion.unwrap_or_default();
        self.has_motion = u32::from(motion.is_some());
    }

    /// Replaces the lines and corners.
    pub fn set(&mut self, lines: &[Line], corners: &[Corner]) -> Result<(), CapacityError> {
        self.line_count = fill("lines", &mut self.lines, lines)?;
        self.corner_count = fill("corners", &mut self.corners, corners)?;
        Ok(())
    }

    pub fn to_record(&self) -> FeaturesRecord<'_> {
        FeaturesRecord {
            header: self.header,
            scan_sent_ns: self.scan_sent_ns,
            processing_ns: self.processing_ns,
            odometry: self.odometry(),
            motion: self.motion(),
            lines: Cow::Borrowed(self.lines()),
            corners: Cow::Borrowed(self.corners()),
        }
    }

    pub fn from_record(record: &FeaturesRecord<'_>) -> Result<Box<Self>, CapacityError> {
        let mut features = <Self as crate::Zeroable>::boxed_zeroed();
        features.header = record.header;
        features.scan_sent_ns = record.scan_sent_ns;
        features.processing_ns = record.processing_ns;
        features.set_odometry(record.odometry);
        features.set_motion(record.motion);
        features.set(&record.lines, &record.corners)?;
        Ok(features)
    }
}

/// The odometry pose paired with a scan (`odom_from_robot`) and its row-major covariance.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
pub struct OdometryAtScan {
    pub pose: Pose2,
    pub covariance: [f64; 9],
}

/// [`Features`] without their unused capacity: what gets written to disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
pub struct FeaturesRecord<'a> {
    pub header: Header,
    pub scan_sent_ns: u64,
    pub processing_ns: u64,
    pub odometry: Option<OdometryAtScan>,
    pub motion: Option<ScanMotion>,
    pub lines: Cow<'a, [Line]>,
    pub corners: Cow<'a, [Corner]>,
}

impl Serialize for Features {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_record().serialize(serializer)
    }
}
