//! CARMEN logs (`.clf`): `FLASER`, `ROBOTLASER1` and `ODOM` lines become scans and odometry;
//! `#` comments and every other record type (`PARAM`, `SYNC`, `RAWLASER1`, ...) are skipped.
//!
//! Line formats (whitespace-separated; poses in metres and radians, ranges in metres):
//! * `FLASER n r1 .. rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp`
//!   (a 180-degree laser, beam 1 on the right; `odom_*` is the raw wheel odometry);
//! * `ROBOTLASER1 type start_angle fov angular_res max_range accuracy remission_mode n r1 .. rn
//!   m rem1 .. remm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
//!   forward_safety side_safety turn_axis ipc_timestamp hostname logger_timestamp`;
//! * `ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp`.
//!
//! Stamps are the `ipc_timestamp`, kept to the nanosecond. A `FLASER` line yields its odometry
//! first and then its scan, both with the line's stamp, so a consumer has the odometry when
//! the scan arrives; but once the log has given an `ODOM` line, odometry comes from `ODOM`
//! lines only. Logs with both (ACES) copy into each `FLASER` the last `ODOM` reading before
//! it, up to a tenth of a second stale, under the laser's stamp: the two sources together
//! would zig-zag, and the `ODOM` lines are the readings at their true times. `ROBOTLASER1`'s robot pose is not published as odometry: a localizer may
//! have corrected it, and logs that have such lines carry the raw odometry in `ODOM` lines.
//! The laser's mounting offset (`laser_*` against `robot_*`) is not used either: the
//! pipeline's sensor frame is the robot frame.

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::io::BufRead;

use crate::angle::wrap_angle;
use crate::error::{LineError, ReadError};
use crate::lines::{NumberedLines, snippet};
use crate::record::{LogRecord, OdometryRecord, ScanGeometry, ScanRecord};
use crate::stamp::parse_stamp_ns;

/// Longest range of the SICK LMS 2xx lasers of `FLASER` logs (data sheet: 80 m). Their "no
/// return" reading, 81.91 m (8191 cm, the largest code), lies beyond it and becomes +inf;
/// the longest real return of the MIT CSAIL log is 42.4 m.
pub const FLASER_RANGE_MAX: f64 = 80.0;

/// Reads the scans and odometry of a CARMEN log in log order.
#[derive(Debug)]
pub struct CarmenReader<R> {
    lines: NumberedLines<R>,
    /// A `FLASER` scan waiting behind its odometry.
    pending: Option<LogRecord>,
    /// Whether an `ODOM` line has been read: from then on the odometry comes from those
    /// lines alone.
    odom_lines: bool,
    /// Stamp of the last scan handed out: scans must move forward in time.
    last_scan: Option<(u64, u64)>,
    skipped: BTreeMap<String, u64>,
    failed: bool,
}

impl<R: BufRead> CarmenReader<R> {
    pub fn new(reader: R) -> Self {
        Self {
            lines: NumberedLines::new(reader),
            pending: None,
            odom_lines: false,
            last_scan: None,
            skipped: BTreeMap::new(),
            failed: false,
        }
    }

    /// Number of the line read last (0 before the first).
    pub fn line_number(&self) -> u64 {
        self.lines.line_number()
    }

    /// Record types skipped so far (`PARAM`, `SYNC`, ...) and how many lines of each.
    pub fn skipped_records(&self) -> &BTreeMap<String, u64> {
        &self.skipped
    }

    /// Parses one non-comment line: `Ok(None)` for a record type that is skipped.
    fn parse_line(&mut self, line: u64, text: &str) -> Result<Option<LogRecord>, LineError> {
        let tokens: Vec<&str> = text.split_whitespace().collect();
        let Some(&kind) = tokens.first() else {
            return Ok(None);
        };
        let mut fields = Fields::new(line, kind, &tokens[1..]);
        match kind {
            "FLASER" => {
                let (odometry, scan) = parse_flaser(&mut fields)?;
                let scan = self.accept_scan(scan)?;
                if self.odom_lines {
                    return Ok(Some(LogRecord::Scan(scan)));
                }
                self.pending = Some(LogRecord::Scan(scan));
                Ok(Some(LogRecord::Odometry(odometry)))
            }
            "ROBOTLASER1" => {
                let scan = parse_robotlaser1(&mut fields)?;
                Ok(Some(LogRecord::Scan(self.accept_scan(scan)?)))
            }
            "ODOM" => {
                let odometry = parse_odom(&mut fields)?;
                self.odom_lines = true;
                Ok(Some(LogRecord::Odometry(odometry)))
            }
            other if is_record_name(other) => {
                *self.skipped.entry(other.to_owned()).or_default() += 1;
                Ok(None)
            }
            _ => Err(LineError::new(
                line,
                format!("not a CARMEN record: {}", snippet(text)),
            )),
        }
    }

