//! CARMEN logs (`.clf`): `FLASER`, `ROBOTLASER1` and `ODOM` lines become scans and odometry;
//! `#` comments and every other record type (`PARAM`, `SYNC`, `RAWLASER1`, ...) are skipped.
//!
//! Line formats (whitespace-separated; poses in metres and radians, ranges in metres):
//! * `FLASER n r1 .. rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp`
//!   (a SICK LMS over 180 degrees, beam 1 at -90 degrees, the step given by the beam count:
//!   [`flaser_angle_increment`]; `odom_*` is the raw wheel odometry);
//! * `ROBOTLASER1 type start_angle fov angular_res max_range accuracy remission_mode n r1 .. rn
//!   m rem1 .. remm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
//!   forward_safety side_safety turn_axis ipc_timestamp hostname logger_timestamp` (its
//!   geometry is the line's own and may change from one line to the next);
//! * `ODOM x y theta tv rv accel ipc_timestamp hostname logger_timestamp`.
//!
//! Stamps are the `ipc_timestamp`, kept to the nanosecond. Records come out in time order
//! within a window ([`crate::reorder`]): a line written after later ones is put in its
//! place, and one too late for that, or repeating a stamp, is dropped and counted. Scans
//! keep the log's order instead when the scans show that it is the order they were taken in
//! ([`crate::scan_order`]), one stamped late going out under a stamp between its neighbours'.
//!
//! A log may carry two odometry sources: `ODOM` lines, and the reading a scan line holds
//! (`odom_*` of `FLASER`, `robot_*` of `ROBOTLASER1`, taken with the scan). One of them is
//! published, as [`OdometryChoice`] says: the replay judges them by the scans before it
//! starts ([`crate::odometry_judge`]), and corrects the chosen source's clock by the offset
//! found. A scan line's reading goes out right before its scan, with the scan's stamp.
//! Unjudged ([`OdometrySource::Auto`]), the scan lines' readings are used until the log gives
//! an `ODOM` line, and the `ODOM` lines from then on. The laser's mounting offset (`laser_*`
//! against `robot_*`) is not used: the pipeline's sensor frame is the robot frame.

use std::collections::{BTreeMap, VecDeque};
use std::f64::consts::{PI, TAU};
use std::io::BufRead;

use crate::error::{LineError, Malformation, ReadError};
use crate::lines::{NumberedLines, snippet};
use crate::odometry_judge::Verdict;
use crate::record::{LogRecord, OdometryRecord, ScanGeometry, ScanRecord};
use crate::reorder::{Entry, ReorderConfig, ReorderCounts, ReorderWindow};
use crate::scan_order::OrderVerdict;
use slam_geom::wrap_angle;
use slam_geom::{Pose2, parse_stamp_ns};

/// Longest range of a `FLASER` scan; readings at or beyond it become +inf (no return). The
/// SICK LMS 2xx of these logs reports "no return" as 81.91 m (8191 cm, its largest code),
/// but CARMEN loggers that clip at their `laser_max_range` write that value instead, and
/// those readings are no returns, not walls. Real returns beyond 50 m are rare indoors and
/// lose only a point, where a phantom return would add one.
pub const FLASER_RANGE_MAX: f64 = 50.0;

/// Bearing step of a `FLASER` scan, from its beam count: the SICK LMS modes over a 180-degree
/// field, 1 degree for 180 or 181 beams, 0.5 for 360 or 361, 0.25 for 721. `None` for a
/// count no mode has. (A count of 180 or 360 is a mode with the last beam left out, so its
/// last beam falls one step short of +90 degrees.)
pub fn flaser_angle_increment(beams: usize) -> Option<f64> {
    let degrees = match beams {
        180 | 181 => 1.0,
        360 | 361 => 0.5,
        721 => 0.25,
        _ => return None,
    };
    Some(f64::to_radians(degrees))
}

/// Reads the scans and odometry of a CARMEN log, put in time order within a
/// [`ReorderConfig`] window (see [`crate::reorder`]).
#[derive(Debug)]
pub struct CarmenReader<R> {
    /// The log's lines; [`crate::LogReader`] sets the stop and reads the counts here.
    pub(crate) lines: NumberedLines<R>,
    window: ReorderWindow,
    /// Which odometry is published, and its clock's offset.
    odometry: OdometryChoice,
    /// The judgement the choice came from, for the console.
    verdict: Option<Verdict>,
    /// The judgement of the scans' order, if they were judged.
    order: Option<OrderVerdict>,
    /// The `FLASER` laser's mount, from the log's `PARAM` lines so far.
    front_laser: FrontLaser,
    /// Whether an `ODOM` line has been read (what [`OdometrySource::Auto`] goes by).
    odom_lines: bool,
    /// Records let out of the window and not yet handed out (a `FLASER`'s scan waits behind
    /// its odometry).
    ready: VecDeque<LogRecord>,
    /// Stamp of the last scan handed out, for the time between scans.
    last_scan: Option<u64>,
    skipped: BTreeMap<String, u64>,
    /// The end of the file (or a read error) has been reached: only the window is left.
    ended: bool,
    /// A stop was requested: nothing more comes out.
    stopped: bool,
}

impl<R: BufRead> CarmenReader<R> {
    /// A reader with the default reordering window.
    pub fn new(reader: R) -> Self {
        Self::with_reorder(reader, ReorderConfig::default())
    }

