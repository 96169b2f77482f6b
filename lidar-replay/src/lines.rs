//! Lines of a text log with their 1-based numbers, so every complaint can name its line.

use std::io::BufRead;

use crate::error::{LineError, Malformation};

/// Reads a log line by line, counting lines and stripping `\n` / `\r\n`.
#[derive(Debug)]
pub(crate) struct NumberedLines<R> {
    reader: R,
    line: u64,
    buffer: Vec<u8>,
}

impl<R: BufRead> NumberedLines<R> {
    pub(crate) fn new(reader: R) -> Self {
        Self {
            reader,
            line: 0,
            buffer: Vec::new(),
        }
    }

    /// Number of the line read last (0 before the first).
    pub(crate) fn line_number(&self) -> u64 {
        self.line
    }

    /// The next line and its number, or `None` at the end of the file. A line that is not
    /// UTF-8 is a [`LineError`] (binary data fed as a log), not an I/O failure.
    pub(crate) fn next_line(&mut self) -> std::io::Result<Option<(u64, Result<&str, LineError>)>> {
        self.buffer.clear();
        // Bytes rather than `read_line`, so one bad byte costs one line, not the whole file.
        if self.reader.read_until(b'\n', &mut self.buffer)? == 0 {
            return Ok(None);
        }
        self.line += 1;
        let mut text: &[u8] = &self.buffer;
        if let Some(rest) = text.strip_suffix(b"\n") {
            text = rest;
        }
        if let Some(rest) = text.strip_suffix(b"\r") {
            text = rest;
        }
        let text = std::str::from_utf8(text)
            .map_err(|_| LineError::new(self.line, Malformation::NotText, "not UTF-8 text"));
        Ok(Some((self.line, text)))
    }
}

/// The start of `text`, for error messages that quote a line or a field.
pub(crate) fn snippet(text: &str) -> String {
    const MAX_CHARS: usize = 40;
    let mut chars = text.chars();
    let head: String = chars.by_ref().take(MAX_CHARS).collect();
    if chars.next().is_some() {
        format!("{head:?}...")
    } else {
        format!("{head:?}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_numbered_and_stripped() {
        let mut lines = NumberedLines::new(&b"a\r\nb\n\xff\nlast"[..]);
        let mut seen = Vec::new();
        while let Some((number, text)) = lines.next_line().unwrap() {
            seen.push((number, text.map(str::to_owned).map_err(|e| e.line)));
        }
        assert_eq!(
            seen,
            vec![
                (1, Ok("a".to_owned())),
                (2, Ok("b".to_owned())),
                (3, Err(3)),
                (4, Ok("last".to_owned())),
            ]
        );
    }

    #[test]
    fn snippets_are_short_and_quoted() {
        assert_eq!(snippet("abc"), "\"abc\"");
        assert!(snippet(&"x".repeat(100)).ends_with("\"..."));
    }
}
