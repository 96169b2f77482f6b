//! Lines of a text log with their 1-based numbers, so every complaint can name its line.
//!
//! The reader trusts nothing about the input's size: a line longer than [`MAX_LINE_BYTES`]
//! (a file without newlines, `/dev/zero`, a binary) is refused and counted like any other
//! malformed line and reading goes on after its next newline, without holding more than the
//! cap in memory. The stop flag is asked between reads, so even an endless line does not
//! keep a replay from ending on Ctrl-C.

use std::io::BufRead;

use crate::error::{LineError, Malformation, ReadError};

/// Longest line a log may have, its newline included. A scan of 8192 beams written as text
/// is well under 100 KiB, so this is far above any real line and still little memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// A stop flag: true once reading should end (Ctrl-C). Asked between reads.
pub type StopFlag = fn() -> bool;

/// The flag of a reader nobody stops.
pub(crate) fn never() -> bool {
    false
}

/// A line's number and its text, or why the text cannot be used.
pub(crate) type NumberedLine<'a> = (u64, Result<&'a str, LineError>);

/// Reads a log line by line, counting lines and stripping `\n` / `\r\n`.
#[derive(Debug)]
pub(crate) struct NumberedLines<R> {
    reader: R,
    line: u64,
    /// Bytes read so far, every line's whole length included.
    bytes: u64,
    buffer: Vec<u8>,
    stop: StopFlag,
}

impl<R: BufRead> NumberedLines<R> {
    pub(crate) fn new(reader: R) -> Self {
        Self {
            reader,
            line: 0,
            bytes: 0,
            buffer: Vec::new(),
            stop: never,
        }
    }

    /// Ends every later read with [`ReadError::Stopped`] once `stop` returns true.
    pub(crate) fn set_stop(&mut self, stop: StopFlag) {
        self.stop = stop;
    }

    /// Number of the line read last (0 before the first).
    pub(crate) fn line_number(&self) -> u64 {
        self.line
    }

    /// Bytes read so far.
    pub(crate) fn bytes_read(&self) -> u64 {
        self.bytes
    }

    /// The next line and its number, or `None` at the end of the file. A line that is not
    /// UTF-8, or longer than [`MAX_LINE_BYTES`], is a [`LineError`] (binary data fed as a
    /// log), not an I/O failure; a stop request is [`ReadError::Stopped`].
    pub(crate) fn next_line(&mut self) -> Result<Option<NumberedLine<'_>>, ReadError> {
        self.buffer.clear();
        // Bytes of the line read so far, those dropped for its length included.
        let mut length = 0u64;
        let mut too_long = false;
        loop {
            if (self.stop)() {
                return Err(ReadError::Stopped);
            }
            // Bytes rather than `read_line`, so one bad byte costs one line, not the whole
            // file; chunk by chunk rather than `read_until`, so a line cannot grow unbounded.
            let chunk = match self.reader.fill_buf() {
                Ok(chunk) => chunk,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e.into()),
            };
            if chunk.is_empty() {
                break;
            }
            let newline = chunk.iter().position(|&b| b == b'\n');
            let take = newline.map_or(chunk.len(), |at| at + 1);
            if !too_long {
                if self.buffer.len() + take > MAX_LINE_BYTES {
                    too_long = true;
                    self.buffer.clear();
                } else {
                    self.buffer.extend_from_slice(&chunk[..take]);
                }
            }
            self.reader.consume(take);
            length += take as u64;
            self.bytes += take as u64;
            if newline.is_some() {
                break;
            }
        }
        if length == 0 {
            return Ok(None);
        }
        self.line += 1;
        if too_long {
            // What a line that long held is not worth keeping for the next one.
            self.buffer.shrink_to(MAX_LINE_BYTES / 16);
            return Ok(Some((
                self.line,
                Err(LineError::new(
                    self.line,
                    Malformation::TooLong,
                    format!("{length} bytes long, over the {MAX_LINE_BYTES} bytes a line may have"),
                )),
            )));
        }
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
    use std::io::BufReader;
    use std::sync::atomic::{AtomicUsize, Ordering};

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
    fn an_overlong_line_is_refused_and_reading_goes_on_after_it() {
        let mut data = b"first\n".to_vec();
        data.extend(vec![b'x'; MAX_LINE_BYTES]);
        data.extend(b"\nlast\n");
        // A small buffer, so the long line comes in many chunks.
        let mut lines = NumberedLines::new(BufReader::with_capacity(64, &data[..]));
        let mut seen = Vec::new();
        while let Some((number, text)) = lines.next_line().unwrap() {
            seen.push((
                number,
                text.map(str::to_owned).map_err(|e| (e.line, e.kind)),
            ));
        }
        assert_eq!(
            seen,
            vec![
                (1, Ok("first".to_owned())),
                (2, Err((2, Malformation::TooLong))),
                (3, Ok("last".to_owned())),
            ]
        );
        assert_eq!(lines.bytes_read(), data.len() as u64);
        // The longest line that fits, its newline included, is kept whole.
        let mut data = vec![b'y'; MAX_LINE_BYTES - 1];
        data.push(b'\n');
        let mut lines = NumberedLines::new(&data[..]);
        let (_, text) = lines.next_line().unwrap().unwrap();
        assert_eq!(text.unwrap().len(), MAX_LINE_BYTES - 1);
    }

    #[test]
    fn a_stop_ends_the_reading_even_within_a_line() {
        // A flag a plain fn can raise: true from its 100th question on.
        static ASKED: AtomicUsize = AtomicUsize::new(0);
        fn after_a_while() -> bool {
            ASKED.fetch_add(1, Ordering::Relaxed) >= 100
        }
        // Zeros without end: one endless line.
        let mut lines = NumberedLines::new(BufReader::with_capacity(64, std::io::repeat(0)));
        lines.set_stop(after_a_while);
        assert!(matches!(lines.next_line(), Err(ReadError::Stopped)));
        assert_eq!(lines.bytes_read(), 100 * 64, "read on until the stop");
    }

    #[test]
    fn snippets_are_short_and_quoted() {
        assert_eq!(snippet("abc"), "\"abc\"");
        assert!(snippet(&"x".repeat(100)).ends_with("\"..."));
    }
}