    pub fn with_reorder(reader: R, reorder: ReorderConfig) -> Self {
        Self {
            lines: NumberedLines::new(reader),
            window: ReorderWindow::new(reorder),
            ready: VecDeque::new(),
            odometry: OdometryChoice::default(),
            verdict: None,
            order: None,
            front_laser: FrontLaser::default(),
            odom_lines: false,
            last_scan: None,
            skipped: BTreeMap::new(),
            ended: false,
            stopped: false,
        }
    }

    /// Publishes the odometry `choice` names (by default [`OdometrySource::Auto`]).
    pub fn with_odometry(mut self, choice: OdometryChoice) -> Self {
        self.odometry = choice;
        self
    }

    /// Keeps the judgement the odometry choice came from.
    pub(crate) fn judged(mut self, verdict: Verdict) -> Self {
        self.verdict = Some(verdict);
        self
    }

    /// What the judgement of the odometry found, if it was judged.
    pub fn verdict(&self) -> Option<&Verdict> {
        self.verdict.as_ref()
    }

    /// Orders the scans among themselves as `verdict` found.
    pub(crate) fn with_scan_order(mut self, verdict: OrderVerdict) -> Self {
        self.window.set_scan_order(verdict.order);
        self.order = Some(verdict);
        self
    }

    /// What the judgement of the scans' order found, if they were judged.
    pub fn order_verdict(&self) -> Option<&OrderVerdict> {
        self.order.as_ref()
    }

    /// Record types skipped so far (`PARAM`, `SYNC`, ...) and how many lines of each.
    pub fn skipped_records(&self) -> &BTreeMap<String, u64> {
        &self.skipped
    }

    /// What putting the records in time order has reordered and dropped so far.
    pub fn reorder_counts(&self) -> &ReorderCounts {
        self.window.counts()
    }

    /// The window the records are put in order with.
    pub fn reorder_config(&self) -> ReorderConfig {
        self.window.config()
    }

    /// Queues what the window let out, filling in the time since the previous scan.
    fn hand_out(&mut self, entry: Entry) {
        let mut with_scan_time = |mut scan: ScanRecord| {
            if let Some(previous) = self.last_scan {
                scan.geometry.scan_time = (scan.stamp_ns - previous) as f64 * 1e-9;
            }
            self.last_scan = Some(scan.stamp_ns);
            LogRecord::Scan(scan)
        };
        match entry {
            Entry::Odometry(odometry) => self.ready.push_back(LogRecord::Odometry(odometry)),
            Entry::Scan(scan) => {
                let scan = with_scan_time(scan);
                self.ready.push_back(scan);
            }
            Entry::OdometryAndScan(odometry, scan) => {
                let scan = with_scan_time(scan);
                self.ready.push_back(LogRecord::Odometry(odometry));
                self.ready.push_back(scan);
            }
        }
    }
}

/// Where a log's published odometry comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OdometrySource {
    /// The scan lines' own readings until an `ODOM` line appears, the `ODOM` lines after.
    #[default]
    Auto,
    /// `ODOM` lines only.
    OdomLines,
    /// The reading in each scan line only (`FLASER` `odom_*`, `ROBOTLASER1` `robot_*`).
    ScanLines,
}

/// The odometry a replay publishes, and by how much its stamps lead the laser's: a reading
/// stamped `t` was taken at `t - lead_ns` in the laser's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OdometryChoice {
    pub source: OdometrySource,
    pub lead_ns: i64,
}

impl OdometryChoice {
    /// `odometry` on the laser's clock.
    fn on_laser_clock(&self, mut odometry: OdometryRecord) -> OdometryRecord {
        odometry.stamp_ns = odometry.stamp_ns.saturating_add_signed(-self.lead_ns);
        odometry
    }
}

/// Where a log's `FLASER` laser sits: `PARAM robot_frontlaser_offset` metres ahead of the
/// robot's origin, facing forward (CARMEN's convention); at the origin until a log says.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct FrontLaser {
    offset: f64,
}

impl FrontLaser {
    fn robot_from_sensor(&self) -> Pose2 {
        Pose2::new(self.offset, 0.0, 0.0)
    }

    /// Takes the offset from a `PARAM name value ...` line's fields, if it names it with a
    /// finite value (a malformed PARAM is one the replay does not use anyway).
    fn read_param(&mut self, fields: &[&str]) {
        if let ["robot_frontlaser_offset", value, ..] = fields
            && let Ok(offset) = value.parse::<f64>()
            && offset.is_finite()
        {
            self.offset = offset;
        }
    }
}

/// One CARMEN record this reader uses.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Parsed {
    /// A scan and the odometry reading its line carries, if any.
    Scan(ScanRecord, Option<OdometryRecord>),
    /// An `ODOM` line.
    Odom(OdometryRecord),
}

