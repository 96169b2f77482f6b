//! The first scans of a CARMEN log, read once before the replay starts for the judgements
//! made from them: which odometry to publish ([`crate::odometry_judge`]) and in what order
//! the scans go ([`crate::scan_order`]).

use std::collections::BTreeMap;
use std::io::BufRead;

use crate::carmen::{FrontLaser, Parsed, parse_record};
use crate::lines::{NumberedLines, StopFlag};
use crate::odometry_judge::{self, Directions};
use crate::record::OdometryRecord;
use crate::scan_order::{self, Profile};

/// Scans read at most: a few minutes of a log, enough to judge by, and a bound on the time
/// before the replay starts.
pub const MAX_SCANS: usize = 4000;

/// Bytes of the log read at most, so that a log with huge or endless lines does not hold
/// up the replay's start.
pub const MAX_BYTES: u64 = 64 << 20;

/// One scan of the start, in the log's order: what the judgements need of it.
#[derive(Debug, Clone)]
pub(crate) struct StartScan {
    /// The log's stamp.
    pub stamp_ns: u64,
    /// Its wall directions, for its turn.
    pub directions: Directions,
    /// Its ranges, thinned, to tell how far it is from another scan.
    pub profile: Profile,
    /// The odometry reading its line carries.
    pub own: Option<OdometryRecord>,
}

/// The start of a log: its first [`MAX_SCANS`] scans in the log's order and the `ODOM`
/// readings up to the last of them.
#[derive(Debug, Clone, Default)]
pub(crate) struct LogStart {
    pub scans: Vec<StartScan>,
    pub odom: Vec<OdometryRecord>,
}

/// Reads the start of the CARMEN log `reader` reads; malformed lines are passed over (the
/// replay reports them), and the end, a read error or a stop ends it.
pub(crate) fn read<R: BufRead>(reader: R, stop: StopFlag) -> LogStart {
    let mut lines = NumberedLines::new(reader.take(MAX_BYTES));
    lines.set_stop(stop);
    let mut skipped = BTreeMap::new();
    let mut mount = FrontLaser::default();
    let mut start = LogStart::default();
    while start.scans.len() < MAX_SCANS {
        let parsed = match lines.next_line() {
            Ok(Some((line, Ok(text)))) => {
                let text = text.trim();
                if text.is_empty() || text.starts_with('#') {
                    continue;
                }
                parse_record(line, text, &mut skipped, &mut mount)
            }
            Ok(Some((_, Err(_)))) => continue,
            Ok(None) | Err(_) => break,
        };
        match parsed {
            Ok(Some(Parsed::Scan(scan, own))) => start.scans.push(StartScan {
                stamp_ns: scan.stamp_ns,
                directions: odometry_judge::directions(&scan),
                profile: scan_order::profile(&scan),
                own,
            }),
            Ok(Some(Parsed::Odom(reading))) => start.odom.push(reading),
            _ => {}
        }
    }
    start
}
