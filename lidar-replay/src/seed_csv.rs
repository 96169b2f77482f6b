//! The seed-hall recording (`seed-hall/scans.csv`, see its FORMAT.md): one scan a line, 1081
//! comma-separated integer ranges in millimetres from a Hokuyo UTM-30LX-class lidar, no
//! timestamps, no odometry.

use std::f64::consts::PI;
use std::io::BufRead;

use crate::error::{LineError, Malformation, ReadError};
use crate::lines::{NumberedLines, snippet};
use crate::record::{LogRecord, ScanGeometry, ScanRecord};

/// Beams per scan: 270 degrees in quarter degrees, both ends included.
pub const BEAMS: usize = 1081;
/// The recording has no timestamps; its scans are stamped this far apart. Consecutive scans
/// are about 0.11 m apart, so 0.1 s is a walking pace of about 1.1 m/s.
pub const NOMINAL_PERIOD_NS: u64 = 100_000_000;
/// Codes below 20 are the sensor's error codes, not distances (SCIP 2.0).
const SMALLEST_RANGE_MM: u32 = 20;
/// The error code for "no object in range" (about 9.5 % of the readings).
const NO_RETURN_CODE: u32 = 1;
/// One mirror turn of a UTM-30LX takes 25 ms and has 1440 quarter-degree steps.
const TIME_INCREMENT_S: f64 = 0.025 / 1440.0;

/// The geometry a UTM-30LX driver publishes. The file's own bearings start at -pi/4 with the
/// scanner's forward direction on +y; the sensor frame has forward on +x, hence -pi/2 more.
/// Range limits are the sensor's own (its `PP` reply: DMIN 23 mm, DMAX 60 000 mm), which
/// keeps every real return of the file (the longest is 36.881 m).
pub const GEOMETRY: ScanGeometry = ScanGeometry {
    angle_min: -3.0 * PI / 4.0,
    angle_increment: PI / 720.0,
    time_increment: TIME_INCREMENT_S,
    scan_time: NOMINAL_PERIOD_NS as f64 * 1e-9,
    range_min: 0.023,
    range_max: 60.0,
};

/// A range code in millimetres as a REP 117 range in metres: code 1 (no return) is +inf,
/// the other error codes below 20 mm are NaN, codes at or beyond the sensor's maximum +inf.
pub fn range_from_code(millimetres: u32) -> f32 {
    if millimetres == NO_RETURN_CODE {
        return f32::INFINITY;
    }
    if millimetres < SMALLEST_RANGE_MM {
        return f32::NAN;
    }
    let metres = f64::from(millimetres) / 1000.0;
    if metres >= GEOMETRY.range_max {
        f32::INFINITY
    } else {
        metres as f32
    }
}

/// Reads the scans of a seed-hall CSV; line `k` is stamped `(k - 1) * 0.1 s`, so a skipped
/// line leaves a gap in time instead of shifting the scans after it.
#[derive(Debug)]
pub struct SeedCsvReader<R> {
    /// The log's lines; [`crate::LogReader`] sets the stop and reads the counts here.
    pub(crate) lines: NumberedLines<R>,
    failed: bool,
}

impl<R: BufRead> SeedCsvReader<R> {
    pub fn new(reader: R) -> Self {
        Self {
            lines: NumberedLines::new(reader),
            failed: false,
        }
    }
}

impl<R: BufRead> Iterator for SeedCsvReader<R> {
    type Item = Result<LogRecord, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        loop {
            let (line, text) = match self.lines.next_line() {
                Ok(Some(next)) => next,
                Ok(None) => return None,
                Err(e) => {
                    self.failed = true;
                    return Some(Err(e));
                }
            };
            let text = match text {
                Ok(text) => text,
                Err(e) => return Some(Err(e.into())),
            };
            if text.trim().is_empty() {
                continue;
            }
            return Some(
                parse_line(line, text)
                    .map(LogRecord::Scan)
                    .map_err(Into::into),
            );
        }
    }
}

