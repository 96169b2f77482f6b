//! Where a run's messages go once converted: the MCAP file (`slam-record`), or a live view
//! (`slam-view`, crate `view-proc`). The conversion ([`crate::Recording`]) is one; only the
//! output differs.

use crate::error::RecordError;
use crate::mcap_file::McapFile;
use crate::schema::ChannelMessage;

/// Takes each converted message on its channel (`M::TOPIC`, under `M::SCHEMA`).
pub trait Output {
    /// `message` at `log_time_ns` (the data's own stamp, so a viewer's timeline is the
    /// sensor's), sent at `publish_time_ns`.
    fn write<M: ChannelMessage>(
        &mut self,
        message: &M,
        log_time_ns: u64,
        publish_time_ns: u64,
    ) -> Result<(), RecordError>;
}

impl Output for McapFile {
    fn write<M: ChannelMessage>(
        &mut self,
        message: &M,
        log_time_ns: u64,
        publish_time_ns: u64,
    ) -> Result<(), RecordError> {
        McapFile::write(self, message, log_time_ns, publish_time_ns)
    }
}
