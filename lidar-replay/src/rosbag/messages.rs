//! The three ROS 2 message types a lidar replay reads from a bag, decoded from CDR:
//! `sensor_msgs/msg/LaserScan`, `nav_msgs/msg/Odometry` and `tf2_msgs/msg/TFMessage`.

use slam_geom::{Pose2, ScanGeometry};

use super::cdr::{Cdr, CdrError};

/// The type names (as a bag's topics and MCAP schemas give them).
pub const LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
pub const ODOMETRY: &str = "nav_msgs/msg/Odometry";
pub const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";

/// A `std_msgs/Header`: its stamp in nanoseconds and frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    pub stamp_ns: u64,
    pub frame_id: String,
}

fn header(cdr: &mut Cdr<'_>) -> Result<Header, CdrError> {
    let sec = cdr.i32("header.stamp.sec")?;
    let nanosec = cdr.u32("header.stamp.nanosec")?;
    let frame_id = cdr.string("header.frame_id")?;
    if sec < 0 || nanosec >= 1_000_000_000 {
        return Err(CdrError::Invalid {
            what: "header.stamp",
            reason: format!("{sec} s {nanosec} ns is no time since the epoch"),
        });
    }
    Ok(Header {
        stamp_ns: sec as u64 * 1_000_000_000 + u64::from(nanosec),
        frame_id,
    })
}

/// A decoded `sensor_msgs/msg/LaserScan`, its ranges in REP 117 form.
#[derive(Debug, Clone, PartialEq)]
pub struct LaserScan {
    pub header: Header,
    pub geometry: ScanGeometry,
    pub ranges: Vec<f32>,
    /// One per beam, or empty (a scan without intensities, or a count that is not the
    /// beams').
    pub intensities: Vec<f32>,
}

impl LaserScan {
    pub fn decode(data: &[u8]) -> Result<Self, CdrError> {
        let mut cdr = Cdr::new(data)?;
        let header = header(&mut cdr)?;
        let angle_min = cdr.f32("angle_min")?;
        let _angle_max = cdr.f32("angle_max")?;
        let angle_increment = cdr.f32("angle_increment")?;
        let time_increment = cdr.f32("time_increment")?;
        let scan_time = cdr.f32("scan_time")?;
        let range_min = cdr.f32("range_min")?;
        let range_max = cdr.f32("range_max")?;
        let ranges = cdr.f32_sequence("ranges")?;
        let mut intensities = cdr.f32_sequence("intensities")?;
        let geometry = ScanGeometry {
            angle_min: f64::from(angle_min),
            angle_increment: f64::from(angle_increment),
            time_increment: finite_or_zero(time_increment),
            scan_time: finite_or_zero(scan_time),
            // A driver that leaves range_min unset (or negative) means "from the sensor".
            range_min: f64::from(range_min).max(0.0),
            range_max: f64::from(range_max),
        };
        geometry.check().map_err(|e| CdrError::Invalid {
            what: "the scan's geometry",
            reason: e.to_string(),
        })?;
        if ranges.is_empty() || ranges.len() > ipc_types::MAX_BEAMS {
            return Err(CdrError::Invalid {
                what: "ranges",
                reason: format!(
                    "{} beams; a scan has 1 to {}",
                    ranges.len(),
                    ipc_types::MAX_BEAMS
                ),
            });
        }
        if intensities.len() != ranges.len() {
            intensities.clear();
        }
        let ranges = ranges
            .into_iter()
            .map(|range| rep117_range(range, &geometry))
            .collect();
        Ok(Self {
            header,
            geometry,
            ranges,
            intensities,
        })
    }
}

fn finite_or_zero(value: f32) -> f64 {
    if value.is_finite() {
        f64::from(value)
    } else {
        0.0
    }
}

/// A range as REP 117 has it: NaN (an error) and ±inf (no return, too close) stay; a
/// reading beyond `range_max` is no return (+inf), as drivers that report their limit
/// rather than an infinity mean it; one below `range_min` (a 0 many drivers write for
/// "nothing measured") is an error (NaN): it claims neither a hit nor a free ray.
pub fn rep117_range(range: f32, geometry: &ScanGeometry) -> f32 {
    if !range.is_finite() {
        range
    } else if f64::from(range) > geometry.range_max {
        f32::INFINITY
    } else if f64::from(range) < geometry.range_min {
        f32::NAN
    } else {
        range
    }
}

