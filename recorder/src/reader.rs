//! Reading a recording back, streaming: the scans and the odometry, in file order, rebuilt
//! exactly as they were published; every other topic is passed over.
//!
//! The file is read a chunk at a time (memory grows with the largest chunk, not the file),
//! and each chunk's CRC is checked before any of its messages is given out, so a damaged
//! chunk yields nothing rather than wrong data. A file cut short (a recorder killed
//! mid-run) reads up to its last complete chunk and then says where it ends.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use mcap::McapError;
use mcap::sans_io::LinearReaderOptions;

use crate::decode::{DecodeError, Recorded, ReplayedChannel};

/// A record (a chunk, a schema, ...) longer than this is taken for damage: a chunk is
/// about a megabyte ([`crate::CHUNK_BYTES`]) plus at most one large message (a long run's
/// final path), so nothing real comes near it, and a damaged length field must not make
/// the reader ask for that much memory.
pub const RECORD_LENGTH_LIMIT: usize = 256 << 20;

/// The first scan must come within this many messages; a foreign file is refused then
/// rather than read to its end.
pub const SNIFF_MESSAGES: u64 = 10_000;

/// After the first scan, how many more messages are looked at for an odometry channel.
/// slam-record writes the odometry a source publishes before or with its first scan.
pub const ODOMETRY_LOOKAHEAD: u64 = 64;

/// Why a recording cannot be replayed at all.
///
/// The underlying error is named `cause`, not `source`, and is part of the message: the
/// message is complete on its own, and `{:#}` does not repeat it.
#[derive(Debug, thiserror::Error)]
pub enum OpenRecordingError {
    #[error("cannot open {path}: {cause}")]
    Io {
        path: PathBuf,
        cause: std::io::Error,
    },
    /// Not a regular file, or too large.
    #[error(transparent)]
    Input(#[from] stage_kit::InputError),
    #[error("{path} is not an MCAP file: {cause}")]
    NotMcap { path: PathBuf, cause: McapError },
    #[error("{path} is damaged before its first scan (after {messages} messages): {cause}")]
    Damaged {
        path: PathBuf,
        messages: u64,
        cause: McapError,
    },
    #[error("{path} is not a recording of slam-record: {reason}")]
    NotARecording { path: PathBuf, reason: String },
}

/// What reading the next replayed message can go wrong with (the underlying error is in
/// the message, as for [`OpenRecordingError`]).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file cannot be read on (cut short, or a damaged chunk): everything before it was
    /// given out, nothing after it will be.
    #[error("the recording cannot be read past its message {messages}: {cause}")]
    Cut { messages: u64, cause: McapError },
    /// One message could not be rebuilt: skip it, read on.
    #[error("message {index} on '{topic}': {cause}")]
    Message {
        index: u64,
        topic: &'static str,
        cause: DecodeError,
    },
    /// A message of a replayed topic on a channel of another schema or encoding: skip it.
    #[error("message {index}: {reason}")]
    Channel { index: u64, reason: String },
}

/// What the check of a recording found out before the replay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordingInfo {
    /// The recording has odometry (seen with its first scan).
    pub has_odometry: bool,
    /// The first scan's stamp.
    pub first_scan_ns: u64,
}

/// The scans and odometry of a recording, in file order.
pub struct RecordingReader<R: Read> {
    messages: mcap::io::MessageReader<R>,
    /// Messages read so far, of every topic.
    read: u64,
    /// Messages of topics a replay does not publish, by topic.
    passed_over: BTreeMap<String, u64>,
}

impl<R: Read> std::fmt::Debug for RecordingReader<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RecordingReader")
            .field("read", &self.read)
            .finish()
    }
}

impl<R: Read> RecordingReader<R> {
    /// Reads the MCAP data of `source` from its start.
    pub fn new(source: R) -> Self {
        let options = LinearReaderOptions::default()
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(RECORD_LENGTH_LIMIT);
        Self {
            messages: mcap::io::MessageReader::new_with_options(source, options),
            read: 0,
            passed_over: BTreeMap::new(),
        }
    }

    /// Messages read so far, of every topic.
    pub fn messages_read(&self) -> u64 {
        self.read
    }

    /// Messages of topics a replay does not publish, by topic.
    pub fn passed_over(&self) -> &BTreeMap<String, u64> {
        &self.passed_over
    }
}