/// Parses one non-comment line: `Ok(None)` for a record type that is skipped (and counted in
/// `skipped`).
pub(crate) fn parse_record(
    line: u64,
    text: &str,
    skipped: &mut BTreeMap<String, u64>,
    mount: &mut FrontLaser,
) -> Result<Option<Parsed>, LineError> {
    let tokens: Vec<&str> = text.split_whitespace().collect();
    let Some(&kind) = tokens.first() else {
        return Ok(None);
    };
    let mut fields = Fields::new(line, kind, &tokens[1..]);
    let parsed = match kind {
        "FLASER" => {
            let (odometry, mut scan) = parse_flaser(&mut fields)?;
            scan.robot_from_sensor = mount.robot_from_sensor();
            Parsed::Scan(scan, Some(odometry))
        }
        "ROBOTLASER1" => {
            let (odometry, scan) = parse_robotlaser1(&mut fields)?;
            Parsed::Scan(scan, Some(odometry))
        }
        "ODOM" => Parsed::Odom(parse_odom(&mut fields)?),
        other if is_record_name(other) => {
            if other == "PARAM" {
                mount.read_param(&tokens[1..]);
            }
            *skipped.entry(other.to_owned()).or_default() += 1;
            return Ok(None);
        }
        _ => {
            return Err(LineError::new(
                line,
                Malformation::NotARecord,
                format!("not a CARMEN record: {}", snippet(text)),
            ));
        }
    };
    Ok(Some(parsed))
}

/// What a parsed record puts in the window under the odometry `choice`; `odom_lines` says
/// whether an `ODOM` line has been read (set here).
fn entry(parsed: Parsed, choice: &OdometryChoice, odom_lines: &mut bool) -> Option<Entry> {
    use OdometrySource::{Auto, OdomLines, ScanLines};
    match (parsed, choice.source) {
        (Parsed::Scan(scan, Some(odometry)), ScanLines) => Some(Entry::OdometryAndScan(
            choice.on_laser_clock(odometry),
            scan,
        )),
        (Parsed::Scan(scan, Some(odometry)), Auto) if !*odom_lines => {
            Some(Entry::OdometryAndScan(odometry, scan))
        }
        (Parsed::Scan(scan, _), _) => Some(Entry::Scan(scan)),
        (Parsed::Odom(odometry), Auto | OdomLines) => {
            *odom_lines = true;
            Some(Entry::Odometry(choice.on_laser_clock(odometry)))
        }
        (Parsed::Odom(_), ScanLines) => None,
    }
}

impl<R: BufRead> Iterator for CarmenReader<R> {
    type Item = Result<LogRecord, ReadError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.stopped {
            return None;
        }
        loop {
            if let Some(record) = self.ready.pop_front() {
                return Some(Ok(record));
            }
            let released = if self.ended {
                self.window.pop_any()
            } else {
                self.window.pop_ready()
            };
            if let Some(entry) = released {
                self.hand_out(entry);
                continue;
            }
            if self.ended {
                return None;
            }
            let Self {
                lines,
                skipped,
                odom_lines,
                odometry,
                front_laser,
                ..
            } = self;
            let parsed = match lines.next_line() {
                Ok(Some((line, Ok(text)))) => {
                    let text = text.trim();
                    if text.is_empty() || text.starts_with('#') {
                        continue;
                    }
                    parse_record(line, text, skipped, front_laser)
                        .map(|parsed| parsed.and_then(|p| entry(p, odometry, odom_lines)))
                }
                Ok(Some((_, Err(e)))) => Err(e),
                Ok(None) => {
                    self.ended = true;
                    continue;
                }
                Err(ReadError::Stopped) => {
                    // Stopped means stopped: what the window holds is not let out either.
                    self.stopped = true;
                    return Some(Err(ReadError::Stopped));
                }
                Err(e) => {
                    // Nothing after a read error can be trusted to be read; what the window
                    // holds still comes out after the error.
                    self.ended = true;
                    return Some(Err(e));
                }
            };
            match parsed {
                Ok(Some(entry)) => self.window.push(entry),
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

    fn error(&self, problem: Malformation, reason: impl std::fmt::Display) -> LineError {
        LineError::new(self.line, problem, format!("{}: {reason}", self.kind)).in_record(self.kind)
    }

    fn token(&mut self, what: &str) -> Result<&'a str, LineError> {
        let token = self.tokens.get(self.next).copied().ok_or_else(|| {
            self.error(
                Malformation::MissingFields,
                format_args!("ends after {} fields, before {what}", self.tokens.len()),
            )
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
            .ok_or_else(|| {
                self.error(
                    Malformation::NotANumber,
                    format_args!("{what}: {} is not a number", snippet(token)),
                )
            })
    }

    fn count(&mut self, what: &str) -> Result<usize, LineError> {
        let token = self.token(what)?;
        token.parse::<usize>().map_err(|_| {
            self.error(
                Malformation::NotANumber,
                format_args!("{what}: {} is not a count", snippet(token)),
            )
        })
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
                    self.error(
                        Malformation::NotANumber,
                        format_args!("range {beam}: {} is not a number", snippet(token)),
                    )
                })?;
            ranges.push(rep117_range(range, range_max));
        }
        Ok(ranges)
    }

    fn beam_count(&mut self, at_least: usize) -> Result<usize, LineError> {
        let n = self.count("the beam count")?;
        if n < at_least || n > ipc_types::MAX_BEAMS {
            return Err(self.error(
                Malformation::BeamCount,
                format_args!(
                    "{n} beams; a scan needs {at_least} to {}",
                    ipc_types::MAX_BEAMS
                ),
            ));
        }
        Ok(n)
    }