    /// Refuses a scan that does not come after the previous one (the pipeline's stamps only
    /// move forward) and fills in the time since it.
    fn accept_scan(&mut self, mut scan: ScanRecord) -> Result<ScanRecord, LineError> {
        if let Some((stamp, line)) = self.last_scan {
            if scan.stamp_ns <= stamp {
                return Err(LineError::new(
                    scan.line,
                    format!("scan stamp is not after the previous scan's (line {line})"),
                ));
            }
            scan.geometry.scan_time = (scan.stamp_ns - stamp) as f64 * 1e-9;
        }
        self.last_scan = Some((scan.stamp_ns, scan.line));
        Ok(scan)
    }
}

impl<R: BufRead> Iterator for CarmenReader<R> {
    type Item = Result<LogRecord, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(record) = self.pending.take() {
            return Some(Ok(record));
        }
        if self.failed {
            return None;
        }
        loop {
            let (line, text) = match self.lines.next_line() {
                Ok(Some((line, Ok(text)))) => (line, text.to_owned()),
                Ok(Some((_, Err(e)))) => return Some(Err(e.into())),
                Ok(None) => return None,
                Err(e) => {
                    self.failed = true;
                    return Some(Err(e.into()));
                }
            };
            let trimmed = text.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            match self.parse_line(line, trimmed) {
                Ok(Some(record)) => return Some(Ok(record)),
                Ok(None) => {}
                Err(e) => return Some(Err(e.into())),
            }
        }
    }
}

/// CARMEN record names are upper-case words (`PARAM`, `RAWLASER1`, `NMEAGGA`).
fn is_record_name(token: &str) -> bool {
    let mut bytes = token.bytes();
    bytes.next().is_some_and(|b| b.is_ascii_uppercase())
        && bytes.all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_')
}

/// The fields of one record after its name, read front to back with errors that say which
/// field of which record on which line is wrong.
struct Fields<'a> {
    line: u64,
    kind: &'a str,
    tokens: &'a [&'a str],
    next: usize,
}

impl<'a> Fields<'a> {
    fn new(line: u64, kind: &'a str, tokens: &'a [&'a str]) -> Self {
        Self {
            line,
            kind,
            tokens,
            next: 0,
        }
    }

    fn error(&self, reason: impl std::fmt::Display) -> LineError {
        LineError::new(self.line, format!("{}: {reason}", self.kind))
    }

    fn token(&mut self, what: &str) -> Result<&'a str, LineError> {
        let token = self.tokens.get(self.next).copied().ok_or_else(|| {
            self.error(format_args!(
                "ends after {} fields, before {what}",
                self.tokens.len()
            ))
        })?;
        self.next += 1;
        Ok(token)
    }

    fn number(&mut self, what: &str) -> Result<f64, LineError> {
        let token = self.token(what)?;
        token
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.error(format_args!("{what}: {} is not a number", snippet(token))))
    }

    fn count(&mut self, what: &str) -> Result<usize, LineError> {
        let token = self.token(what)?;
        token
            .parse::<usize>()
            .map_err(|_| self.error(format_args!("{what}: {} is not a count", snippet(token))))
    }

    /// `n` ranges in metres, as REP 117 values against `range_max`.
    fn ranges(&mut self, n: usize, range_max: f64) -> Result<Vec<f32>, LineError> {
        let mut ranges = Vec::with_capacity(n);
        for beam in 1..=n {
            let token = self.token("the last range")?;
            // Straight to f32, the message's type, so no value is rounded twice.
            let range = token
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    self.error(format_args!(
                        "range {beam}: {} is not a number",
                        snippet(token)
                    ))
                })?;
            ranges.push(rep117_range(range, range_max));
        }
        Ok(ranges)
    }

    fn beam_count(&mut self, at_least: usize) -> Result<usize, LineError> {
        let n = self.count("the beam count")?;
        if n < at_least || n > ipc_types::MAX_BEAMS {
            return Err(self.error(format_args!(
                "{n} beams; a scan needs {at_least} to {}",
                ipc_types::MAX_BEAMS
            )));
        }
        Ok(n)
    }

    fn stamp(&mut self) -> Result<u64, LineError> {
        let token = self.token("ipc_timestamp")?;
        parse_stamp_ns(token).map_err(|e| self.error(format_args!("ipc_timestamp: {e}")))
    }

    /// Skips fields this reader does not use (they must still be there).
    fn skip(&mut self, what: &str, count: usize) -> Result<(), LineError> {
        for _ in 0..count {
            self.token(what)?;
        }
        Ok(())
    }

    /// The hostname and logger timestamp that end every record, and nothing after them.
    fn finish(&mut self) -> Result<(), LineError> {
        self.skip("hostname and logger_timestamp", 2)?;
        if self.next != self.tokens.len() {
            return Err(self.error(format_args!(
                "{} fields, expected {}",
                self.tokens.len(),
                self.next
            )));
        }
        Ok(())
    }
}

