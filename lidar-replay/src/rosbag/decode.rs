//! What each message is to the replay: a scan, odometry (an Odometry message or the odom
//! transforms of a `/tf` message) or a message of a topic it does not publish; a message
//! it would use but cannot is a [`LineError`] naming its topic.

use slam_geom::Pose2;

use super::cdr::CdrError;
use super::info::BagInfo;
use super::messages::{LASER_SCAN, LaserScan, ODOMETRY, Odometry, TF_MESSAGE, TfMessage};
use super::options::BagOptions;
use super::storage::{Channel, RawMessage};
use super::topics::{OdometryStream, TF_TOPIC};
use crate::error::{LineError, Malformation};
use crate::record::OdometryRecord;

/// How messages of each topic are used.
#[derive(Debug, Clone)]
pub(super) struct Plan {
    pub(super) scan_topic: String,
    pub(super) odometry: Option<OdometryStream>,
    pub(super) base_frame: String,
    pub(super) odom_frame: String,
    pub(super) mount: Pose2,
}

/// What one message is to the replay.
pub(super) enum Decoded {
    Scan(LaserScan),
    Odometry(OdometryRecord),
    /// Odometry transforms of a `/tf` message (none when it has none of the base frame).
    Tf(Vec<OdometryRecord>),
    /// A message of a topic the replay does not publish.
    PassedOver,
}

/// The message being decoded, to name it in what goes wrong.
struct At<'a> {
    index: u64,
    topic: &'a str,
    expected: &'static str,
}

impl At<'_> {
    fn error(&self, kind: Malformation, reason: String) -> LineError {
        LineError::new(self.index, kind, reason).in_record(self.topic)
    }

    fn undecodable(&self, e: CdrError) -> LineError {
        let At {
            index,
            topic,
            expected,
        } = self;
        self.error(
            Malformation::Undecodable,
            format!("message {index} on {topic} is no {expected}: {e}"),
        )
    }

    /// `Err` for a channel of another type than expected (one that names none passes) or
    /// another encoding than CDR.
    fn check(&self, channel: &Channel) -> Result<(), LineError> {
        if (channel.type_name.is_empty() || channel.type_name == self.expected)
            && channel.encoding == "cdr"
        {
            return Ok(());
        }
        let At {
            index,
            topic,
            expected,
        } = self;
        let type_name = if channel.type_name.is_empty() {
            "of no named type"
        } else {
            &channel.type_name
        };
        Err(self.error(
            Malformation::WrongType,
            format!(
                "message {index} on {topic} is {type_name} in '{}', not {expected} in cdr",
                channel.encoding
            ),
        ))
    }
}

impl Plan {
    /// The plan of the replay the survey chose.
    pub(super) fn of(info: &BagInfo) -> Self {
        Self {
            scan_topic: info.scan_topic.clone(),
            odometry: info.odometry.clone(),
            base_frame: info.base_frame.clone(),
            odom_frame: info.odom_frame.clone(),
            mount: info.mount.pose(),
        }
    }

    /// A plan that decodes the scans of `scan_topic` alone, for the survey.
    pub(super) fn scans_only(scan_topic: &str, options: &BagOptions) -> Self {
        Self {
            scan_topic: scan_topic.to_owned(),
            odometry: None,
            base_frame: options.base_frame.clone(),
            odom_frame: options.odom_frame.clone(),
            mount: Pose2::IDENTITY,
        }
    }

    /// Decodes `message`, the `index`-th of the bag. `Err` for a message the replay would
    /// use but cannot: of another type or encoding, or not decodable.
    pub(super) fn decode(&self, index: u64, message: &RawMessage) -> Result<Decoded, LineError> {
        let topic = message.channel.topic.as_str();
        let Some(expected) = self.expected(topic) else {
            return Ok(Decoded::PassedOver);
        };
        let at = At {
            index,
            topic,
            expected,
        };
        at.check(&message.channel)?;
        match expected {
            LASER_SCAN => Ok(Decoded::Scan(scan(message).map_err(|e| at.undecodable(e))?)),
            ODOMETRY => Ok(Decoded::Odometry(self.odometry(&at, message)?)),
            _ => Ok(Decoded::Tf(
                self.tf(index, message).map_err(|e| at.undecodable(e))?,
            )),
        }
    }

    /// The type the replay uses on `topic`; `None` for a topic it passes over.
    fn expected(&self, topic: &str) -> Option<&'static str> {
        if topic == self.scan_topic {
            Some(LASER_SCAN)
        } else if matches!(&self.odometry, Some(OdometryStream::Topic(t)) if t == topic) {
            Some(ODOMETRY)
        } else if topic == TF_TOPIC && self.odometry == Some(OdometryStream::Tf) {
            Some(TF_MESSAGE)
        } else {
            None
        }
    }

    /// An Odometry message of the base frame.
    fn odometry(&self, at: &At, message: &RawMessage) -> Result<OdometryRecord, LineError> {
        let odometry = Odometry::decode(&message.data).map_err(|e| at.undecodable(e))?;
        if odometry.child_frame_id != self.base_frame {
            return Err(at.error(
                Malformation::OtherFrame,
                format!(
                    "message {} on {} is the odometry of {}, not of {} (--base-frame)",
                    at.index, at.topic, odometry.child_frame_id, self.base_frame
                ),
            ));
        }
        Ok(OdometryRecord {
            line: at.index,
            stamp_ns: stamp_or_log_time(odometry.header.stamp_ns, message),
            x: odometry.pose.x,
            y: odometry.pose.y,
            yaw: odometry.pose.yaw,
            linear_velocity: odometry.linear_velocity,
            angular_velocity: odometry.angular_velocity,
            log_covariance: odometry.covariance,
        })
    }

    /// The odom-to-base transforms of a `/tf` message, as odometry without velocities.
    fn tf(&self, index: u64, message: &RawMessage) -> Result<Vec<OdometryRecord>, CdrError> {
        let tf = TfMessage::decode(&message.data)?;
        let mut poses = Vec::new();
        for transform in &tf.transforms {
            if transform.header.frame_id != self.odom_frame
                || transform.child_frame_id != self.base_frame
            {
                continue;
            }
            let pose = transform.planar()?;
            poses.push(OdometryRecord {
                line: index,
                stamp_ns: stamp_or_log_time(transform.header.stamp_ns, message),
                x: pose.x,
                y: pose.y,
                yaw: pose.yaw,
                linear_velocity: 0.0,
                angular_velocity: 0.0,
                log_covariance: [0.0; 9],
            });
        }
        Ok(poses)
    }
}

/// A LaserScan message.
fn scan(message: &RawMessage) -> Result<LaserScan, CdrError> {
    let mut scan = LaserScan::decode(&message.data)?;
    scan.header.stamp_ns = stamp_or_log_time(scan.header.stamp_ns, message);
    Ok(scan)
}

/// A header's stamp, or where a driver never set it (0) the recorder's time, the nearest.
fn stamp_or_log_time(stamp_ns: u64, message: &RawMessage) -> u64 {
    match stamp_ns {
        0 => message.log_time_ns,
        stamp => stamp,
    }
}
