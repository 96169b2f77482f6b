//! Which of a CARMEN log's odometry sources to publish, and on what clock, judged by the
//! scans before the replay starts.
//!
//! A log's odometry stamps need not be the times of the readings: a logger may stamp them
//! when it writes them (in bursts, readings a millisecond apart each a few centimetres on),
//! its clock may run ahead of or behind the laser's, and a scan line's own reading may be
//! the last one received rather than one taken with the scan. The scans themselves say
//! which is right: the turn between two consecutive scans is measured from the scans alone
//! (the shift between their histograms of wall directions, which the robot's translation
//! does not change), and each candidate (the `ODOM` lines, the scan lines' readings, each
//! with a clock lead from [`-MAX_LEAD_S`, `MAX_LEAD_S`]) is scored by how far its turns
//! over the same pairs of scans differ from the scans'. The candidate that differs least is
//! published. Only the turn is compared: it needs no map, and the wheels' distance scale and
//! the laser's mount do not change it.

use std::f64::consts::PI;
use std::io::BufRead;

use slam_geom::wrap_angle;

use crate::carmen::{OdometryChoice, OdometrySource};
use crate::lines::StopFlag;
use crate::record::{OdometryRecord, ScanRecord};
use crate::start::{self, LogStart};

/// Bytes of the log the judgement reads at most ([`start::MAX_BYTES`]).
pub const MAX_BYTES: u64 = start::MAX_BYTES;

/// The largest clock lead looked for, seconds, either way.
pub const MAX_LEAD_S: f64 = 1.0;

/// Step of the leads tried, seconds.
const LEAD_STEP_S: f64 = 0.01;

/// Bins of the wall-direction histogram over half a turn (walls have no sense).
const BINS: usize = 180;

/// The largest turn between consecutive scans measured, in bins (degrees).
const MAX_SHIFT: usize = 45;

/// Neighbouring points further apart than this are not one wall, metres.
const MAX_GAP: f64 = 0.3;

/// A pair's difference counts at most this much, radians: a scan pair the histogram
/// misreads (a scan of clutter) is one vote, not a veto.
const MAX_DIFFERENCE: f64 = 0.1;

/// The scans must have turned at least this much in all for a verdict, radians.
const MIN_TOTAL_TURN: f64 = 1.0;

/// What the judgement found.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    pub choice: OdometryChoice,
    /// Mean difference, radians per scan pair, of each source at its best lead.
    pub odom_lines: Option<(f64, i64)>,
    pub scan_lines: Option<(f64, i64)>,
    /// Share of consecutive `ODOM` readings faster than a robot (stamped in bursts).
    pub odom_bursts: f64,
}

impl Verdict {
    /// One line for the console: what was found and chosen.
    pub fn describe(&self) -> String {
        let source = match self.choice.source {
            OdometrySource::Auto => {
                return "odometry: as the log gives it (too few turns to judge)".into();
            }
            OdometrySource::OdomLines => "ODOM lines",
            OdometrySource::ScanLines => "the scan lines' readings",
        };
        let mut text = format!("odometry: using {source}");
        if self.odom_lines.is_some() && self.odom_bursts > 0.1 {
            text.push_str(&format!(
                " (ODOM lines stamped in bursts: {:.0} % of steps faster than a robot)",
                100.0 * self.odom_bursts
            ));
        }
        let lead = self.choice.lead_ns as f64 * 1e-9;
        if lead.abs() >= 2.0 * LEAD_STEP_S {
            let (way, by) = if lead > 0.0 {
                ("leads", lead)
            } else {
                ("lags", -lead)
            };
            text.push_str(&format!("; it {way} the laser by {by:.2} s, corrected"));
        }
        text
    }
}

/// Judges the odometry of the CARMEN log `reader` reads; malformed lines are passed over
/// (the replay reports them). `None` when the log has no odometry at all.
pub fn judge<R: BufRead>(reader: R, stop: StopFlag) -> Option<Verdict> {
    judge_start(&start::read(reader, stop))
}

/// Judges the odometry of a log by its start.
pub(crate) fn judge_start(start: &LogStart) -> Option<Verdict> {
    let LogStart { scans, odom } = start;
    let own: Vec<OdometryRecord> = scans.iter().filter_map(|scan| scan.own).collect();
    if own.is_empty() && odom.is_empty() {
        return None;
    }
    let turns = scan_turns(scans);
    let stamps: Vec<u64> = scans.iter().map(|scan| scan.stamp_ns).collect();
    let total: f64 = turns.iter().flatten().map(|t| t.abs()).sum();
    let interval = median_interval_ns(&stamps);
    let judge =
        |readings: Vec<OdometryRecord>| best_lead(&by_stamp(readings), &stamps, &turns, interval);
    let odom_bursts = bursts(&by_stamp(odom.clone()));
    let odom_lines = (!odom.is_empty()).then(|| judge(odom.clone()));
    let scan_lines = (own.len() == scans.len()).then(|| judge(own));
    let choice = if total < MIN_TOTAL_TURN {
        OdometryChoice::default()
    } else {
        match (odom_lines, scan_lines) {
            (Some((a, lead)), Some((b, _))) if a <= b => OdometryChoice {
                source: OdometrySource::OdomLines,
                lead_ns: lead,
            },
            (_, Some((_, lead))) => OdometryChoice {
                source: OdometrySource::ScanLines,
                lead_ns: lead,
            },
            (Some((_, lead)), None) => OdometryChoice {
                source: OdometrySource::OdomLines,
                lead_ns: lead,
            },
            (None, None) => OdometryChoice::default(),
        }
    };
    Some(Verdict {
        choice,
        odom_lines,
        scan_lines,
        odom_bursts,
    })
}

