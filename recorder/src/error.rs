//! Why a recording failed.

/// An error of the recording: the file could not be created or written, or another output
/// (a live view) could not take a message.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error("cannot create {path}: {source}")]
    Create {
        path: String,
        source: std::io::Error,
    },
    #[error("cannot write the recording {path}: {source}")]
    Mcap {
        path: String,
        source: mcap::McapError,
    },
    #[error("cannot encode a message for {topic}: {source}")]
    Encode {
        topic: &'static str,
        source: serde_json::Error,
    },
    /// The output's own error is named `cause` and is part of the message, which `{:#}`
    /// then does not repeat.
    #[error("cannot send a message on {topic}: {cause}")]
    Output {
        topic: &'static str,
        cause: Box<dyn std::error::Error + Send + Sync>,
    },
}
