//! The MCAP storage of rosbag2 (`.mcap`), read as a stream, a chunk at a time, each
//! chunk's CRC checked before any of its messages is used (as a run.mcap is read).

use std::collections::HashMap;
use std::io::{Read, Seek, SeekFrom};
use std::sync::Arc;

use mcap::sans_io::LinearReaderOptions;
use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};

use super::storage::{Channel, Damaged, MessageSource, RawMessage};

/// A record (a chunk, a schema, ...) longer than this is taken for damage: rosbag2 writes
/// chunks of a few megabytes, and a damaged length must not ask for that much memory.
pub const RECORD_LENGTH_LIMIT: usize = 1 << 30;

/// The messages of an MCAP file in file order.
pub struct McapSource<R: Read> {
    messages: mcap::io::MessageReader<R>,
    channels: HashMap<u16, Arc<Channel>>,
    ended: bool,
}

impl<R: Read> McapSource<R> {
    pub fn new(source: R) -> Self {
        let options = LinearReaderOptions::default()
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(RECORD_LENGTH_LIMIT);
        Self {
            messages: mcap::io::MessageReader::new_with_options(source, options),
            channels: HashMap::new(),
            ended: false,
        }
    }
}

/// A channel as the bag reader sees it: its topic, its schema's name (the ROS type) and its
/// message encoding.
fn channel_of(channel: &mcap::Channel<'_>) -> Channel {
    Channel {
        topic: channel.topic.clone(),
        type_name: channel
            .schema
            .as_ref()
            .map(|schema| schema.name.clone())
            .unwrap_or_default(),
        encoding: channel.message_encoding.clone(),
    }
}

impl<R: Read> MessageSource for McapSource<R> {
    fn next_message(&mut self) -> Option<Result<RawMessage, Damaged>> {
        if self.ended {
            return None;
        }
        match self.messages.next()? {
            Ok(message) => {
                let channel = self
                    .channels
                    .entry(message.channel.id)
                    .or_insert_with(|| Arc::new(channel_of(&message.channel)))
                    .clone();
                Some(Ok(RawMessage {
                    channel,
                    log_time_ns: message.log_time,
                    data: message.data.into_owned(),
                }))
            }
            Err(e) => {
                // The reader gives nothing more after an error.
                self.ended = true;
                Some(Err(Damaged(e.to_string())))
            }
        }
    }
}

/// The channels an MCAP file's summary section lists, if it has a readable one (a file
/// cut short has none).
pub fn summary_channels<F: Read + Seek>(mut file: F) -> Option<Vec<Channel>> {
    let size = file.seek(SeekFrom::End(0)).ok()?;
    let options = SummaryReaderOptions::default()
        .with_file_size(size)
        .with_record_length_limit(RECORD_LENGTH_LIMIT);
    let mut reader = SummaryReader::new_with_options(options);
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(need) => {
                let read = file.read(reader.insert(need)).ok()?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let at = file.seek(to).ok()?;
                reader.notify_seeked(at);
            }
        }
    }
    let summary = reader.finish()?;
    let mut channels: Vec<(u16, Channel)> = summary
        .channels
        .values()
        .map(|channel| (channel.id, channel_of(channel)))
        .collect();
    channels.sort_by_key(|(id, _)| *id);
    Some(channels.into_iter().map(|(_, channel)| channel).collect())
}
