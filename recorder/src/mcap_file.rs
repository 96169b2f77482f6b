//! The MCAP file: channels registered as they first carry a message, zstd-compressed chunks,
//! each on disk as soon as it is complete.

use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions, Writer};

use crate::error::RecordError;
use crate::schema::{ChannelMessage, MESSAGE_ENCODING, SCHEMA_ENCODING};

/// Uncompressed bytes a chunk holds before it is compressed and written: about a hundred
/// 1081-beam scans, 2.5 s of a 40 Hz sensor.
pub const CHUNK_BYTES: u64 = 1 << 20;
/// A chunk is closed and written at least this often, so a live run that dies loses at
/// most this much however slowly data comes.
pub const FLUSH_PERIOD: Duration = Duration::from_secs(1);

/// What a channel carried.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelCount {
    pub topic: &'static str,
    pub schema: &'static str,
    pub messages: u64,
}

/// zstd level of the chunks.
pub const ZSTD_LEVEL: u32 = 1;

/// An MCAP file being written.
pub struct McapFile {
    path: PathBuf,
    writer: Writer<File>,
    /// Channel id and message count by topic.
    channels: BTreeMap<&'static str, (u16, ChannelCount)>,
    buffer: Vec<u8>,
    last_flush: Instant,
}

impl std::fmt::Debug for McapFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("McapFile")
            .field("path", &self.path)
            .finish()
    }
}

impl McapFile {
    /// Creates (or truncates) `path`.
    pub fn create(path: &Path) -> Result<Self, RecordError> {
        // Unbuffered: the writer gathers a whole chunk in memory and hands it over in a few
        // writes, which must reach the file then, not when a buffer of ours fills.
        let file = File::create(path).map_err(|source| RecordError::Create {
            path: path.display().to_string(),
            source,
        })?;
        let writer = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .chunk_size(Some(CHUNK_BYTES))
            // Compress on this thread: the machine's cores belong to the pipeline, and a
            // chunk every hundred scans is cheap.
            .compression_threads(0)
            // zstd's fastest level: the recorder shares the machine with the pipeline, and
            // level 3 (the default) spent 40 % of its time compressing for a few percent
            // of size.
            .compression_level(ZSTD_LEVEL)
            .profile("")
            .library(concat!("slam-record ", env!("CARGO_PKG_VERSION")))
            .create(file)
            .map_err(|source| RecordError::Mcap {
                path: path.display().to_string(),
                source,
            })?;
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            channels: BTreeMap::new(),
            buffer: Vec::with_capacity(64 * 1024),
            last_flush: Instant::now(),
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn mcap_error(&self, source: mcap::McapError) -> RecordError {
        RecordError::Mcap {
            path: self.path.display().to_string(),
            source,
        }
    }

    /// Writes `message` on its channel at `log_time_ns` (the data's own stamp, so a viewer's
    /// timeline is the sensor's) with `publish_time_ns` (when it was sent).
    pub fn write<M: ChannelMessage>(
        &mut self,
        message: &M,
        log_time_ns: u64,
        publish_time_ns: u64,
    ) -> Result<(), RecordError> {
        let (channel_id, sequence) = {
            let (id, count) = self.channel::<M>()?;
            // MCAP numbers messages per channel in 32 bits; a wrap only blurs that hint.
            let sequence = count.messages as u32;
            count.messages += 1;
            (*id, sequence)
        };
        self.buffer.clear();
        serde_json::to_writer(&mut self.buffer, message).map_err(|source| RecordError::Encode {
            topic: M::TOPIC,
            source,
        })?;
        let header = MessageHeader {
            channel_id,
            sequence,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        if let Err(e) = self.writer.write_to_known_channel(&header, &self.buffer) {
            return Err(self.mcap_error(e));
        }
        if self.last_flush.elapsed() >= FLUSH_PERIOD {
            self.flush()?;
        }
        Ok(())
    }

    /// Closes the current chunk and hands it to the file.
    pub fn flush(&mut self) -> Result<(), RecordError> {
        self.last_flush = Instant::now();
        self.writer.flush().map_err(|e| self.mcap_error(e))
    }

    /// The channel of `M` and its count, registered with its schema on first use.
    fn channel<M: ChannelMessage>(&mut self) -> Result<(&u16, &mut ChannelCount), RecordError> {
        let entry = match self.channels.entry(M::TOPIC) {
            Entry::Occupied(entry) => entry.into_mut(),
            Entry::Vacant(entry) => {
                let path = &self.path;
                let error = |source| RecordError::Mcap {
                    path: path.display().to_string(),
                    source,
                };
                let schema = M::schema().to_string();
                let schema_id = self
                    .writer
                    .add_schema(M::SCHEMA, SCHEMA_ENCODING, schema.as_bytes())
                    .map_err(error)?;
                let id = self
                    .writer
                    .add_channel(schema_id, M::TOPIC, MESSAGE_ENCODING, &BTreeMap::new())
                    .map_err(error)?;
                entry.insert((
                    id,
                    ChannelCount {
                        topic: M::TOPIC,
                        schema: M::SCHEMA,
                        messages: 0,
                    },
                ))
            }
        };
        Ok((&entry.0, &mut entry.1))
    }

    /// Writes the summary (indexes, statistics) and closes the file; returns what each
    /// channel carried.
    pub fn finish(mut self) -> Result<Vec<ChannelCount>, RecordError> {
        if let Err(e) = self.writer.finish() {
            return Err(self.mcap_error(e));
        }
        Ok(self.channels.into_values().map(|(_, c)| c).collect())
    }
}