/// A decoded `nav_msgs/msg/Odometry`: the planar pose of `child_frame_id` in
/// `header.frame_id`, its (x, y, yaw) covariance and the forward and turn rates.
#[derive(Debug, Clone, PartialEq)]
pub struct Odometry {
    pub header: Header,
    pub child_frame_id: String,
    pub pose: Pose2,
    /// Row-major over (x, y, yaw), from the message's 6x6 (x, y, z, roll, pitch, yaw).
    pub covariance: [f64; 9],
    pub linear_velocity: f64,
    pub angular_velocity: f64,
}

impl Odometry {
    pub fn decode(data: &[u8]) -> Result<Self, CdrError> {
        let mut cdr = Cdr::new(data)?;
        let header = header(&mut cdr)?;
        let child_frame_id = cdr.string("child_frame_id")?;
        let [x, y, _z] = cdr.f64_array::<3>("pose.position")?;
        let quaternion = cdr.f64_array::<4>("pose.orientation")?;
        let pose_covariance = cdr.f64_array::<36>("pose.covariance")?;
        let linear = cdr.f64_array::<3>("twist.linear")?;
        let angular = cdr.f64_array::<3>("twist.angular")?;
        let _twist_covariance = cdr.f64_array::<36>("twist.covariance")?;
        let pose = Pose2::new(x, y, yaw_of(quaternion, "pose.orientation")?);
        if !(pose.x.is_finite() && pose.y.is_finite()) {
            return Err(CdrError::Invalid {
                what: "pose.position",
                reason: "not finite".into(),
            });
        }
        // (x, y, yaw) are rows and columns 0, 1 and 5 of the 6x6.
        const PLANAR: [usize; 3] = [0, 1, 5];
        let mut covariance = [0.0; 9];
        for (i, row) in PLANAR.iter().enumerate() {
            for (j, column) in PLANAR.iter().enumerate() {
                covariance[i * 3 + j] = pose_covariance[row * 6 + column];
            }
        }
        // A covariance that is no covariance (unknown: -1, NaN) is none.
        let usable = covariance.iter().all(|v| v.is_finite())
            && [0, 4, 8].iter().all(|&i| covariance[i] >= 0.0);
        if !usable {
            covariance = [0.0; 9];
        }
        let rate = |v: f64| if v.is_finite() { v } else { 0.0 };
        Ok(Self {
            header,
            child_frame_id,
            pose,
            covariance,
            linear_velocity: rate(linear[0]),
            angular_velocity: rate(angular[2]),
        })
    }
}

/// One `geometry_msgs/msg/TransformStamped`: `child_frame_id` in `header.frame_id`.
#[derive(Debug, Clone, PartialEq)]
pub struct Transform {
    pub header: Header,
    pub child_frame_id: String,
    pub translation: [f64; 3],
    /// (x, y, z, w).
    pub rotation: [f64; 4],
}

impl Transform {
    /// The planar pose of the child in the parent: x, y and the yaw of the rotation.
    pub fn planar(&self) -> Result<Pose2, CdrError> {
        Ok(Pose2::new(
            self.translation[0],
            self.translation[1],
            yaw_of(self.rotation, "transform.rotation")?,
        ))
    }

    /// How far the child's z axis leans from the parent's, radians: 0 for a level
    /// mount, pi for one upside down.
    pub fn tilt(&self) -> f64 {
        let [x, y, _, _] = unit(self.rotation).unwrap_or([0.0, 0.0, 0.0, 1.0]);
        // The z row of the rotation matrix's z column: 1 - 2 (x^2 + y^2).
        (1.0 - 2.0 * (x * x + y * y)).clamp(-1.0, 1.0).acos()
    }
}

/// A decoded `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, PartialEq)]
pub struct TfMessage {
    pub transforms: Vec<Transform>,
}

impl TfMessage {
    pub fn decode(data: &[u8]) -> Result<Self, CdrError> {
        let mut cdr = Cdr::new(data)?;
        // Each transform has at least a header (12 bytes), a frame and 7 f64.
        let count = cdr.count("transforms", 12 + 4 + 56)?;
        let mut transforms = Vec::with_capacity(count);
        for _ in 0..count {
            let header = header(&mut cdr)?;
            let child_frame_id = cdr.string("child_frame_id")?;
            let translation = cdr.f64_array::<3>("transform.translation")?;
            let rotation = cdr.f64_array::<4>("transform.rotation")?;
            if !translation.iter().all(|v| v.is_finite()) {
                return Err(CdrError::Invalid {
                    what: "transform.translation",
                    reason: "not finite".into(),
                });
            }
            transforms.push(Transform {
                header,
                child_frame_id,
                translation,
                rotation,
            });
        }
        Ok(Self { transforms })
    }
}

