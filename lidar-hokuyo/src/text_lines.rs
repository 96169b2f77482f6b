//! Lines from a byte stream whose reads may time out (a TCP socket with a read timeout), so a
//! reader can notice Ctrl-C and a silent peer while it waits.

use std::io::{self, Read};
use std::time::{Duration, Instant};

/// Longest line accepted. SCIP lines are at most 65 characters, information lines a few
/// dozen; anything longer means the peer does not speak SCIP.
pub const MAX_LINE: usize = 1024;

/// Why no line came.
#[derive(Debug, thiserror::Error)]
pub enum LineError {
    #[error("the connection was closed")]
    Closed,
    #[error("no complete line within {0:?}")]
    TimedOut(Duration),
    #[error("stopped by a signal")]
    Stopped,
    #[error("line longer than {MAX_LINE} bytes")]
    TooLong,
    #[error("cannot read: {0}")]
    Io(#[from] io::Error),
}

/// How lines end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ending {
    /// Sensor replies: LF, and an empty line is meaningful (it ends a reply).
    Lf,
    /// Host commands: CR, LF or both; empty lines carry nothing.
    CrOrLf,
}

/// Splits a stream into lines, keeping what it read past the last one.
#[derive(Debug)]
pub struct LineReader<S> {
    stream: S,
    buffer: Vec<u8>,
    consumed: usize,
    ending: Ending,
    /// Bytes read from the stream so far.
    received: u64,
}

impl<S: Read> LineReader<S> {
    /// Reads LF-terminated replies of a sensor.
    pub fn replies(stream: S) -> Self {
        Self::new(stream, Ending::Lf)
    }

    /// Reads commands of a host, which may end in CR, LF or both.
    pub fn commands(stream: S) -> Self {
        Self::new(stream, Ending::CrOrLf)
    }

    fn new(stream: S, ending: Ending) -> Self {
        Self {
            stream,
            buffer: Vec::with_capacity(4096),
            consumed: 0,
            ending,
            received: 0,
        }
    }