/// A logged range as a REP 117 range: a zero or negative reading is an error (NaN), one at
/// or beyond the maximum range means nothing was hit (+inf).
fn rep117_range(range: f32, range_max: f64) -> f32 {
    if range <= 0.0 {
        f32::NAN
    } else if f64::from(range) >= range_max {
        f32::INFINITY
    } else {
        range
    }
}

fn parse_flaser(fields: &mut Fields<'_>) -> Result<(OdometryRecord, ScanRecord), LineError> {
    let n = fields.beam_count(2)?;
    let ranges = fields.ranges(n, FLASER_RANGE_MAX)?;
    // The first pose may be corrected by a localizer; the raw odometry follows it.
    fields.skip("x y theta", 3)?;
    let x = fields.number("odom_x")?;
    let y = fields.number("odom_y")?;
    let theta = fields.number("odom_theta")?;
    let stamp_ns = fields.stamp()?;
    fields.finish()?;
    let line = fields.line;
    let odometry = OdometryRecord {
        line,
        stamp_ns,
        x,
        y,
        yaw: wrap_angle(theta),
        linear_velocity: 0.0,
        angular_velocity: 0.0,
    };
    let scan = ScanRecord {
        line,
        stamp_ns,
        // 180 degrees from the right (-y) to the left (+y), both ends included.
        geometry: ScanGeometry {
            angle_min: -PI / 2.0,
            angle_increment: PI / (n - 1) as f64,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.0,
            range_max: FLASER_RANGE_MAX,
        },
        ranges,
        intensities: Vec::new(),
    };
    Ok((odometry, scan))
}

fn parse_robotlaser1(fields: &mut Fields<'_>) -> Result<ScanRecord, LineError> {
    fields.skip("the laser type", 1)?;
    let start_angle = fields.number("start_angle")?;
    let _fov = fields.number("fov")?;
    let angular_res = fields.number("angular_res")?;
    let max_range = fields.number("max_range")?;
    if angular_res == 0.0 {
        return Err(fields.error("angular_res is 0"));
    }
    if max_range <= 0.0 {
        return Err(fields.error(format_args!("max_range {max_range} is not positive")));
    }
    fields.skip("accuracy and remission_mode", 2)?;
    let n = fields.beam_count(1)?;
    let ranges = fields.ranges(n, max_range)?;
    let m = fields.count("the remission count")?;
    let mut remissions = Vec::with_capacity(m.min(n));
    for index in 1..=m {
        remissions.push(fields.number(&format!("remission {index}"))? as f32);
    }
    // Remissions are the beams' intensities only when there is one per beam.
    if remissions.len() != n {
        remissions.clear();
    }
    fields.skip(
        "laser pose, robot pose, tv, rv, forward_safety, side_safety, turn_axis",
        11,
    )?;
    let stamp_ns = fields.stamp()?;
    fields.finish()?;
    Ok(ScanRecord {
        line: fields.line,
        stamp_ns,
        // CARMEN places beam i at start_angle + i * angular_res, as here.
        geometry: ScanGeometry {
            angle_min: start_angle,
            angle_increment: angular_res,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.0,
            range_max: max_range,
        },
        ranges,
        intensities: remissions,
    })
}