impl<R: Read> Iterator for RecordingReader<R> {
    type Item = Result<Recorded, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let message = match self.messages.next()? {
                Ok(message) => message,
                // The reader gives nothing more after an error.
                Err(cause) => {
                    return Some(Err(ReadError::Cut {
                        messages: self.read,
                        cause,
                    }));
                }
            };
            self.read += 1;
            let index = self.read;
            let channel = &message.channel;
            let Some(replayed) = ReplayedChannel::of_topic(&channel.topic) else {
                *self.passed_over.entry(channel.topic.clone()).or_default() += 1;
                continue;
            };
            let schema = channel.schema.as_ref().map(|s| s.name.as_str());
            if let Some(reason) = replayed.mismatch(schema, &channel.message_encoding) {
                return Some(Err(ReadError::Channel { index, reason }));
            }
            return Some(
                replayed
                    .decode(&message.data)
                    .map_err(|cause| ReadError::Message {
                        index,
                        topic: replayed.topic(),
                        cause,
                    }),
            );
        }
    }
}

/// A recording: read as a stream; the limit keeps out what no run recorded.
pub const RECORDING_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "recording",
    limit_name: "recorder::RECORDING_INPUT",
    max_bytes: 64 << 30,
};

/// Opens `path` for replay after checking that it is a recording of slam-record with at
/// least one scan that can be rebuilt (among its first [`SNIFF_MESSAGES`] messages).
pub fn open_recording(
    path: &Path,
) -> Result<(RecordingReader<BufReader<File>>, RecordingInfo), OpenRecordingError> {
    let open = || -> Result<_, OpenRecordingError> {
        let file = RECORDING_INPUT.open(path, stage_kit::input::Links::Follow)?;
        Ok(RecordingReader::new(BufReader::new(file)))
    };
    let info = check_recording(open()?).map_err(|problem| match problem {
        Problem::NotMcap(cause) => OpenRecordingError::NotMcap {
            path: path.to_path_buf(),
            cause,
        },
        Problem::Damaged { messages, cause } => OpenRecordingError::Damaged {
            path: path.to_path_buf(),
            messages,
            cause,
        },
        Problem::Foreign(reason) => OpenRecordingError::NotARecording {
            path: path.to_path_buf(),
            reason,
        },
    })?;
    // Read again from the top, so the messages looked at are replayed too.
    Ok((open()?, info))
}

/// Why [`check_recording`] refused some data.
#[derive(Debug)]
enum Problem {
    NotMcap(McapError),
    Damaged { messages: u64, cause: McapError },
    Foreign(String),
}

/// Reads until the first scan that can be rebuilt (and a little beyond, for the odometry).
fn check_recording<R: Read>(mut reader: RecordingReader<R>) -> Result<RecordingInfo, Problem> {
    let mut has_odometry = false;
    let mut first_scan_ns = None;
    // Messages read when the first scan came.
    let mut first_scan_at = None;
    let mut first_problem: Option<String> = None;
    while let Some(next) = reader.next() {
        match next {
            Ok(Recorded::Scan(scan)) => {
                if first_scan_ns.is_none() {
                    first_scan_ns = Some(scan.header.stamp_ns);
                    first_scan_at = Some(reader.messages_read());
                }
            }
            Ok(Recorded::Odometry(_)) => has_odometry = true,
            Err(ReadError::Cut { messages, cause }) => {
                if first_scan_ns.is_some() {
                    // Cut later on: the replay reads up to there and reports it.
                    break;
                }
                return Err(match cause {
                    McapError::BadMagic => Problem::NotMcap(cause),
                    cause => Problem::Damaged { messages, cause },
                });
            }
            Err(e @ (ReadError::Message { .. } | ReadError::Channel { .. })) => {
                first_problem.get_or_insert(e.to_string());
            }
        }
        let read = reader.messages_read();
        let done = match first_scan_at {
            Some(at) => has_odometry || read >= at + ODOMETRY_LOOKAHEAD,
            None => read >= SNIFF_MESSAGES,
        };
        if done {
            break;
        }
    }
    let Some(first_scan_ns) = first_scan_ns else {
        let read = reader.messages_read();
        let mut reason = if read >= SNIFF_MESSAGES {
            format!("no scan it can replay in its first {SNIFF_MESSAGES} messages")
        } else {
            format!("no scan it can replay in its {read} messages")
        };
        if let Some(problem) = first_problem {
            reason.push_str(&format!(" (first problem: {problem})"));
        }
        let topics: Vec<String> = reader
            .passed_over()
            .iter()
            .map(|(topic, count)| format!("{topic} x{count}"))
            .collect();
        if !topics.is_empty() {
            reason.push_str(&format!("; topics in it: {}", topics.join(", ")));
        }
        return Err(Problem::Foreign(reason));
    };
    Ok(RecordingInfo {
        has_odometry,
        first_scan_ns,
    })
}