fn parse_line(line: u64, text: &str) -> Result<ScanRecord, LineError> {
    let mut ranges = Vec::with_capacity(BEAMS);
    for (index, field) in text.split(',').enumerate() {
        let field = field.trim();
        let millimetres: u32 = field.parse().map_err(|_| {
            LineError::new(
                line,
                Malformation::NotANumber,
                format!(
                    "beam {}: {} is not a range in millimetres",
                    index + 1,
                    snippet(field)
                ),
            )
        })?;
        ranges.push(range_from_code(millimetres));
    }
    if ranges.len() != BEAMS {
        let kind = if ranges.len() < BEAMS {
            Malformation::MissingFields
        } else {
            Malformation::ExtraFields
        };
        return Err(LineError::new(
            line,
            kind,
            format!("{} ranges, expected {BEAMS}", ranges.len()),
        ));
    }
    Ok(ScanRecord {
        line,
        stamp_ns: (line - 1) * NOMINAL_PERIOD_NS,
        log_stamp_ns: (line - 1) * NOMINAL_PERIOD_NS,
        geometry: GEOMETRY,
        ranges,
        intensities: Vec::new(),
        robot_from_sensor: slam_geom::Pose2::IDENTITY,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CSV line starting with `first`, padded with 5 m readings to a full scan.
    fn row(first: &[&str]) -> String {
        let mut codes: Vec<String> = first.iter().map(|s| (*s).to_owned()).collect();
        codes.resize(BEAMS, "5000".to_owned());
        codes.join(",")
    }

    fn read(text: &str) -> Vec<Result<LogRecord, String>> {
        SeedCsvReader::new(text.as_bytes())
            .map(|r| r.map_err(|e| e.to_string()))
            .collect()
    }

    fn scan(record: &Result<LogRecord, String>) -> &ScanRecord {
        match record {
            Ok(LogRecord::Scan(scan)) => scan,
            other => panic!("expected a scan, got {other:?}"),
        }
    }

    #[test]
    fn codes_become_rep117_ranges() {
        let records = read(&row(&[
            "1", "19", "0", "20", "1234", "36881", "60000", "70000",
        ]));
        let ranges = &scan(&records[0]).ranges;
        assert_eq!(ranges[0], f32::INFINITY, "1 = no return");
        assert!(
            ranges[1].is_nan() && ranges[2].is_nan(),
            "other codes = error"
        );
        assert_eq!(ranges[3], 0.02);
        assert_eq!(ranges[4], 1.234);
        assert_eq!(ranges[5], 36.881);
        assert_eq!(ranges[6], f32::INFINITY);
        assert_eq!(ranges[7], f32::INFINITY);
        assert_eq!(ranges.len(), BEAMS);
    }

    #[test]
    fn geometry_puts_the_scanners_forward_beam_on_x() {
        // Beam 541 (index 540) is the scanner's forward direction (FORMAT.md).
        let forward = GEOMETRY.angle_min + 540.0 * GEOMETRY.angle_increment;
        assert!(forward.abs() < 1e-12);
        let last = GEOMETRY.angle_min + (BEAMS - 1) as f64 * GEOMETRY.angle_increment;
        assert!((last - 3.0 * PI / 4.0).abs() < 1e-12);
    }

    #[test]
    fn lines_are_stamped_by_their_number_and_bad_ones_named() {
        let text = format!(
            "{}\n{}\n\n{}\n1,2,3\r\n{}\r\n",
            row(&[]),
            row(&["7", "8", "-1"]),
            row(&[]),
            row(&[])
        );
        let records = read(&text);
        assert_eq!(records.len(), 5);
        assert_eq!(scan(&records[0]).stamp_ns, 0);
        assert_eq!(
            records[1].as_ref().err().map(String::as_str),
            Some("line 2: beam 3: \"-1\" is not a range in millimetres")
        );
        // Line 3 is blank; line 4 keeps its place in time.
        assert_eq!(scan(&records[2]).stamp_ns, 300_000_000);
        assert_eq!(scan(&records[2]).line, 4);
        assert_eq!(
            records[3].as_ref().err().map(String::as_str),
            Some("line 5: 3 ranges, expected 1081")
        );
        assert_eq!(scan(&records[4]).stamp_ns, 500_000_000);
    }
}