    fn stamp(&mut self) -> Result<u64, LineError> {
        let token = self.token("ipc_timestamp")?;
        parse_stamp_ns(token)
            .map_err(|e| self.error(Malformation::BadStamp, format_args!("ipc_timestamp: {e}")))
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
            return Err(self.error(
                Malformation::ExtraFields,
                format_args!("{} fields, expected {}", self.tokens.len(), self.next),
            ));
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
    let Some(angle_increment) = flaser_angle_increment(n) else {
        return Err(fields.error(
            Malformation::BeamCount,
            format_args!(
                "{n} beams match no SICK LMS mode (180 or 181 at 1 degree, 360 or 361 at \
                 0.5, 721 at 0.25)"
            ),
        ));
    };
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
        log_covariance: [0.0; 9],
    };
    let scan = ScanRecord {
        line,
        stamp_ns,
        log_stamp_ns: stamp_ns,
        // Beam 1 on the right (-y), counter-clockwise in the mode's steps.
        geometry: ScanGeometry {
            angle_min: -PI / 2.0,
            angle_increment,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.0,
            range_max: FLASER_RANGE_MAX,
        },
        ranges,
        intensities: Vec::new(),
        // Set by the reader from the log's `robot_frontlaser_offset`.
        robot_from_sensor: Pose2::IDENTITY,
    };
    Ok((odometry, scan))
}

