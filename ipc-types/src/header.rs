//! The header every message starts with.

use iceoryx2::prelude::ZeroCopySend;
use serde::{Deserialize, Serialize};
use zerocopy::FromZeros;

/// Length of the fixed frame-id buffer, NUL padded.
pub const FRAME_ID_LEN: usize = 32;

/// Bit in [`Header::flags`]: the publisher has no more data; this message carries none.
///
/// It travels on the data service itself, so it arrives after every message sent before it.
pub const FLAG_END_OF_STREAM: u32 = 1;

/// Bit in [`Header::flags`]: a result sent again and again as it improves (a path) is in its
/// last form: sent at the end of the stream, or as the publisher stops.
pub const FLAG_FINAL: u32 = 2;

/// Sequence, time and frame of a message, after ROS `std_msgs/Header`.
///
/// Its serde form names the frame as text, as every message's serde form leaves out the
/// padding (`reserved`): that form is what a recording holds, readable as it is.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, ZeroCopySend, FromZeros, Serialize, Deserialize)]
#[cfg_attr(feature = "json-schema", derive(schemars::JsonSchema))]
#[type_name("slam::Header::v1")]
pub struct Header {
    /// Sequence number of the source scan, counting from 0 without gaps at the source.
    pub seq: u64,
    /// Acquisition time in the sensor's clock domain, nanoseconds.
    pub stamp_ns: u64,
    /// CLOCK_REALTIME when the message was published, nanoseconds; for latency.
    pub sent_ns: u64,
    /// NUL-padded UTF-8 frame name, e.g. `laser`.
    #[serde(with = "frame_id_text")]
    #[cfg_attr(feature = "json-schema", schemars(with = "String"))]
    pub frame_id: [u8; FRAME_ID_LEN],
    /// `FLAG_*` bits.
    pub flags: u32,
    /// Keeps the layout free of implicit padding; always 0.
    #[serde(skip)]
    pub reserved: u32,
}

impl Header {
    /// A header with the given sequence, stamp and frame name (cut to [`FRAME_ID_LEN`] bytes
    /// at a character boundary).
    pub fn new(seq: u64, stamp_ns: u64, frame_id: &str) -> Self {
        let mut header = Self {
            seq,
            stamp_ns,
            sent_ns: 0,
            frame_id: [0; FRAME_ID_LEN],
            flags: 0,
            reserved: 0,
        };
        header.set_frame_id(frame_id);
        header
    }

    /// Sets the frame name, cut to [`FRAME_ID_LEN`] bytes at a character boundary.
    pub fn set_frame_id(&mut self, frame_id: &str) {
        self.frame_id = frame_id_text::to_bytes(frame_id);
    }

    /// The frame name, or `""` when it is not valid UTF-8.
    pub fn frame_id(&self) -> &str {
        frame_id_text::of_bytes(&self.frame_id)
    }

    /// True when this message only marks the end of the stream.
    pub fn is_end_of_stream(&self) -> bool {
        self.flags & FLAG_END_OF_STREAM != 0
    }

    /// True when the message belongs to a result's last form ([`FLAG_FINAL`]).
    pub fn is_final(&self) -> bool {
        self.flags & FLAG_FINAL != 0
    }
}

/// The frame name's buffer and its text, both ways; serde writes the text.
mod frame_id_text {
    use serde::{Deserialize, Deserializer, Serializer};

    use super::FRAME_ID_LEN;

    /// `frame_id` cut to [`FRAME_ID_LEN`] bytes at a character boundary, NUL padded.
    pub(super) fn to_bytes(frame_id: &str) -> [u8; FRAME_ID_LEN] {
        let mut end = frame_id.len().min(FRAME_ID_LEN);
        while !frame_id.is_char_boundary(end) {
            end -= 1;
        }
        let mut bytes = [0; FRAME_ID_LEN];
        bytes[..end].copy_from_slice(&frame_id.as_bytes()[..end]);
        bytes
    }

    /// The text before the first NUL, or `""` when it is not valid UTF-8.
    pub(super) fn of_bytes(bytes: &[u8; FRAME_ID_LEN]) -> &str {
        let len = bytes.iter().position(|&b| b == 0).unwrap_or(FRAME_ID_LEN);
        std::str::from_utf8(&bytes[..len]).unwrap_or("")
    }

    pub(super) fn serialize<S: Serializer>(
        bytes: &[u8; FRAME_ID_LEN],
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(of_bytes(bytes))
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<[u8; FRAME_ID_LEN], D::Error> {
        Ok(to_bytes(&String::deserialize(deserializer)?))
    }
}

/// CLOCK_REALTIME now, in nanoseconds since the Unix epoch (0 if the clock is before it).
pub fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX))
        .unwrap_or(0)
}