/// A scan's histogram of wall directions.
pub(crate) type Directions = [f64; BINS];

fn by_stamp(mut readings: Vec<OdometryRecord>) -> Vec<OdometryRecord> {
    readings.sort_by_key(|r| r.stamp_ns);
    readings
}

/// Share of consecutive readings (that moved) faster than 10 m/s.
fn bursts(readings: &[OdometryRecord]) -> f64 {
    let (mut fast, mut moved) = (0usize, 0usize);
    for pair in readings.windows(2) {
        let distance = (pair[1].x - pair[0].x).hypot(pair[1].y - pair[0].y);
        if distance > 1e-4 {
            moved += 1;
            let dt = pair[1].stamp_ns.saturating_sub(pair[0].stamp_ns) as f64 * 1e-9;
            if distance > 10.0 * dt {
                fast += 1;
            }
        }
    }
    fast as f64 / moved.max(1) as f64
}

/// The histogram of wall directions of a scan: each pair of neighbouring points on one
/// wall adds its length at its direction (modulo half a turn), split between two bins.
pub(crate) fn directions(scan: &ScanRecord) -> Directions {
    let g = &scan.geometry;
    let mut histogram = [0.0; BINS];
    let mut previous: Option<(f64, f64)> = None;
    for (i, &range) in scan.ranges.iter().enumerate() {
        let range = f64::from(range);
        if !(range.is_finite() && range >= g.range_min && range <= g.range_max) {
            previous = None;
            continue;
        }
        let bearing = g.angle_min + i as f64 * g.angle_increment;
        let point = (range * bearing.cos(), range * bearing.sin());
        if let Some(p) = previous {
            let (dx, dy) = (point.0 - p.0, point.1 - p.1);
            let length = dx.hypot(dy);
            if length > 1e-3 && length < MAX_GAP {
                let bin = dy.atan2(dx).rem_euclid(PI) / PI * BINS as f64;
                let low = bin.floor();
                let share = bin - low;
                histogram[low as usize % BINS] += length * (1.0 - share);
                histogram[(low as usize + 1) % BINS] += length * share;
            }
        }
        previous = Some(point);
    }
    histogram
}

/// The turn between each scan and the one before it (file order), radians: the shift that
/// best lines up their wall directions, refined between bins; `None` for the first scan or
/// a scan with no walls.
fn scan_turns(scans: &[start::StartScan]) -> Vec<Option<f64>> {
    let mut turns = vec![None];
    for pair in scans.windows(2) {
        turns.push(turn_between(&pair[0].directions, &pair[1].directions));
    }
    turns
}

fn turn_between(before: &[f64; BINS], after: &[f64; BINS]) -> Option<f64> {
    // A robot that turned left by w sees its walls w further right: after(d) = before(d + w).
    let score = |shift: isize| -> f64 {
        (0..BINS)
            .map(|d| after[d] * before[(d as isize + shift).rem_euclid(BINS as isize) as usize])
            .sum()
    };
    let shifts = -(MAX_SHIFT as isize)..=MAX_SHIFT as isize;
    let (best, peak) = shifts
        .map(|s| (s, score(s)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    if peak <= 0.0 {
        return None;
    }
    let (left, right) = (score(best - 1), score(best + 1));
    let curvature = left - 2.0 * peak + right;
    let offset = if curvature < 0.0 {
        0.5 * (left - right) / curvature
    } else {
        0.0
    };
    Some((best as f64 + offset) * PI / BINS as f64)
}

/// The lead (nanoseconds) at which `readings` turn most like the scans, and their mean
/// difference per pair of scans there. A lead shorter than the time between scans is taken
/// as none: within one scan the fit outweighs the wheels' timing, and the scans' turns
/// locate so short a lead least surely.
fn best_lead(
    readings: &[OdometryRecord],
    stamps: &[u64],
    turns: &[Option<f64>],
    interval_ns: u64,
) -> (f64, i64) {
    let steps = (MAX_LEAD_S / LEAD_STEP_S).round() as i64;
    let best = (-steps..=steps)
        .map(|k| {
            let lead_ns = (k as f64 * LEAD_STEP_S * 1e9).round() as i64;
            (difference(readings, stamps, turns, lead_ns), lead_ns)
        })
        // Nearest to no lead among equals: a lead is a finding, not a default.
        .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.abs().cmp(&b.1.abs())))
        .unwrap_or((f64::INFINITY, 0));
    if best.1.unsigned_abs() < interval_ns {
        (difference(readings, stamps, turns, 0), 0)
    } else {
        best
    }
}