fn parse_robotlaser1(fields: &mut Fields<'_>) -> Result<(OdometryRecord, ScanRecord), LineError> {
    fields.skip("the laser type", 1)?;
    let start_angle = fields.number("start_angle")?;
    let _fov = fields.number("fov")?;
    let angular_res = fields.number("angular_res")?;
    let max_range = fields.number("max_range")?;
    if angular_res == 0.0 {
        return Err(fields.error(Malformation::BadGeometry, "angular_res is 0"));
    }
    if max_range <= 0.0 {
        return Err(fields.error(
            Malformation::BadGeometry,
            format_args!("max_range {max_range} is not positive"),
        ));
    }
    fields.skip("accuracy and remission_mode", 2)?;
    let n = fields.beam_count(1)?;
    // More than a turn would put two beams on one bearing: the geometry is wrong, not the
    // scan unusual.
    if (n - 1) as f64 * angular_res.abs() > TAU + 1e-9 {
        return Err(fields.error(
            Malformation::BadGeometry,
            format_args!("{n} beams of {angular_res} rad span more than a full turn"),
        ));
    }
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
    let laser = Pose2::new(
        fields.number("laser_x")?,
        fields.number("laser_y")?,
        wrap_angle(fields.number("laser_theta")?),
    );
    let x = fields.number("robot_x")?;
    let y = fields.number("robot_y")?;
    let theta = fields.number("robot_theta")?;
    let linear_velocity = fields.number("tv")?;
    let angular_velocity = fields.number("rv")?;
    fields.skip("forward_safety, side_safety, turn_axis", 3)?;
    let stamp_ns = fields.stamp()?;
    fields.finish()?;
    let odometry = OdometryRecord {
        line: fields.line,
        stamp_ns,
        x,
        y,
        yaw: wrap_angle(theta),
        linear_velocity,
        angular_velocity,
        log_covariance: [0.0; 9],
    };
    let scan = ScanRecord {
        line: fields.line,
        stamp_ns,
        log_stamp_ns: stamp_ns,
        // CARMEN places beam i at start_angle + i * angular_res, as here; each line has its
        // own, which may differ from the previous line's.
        geometry: ScanGeometry {
            angle_min: wrap_angle(start_angle),
            angle_increment: angular_res,
            time_increment: 0.0,
            scan_time: 0.0,
            range_min: 0.0,
            range_max: max_range,
        },
        ranges,
        intensities: remissions,
        // The laser's pose against the robot's, both by the same odometry.
        robot_from_sensor: odometry.pose().between(&laser),
    };
    Ok((odometry, scan))
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
        log_covariance: [0.0; 9],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reorder::Records;

    fn read(text: &str) -> Vec<Result<LogRecord, String>> {
        CarmenReader::new(text.as_bytes())
            .map(|r| r.map_err(|e| e.to_string()))
            .collect()
    }

    /// A `FLASER` line of 180 beams (a 1-degree mode), the first ones `ranges`, the rest 1 m.
    fn flaser(ranges: &[&str], odom: &str, stamp: &str) -> String {
        flaser_of(180, ranges, odom, stamp)
    }

    fn flaser_of(beams: usize, ranges: &[&str], odom: &str, stamp: &str) -> String {
        let mut all: Vec<&str> = ranges.to_vec();
        all.resize(beams, "1.0");
        format!(
            "FLASER {beams} {} 9 9 9 {odom} {stamp} b21 0.086295",
            all.join(" ")
        )
    }

    /// What a reader yields, one short line each: `odom LINE STAMP`, `scan LINE STAMP` or
    /// the error; and what its window counted.
    fn outline(text: &str, reorder: ReorderConfig) -> (Vec<String>, ReorderCounts) {
        let mut reader = CarmenReader::with_reorder(text.as_bytes(), reorder);
        let lines = reader
            .by_ref()
            .map(|r| match r {
                Ok(LogRecord::Scan(s)) => format!("scan {} {}", s.line, s.stamp_ns),
                Ok(LogRecord::Odometry(o)) => format!("odom {} {}", o.line, o.stamp_ns),
                Err(e) => e.to_string(),
            })
            .collect();
        (lines, *reader.reorder_counts())
    }

    fn records(scans: u64, odometry: u64) -> Records {
        Records { scans, odometry }
    }

    const SECOND: u64 = 1_000_000_000;

    #[test]
    fn flaser_gives_odometry_then_its_scan_with_one_exact_stamp() {
        let line = flaser(
            &["1.40", "81.91", "0.00", "42.40", "80.00", "50.00", "49.99"],
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
        assert_eq!(scan.ranges[4], f32::INFINITY, "beyond the maximum range");
        assert_eq!(scan.ranges[5], f32::INFINITY, "ACES's 50 m = no return");
        assert_eq!(scan.ranges[6], 49.99);
        assert_eq!(scan.geometry.angle_min, -PI / 2.0);
        assert_eq!(scan.geometry.angle_increment, 1.0_f64.to_radians());
        assert_eq!((scan.line, odometry.line), (1, 1));
    }

    #[test]
    fn mit_csail_geometry_is_half_degree_steps_from_the_right() {
        let records = read(&flaser_of(361, &[], "0 0 0", "1.0"));
        let Ok(LogRecord::Scan(scan)) = &records[1] else {
            panic!("{records:?}");
        };
        assert!((scan.geometry.angle_increment - 0.5_f64.to_radians()).abs() < 1e-15);
        let last = scan.geometry.angle_min + 360.0 * scan.geometry.angle_increment;
        assert!((last - PI / 2.0).abs() < 1e-12);
    }

    #[test]
    fn flaser_geometry_follows_the_sick_modes_and_other_counts_are_refused() {
        // (beams, step in degrees, bearing of the last beam in degrees)
        let modes = [
            (180, 1.0, 89.0_f64),
            (181, 1.0, 90.0),
            (360, 0.5, 89.5),
            (361, 0.5, 90.0),
            (721, 0.25, 90.0),
        ];
        for (beams, step, last) in modes {
            let records = read(&flaser_of(beams, &[], "0 0 0", "1.0"));
            let Some(Ok(LogRecord::Scan(scan))) = records.get(1) else {
                panic!("{beams} beams: {records:?}");
            };
            let geometry = scan.geometry;
            assert_eq!(
                geometry.angle_min,
                -PI / 2.0,
                "{beams} beams: beam 1 on the right"
            );
            assert!(
                (geometry.angle_increment - f64::to_radians(step)).abs() < 1e-15,
                "{beams} beams: {} rad",
                geometry.angle_increment
            );
            let end = geometry.angle_min + (beams - 1) as f64 * geometry.angle_increment;
            assert!(
                (end - last.to_radians()).abs() < 1e-12,
                "{beams} beams end at {end}"
            );
        }
        let text = [5, 179, 362, 720]
            .iter()
            .enumerate()
            .map(|(k, &beams)| flaser_of(beams, &[], "0 0 0", &format!("{}.0", k + 1)))
            .chain([flaser(&[], "0 0 0", "9.0")])
            .collect::<Vec<_>>()
            .join("\n");
        let mut reader = CarmenReader::new(text.as_bytes());
        let results: Vec<_> = reader.by_ref().collect();
        let errors: Vec<(String, String)> = results
            .iter()
            .filter_map(|r| match r {
                Err(ReadError::Line(e)) => Some((e.to_string(), e.category())),
                _ => None,
            })
            .collect();
        assert_eq!(errors.len(), 4, "{results:?}");
        assert_eq!(
            errors[0],
            (
                "line 1: FLASER: 5 beams match no SICK LMS mode (180 or 181 at 1 degree, 360 \
                 or 361 at 0.5, 721 at 0.25)"
                    .to_owned(),
                "FLASER: impossible beam count".to_owned()
            )
        );
        assert!(
            errors[3]
                .0
                .starts_with("line 4: FLASER: 720 beams match no")
        );
        assert_eq!(results.len(), 6, "the good line after them is read");
    }

    #[test]
    fn robotlaser1_brings_its_own_geometry_and_remissions() {
        let line = "ROBOTLASER1 0 -1.25 2.5 0.0125 50.0 0.01 0 3 1.5 50.0 2.5 \
                    3 10 20 30 0.1 0 0 1 2 0.5 0.3 0.1 0 0 0 0.000001 host 5.5";
        let records = read(line);
        let [Ok(LogRecord::Odometry(odometry)), Ok(LogRecord::Scan(scan))] = &records[..] else {
            panic!("{records:?}");
        };
        // Without ODOM lines the robot pose of the line is the odometry, at the scan's stamp.
        assert_eq!(odometry.pose(), slam_geom::Pose2::new(1.0, 2.0, 0.5));
        assert_eq!(
            (odometry.linear_velocity, odometry.angular_velocity),
            (0.3, 0.1)
        );
        assert_eq!(odometry.stamp_ns, 1_000);
        assert_eq!(scan.stamp_ns, 1_000);
        assert_eq!(scan.geometry.angle_min, -1.25);
        assert_eq!(scan.geometry.angle_increment, 0.0125);
        assert_eq!(scan.geometry.range_max, 50.0);
        assert_eq!(scan.ranges, vec![1.5, f32::INFINITY, 2.5]);
        assert_eq!(scan.intensities, vec![10.0, 20.0, 30.0]);

        let without = "ROBOTLASER1 0 -1.5 3.0 1.5 50.0 0.01 0 3 1 2 3 0 \
                       0 0 0 1 2 0.5 0.3 0.1 0 0 0 7.25 host 5.5";
        let records = read(without);
        let Ok(LogRecord::Scan(scan)) = &records[1] else {
            panic!("{records:?}");
        };
        assert!(scan.intensities.is_empty());
        assert_eq!(scan.stamp_ns, 7_250_000_000);
    }

    #[test]
    fn the_front_laser_offset_places_flaser_scans_on_the_robot() {
        let text = [
            flaser(&[], "0 0 0", "1.0"),
            "PARAM robot_frontlaser_offset 0.25 host 0".to_owned(),
            "PARAM robot_frontlaser_offset nonsense host 0".to_owned(),
            flaser(&[], "0 0 0", "1.1"),
        ]
        .join("\n");
        let mounts: Vec<Pose2> = read(&text)
            .into_iter()
            .filter_map(|r| match r {
                Ok(LogRecord::Scan(scan)) => Some(scan.robot_from_sensor),
                _ => None,
            })
            .collect();
        assert_eq!(mounts, [Pose2::IDENTITY, Pose2::new(0.25, 0.0, 0.0)]);
    }

    #[test]
    fn robotlaser1_places_its_laser_by_the_laser_and_robot_poses() {
        // The laser at (1.2, 2.1, 0.6) where the robot is at (1, 2, 0.5).
        let line = "ROBOTLASER1 0 -1.5 3.0 1.5 50.0 0.01 0 3 1 2 3 0 \
                    1.2 2.1 0.6 1 2 0.5 0.3 0.1 0 0 0 7.25 host 5.5";
        let records = read(line);
        let Ok(LogRecord::Scan(scan)) = &records[1] else {
            panic!("{records:?}");
        };
        let robot = Pose2::new(1.0, 2.0, 0.5);
        let laser = robot.compose(&scan.robot_from_sensor);
        assert!((laser.x - 1.2).abs() < 1e-12 && (laser.y - 2.1).abs() < 1e-12);
        assert!((laser.yaw - 0.6).abs() < 1e-12);
    }

    #[test]
    fn odom_lines_take_over_from_the_scan_lines_readings_unless_judged_otherwise() {
        let text = [
            robotlaser1(-1.5, 0.5, 8.0, &["1", "2", "3"], "1.0"),
            "ODOM 5 6 0.2 0 0 0 1.05 host 0".to_owned(),
            robotlaser1(-1.5, 0.5, 8.0, &["1", "2", "3"], "1.1"),
        ]
        .join("\n");
        let kinds = |choice: OdometryChoice| -> Vec<(char, u64)> {
            CarmenReader::new(text.as_bytes())
                .with_odometry(choice)
                .map(|r| match r.expect("well-formed") {
                    LogRecord::Odometry(o) => ('o', o.stamp_ns),
                    LogRecord::Scan(s) => ('s', s.stamp_ns),
                })
                .collect()
        };
        let auto = kinds(OdometryChoice::default());
        assert_eq!(
            auto,
            [
                ('o', 1_000_000_000),
                ('s', 1_000_000_000),
                ('o', 1_050_000_000),
                ('s', 1_100_000_000)
            ]
        );
        let scan_lines = kinds(OdometryChoice {
            source: OdometrySource::ScanLines,
            lead_ns: 0,
        });
        assert_eq!(
            scan_lines,
            [
                ('o', 1_000_000_000),
                ('s', 1_000_000_000),
                ('o', 1_100_000_000),
                ('s', 1_100_000_000)
            ]
        );
        // ODOM lines 20 ms ahead of the laser: their reading is put 20 ms earlier.
        let odom = kinds(OdometryChoice {
            source: OdometrySource::OdomLines,
            lead_ns: 20_000_000,
        });
        assert_eq!(
            odom,
            [
                ('s', 1_000_000_000),
                ('o', 1_030_000_000),
                ('s', 1_100_000_000)
            ]
        );
    }

    /// A `ROBOTLASER1` line with `ranges`, no remissions, stamped `stamp`.
    fn robotlaser1(start: f64, res: f64, max_range: f64, ranges: &[&str], stamp: &str) -> String {
        format!(
            "ROBOTLASER1 0 {start} {} {res} {max_range} 0.01 0 {} {} 0 \
             0.1 0 0 1 2 0.5 0.3 0.1 0 0 0 {stamp} host 0",
            res * (ranges.len() - 1) as f64,
            ranges.len(),
            ranges.join(" ")
        )
    }

    #[test]
    fn robotlaser1_geometry_may_change_from_line_to_line() {
        let text = [
            robotlaser1(-1.5, 0.5, 8.0, &["1", "8", "3", "4", "5", "6", "7"], "1.0"),
            robotlaser1(-0.5, 0.25, 30.0, &["1", "8", "3", "4", "5"], "1.1"),
            // Another mounting: counter-clockwise from behind, unwrapped in the log.
            robotlaser1(3.5, 0.125, 80.0, &["1", "8"], "1.2"),
            robotlaser1(-1.5, 0.5, 8.0, &["1", "8", "3", "4", "5", "6", "7"], "1.3"),
            // 40 beams of 10 degrees overlap themselves: refused, reading goes on.
            robotlaser1(-PI, 10f64.to_radians(), 8.0, &["1"; 40], "1.4"),
        ]
        .join("\n");
        let records = read(&text);
        let scans: Vec<&ScanRecord> = records
            .iter()
            .filter_map(|r| match r {
                Ok(LogRecord::Scan(scan)) => Some(scan),
                _ => None,
            })
            .collect();
        let geometry: Vec<(f64, f64, f64, usize)> = scans
            .iter()
            .map(|s| {
                let g = s.geometry;
                (g.angle_min, g.angle_increment, g.range_max, s.ranges.len())
            })
            .collect();
        assert_eq!(
            geometry,
            vec![
                (-1.5, 0.5, 8.0, 7),
                (-0.5, 0.25, 30.0, 5),
                (wrap_angle(3.5), 0.125, 80.0, 2),
                (-1.5, 0.5, 8.0, 7),
            ]
        );
        assert!(wrap_angle(3.5) < 0.0, "wrapped to [-pi, pi)");
        // 8 m is "no return" on the 8 m lines only.
        assert_eq!(scans[0].ranges[1], f32::INFINITY);
        assert_eq!(scans[1].ranges[1], 8.0);
        assert_eq!(scans[2].ranges[1], 8.0);
        assert_eq!(scans[3].ranges[1], f32::INFINITY);
        let Some(Err(refused)) = records.first() else {
            panic!("{records:?}");
        };
        assert!(
            refused.starts_with("line 5: ROBOTLASER1: 40 beams of 0.17453"),
            "{refused}"
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
            flaser(&[], "0 0 0", "10.5"),
            "FLASER 180 1 2".to_owned(),
            flaser(&["1", "x"], "0 0 0", "11.5"),
            "ODOM 1 2 3 0 0 0 -12.0 host 0".to_owned(),
            "14029,14083,14083".to_owned(),
            "SYNC tag 0 host 0".to_owned(),
            "  # indented comment".to_owned(),
            flaser(&[], "0 0 0", "10.5"),
            flaser(&[], "0 0 0", "12.000000001"),
            flaser(&[], "0 0 0", "13.0") + " extra",
        ]
        .join("\n");
        let mut reader = CarmenReader::new(text.as_bytes());
        let results: Vec<_> = reader.by_ref().collect();
        let summary: Vec<String> = results
            .iter()
            .map(|r| match r {
                Ok(LogRecord::Scan(s)) => format!("scan {} {}", s.line, s.stamp_ns),
                Ok(LogRecord::Odometry(o)) => format!("odom {} {}", o.line, o.stamp_ns),
                Err(ReadError::Line(e)) => format!("{e} [{}]", e.category()),
                Err(e) => e.to_string(),
            })
            .collect();
        // Errors come as the lines are read; records once their window has passed (here at
        // the end, all being within 2 s).
        assert_eq!(
            summary,
            vec![
                "line 5: FLASER: ends after 3 fields, before the last range \
                 [FLASER: fields missing]",
                "line 6: FLASER: range 2: \"x\" is not a number [FLASER: a field is not a number]",
                "line 7: ODOM: ipc_timestamp: \"-12.0\" is not a timestamp in seconds \
                 (expected digits before the decimal point) [ODOM: bad timestamp]",
                "line 8: not a CARMEN record: \"14029,14083,14083\" [not a record of the format]",
                "line 13: FLASER: 191 fields, expected 190 [FLASER: extra fields]",
                "odom 4 10500000000",
                "scan 4 10500000000",
                "odom 12 12000000001",
                "scan 12 12000000001",
            ]
        );
        assert_eq!(
            reader.skipped_records().iter().collect::<Vec<_>>(),
            vec![(&"PARAM".to_owned(), &1), (&"SYNC".to_owned(), &1)]
        );
        assert_eq!(
            reader.reorder_counts().duplicate,
            records(1, 1),
            "line 11 repeats line 4"
        );
    }

    #[test]
    fn a_scan_knows_the_time_since_the_previous_one_in_time_order() {
        let text = [
            flaser(&[], "0 0 0", "10.0"),
            flaser(&[], "0 0 0", "10.5"),
            flaser(&[], "0 0 0", "10.25"),
        ]
        .join("\n");
        let scans: Vec<ScanRecord> = read(&text)
            .into_iter()
            .filter_map(|r| match r {
                Ok(LogRecord::Scan(s)) => Some(s),
                _ => None,
            })
            .collect();
        let times: Vec<(u64, f64)> = scans
            .iter()
            .map(|s| (s.line, s.geometry.scan_time))
            .collect();
        assert_eq!(times, vec![(1, 0.0), (3, 0.25), (2, 0.25)]);
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

    #[test]
    fn after_an_odom_line_flaser_odometry_is_not_replayed() {
        let text = [
            flaser(&[], "5 5 0", "10.0"),
            "ODOM 1 0 0 0 0 0 10.05 host 0".to_owned(),
            // ACES copies the last ODOM reading into the next FLASER, stale.
            flaser(&[], "1 0 0", "10.1"),
            "ODOM 2 0 0 0 0 0 10.15 host 0".to_owned(),
        ]
        .join("\n");
        let (lines, _) = outline(&text, ReorderConfig::default());
        assert_eq!(
            lines,
            vec![
                "odom 1 10000000000",
                "scan 1 10000000000",
                "odom 2 10050000000",
                "scan 3 10100000000",
                "odom 4 10150000000",
            ]
        );
    }

    #[test]
    fn a_log_in_time_order_comes_out_as_it_is() {
        let text = [
            flaser(&[], "0 0 0", "10.0"),
            "ODOM 0 0 0 0 0 0 10.05 host 0".to_owned(),
            flaser(&[], "0 0 0", "10.1"),
            flaser(&[], "0 0 0", "10.2"),
        ]
        .join("\n");
        let (lines, counts) = outline(&text, ReorderConfig::default());
        assert_eq!(
            lines,
            vec![
                "odom 1 10000000000",
                "scan 1 10000000000",
                "odom 2 10050000000",
                // After an ODOM line, FLASER odometry is no longer used.
                "scan 3 10100000000",
                "scan 4 10200000000",
            ]
        );
        assert_eq!(counts, ReorderCounts::default());
    }

    #[test]
    fn lines_that_go_back_within_the_window_are_put_in_order() {
        // As in ACES: an ODOM line written before the FLASER taken before it.
        let text = [
            flaser(&[], "0 0 0", "10.0"),
            flaser(&[], "0 0 0", "10.5"),
            "ODOM 0 0 0 0 0 0 10.2 host 0".to_owned(),
            flaser(&[], "0 0 0", "10.3"),
            flaser(&[], "0 0 0", "11.9"),
        ]
        .join("\n");
        let (lines, counts) = outline(&text, ReorderConfig::default());
        assert_eq!(
            lines,
            vec![
                "odom 1 10000000000",
                "scan 1 10000000000",
                "odom 3 10200000000",
                "scan 4 10300000000",
                "odom 2 10500000000",
                "scan 2 10500000000",
                "scan 5 11900000000",
            ]
        );
        assert_eq!(counts.reordered, records(1, 1));
        assert_eq!(counts.late.total() + counts.duplicate.total(), 0);
    }

    #[test]
    fn a_line_later_than_the_window_is_dropped() {
        let text = [
            flaser(&[], "0 0 0", "10.0"),
            // More than 2 s on: 10.0 goes out.
            flaser(&[], "0 0 0", "12.5"),
            // Older than what went out: too late.
            flaser(&[], "0 0 0", "9.5"),
            flaser(&[], "0 0 0", "12.8"),
            // Back by 0.8 s but after what went out: put in place.
            flaser(&[], "0 0 0", "12.0"),
            "ODOM 0 0 0 0 0 0 9.9 host 0".to_owned(),
        ]
        .join("\n");
        let (lines, counts) = outline(&text, ReorderConfig::default());
        assert_eq!(
            lines,
            vec![
                "odom 1 10000000000",
                "scan 1 10000000000",
                "odom 5 12000000000",
                "scan 5 12000000000",
                "odom 2 12500000000",
                "scan 2 12500000000",
                "odom 4 12800000000",
                "scan 4 12800000000",
            ]
        );
        assert_eq!(counts.late, records(1, 2));
        assert_eq!(counts.reordered, records(1, 1));

        // The same with a window of 0.25 s: 12.8 lets 12.5 out, so 12.0 is too late as well.
        let narrow = ReorderConfig {
            window_ns: SECOND / 4,
            ..ReorderConfig::default()
        };
        let (lines, counts) = outline(&text, narrow);
        assert_eq!(lines.len(), 6, "{lines:?}");
        assert_eq!(counts.late, records(2, 3));
        assert_eq!(counts.reordered, records(0, 0));
    }

    #[test]
    fn repeated_stamps_are_dropped_and_odometry_stays_before_its_scan() {
        let text = [
            flaser(&[], "0 0 0", "10.0"),
            // The same instant as the FLASER's odometry: a repeat.
            "ODOM 0 0 0 0 0 0 10.0 host 0".to_owned(),
            // A scan of a stamp already scanned.
            robotlaser1(-1.5, 0.5, 8.0, &["1", "2"], "10.0"),
            // An ODOM line first, then the FLASER of the same instant: its scan comes right
            // after that ODOM pose (its own odometry is not used after an ODOM line).
            "ODOM 0 0 0 0 0 0 10.5 host 0".to_owned(),
            flaser(&[], "0 0 0", "10.5"),
            // A FLASER scan again.
            flaser(&[], "0 0 0", "10.0"),
        ]
        .join("\n");
        let (lines, counts) = outline(&text, ReorderConfig::default());
        assert_eq!(
            lines,
            vec![
                "odom 1 10000000000",
                "scan 1 10000000000",
                "odom 4 10500000000",
                "scan 5 10500000000",
            ]
        );
        assert_eq!(counts.duplicate, records(2, 1));
        assert_eq!(
            counts.reordered,
            records(0, 0),
            "what went out is not counted"
        );
    }

    #[test]
    fn the_cap_bounds_what_is_held_and_lets_the_oldest_out_early() {
        let text = ["10.0", "10.4", "10.2", "10.1", "10.05"]
            .map(|stamp| flaser(&[], "0 0 0", stamp))
            .join("\n");
        let capped = ReorderConfig {
            max_held: 2,
            ..ReorderConfig::default()
        };
        let (lines, counts) = outline(&text, capped);
        let scans: Vec<&String> = lines.iter().filter(|l| l.starts_with("scan")).collect();
        assert_eq!(
            scans,
            vec![
                "scan 1 10000000000",
                "scan 4 10100000000",
                "scan 3 10200000000",
                "scan 2 10400000000",
            ]
        );
        // 10.0 went out when 10.2 came, 10.1 when it came itself; 10.05 was then too late.
        assert_eq!(counts.forced_out, records(2, 2));
        assert_eq!(counts.late, records(1, 1));
        assert_eq!(counts.reordered, records(2, 2));
        // Without the cap, the window alone would have placed every line.
        let (lines, counts) = outline(&text, ReorderConfig::default());
        assert_eq!(lines.len(), 10);
        assert_eq!(counts.late.total() + counts.forced_out.total(), 0);
    }
}
