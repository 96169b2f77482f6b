//! A bag's messages as its storage gives them, whatever the storage: each with its topic,
//! its type and its time of recording, in the order the storage keeps them.

use std::sync::Arc;

/// A topic as a storage declares it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channel {
    pub topic: String,
    /// `sensor_msgs/msg/LaserScan`, ... (empty when the storage names none).
    pub type_name: String,
    /// `cdr` for ROS 2 messages.
    pub encoding: String,
}

/// One stored message, its payload still serialized.
#[derive(Debug, Clone)]
pub struct RawMessage {
    pub channel: Arc<Channel>,
    /// When the recorder received it (ns): the storage's order, not the header's stamp.
    pub log_time_ns: u64,
    pub data: Vec<u8>,
}

/// A storage that cannot be read on: everything before was given out, nothing after will be.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Damaged(pub String);

/// The messages of one storage file.
pub trait MessageSource {
    /// The next message, `Err` once when the file cannot be read on, `None` at its end.
    fn next_message(&mut self) -> Option<Result<RawMessage, Damaged>>;
}
