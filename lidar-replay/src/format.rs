//! The log formats, one reader over either, and the check that refuses a file that is not
//! of its format before anything is published.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::Path;

use crate::carmen::CarmenReader;
use crate::error::{CheckError, OpenError, ReadError};
use crate::lines::{NumberedLines, StopFlag, never};
use crate::odometry_judge::{self, Verdict};
use crate::record::LogRecord;
use crate::reorder::{ReorderConfig, ReorderCounts};
use crate::rosbag::{BagError, BagInfo, BagOptions, BagReader};
use crate::scan_order::{self, OrderVerdict};
use crate::seed_csv::SeedCsvReader;
use crate::start;

/// A file whose first scan is not among its first this many lines is refused: CARMEN logs
/// open with a few hundred `PARAM` lines at most.
pub const SNIFF_LINES: u64 = 5_000;

/// ... nor among its first this many bytes: the lines may be long (up to
/// [`crate::MAX_LINE_BYTES`] each), and a file without newlines (`/dev/zero`) has no second
/// line at all. A real log's first scan comes within its first few hundred kilobytes.
pub const SNIFF_BYTES: u64 = 64 << 20;

/// A text log. It is read as a stream, a line at most [`crate::MAX_LINE_BYTES`], and refused
/// when no scan comes within [`SNIFF_BYTES`], so what it may hold is bounded by those; the
/// size limit keeps out only what is no file of records (a sparse file of tebibytes).
pub const LOG_INPUT: stage_kit::InputKind = stage_kit::InputKind {
    what: "log",
    limit_name: "lidar_replay::LOG_INPUT",
    max_bytes: 4 << 40,
};

/// The kind of input a file of `format` is, with its size limit.
pub fn input_kind(format: LogFormat) -> stage_kit::InputKind {
    match format {
        LogFormat::SeedCsv | LogFormat::Carmen => LOG_INPUT,
        LogFormat::Mcap => recorder::RECORDING_INPUT,
        LogFormat::Rosbag => crate::rosbag::BAG_FILE_INPUT,
    }
}

/// The formats `lidar-replay` reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    /// `seed-hall/scans.csv`: 1081 ranges in millimetres a line, no stamps, no odometry.
    SeedCsv,
    /// CARMEN `.clf`: `FLASER`, `ROBOTLASER1` and `ODOM` lines.
    Carmen,
    /// `run.mcap` of `slam-record`: the scans and odometry of a run, published again
    /// exactly as they were. Not a text log: it is read with [`crate::open_recording`].
    Mcap,
    /// A ROS 2 bag (rosbag2): a bag directory, or a bare `.mcap` or `.db3` file of ROS 2
    /// messages ([`crate::rosbag`]). Not a text log: it is read with
    /// [`crate::rosbag::open_bag_until`].
    Rosbag,
}

impl LogFormat {
    /// Name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::SeedCsv => "seed-csv",
            Self::Carmen => "carmen",
            Self::Mcap => "mcap",
            Self::Rosbag => "rosbag2",
        }
    }

    /// Whether logs of this format can carry odometry at all.
    pub fn can_have_odometry(self) -> bool {
        match self {
            Self::SeedCsv => false,
            Self::Carmen | Self::Mcap | Self::Rosbag => true,
        }
    }

    /// Whether a log of this format is read line by line ([`open_log`]).
    pub fn is_text(self) -> bool {
        matches!(self, Self::SeedCsv | Self::Carmen)
    }

    /// The format of the log at `path` where it can be told without being told: a
    /// directory is a rosbag2 bag, a `.db3` its SQLite3 storage, a `.mcap` a bag when its
    /// channels are ROS 2's (CDR) and a run of slam-record otherwise, `.clf` CARMEN and
    /// `.csv` the seed-hall scans. `None` for anything else.
    pub fn detect(path: &Path) -> Option<Self> {
        if path.is_dir() {
            return Some(Self::Rosbag);
        }
        match path.extension()?.to_str()? {
            "db3" => Some(Self::Rosbag),
            // One that cannot be read far enough to tell is left to the recording's
            // reader, which says what is wrong with it.
            "mcap" => Some(match crate::rosbag::is_ros2_mcap(path) {
                Some(true) => Self::Rosbag,
                _ => Self::Mcap,
            }),
            "clf" => Some(Self::Carmen),
            "csv" => Some(Self::SeedCsv),
            _ => None,
        }
    }
}

impl std::fmt::Display for LogFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for LogFormat {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "seed-csv" => Ok(Self::SeedCsv),
            "carmen" => Ok(Self::Carmen),
            "mcap" => Ok(Self::Mcap),
            "rosbag2" => Ok(Self::Rosbag),
            other => Err(format!(
                "unknown log format '{other}' (seed-csv, carmen, mcap or rosbag2)"
            )),
        }
    }
}

