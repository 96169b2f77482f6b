//! An output of a run that could not be written whole (a full disk, a file system gone
//! read-only): named in metrics.json and in map-sink's closing summary.

use std::error::Error;

use serde::{Deserialize, Serialize};

/// A file of the run that stopped short or was not written, and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct IncompleteOutput {
    /// The file's name in the run's directory.
    pub file: String,
    /// What happened: for a trajectory stream, the lines it kept and the error that
    /// stopped it; for a whole-file result, the error that kept it from being written.
    pub problem: String,
}

impl IncompleteOutput {
    /// `file` could not be written because of `error`; `what` says what became of it.
    pub fn new(file: &str, what: &str, error: &dyn Error) -> Self {
        Self {
            file: file.to_owned(),
            problem: format!("{what}: {}", chain(error)),
        }
    }

    /// `file: problem`, one line.
    pub fn line(&self) -> String {
        format!("{}: {}", self.file, self.problem)
    }
}

/// The error and its causes, `: `-separated (as `{:#}` prints an anyhow error).
fn chain(error: &dyn Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(cause) = source {
        text.push_str(&format!(": {cause}"));
        source = cause.source();
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_problem_names_the_cause() {
        let error = crate::EvalError::Io {
            path: "run/dead_reckoning.tum".into(),
            source: std::io::Error::from_raw_os_error(28),
        };
        let output = IncompleteOutput::new("dead_reckoning.tum", "stopped after 3 lines", &error);
        let line = output.line();
        assert!(
            line.starts_with(
                "dead_reckoning.tum: stopped after 3 lines: cannot read \
                 run/dead_reckoning.tum: "
            ),
            "{line}"
        );
        assert!(line.contains("No space left on device"), "{line}");
    }
}