    /// The next line without its terminator. Waits at most `timeout` for it and gives up
    /// early when `stop` says so.
    ///
    /// Both are checked before every read (the deadline from the second on), whether the
    /// last read brought bytes or timed out: a peer that keeps sending bytes that make no
    /// line, or lines nobody waits for, must not hold the reader past its deadline or a stop.
    pub fn read_line(
        &mut self,
        timeout: Duration,
        stop: &dyn Fn() -> bool,
    ) -> Result<Vec<u8>, LineError> {
        let start = Instant::now();
        let mut chunk = [0u8; 4096];
        let mut first_read = true;
        loop {
            if let Some(line) = self.take_line() {
                return Ok(line);
            }
            if self.buffer.len() - self.consumed > MAX_LINE {
                return Err(LineError::TooLong);
            }
            if stop() {
                return Err(LineError::Stopped);
            }
            // One read is always tried, so a zero timeout still takes what has come.
            if !first_read && start.elapsed() >= timeout {
                return Err(LineError::TimedOut(timeout));
            }
            first_read = false;
            match self.stream.read(&mut chunk) {
                Ok(0) => return Err(LineError::Closed),
                Ok(n) => {
                    self.compact();
                    self.buffer.extend_from_slice(&chunk[..n]);
                    self.received += n as u64;
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock
                            | io::ErrorKind::TimedOut
                            | io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(LineError::Io(e)),
            }
        }
    }

    /// Bytes received so far, for telling a silent peer from one that talks nonsense.
    pub fn bytes_received(&self) -> u64 {
        self.received
    }

    /// The stream, to write to it.
    pub fn get_mut(&mut self) -> &mut S {
        &mut self.stream
    }

    /// The stream.
    pub fn get_ref(&self) -> &S {
        &self.stream
    }

    /// The stream; bytes read past the last line are lost.
    pub fn into_inner(self) -> S {
        self.stream
    }

    fn take_line(&mut self) -> Option<Vec<u8>> {
        loop {
            let rest = &self.buffer[self.consumed..];
            let end = match self.ending {
                Ending::Lf => rest.iter().position(|&b| b == b'\n'),
                Ending::CrOrLf => rest.iter().position(|&b| b == b'\n' || b == b'\r'),
            }?;
            let mut line = &rest[..end];
            self.consumed += end + 1;
            match self.ending {
                Ending::Lf => {
                    // SCIP characters are never CR, so a CR before the LF is a terminator.
                    line = line.strip_suffix(b"\r").unwrap_or(line);
                    return Some(line.to_vec());
                }
                Ending::CrOrLf if line.is_empty() => {}
                Ending::CrOrLf => return Some(line.to_vec()),
            }
        }
    }

    fn compact(&mut self) {
        if self.consumed > 0 {
            self.buffer.drain(..self.consumed);
            self.consumed = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NEVER: &dyn Fn() -> bool = &|| false;
    const SECOND: Duration = Duration::from_secs(1);

    /// Hands out its data a few bytes per read, then times out for ever.
    struct Trickle {
        data: Vec<u8>,
        at: usize,
        step: usize,
    }

    impl Trickle {
        fn new(data: &[u8], step: usize) -> Self {
            Self {
                data: data.to_vec(),
                at: 0,
                step,
            }
        }
    }

    impl Read for Trickle {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            if self.at >= self.data.len() {
                return Err(io::ErrorKind::WouldBlock.into());
            }
            let n = self.step.min(buf.len()).min(self.data.len() - self.at);
            buf[..n].copy_from_slice(&self.data[self.at..self.at + n]);
            self.at += n;
            Ok(n)
        }
    }

    #[test]
    fn replies_keep_empty_lines_and_survive_short_reads() {
        let mut reader = LineReader::replies(Trickle::new(b"PP\r\n00P\n\nVV\n", 3));
        let lines: Vec<_> = (0..4)
            .map(|_| reader.read_line(SECOND, NEVER).unwrap())
            .collect();
        assert_eq!(lines, [&b"PP"[..], b"00P", b"", b"VV"]);
        assert!(matches!(
            reader.read_line(Duration::ZERO, NEVER),
            Err(LineError::TimedOut(_))
        ));
    }

    #[test]
    fn commands_end_in_cr_lf_or_both() {
        let mut reader = LineReader::commands(&b"VV\rPP\nII\r\n\r\nQT\n"[..]);
        for expected in [&b"VV"[..], b"PP", b"II", b"QT"] {
            assert_eq!(reader.read_line(SECOND, NEVER).unwrap(), expected);
        }
        assert!(matches!(
            reader.read_line(SECOND, NEVER),
            Err(LineError::Closed)
        ));
    }

    #[test]
    fn a_stop_request_ends_the_wait() {
        let mut reader = LineReader::replies(Trickle::new(b"partial", 100));
        assert!(matches!(
            reader.read_line(Duration::from_secs(60), &|| true),
            Err(LineError::Stopped)
        ));
    }

    /// Hands out a byte at a time for ever, never a timeout: a peer that keeps talking.
    struct Chatter(u8);

    impl Read for Chatter {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            buf[0] = self.0;
            Ok(1)
        }
    }

    #[test]
    fn a_peer_that_never_falls_silent_still_meets_the_deadline_and_the_stop() {
        // Bare newlines: empty lines, one per read, never a timed-out read.
        let mut reader = LineReader::commands(Chatter(b'\n'));
        let started = Instant::now();
        assert!(matches!(
            reader.read_line(Duration::from_millis(50), NEVER),
            Err(LineError::TimedOut(_))
        ));
        assert!(started.elapsed() < Duration::from_secs(5));
        assert!(reader.bytes_received() > 0);
        // Bytes that never end a line are caught by the length cap; a stop comes first.
        let mut reader = LineReader::replies(Chatter(b'x'));
        assert!(matches!(
            reader.read_line(Duration::from_secs(60), &|| true),
            Err(LineError::Stopped)
        ));
    }

    #[test]
    fn endless_lines_are_refused() {
        let data = vec![b'0'; 3 * MAX_LINE];
        let mut reader = LineReader::replies(&data[..]);
        assert!(matches!(
            reader.read_line(SECOND, NEVER),
            Err(LineError::TooLong)
        ));
    }
}