/// Reads a log of either format as [`LogRecord`]s in publishing order. A malformed line
/// comes as [`ReadError::Line`] and the next call goes on after it.
#[derive(Debug)]
pub enum LogReader<R> {
    SeedCsv(SeedCsvReader<R>),
    // Boxed: it carries its reordering window, ten times the CSV reader's size.
    Carmen(Box<CarmenReader<R>>),
    /// A ROS 2 bag, opened with [`open_bag_until`] (boxed: it carries its window).
    Rosbag(Box<BagReader>),
    /// An MCAP recording (or a bag) asked for as a text log: yields [`ReadError::NotText`]
    /// once.
    NotText {
        told: bool,
    },
}

impl<R: BufRead> LogReader<R> {
    /// A reader with the default reordering window ([`ReorderConfig::default`]).
    pub fn new(format: LogFormat, reader: R) -> Self {
        Self::with_reorder(format, reader, ReorderConfig::default())
    }

    /// A reader that puts records in time order within `reorder` (logs that have stamps of
    /// their own; seed-csv is stamped in line order and needs none).
    pub fn with_reorder(format: LogFormat, reader: R, reorder: ReorderConfig) -> Self {
        match format {
            LogFormat::SeedCsv => Self::SeedCsv(SeedCsvReader::new(reader)),
            LogFormat::Carmen => {
                Self::Carmen(Box::new(CarmenReader::with_reorder(reader, reorder)))
            }
            LogFormat::Mcap | LogFormat::Rosbag => Self::NotText { told: false },
        }
    }

    /// Publishes the odometry `verdict` chose (CARMEN logs; others have one source).
    pub fn with_odometry_verdict(mut self, verdict: Verdict) -> Self {
        if let Self::Carmen(reader) = self {
            self = Self::Carmen(Box::new(
                reader.with_odometry(verdict.choice).judged(verdict),
            ));
        }
        self
    }

    /// What the judgement of the log's odometry found, if it was judged.
    pub fn odometry_verdict(&self) -> Option<&Verdict> {
        match self {
            Self::Carmen(reader) => reader.verdict(),
            _ => None,
        }
    }

    /// Orders the scans among themselves as `verdict` found (CARMEN logs; others have
    /// their scans in order).
    pub fn with_order_verdict(mut self, verdict: OrderVerdict) -> Self {
        if let Self::Carmen(reader) = self {
            self = Self::Carmen(Box::new(reader.with_scan_order(verdict)));
        }
        self
    }

    /// What the judgement of the order of the log's scans found, if they were judged.
    pub fn order_verdict(&self) -> Option<&OrderVerdict> {
        match self {
            Self::Carmen(reader) => reader.order_verdict(),
            _ => None,
        }
    }

    /// Ends the reading with [`ReadError::Stopped`] once `stop` returns true; it is asked
    /// between reads, so even an endless line does not hold up a stop.
    pub fn stop_when(mut self, stop: StopFlag) -> Self {
        match &mut self {
            Self::SeedCsv(reader) => reader.lines.set_stop(stop),
            Self::Carmen(reader) => reader.lines.set_stop(stop),
            // A bag takes its stop when it is opened.
            Self::Rosbag(_) | Self::NotText { .. } => {}
        }
        self
    }

    /// The lines of a text log; `None` for a recording asked for as one.
    fn lines(&self) -> Option<&NumberedLines<R>> {
        match self {
            Self::SeedCsv(reader) => Some(&reader.lines),
            Self::Carmen(reader) => Some(&reader.lines),
            Self::Rosbag(_) | Self::NotText { .. } => None,
        }
    }

    /// Bytes read so far.
    fn bytes_read(&self) -> u64 {
        self.lines().map_or(0, NumberedLines::bytes_read)
    }

    /// The reordering window and what it did so far; `None` for a format read in line order.
    pub fn reordering(&self) -> Option<(ReorderConfig, ReorderCounts)> {
        match self {
            Self::SeedCsv(_) | Self::NotText { .. } => None,
            Self::Carmen(reader) => Some((reader.reorder_config(), *reader.reorder_counts())),
            Self::Rosbag(reader) => Some(reader.reordering()),
        }
    }

    /// Number of the line read last (0 before the first); a bag's messages read.
    pub fn line_number(&self) -> u64 {
        match self {
            Self::Rosbag(reader) => reader.messages_read(),
            _ => self.lines().map_or(0, NumberedLines::line_number),
        }
    }