/// The quaternion (x, y, z, w) normalised; `None` when it has no length.
fn unit(q: [f64; 4]) -> Option<[f64; 4]> {
    let norm = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    (norm.is_finite() && norm > 1e-9).then(|| q.map(|v| v / norm))
}

/// The yaw (rotation about z) of a quaternion (x, y, z, w), wrapped to [-pi, pi).
pub fn yaw_of(q: [f64; 4], what: &'static str) -> Result<f64, CdrError> {
    let [x, y, z, w] = unit(q).ok_or_else(|| CdrError::Invalid {
        what,
        reason: format!("{q:?} is no rotation"),
    })?;
    let yaw = f64::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
    Ok(slam_geom::wrap_angle(yaw))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::super::cdr::write::CdrWriter;
    use super::*;

    /// A LaserScan's CDR: `ranges` and `intensities` as given.
    pub(crate) fn laser_scan(
        little_endian: bool,
        stamp: (i32, u32),
        frame: &str,
        ranges: &[f32],
        intensities: &[f32],
    ) -> Vec<u8> {
        let mut w = CdrWriter::new(little_endian);
        w.header(stamp.0, stamp.1, frame);
        let increment = std::f32::consts::PI / 180.0;
        let angle_min = -std::f32::consts::FRAC_PI_2;
        for value in [
            angle_min,
            angle_min + increment * (ranges.len() as f32 - 1.0),
            increment,
            0.0,
            0.025,
            0.1,
            30.0,
        ] {
            w.f32(value);
        }
        w.u32(ranges.len() as u32);
        for &r in ranges {
            w.f32(r);
        }
        w.u32(intensities.len() as u32);
        for &i in intensities {
            w.f32(i);
        }
        w.bytes
    }

    /// An Odometry's CDR of `child` in `parent` at (x, y, yaw), its pose covariance's
    /// diagonal `variance`, forward speed `v` and turn rate `w`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn odometry(
        little_endian: bool,
        stamp: (i32, u32),
        parent: &str,
        child: &str,
        pose: (f64, f64, f64),
        variance: f64,
        v: f64,
        w_rate: f64,
    ) -> Vec<u8> {
        let mut w = CdrWriter::new(little_endian);
        w.header(stamp.0, stamp.1, parent).string(child);
        let (x, y, yaw) = pose;
        for value in [x, y, 0.0, 0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()] {
            w.f64(value);
        }
        for i in 0..36 {
            w.f64(if i % 7 == 0 { variance } else { 0.0 });
        }
        for value in [v, 0.0, 0.0, 0.0, 0.0, w_rate] {
            w.f64(value);
        }
        for _ in 0..36 {
            w.f64(0.0);
        }
        w.bytes
    }

    /// One transform for [`tf_message`]: (stamp, parent, child, x, y, yaw).
    pub(crate) type PlanarTransform<'a> = ((i32, u32), &'a str, &'a str, f64, f64, f64);

    /// A TFMessage's CDR.
    pub(crate) fn tf_message(transforms: &[PlanarTransform<'_>]) -> Vec<u8> {
        let mut w = CdrWriter::new(true);
        w.u32(transforms.len() as u32);
        for &(stamp, parent, child, x, y, yaw) in transforms {
            w.header(stamp.0, stamp.1, parent).string(child);
            for value in [x, y, 0.0, 0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()] {
                w.f64(value);
            }
        }
        w.bytes
    }

    #[test]
    fn a_laser_scan_decodes_in_either_byte_order() {
        for little_endian in [true, false] {
            let bytes = laser_scan(
                little_endian,
                (1_134_864_629, 895_182_000),
                "laser",
                &[1.0, 2.5, 3.0],
                &[10.0, 20.0, 30.0],
            );
            let scan = LaserScan::decode(&bytes).unwrap();
            assert_eq!(scan.header.stamp_ns, 1_134_864_629_895_182_000);
            assert_eq!(scan.header.frame_id, "laser");
            assert_eq!(
                scan.geometry.angle_min,
                f64::from(-std::f32::consts::FRAC_PI_2)
            );
            assert_eq!(
                scan.geometry.angle_increment,
                f64::from(std::f32::consts::PI / 180.0)
            );
            assert_eq!(scan.geometry.scan_time, f64::from(0.025_f32));
            assert_eq!(scan.geometry.range_min, f64::from(0.1_f32));
            assert_eq!(scan.geometry.range_max, 30.0);
            assert_eq!(scan.ranges, [1.0, 2.5, 3.0]);
            assert_eq!(scan.intensities, [10.0, 20.0, 30.0]);
        }
    }

    #[test]
    fn ranges_follow_rep_117() {
        // range_min 0.1, range_max 30.
        let bytes = laser_scan(
            true,
            (1, 0),
            "laser",
            &[
                f32::NAN,
                f32::INFINITY,
                f32::NEG_INFINITY,
                0.05,
                31.0,
                30.0,
                0.1,
                5.0,
            ],
            &[1.0],
        );
        let scan = LaserScan::decode(&bytes).unwrap();
        assert!(scan.ranges[0].is_nan(), "an error stays an error");
        assert_eq!(scan.ranges[1..3], [f32::INFINITY, f32::NEG_INFINITY]);
        assert!(scan.ranges[3].is_nan(), "below range_min: nothing measured");
        assert_eq!(scan.ranges[4..], [f32::INFINITY, 30.0, 0.1, 5.0]);
        // Intensities that are not one per beam are none.
        assert!(scan.intensities.is_empty());
    }

    #[test]
    fn a_damaged_scan_is_an_error() {
        let bytes = laser_scan(true, (1, 0), "laser", &[1.0; 10], &[]);
        for cut in [0, 3, 10, 30, bytes.len() - 5] {
            assert!(LaserScan::decode(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let no_beams = laser_scan(true, (1, 0), "laser", &[], &[]);
        assert!(LaserScan::decode(&no_beams).is_err());
        let before_epoch = laser_scan(true, (-1, 0), "laser", &[1.0], &[]);
        assert!(LaserScan::decode(&before_epoch).is_err());
        // An Odometry is no LaserScan: its bytes do not read as one.
        let odometry = odometry(
            true,
            (1, 0),
            "odom",
            "base_link",
            (0.0, 0.0, 0.0),
            0.0,
            0.0,
            0.0,
        );
        assert!(LaserScan::decode(&odometry).is_err());
    }

    #[test]
    fn odometry_gives_the_planar_pose_covariance_and_rates() {
        for little_endian in [true, false] {
            let bytes = odometry(
                little_endian,
                (5, 500),
                "odom",
                "base_link",
                (1.0, -2.0, 0.5),
                0.01,
                0.3,
                -0.1,
            );
            let odometry = Odometry::decode(&bytes).unwrap();
            assert_eq!(odometry.header.stamp_ns, 5_000_000_500);
            assert_eq!(odometry.header.frame_id, "odom");
            assert_eq!(odometry.child_frame_id, "base_link");
            assert_eq!((odometry.pose.x, odometry.pose.y), (1.0, -2.0));
            assert!((odometry.pose.yaw - 0.5).abs() < 1e-12);
            assert_eq!(
                odometry.covariance,
                [0.01, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 0.01]
            );
            assert_eq!(odometry.linear_velocity, 0.3);
            assert_eq!(odometry.angular_velocity, -0.1);
        }
        // Unknown covariance (-1) is none.
        let unknown = odometry(
            true,
            (5, 0),
            "odom",
            "base_link",
            (0.0, 0.0, 0.0),
            -1.0,
            0.0,
            0.0,
        );
        assert_eq!(Odometry::decode(&unknown).unwrap().covariance, [0.0; 9]);
    }

    #[test]
    fn tf_messages_give_each_transform() {
        let bytes = tf_message(&[
            ((3, 0), "odom", "base_link", 1.0, 2.0, -3.0),
            ((3, 5), "base_link", "laser", 0.25, 0.0, 0.0),
        ]);
        let tf = TfMessage::decode(&bytes).unwrap();
        assert_eq!(tf.transforms.len(), 2);
        let first = tf.transforms[0].planar().unwrap();
        assert_eq!((first.x, first.y), (1.0, 2.0));
        assert!((first.yaw + 3.0).abs() < 1e-12);
        assert_eq!(tf.transforms[1].header.stamp_ns, 3_000_000_005);
        assert_eq!(tf.transforms[1].child_frame_id, "laser");
        assert!(tf.transforms[1].tilt() < 1e-12);
        assert!(TfMessage::decode(&bytes[..bytes.len() - 1]).is_err());
    }

    #[test]
    fn an_upside_down_mount_leans_half_a_turn() {
        let flipped = Transform {
            header: Header {
                stamp_ns: 0,
                frame_id: "base_link".into(),
            },
            child_frame_id: "laser".into(),
            translation: [0.0; 3],
            rotation: [1.0, 0.0, 0.0, 0.0],
        };
        assert!((flipped.tilt() - std::f64::consts::PI).abs() < 1e-9);
    }
}
