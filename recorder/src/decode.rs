//! A recorded message back into the pipeline's message: the inverse of the encoders, for
//! the topics a replay publishes again (the scans and the odometry).

use crate::scan::ScanMessage;
use crate::schema::{ChannelMessage, MESSAGE_ENCODING};

/// Why a recorded message could not be rebuilt.
#[derive(Debug, thiserror::Error)]
pub enum DecodeError {
    #[error("not the JSON slam-record writes: {0}")]
    Json(#[from] serde_json::Error),
    #[error(
        "stamp {sec} s {nsec} ns is no stamp (nsec must be below 1e9, the whole within 64 bits)"
    )]
    Stamp { sec: u64, nsec: u32 },
    #[error("a non-finite range at beam {index}, but the scan has {beams} beams")]
    BeamIndex { index: u32, beams: usize },
    #[error(transparent)]
    Capacity(#[from] ipc_types::CapacityError),
}

/// A message of a recording that a replay publishes.
#[derive(Debug, Clone, PartialEq)]
pub enum Recorded {
    Scan(Box<ipc_types::LaserScan>),
    Odometry(Box<ipc_types::Odometry>),
}

impl Recorded {
    /// The data's stamp (the message's log time in the recording).
    pub fn stamp_ns(&self) -> u64 {
        match self {
            Self::Scan(scan) => scan.header.stamp_ns,
            Self::Odometry(odometry) => odometry.header.stamp_ns,
        }
    }
}

/// The recorded channels a replay publishes again, as slam-record writes them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReplayedChannel {
    Scan,
    Odometry,
}

impl ReplayedChannel {
    pub const ALL: [Self; 2] = [Self::Scan, Self::Odometry];

    pub fn topic(self) -> &'static str {
        match self {
            Self::Scan => ScanMessage::TOPIC,
            Self::Odometry => ipc_types::Odometry::TOPIC,
        }
    }

    pub fn schema(self) -> &'static str {
        match self {
            Self::Scan => ScanMessage::SCHEMA,
            Self::Odometry => ipc_types::Odometry::SCHEMA,
        }
    }

    /// The channel of `topic`, if a replay publishes it.
    pub fn of_topic(topic: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.topic() == topic)
    }

    /// `None` when a channel of this topic has the schema and encoding slam-record gives
    /// it, else what it has instead.
    pub fn mismatch(self, schema: Option<&str>, message_encoding: &str) -> Option<String> {
        let schema = schema.unwrap_or("no schema");
        (schema != self.schema() || message_encoding != MESSAGE_ENCODING).then(|| {
            format!(
                "'{}' carries {schema} in {message_encoding}, not {} in {MESSAGE_ENCODING}",
                self.topic(),
                self.schema()
            )
        })
    }

    /// Rebuilds a message of this channel from its recorded bytes.
    pub fn decode(self, data: &[u8]) -> Result<Recorded, DecodeError> {
        Ok(match self {
            Self::Scan => {
                Recorded::Scan(serde_json::from_slice::<ScanMessage>(data)?.to_laser_scan()?)
            }
            Self::Odometry => Recorded::Odometry(Box::new(serde_json::from_slice::<
                ipc_types::Odometry,
            >(data)?)),
        })
    }
}