    /// Whether what is read are messages of a recording rather than lines of a text.
    pub fn reads_messages(&self) -> bool {
        matches!(self, Self::Rosbag(_))
    }

    /// Record types the reader skipped as not its business, with their line counts (a
    /// bag's topics not replayed, with their message counts).
    pub fn skipped_records(&self) -> Vec<(String, u64)> {
        match self {
            Self::SeedCsv(_) | Self::NotText { .. } => Vec::new(),
            Self::Rosbag(reader) => reader
                .passed_over()
                .iter()
                .map(|(topic, count)| (topic.clone(), *count))
                .collect(),
            Self::Carmen(reader) => reader
                .skipped_records()
                .iter()
                .map(|(name, count)| (name.clone(), *count))
                .collect(),
        }
    }
}

impl<R: BufRead> Iterator for LogReader<R> {
    type Item = Result<LogRecord, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            Self::SeedCsv(reader) => reader.next(),
            Self::Carmen(reader) => reader.next(),
            Self::Rosbag(reader) => reader.next(),
            Self::NotText { told } => {
                (!std::mem::replace(told, true)).then_some(Err(ReadError::NotText))
            }
        }
    }
}

/// Reads `reader` as `format` until its first scan. `Err` says why the data is not a log of
/// that format: no valid scan in the first [`SNIFF_LINES`] lines or [`SNIFF_BYTES`] bytes,
/// or before the end.
pub fn check_format<R: BufRead>(format: LogFormat, reader: R) -> Result<(), CheckError> {
    check_format_until(format, reader, never)
}

/// [`check_format`] that gives up with [`CheckError::Stopped`] once `stop` returns true.
pub fn check_format_until<R: BufRead>(
    format: LogFormat,
    reader: R,
    stop: StopFlag,
) -> Result<(), CheckError> {
    // The budget in bytes ends the check as an end of file would, even within one line.
    let mut log = LogReader::new(format, reader.take(SNIFF_BYTES)).stop_when(stop);
    let mut first_problem = None;
    while log.line_number() < SNIFF_LINES {
        match log.next() {
            Some(Ok(LogRecord::Scan(_))) => return Ok(()),
            Some(Ok(LogRecord::Odometry(_))) => {}
            Some(Err(ReadError::Line(e))) => {
                first_problem.get_or_insert(e);
            }
            Some(Err(ReadError::Io(e))) => return Err(e.into()),
            Some(Err(ReadError::NotText)) => {
                return Err(CheckError::Mismatch(ReadError::NotText.to_string()));
            }
            Some(Err(ReadError::Stopped)) => return Err(CheckError::Stopped),
            Some(Err(ReadError::Cut { .. })) | None => break,
        }
    }
    let lines = log.line_number();
    let mut reason = if log.bytes_read() >= SNIFF_BYTES {
        format!("no valid scan in its first {} MiB", SNIFF_BYTES >> 20)
    } else if lines < SNIFF_LINES {
        format!("no valid scan in its {lines} lines")
    } else {
        format!("no valid scan in its first {SNIFF_LINES} lines")
    };
    if let Some(problem) = first_problem {
        reason.push_str(&format!(" (first problem: {problem})"));
    }
    let skipped = log.skipped_records();
    if !skipped.is_empty() {
        let list: Vec<String> = skipped
            .iter()
            .map(|(name, count)| format!("{name} x{count}"))
            .collect();
        reason.push_str(&format!("; records not replayed: {}", list.join(", ")));
    }
    Err(CheckError::Mismatch(reason))
}

/// Opens a log for replay after checking that it is of `format` (see [`check_format`]),
/// its records put in time order within `reorder`.
pub fn open_log(
    format: LogFormat,
    path: &Path,
    reorder: ReorderConfig,
) -> Result<LogReader<BufReader<File>>, OpenError> {
    open_log_until(format, path, reorder, never)
}