/// The median time between consecutive scans (file order) that are apart at all.
fn median_interval_ns(stamps: &[u64]) -> u64 {
    let mut intervals: Vec<u64> = stamps
        .windows(2)
        .map(|w| w[1].saturating_sub(w[0]))
        .filter(|&dt| dt > 0)
        .collect();
    intervals.sort_unstable();
    intervals.get(intervals.len() / 2).copied().unwrap_or(0)
}

/// The mean, over pairs of consecutive scans, of the (clipped) difference between the
/// scans' turn and the readings' turn over the same times, the readings `lead_ns` ahead.
fn difference(
    readings: &[OdometryRecord],
    stamps: &[u64],
    turns: &[Option<f64>],
    lead_ns: i64,
) -> f64 {
    let yaw_at = |stamp: u64| yaw_at(readings, stamp.saturating_add_signed(lead_ns));
    let (mut sum, mut count) = (0.0, 0usize);
    for (k, turn) in turns.iter().enumerate().skip(1) {
        let (Some(turn), Some(a), Some(b)) = (turn, yaw_at(stamps[k - 1]), yaw_at(stamps[k]))
        else {
            continue;
        };
        sum += wrap_angle(wrap_angle(b - a) - turn)
            .abs()
            .min(MAX_DIFFERENCE);
        count += 1;
    }
    if count == 0 {
        f64::INFINITY
    } else {
        sum / count as f64
    }
}

/// The readings' yaw at `stamp`, interpolated; `None` outside them.
fn yaw_at(readings: &[OdometryRecord], stamp: u64) -> Option<f64> {
    let after = readings.partition_point(|r| r.stamp_ns < stamp);
    let b = readings.get(after)?;
    if b.stamp_ns == stamp || after == 0 {
        return (b.stamp_ns == stamp).then_some(b.yaw);
    }
    let a = &readings[after - 1];
    let share = (stamp - a.stamp_ns) as f64 / (b.stamp_ns - a.stamp_ns) as f64;
    Some(a.yaw + share * wrap_angle(b.yaw - a.yaw))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_log::{flaser, odom, pose};

    #[test]
    fn a_clock_lead_of_half_a_second_either_way_is_found() {
        for lead in [0.5, -0.5] {
            let mut log = String::new();
            for k in 0..300 {
                let t = 100.0 + 0.1 * f64::from(k);
                // The scan lines' readings stand still: only the ODOM lines tell the turns.
                log += &flaser(t, (0.0, 0.0, 0.0), pose(t));
                log += &odom(t + lead + 0.05, pose(t + 0.05));
            }
            let verdict = judge(log.as_bytes(), crate::lines::never).expect("odometry");
            assert_eq!(verdict.choice.source, OdometrySource::OdomLines);
            let found = verdict.choice.lead_ns as f64 * 1e-9;
            assert!((found - lead).abs() <= 0.02, "lead {lead}: found {found}");
            assert!(
                verdict.describe().contains("corrected"),
                "{}",
                verdict.describe()
            );
        }
    }

    #[test]
    fn odom_lines_stamped_in_bursts_lose_to_the_scan_lines_readings() {
        let mut log = String::new();
        for k in 0..300 {
            let t = 100.0 + 0.1 * f64::from(k);
            log += &flaser(t, pose(t), pose(t));
            // Readings every 50 ms, written (and stamped) four at a time, a millisecond apart.
            for j in 0..2 {
                let taken = t + 0.05 * f64::from(j);
                let written = 100.0
                    + 0.2 * ((taken - 100.0) / 0.2).floor()
                    + 0.001 * f64::from(k % 2 * 2 + j);
                log += &odom(written, pose(taken));
            }
        }
        let verdict = judge(log.as_bytes(), crate::lines::never).expect("odometry");
        assert_eq!(verdict.choice.source, OdometrySource::ScanLines);
        assert_eq!(verdict.choice.lead_ns, 0);
        assert!(verdict.odom_bursts > 0.5, "{}", verdict.odom_bursts);
        assert!(
            verdict.describe().contains("stamped in bursts"),
            "{}",
            verdict.describe()
        );
    }

    #[test]
    fn odometry_on_time_is_left_on_time() {
        let mut log = String::new();
        for k in 0..300 {
            let t = 100.0 + 0.1 * f64::from(k);
            log += &flaser(t, pose(t), pose(t));
        }
        let verdict = judge(log.as_bytes(), crate::lines::never).expect("odometry");
        assert_eq!(
            verdict.choice,
            OdometryChoice {
                source: OdometrySource::ScanLines,
                lead_ns: 0
            }
        );
        let (difference, _) = verdict.scan_lines.expect("judged");
        assert!(difference < 0.01, "{difference}");
    }

    #[test]
    fn a_log_without_odometry_has_no_verdict() {
        assert_eq!(
            judge("PARAM a 1 h 0\n".as_bytes(), crate::lines::never),
            None
        );
    }
}
