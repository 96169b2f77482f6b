//! Why a line was skipped and why a log was refused.

use std::path::PathBuf;

use crate::format::LogFormat;

/// What is wrong with a malformed line, coarsely: the replay's summary counts lines by it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Malformation {
    /// Bytes that are not UTF-8 text.
    NotText,
    /// A line longer than [`crate::MAX_LINE_BYTES`] (no newline in sight).
    TooLong,
    /// A line that is no record of the format at all.
    NotARecord,
    /// The line ends before all its fields.
    MissingFields,
    /// Fields after the last one the record has.
    ExtraFields,
    /// A field that should be a number (or a count) is not.
    NotANumber,
    /// The timestamp is not plain decimal seconds.
    BadStamp,
    /// A beam count the laser cannot have (no scanning mode, or more than a message holds).
    BeamCount,
    /// Angles or range limits that describe no scan.
    BadGeometry,
    /// A message of a recording that cannot be rebuilt.
    Undecodable,
    /// A message of a bag's replayed topic of another type or encoding than the topic's.
    WrongType,
    /// A bag's odometry of another frame than the robot's.
    OtherFrame,
}

impl std::fmt::Display for Malformation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::NotText => "not UTF-8 text",
            Self::TooLong => "line too long",
            Self::NotARecord => "not a record of the format",
            Self::MissingFields => "fields missing",
            Self::ExtraFields => "extra fields",
            Self::NotANumber => "a field is not a number",
            Self::BadStamp => "bad timestamp",
            Self::BeamCount => "impossible beam count",
            Self::BadGeometry => "impossible scan geometry",
            Self::Undecodable => "message cannot be decoded",
            Self::WrongType => "message of another type",
            Self::OtherFrame => "odometry of another frame",
        })
    }
}

/// A line of a log that could not be used; the reader skips it and goes on.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {reason}")]
pub struct LineError {
    /// 1-based line number.
    pub line: u64,
    /// What kind of problem it is, for counting.
    pub kind: Malformation,
    /// The record type the line claims to be (`FLASER`), when it names a known one.
    pub record: Option<String>,
    pub reason: String,
}

impl LineError {
    pub(crate) fn new(line: u64, kind: Malformation, reason: impl Into<String>) -> Self {
        Self {
            line,
            kind,
            record: None,
            reason: reason.into(),
        }
    }

    /// A message of a recording that could not be rebuilt; its `line` is its place among
    /// the recording's messages.
    pub fn undecodable(error: &recorder::ReadError) -> Self {
        let (index, topic) = match error {
            recorder::ReadError::Message { index, topic, .. } => (*index, Some(*topic)),
            recorder::ReadError::Channel { index, .. } => (*index, None),
            recorder::ReadError::Cut { messages, .. } => (*messages, None),
        };
        let line = Self::new(index, Malformation::Undecodable, error.to_string());
        match topic {
            Some(topic) => line.in_record(topic),
            None => line,
        }
    }

    pub(crate) fn in_record(mut self, record: &str) -> Self {
        self.record = Some(record.to_owned());
        self
    }

    /// A short name of the problem without the line's particulars, e.g. `FLASER: fields
    /// missing`, so that lines can be counted by it.
    pub fn category(&self) -> String {
        match &self.record {
            Some(record) => format!("{record}: {}", self.kind),
            None => self.kind.to_string(),
        }
    }
}

/// What reading the next record of a log can go wrong with.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// A malformed line: report it, skip it, read on.
    #[error(transparent)]
    Line(#[from] LineError),
    /// The file itself cannot be read any more: stop.
    #[error("cannot read the log: {0}")]
    Io(#[from] std::io::Error),
    /// The stop flag was raised (Ctrl-C): nothing more is read.
    #[error("reading stopped: a stop was requested")]
    Stopped,
    /// [`crate::LogFormat::Mcap`] asked of the text readers.
    #[error("an MCAP recording is not a text log: it is read with open_recording")]
    NotText,
    /// A bag that cannot be read on (cut short, a damaged chunk or page): everything before
    /// it was given out, nothing after it will be.
    #[error("the bag cannot be read past its message {messages}: {cause}")]
    Cut { messages: u64, cause: String },
}

/// Why a log cannot be replayed at all.
#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    #[error("cannot open {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Not a regular file, or too large.
    #[error(transparent)]
    Input(#[from] stage_kit::InputError),
    /// The file is not a log of the given format, or has no scan where one must be.
    #[error("{path} is not a {format} log: {reason}")]
    NotThisFormat {
        path: PathBuf,
        format: LogFormat,
        reason: String,
    },
    /// The stop flag was raised while the file was being checked.
    #[error("stopped while checking {path}")]
    Stopped { path: PathBuf },
}

/// Why [`crate::check_format`] refused some data.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    #[error("cannot read the log: {0}")]
    Io(#[from] std::io::Error),
    /// Not a log of the format; the text says why.
    #[error("{0}")]
    Mismatch(String),
    /// The stop flag was raised before the check was done.
    #[error("stopped while checking the log")]
    Stopped,
}