fn parse_odom(fields: &mut Fields<'_>) -> Result<OdometryRecord, LineError> {
    let x = fields.number("x")?;
    let y = fields.number("y")?;
    let theta = fields.number("theta")?;
    let tv = fields.number("tv")?;
    let rv = fields.number("rv")?;
    fields.skip("accel", 1)?;
    let stamp_ns = fields.stamp()?;
    fields.finish()?;
    Ok(OdometryRecord {
        line: fields.line,
        stamp_ns,
        x,
        y,
        yaw: wrap_angle(theta),
        linear_velocity: tv,
        angular_velocity: rv,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Vec<Result<LogRecord, String>> {
        CarmenReader::new(text.as_bytes())
            .map(|r| r.map_err(|e| e.to_string()))
            .collect()
    }

    fn flaser(ranges: &[&str], odom: &str, stamp: &str) -> String {
        format!(
            "FLASER {} {} 9 9 9 {odom} {stamp} b21 0.086295",
            ranges.len(),
            ranges.join(" ")
        )
    }

    #[test]
    fn flaser_gives_odometry_then_its_scan_with_one_exact_stamp() {
        let line = flaser(
            &["1.40", "81.91", "0.00", "42.40", "80.00"],
            "576.536523 0.106594 -2.255213",
            "1134864629.895182",
        );
        let records = read(&line);
        assert_eq!(records.len(), 2);
        let Ok(LogRecord::Odometry(odometry)) = &records[0] else {
            panic!("{records:?}");
        };
        let Ok(LogRecord::Scan(scan)) = &records[1] else {
            panic!("{records:?}");
        };
        assert_eq!(odometry.stamp_ns, 1_134_864_629_895_182_000);
        assert_eq!(scan.stamp_ns, odometry.stamp_ns);
        assert_eq!((odometry.x, odometry.y), (576.536523, 0.106594));
        assert_eq!(odometry.yaw, -2.255213);
        assert_eq!(scan.ranges[0], 1.40);
        assert_eq!(scan.ranges[1], f32::INFINITY, "81.91 m = no return");
        assert!(scan.ranges[2].is_nan(), "0 = error");
        assert_eq!(scan.ranges[3], 42.40);
        assert_eq!(scan.ranges[4], f32::INFINITY, "at the maximum range");
        assert_eq!(scan.geometry.angle_min, -PI / 2.0);
        assert_eq!(scan.geometry.angle_increment, PI / 4.0);
        assert_eq!((scan.line, odometry.line), (1, 1));
    }

    #[test]
    fn mit_csail_geometry_is_half_degree_steps_from_the_right() {
        let ranges = vec!["1.0"; 361];
        let records = read(&flaser(&ranges, "0 0 0", "1.0"));
        let Ok(LogRecord::Scan(scan)) = &records[1] else {
            panic!("{records:?}");
        };
        assert!((scan.geometry.angle_increment - 0.5_f64.to_radians()).abs() < 1e-15);
        let last = scan.geometry.angle_min + 360.0 * scan.geometry.angle_increment;
        assert!((last - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn robotlaser1_brings_its_own_geometry_and_remissions() {
        let line = "ROBOTLASER1 0 -1.25 2.5 0.0125 50.0 0.01 0 3 1.5 50.0 2.5 \
                    3 10 20 30 0.1 0 0 1 2 0.5 0.3 0.1 0 0 0 0.000001 host 5.5";
        let records = read(line);
        let Ok(LogRecord::Scan(scan)) = &records[0] else {
            panic!("{records:?}");
        };
        assert_eq!(records.len(), 1, "no odometry from ROBOTLASER1");
        assert_eq!(scan.stamp_ns, 1_000);
        assert_eq!(scan.geometry.angle_min, -1.25);
        assert_eq!(scan.geometry.angle_increment, 0.0125);
        assert_eq!(scan.geometry.range_max, 50.0);
        assert_eq!(scan.ranges, vec![1.5, f32::INFINITY, 2.5]);
        assert_eq!(scan.intensities, vec![10.0, 20.0, 30.0]);

        let without = "ROBOTLASER1 0 -1.5 3.0 1.5 50.0 0.01 0 3 1 2 3 0 \
                       0 0 0 1 2 0.5 0.3 0.1 0 0 0 7.25 host 5.5";
        let records = read(without);
        let Ok(LogRecord::Scan(scan)) = &records[0] else {
            panic!("{records:?}");
        };
        assert!(scan.intensities.is_empty());
        assert_eq!(scan.stamp_ns, 7_250_000_000);
    }

    #[test]
    fn after_an_odom_line_flaser_odometry_is_not_replayed() {
        let text = [
            flaser(&["1", "2"], "5 5 0", "10.0"),
            "ODOM 1 0 0 0 0 0 10.05 host 0".to_owned(),
            // ACES copies the last ODOM reading into the next FLASER, stale.
            flaser(&["1", "2"], "1 0 0", "10.1"),
            "ODOM 2 0 0 0 0 0 10.15 host 0".to_owned(),
        ]
        .join("\n");
        let kinds: Vec<(&str, u64)> = read(&text)
            .iter()
            .map(|r| match r {
                Ok(LogRecord::Odometry(o)) => ("odometry", o.line),
                Ok(LogRecord::Scan(s)) => ("scan", s.line),
                Err(e) => panic!("{e}"),
            })
            .collect();
        assert_eq!(
            kinds,
            [
                ("odometry", 1),
                ("scan", 1),
                ("odometry", 2),
                ("scan", 3),
                ("odometry", 4)
            ]
        );
    }

    #[test]
    fn odom_lines_carry_velocities_and_wrapped_yaw() {
        let records = read("ODOM 1.5 -2 3.5 0.4 -0.1 0 1058295543.123456 host 0.5\n");
        let Ok(LogRecord::Odometry(odometry)) = &records[0] else {
            panic!("{records:?}");
        };
        assert_eq!(odometry.stamp_ns, 1_058_295_543_123_456_000);
        assert_eq!((odometry.x, odometry.y), (1.5, -2.0));
        assert!((odometry.yaw - (3.5 - 2.0 * PI)).abs() < 1e-12);
        assert_eq!(
            (odometry.linear_velocity, odometry.angular_velocity),
            (0.4, -0.1)
        );
    }

    #[test]
    fn comments_and_other_records_are_skipped_and_bad_lines_named() {
        let text = [
            "# a comment".to_owned(),
            "PARAM robot_length 0.5 nohost 0".to_owned(),
            String::new(),
            flaser(&["1", "2"], "0 0 0", "10.5"),
            "FLASER 3 1 2".to_owned(),
            flaser(&["1", "x"], "0 0 0", "11.5"),
            "ODOM 1 2 3 0 0 0 -12.0 host 0".to_owned(),
            "14029,14083,14083".to_owned(),
            "SYNC tag 0 host 0".to_owned(),
            "  # indented comment".to_owned(),
            flaser(&["1", "2"], "0 0 0", "10.5"),
            flaser(&["1", "2"], "0 0 0", "12.000000001"),
            flaser(&["1", "2"], "0 0 0", "13.0") + " extra",
        ]
        .join("\n");
        let mut reader = CarmenReader::new(text.as_bytes());
        let records: Vec<_> = reader
            .by_ref()
            .map(|r| r.map_err(|e| e.to_string()))
            .collect();
        let summary: Vec<String> = records
            .iter()
            .map(|r| match r {
                Ok(LogRecord::Scan(s)) => format!("scan {} {}", s.line, s.stamp_ns),
                Ok(LogRecord::Odometry(o)) => format!("odom {} {}", o.line, o.stamp_ns),
                Err(e) => e.clone(),
            })
            .collect();
        assert_eq!(
            summary,
            vec![
                "odom 4 10500000000",
                "scan 4 10500000000",
                "line 5: FLASER: ends after 3 fields, before the last range",
                "line 6: FLASER: range 2: \"x\" is not a number",
                "line 7: ODOM: ipc_timestamp: \"-12.0\" is not a timestamp in seconds \
                 (expected digits before the decimal point)",
                "line 8: not a CARMEN record: \"14029,14083,14083\"",
                "line 11: scan stamp is not after the previous scan's (line 4)",
                "odom 12 12000000001",
                "scan 12 12000000001",
                "line 13: FLASER: 13 fields, expected 12",
            ]
        );
        assert_eq!(
            reader.skipped_records().iter().collect::<Vec<_>>(),
            vec![(&"PARAM".to_owned(), &1), (&"SYNC".to_owned(), &1)]
        );
    }

    #[test]
    fn a_scan_knows_the_time_since_the_previous_one() {
        let text = [
            flaser(&["1", "2"], "0 0 0", "10.0"),
            flaser(&["1", "2"], "0 0 0", "10.25"),
        ]
        .join("\n");
        let scans: Vec<ScanRecord> = read(&text)
            .into_iter()
            .filter_map(|r| match r {
                Ok(LogRecord::Scan(s)) => Some(s),
                _ => None,
            })
            .collect();
        assert_eq!(scans[0].geometry.scan_time, 0.0);
        assert_eq!(scans[1].geometry.scan_time, 0.25);
    }

    #[test]
    fn impossible_beam_counts_are_refused() {
        let records = read("FLASER 1 1.0 0 0 0 0 0 0 1.0 h 0\nFLASER 9000 1.0");
        assert_eq!(
            records[0].as_ref().err().map(String::as_str),
            Some("line 1: FLASER: 1 beams; a scan needs 2 to 8192")
        );
        assert_eq!(
            records[1].as_ref().err().map(String::as_str),
            Some("line 2: FLASER: 9000 beams; a scan needs 2 to 8192")
        );
    }
}
