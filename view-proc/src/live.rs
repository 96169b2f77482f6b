//! The recording's channels, live: each converted message logged on a Foxglove SDK channel
//! of the same topic and schema, which the WebSocket server advertises to its clients.

use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::sync::Arc;

use foxglove::{ChannelBuilder, Context, PartialMetadata, RawChannel, Schema};
use recorder::{ChannelMessage, MESSAGE_ENCODING, Output, RecordError, SCHEMA_ENCODING};

use crate::error::ViewError;

/// The live channels, by topic, in one Foxglove context (the server's).
#[derive(Debug)]
pub struct LiveChannels {
    context: Arc<Context>,
    channels: BTreeMap<&'static str, Arc<RawChannel>>,
    buffer: Vec<u8>,
    /// Messages encoded and handed to the server (a client subscribed to their channel).
    sent: u64,
}

impl LiveChannels {
    pub fn new(context: Arc<Context>) -> Self {
        Self {
            context,
            channels: BTreeMap::new(),
            buffer: Vec::with_capacity(64 * 1024),
            sent: 0,
        }
    }

    /// Opens the channel of `M` now, so that a client sees it advertised before its first
    /// message (a grid comes seconds into a run). A channel is otherwise opened with its
    /// first message.
    pub fn declare<M: ChannelMessage>(&mut self) -> Result<&Arc<RawChannel>, ViewError> {
        Ok(match self.channels.entry(M::TOPIC) {
            Entry::Occupied(entry) => entry.into_mut(),
            Entry::Vacant(entry) => entry.insert(open_channel::<M>(&self.context)?),
        })
    }

    /// Messages handed to the server so far.
    pub fn sent(&self) -> u64 {
        self.sent
    }
}

impl Output for LiveChannels {
    /// Encodes and logs `message` only when a client subscribes to its channel: a view
    /// that nobody watches costs the machine next to nothing.
    fn write<M: ChannelMessage>(
        &mut self,
        message: &M,
        log_time_ns: u64,
        _publish_time_ns: u64,
    ) -> Result<(), RecordError> {
        let channel = self.declare::<M>().map_err(|e| RecordError::Output {
            topic: M::TOPIC,
            cause: Box::new(e),
        })?;
        if !channel.has_sinks() {
            return Ok(());
        }
        let channel = Arc::clone(channel);
        self.buffer.clear();
        serde_json::to_writer(&mut self.buffer, message).map_err(|source| RecordError::Encode {
            topic: M::TOPIC,
            source,
        })?;
        channel.log_with_meta(
            &self.buffer,
            PartialMetadata {
                log_time: Some(log_time_ns),
            },
        );
        self.sent += 1;
        Ok(())
    }
}

/// The channel of `M` in `context`: its topic, JSON under its JSON schema, as in run.mcap.
fn open_channel<M: ChannelMessage>(context: &Arc<Context>) -> Result<Arc<RawChannel>, ViewError> {
    let schema = Schema::new(
        M::SCHEMA,
        SCHEMA_ENCODING,
        M::schema().to_string().into_bytes(),
    );
    ChannelBuilder::new(M::TOPIC)
        .message_encoding(MESSAGE_ENCODING)
        .schema(schema)
        .context(context)
        .build_raw()
        .map_err(|cause| ViewError::Channel {
            topic: M::TOPIC,
            cause,
        })
}
