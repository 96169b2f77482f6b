//! Our message header, as every message of our own schemas carries it.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `ipc_types::Header` with its frame as a string and its end-of-stream flag as it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct HeaderJson {
    /// Sequence number of the source scan.
    pub seq: u64,
    /// Acquisition time in the sensor's clock, nanoseconds.
    pub stamp_ns: u64,
    /// CLOCK_REALTIME when the message was published, nanoseconds.
    pub sent_ns: u64,
    pub frame_id: String,
    pub flags: u32,
}

impl From<&ipc_types::Header> for HeaderJson {
    fn from(h: &ipc_types::Header) -> Self {
        Self {
            seq: h.seq,
            stamp_ns: h.stamp_ns,
            sent_ns: h.sent_ns,
            frame_id: h.frame_id().to_owned(),
            flags: h.flags,
        }
    }
}

impl HeaderJson {
    /// The header this was made from.
    pub fn to_header(&self) -> ipc_types::Header {
        let mut header = ipc_types::Header::new(self.seq, self.stamp_ns, &self.frame_id);
        header.sent_ns = self.sent_ns;
        header.flags = self.flags;
        header
    }
}
