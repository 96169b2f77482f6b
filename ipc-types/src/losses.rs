//! What a process skipped or lost, told to slam-launch on stdout as it ends.
//!
//! Each stage counts the data it could not use (malformed log lines, scans it skipped,
//! corners that did not fit a message, ...) and writes them to its stderr, which goes to its
//! log file, where nobody looks after a run that ended well. So, as it ends, a stage also
//! prints its counts on one line of stdout, the channel it already reports on to the
//! launcher (`ready`, [`crate::progress`]):
//!
//! ```text
//! losses malformed_lines=3 late_scans=1 repeated_odometry=55
//! ```
//!
//! Keys are words joined by `_`, values counts; zero counts may be left out, and the line is
//! printed when the process was started with [`crate::progress::ENV`] set, as slam-launch
//! starts its stages. The launcher lists every nonzero count per stage at the end of the run.
//! A line rather than a file in the output directory: only map-sink knows that directory, and
//! a stage run by hand has none.

use std::io::Write;

/// The first word of a losses line.
pub const PREFIX: &str = "losses";

/// The line for `counts` (zero counts left out).
pub fn line(counts: &[(&str, u64)]) -> String {
    let mut text = PREFIX.to_owned();
    for (key, count) in counts.iter().filter(|(_, count)| *count > 0) {
        text.push_str(&format!(" {key}={count}"));
    }
    text
}

/// Prints the line for `counts` on stdout when the launcher asked for reports. A launcher
/// that has gone is no reason to fail: the error is ignored.
pub fn report(counts: &[(&str, u64)]) {
    if std::env::var_os(crate::progress::ENV).is_none() {
        return;
    }
    let mut stdout = std::io::stdout().lock();
    let _ = writeln!(stdout, "{}", line(counts));
    let _ = stdout.flush();
}

/// The counts of a losses line without its first word; words that are not `key=count` are
/// skipped.
pub fn parse(rest: &str) -> Vec<(String, u64)> {
    rest.split_whitespace()
        .filter_map(|word| {
            let (key, count) = word.split_once('=')?;
            Some((key.to_owned(), count.parse().ok()?))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_round_trips_without_its_zeros() {
        let text = line(&[("skipped_scans", 2), ("refused_odometry", 0), ("late", 7)]);
        assert_eq!(text, "losses skipped_scans=2 late=7");
        let rest = text.strip_prefix(PREFIX).unwrap();
        assert_eq!(
            parse(rest),
            [("skipped_scans".to_owned(), 2), ("late".to_owned(), 7)]
        );
        assert_eq!(line(&[("x", 0)]), "losses");
        assert_eq!(
            parse(" a=1 junk b=x c=3"),
            [("a".into(), 1), ("c".into(), 3)]
        );
    }
}