/// [`open_log`] whose check and reading end once `stop` returns true (Ctrl-C): the check
/// with [`OpenError::Stopped`], the reading with [`ReadError::Stopped`].
pub fn open_log_until(
    format: LogFormat,
    path: &Path,
    reorder: ReorderConfig,
    stop: StopFlag,
) -> Result<LogReader<BufReader<File>>, OpenError> {
    let open = || -> Result<_, OpenError> {
        let file = LOG_INPUT.open(path, stage_kit::input::Links::Follow)?;
        Ok(BufReader::new(file))
    };
    check_format_until(format, open()?, stop).map_err(|e| match e {
        CheckError::Io(source) => OpenError::Io {
            path: path.to_path_buf(),
            source,
        },
        CheckError::Mismatch(reason) => OpenError::NotThisFormat {
            path: path.to_path_buf(),
            format,
            reason,
        },
        CheckError::Stopped => OpenError::Stopped {
            path: path.to_path_buf(),
        },
    })?;
    let (verdict, order) = match format {
        LogFormat::Carmen => {
            let start = start::read(open()?, stop);
            (
                odometry_judge::judge_start(&start),
                Some(scan_order::judge_start(&start)),
            )
        }
        LogFormat::SeedCsv | LogFormat::Mcap | LogFormat::Rosbag => (None, None),
    };
    // Read again from the top, so the lines looked at are replayed and reported as usual.
    let mut reader = LogReader::with_reorder(format, open()?, reorder).stop_when(stop);
    if let Some(verdict) = verdict {
        reader = reader.with_odometry_verdict(verdict);
    }
    if let Some(order) = order {
        reader = reader.with_order_verdict(order);
    }
    Ok(reader)
}

/// Opens a ROS 2 bag for replay after surveying it ([`crate::rosbag::open_bag_until`]):
/// a reader of its scans and odometry like any log's, and what the survey found.
pub fn open_bag_until(
    path: &Path,
    options: &BagOptions,
    stop: StopFlag,
) -> Result<(LogReader<BufReader<File>>, BagInfo), BagError> {
    let (reader, info) = crate::rosbag::open_bag_until(path, options, stop)?;
    Ok((LogReader::Rosbag(Box::new(reader)), info))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A valid `FLASER` line: 180 beams of 1 m.
    fn flaser() -> String {
        format!(
            "FLASER 180 {} 0 0 0 0 0 0 1.0 h 0\n",
            vec!["1.0"; 180].join(" ")
        )
    }

    fn refusal(format: LogFormat, text: &str) -> String {
        match check_format(format, text.as_bytes()) {
            Err(CheckError::Mismatch(reason)) => reason,
            other => panic!("not refused: {other:?}"),
        }
    }

    #[test]
    fn a_csv_is_not_a_carmen_log() {
        let csv = "14029,14083\n14029,14083\n";
        assert_eq!(
            refusal(LogFormat::Carmen, csv),
            "no valid scan in its 2 lines (first problem: line 1: not a CARMEN record: \
             \"14029,14083\")"
        );
    }

    #[test]
    fn a_carmen_log_is_not_a_seed_csv() {
        let clf = format!("# message formats\n{}", flaser());
        let reason = refusal(LogFormat::SeedCsv, &clf);
        assert!(reason.starts_with("no valid scan in its 2 lines (first problem: line 1: "));
    }

    #[test]
    fn other_record_types_are_named_when_there_is_no_scan() {
        let clf = "PARAM a 1 h 0\nRAWLASER1 whatever\nRAWLASER1 whatever\n";
        assert_eq!(
            refusal(LogFormat::Carmen, clf),
            "no valid scan in its 3 lines; records not replayed: PARAM x1, RAWLASER1 x2"
        );
    }

    #[test]
    fn an_empty_file_is_refused() {
        assert_eq!(
            refusal(LogFormat::Carmen, ""),
            "no valid scan in its 0 lines"
        );
    }

    #[test]
    fn the_first_scan_must_come_early() {
        let mut text = "PARAM a 1 h 0\n".repeat(SNIFF_LINES as usize);
        text.push_str(&flaser());
        assert_eq!(
            refusal(LogFormat::Carmen, &text),
            format!(
                "no valid scan in its first {SNIFF_LINES} lines; records not replayed: PARAM x{SNIFF_LINES}"
            )
        );
        let text = format!("PARAM a 1 h 0\nbad\n{}", flaser());
        assert!(check_format(LogFormat::Carmen, text.as_bytes()).is_ok());
    }

    #[test]
    fn a_recording_is_not_opened_as_a_text_log() {
        assert_eq!(
            refusal(LogFormat::Mcap, "anything"),
            "an MCAP recording is not a text log: it is read with open_recording"
        );
    }

    #[test]
    fn formats_parse_from_their_names() {
        assert_eq!("seed-csv".parse(), Ok(LogFormat::SeedCsv));
        assert_eq!("carmen".parse(), Ok(LogFormat::Carmen));
        assert_eq!("mcap".parse(), Ok(LogFormat::Mcap));
        assert_eq!("rosbag2".parse(), Ok(LogFormat::Rosbag));
        assert_eq!(LogFormat::Rosbag.to_string(), "rosbag2");
        assert!("csv".parse::<LogFormat>().is_err());
        assert_eq!(LogFormat::Carmen.to_string(), "carmen");
    }
}
