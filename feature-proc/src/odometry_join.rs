//! Pairs each scan with the odometry pose at its stamp, as a function of the streams'
//! contents alone (docs/CONVENTIONS.md, "Joining streams").
//!
//! Odometry and scans travel on separate topics, so which of them a process sees first
//! depends on scheduling. The rule here does not: a scan's odometry is interpolated between
//! the last reading at or before its stamp and the first one after it, so a scan is
//! resolved only once the track holds a reading at or after its stamp, or the odometry
//! stream has ended. Beyond the ends of the track the pose is extrapolated from the two
//! readings nearest to that end, for at most [`MAX_EXTRAPOLATION_NS`].

use std::collections::VecDeque;

use nalgebra::Matrix3;
use slam_geom::Pose2;

/// Longest time a pose is extrapolated past the first or last odometry reading. Wheel
/// odometry runs at 10 Hz or faster; further out, the constant-velocity guess is worse than
/// holding the nearest reading.
pub const MAX_EXTRAPOLATION_NS: u64 = 200_000_000;

/// One odometry reading: `odom_from_robot` at `stamp_ns` and the covariance of that
/// integrated pose (docs/CONVENTIONS.md, "Odometry").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdometryReading {
    pub stamp_ns: u64,
    pub pose: Pose2,
    pub covariance: Matrix3<f64>,
}

/// Why [`OdometryTrack::push`] refused a reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RefusedReading {
    #[error("the odometry reading is not finite")]
    NotFinite,
    #[error("the odometry reading is older than one already received")]
    OutOfOrder,
    #[error("an odometry reading with this stamp was already received")]
    Duplicate,
}

/// The odometry readings received so far, in stamp order, and whether their stream ended.
#[derive(Debug, Clone, Default)]
pub struct OdometryTrack {
    readings: VecDeque<OdometryReading>,
    ended: bool,
}

impl OdometryTrack {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a reading, or says why it is refused. Readings must come in stamp order: one
    /// older than the newest held, or with its stamp, is refused. A scan is paired as soon as
    /// a reading at or after its stamp is held, so a later reading at or before that stamp
    /// would change the pairing depending on when the scan happened to be paired; refusing it
    /// makes the track a function of its own stream's order alone.
    pub fn push(&mut self, reading: OdometryReading) -> Result<(), RefusedReading> {
        let finite = [reading.pose.x, reading.pose.y, reading.pose.yaw]
            .iter()
            .chain(reading.covariance.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(RefusedReading::NotFinite);
        }
        match self.readings.back() {
            Some(last) if reading.stamp_ns < last.stamp_ns => Err(RefusedReading::OutOfOrder),
            Some(last) if reading.stamp_ns == last.stamp_ns => Err(RefusedReading::Duplicate),
            _ => {
                self.readings.push_back(reading);
                Ok(())
            }
        }
    }

    /// Marks the end of the odometry stream: nothing more will come.
    pub fn end(&mut self) {
        self.ended = true;
    }

    pub fn has_ended(&self) -> bool {
        self.ended
    }

    /// Readings held.
    pub fn len(&self) -> usize {
        self.readings.len()
    }

    pub fn is_empty(&self) -> bool {
        self.readings.is_empty()
    }

    /// Whether the pose at `stamp_ns` is final: a reading at or after it is held, or the
    /// stream has ended. Until then a later reading could still change it. A stamp before
    /// the first reading is extrapolated from the first two, so it waits for the second:
    /// with one alone the pose would depend on whether the next had come yet.
    pub fn resolves(&self, stamp_ns: u64) -> bool {
        let before_first = self
            .readings
            .front()
            .is_some_and(|first| stamp_ns < first.stamp_ns);
        self.ended
            || (self
                .readings
                .back()
                .is_some_and(|last| last.stamp_ns >= stamp_ns)
                && !(before_first && self.readings.len() < 2))
    }

    /// The odometry at `stamp_ns` from the readings held: interpolated between the two
    /// around it, extrapolated (for at most [`MAX_EXTRAPOLATION_NS`]) from the two nearest
    /// an end, the one reading itself if there is only one; `None` without readings. The
    /// covariance is blended like the pose (a convex combination keeps it positive
    /// definite) and held at the end's value when extrapolating.
    pub fn at(&self, stamp_ns: u64) -> Option<OdometryReading> {
        let n = self.readings.len();
        let after = self.readings.partition_point(|r| r.stamp_ns < stamp_ns);
        let (a, b) = match (after, n) {
            (_, 0) => return None,
            (_, 1) => return Some(self.readings[0].with_stamp(stamp_ns)),
            (0, _) => (&self.readings[0], &self.readings[1]),
            (i, _) if i == n => (&self.readings[n - 2], &self.readings[n - 1]),
            (i, _) => (&self.readings[i - 1], &self.readings[i]),
        };
        if b.stamp_ns == stamp_ns {
            return Some(*b);
        }
        let span = (b.stamp_ns - a.stamp_ns) as f64;
        let clamped = stamp_ns.clamp(
            a.stamp_ns.saturating_sub(MAX_EXTRAPOLATION_NS),
            b.stamp_ns.saturating_add(MAX_EXTRAPOLATION_NS),
        );
        let t = (clamped as f64 - a.stamp_ns as f64) / span;
        let w = t.clamp(0.0, 1.0);
        Some(OdometryReading {
            stamp_ns,
            pose: a.pose.interpolate(&b.pose, t),
            covariance: a.covariance * (1.0 - w) + b.covariance * w,
        })
    }

    /// Drops readings that no scan at or after `stamp_ns` needs: it keeps the last two at or
    /// before it (the bracket and the extrapolation at the start need no more).
    pub fn forget_before(&mut self, stamp_ns: u64) {
        let at_or_before = self.readings.partition_point(|r| r.stamp_ns <= stamp_ns);
        let drop = at_or_before.saturating_sub(2);
        self.readings.drain(..drop);
    }
}

impl OdometryReading {
    fn with_stamp(self, stamp_ns: u64) -> Self {
        Self { stamp_ns, ..self }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    fn reading(stamp_ms: u64, x: f64, yaw: f64) -> OdometryReading {
        OdometryReading {
            stamp_ns: stamp_ms * MS,
            pose: Pose2::new(x, 0.0, yaw),
            covariance: Matrix3::identity() * x.abs().max(0.01),
        }
    }

    fn push(track: &mut OdometryTrack, reading: OdometryReading) {
        track.push(reading).expect("an in-order, finite reading");
    }

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-12 && (a.y - b.y).abs() < 1e-12 && (a.yaw - b.yaw).abs() < 1e-12
    }

    #[test]
    fn a_stamp_before_the_first_reading_waits_for_the_second() {
        let mut track = OdometryTrack::new();
        push(&mut track, reading(100, 1.0, 0.0));
        // One reading would answer with itself; two extrapolate back from both. Resolving
        // early would make the answer depend on when the second came.
        assert!(!track.resolves(90 * MS));
        assert!(track.resolves(100 * MS));
        push(&mut track, reading(110, 2.0, 0.0));
        assert!(track.resolves(90 * MS));
        let at = track.at(90 * MS).expect("two readings");
        push(&mut track, reading(120, 3.0, 0.0));
        assert_eq!(track.at(90 * MS), Some(at), "later readings change nothing");
        let mut ended = OdometryTrack::new();
        push(&mut ended, reading(100, 1.0, 0.0));
        ended.end();
        assert!(ended.resolves(90 * MS), "nothing more will come");
    }

    #[test]
    fn odometry_after_its_scan_is_waited_for_then_interpolated() {
        let mut track = OdometryTrack::new();
        push(&mut track, reading(0, 0.0, 0.0));
        // The scan at 25 ms arrives before the reading at 50 ms: not resolved yet.
        assert!(!track.resolves(25 * MS));
        push(&mut track, reading(50, 1.0, 0.2));
        assert!(track.resolves(25 * MS));
        let at = track.at(25 * MS).unwrap();
        assert!(close(&at.pose, &Pose2::new(0.5, 0.0, 0.1)));
        assert_eq!(at.stamp_ns, 25 * MS);
        assert!((at.covariance[(0, 0)] - 0.505).abs() < 1e-12);
    }

    #[test]
    fn odometry_before_its_scan_and_at_its_stamp() {
        let mut track = OdometryTrack::new();
        for (t, x) in [(0, 0.0), (10, 0.1), (20, 0.2), (30, 0.3)] {
            push(&mut track, reading(t, x, 0.0));
        }
        // Everything already there: resolved at once, the same answer whatever came first.
        assert!(track.resolves(20 * MS));
        assert!(close(
            &track.at(20 * MS).unwrap().pose,
            &Pose2::new(0.2, 0.0, 0.0)
        ));
        assert!(close(
            &track.at(15 * MS).unwrap().pose,
            &Pose2::new(0.15, 0.0, 0.0)
        ));
        // Forgetting what earlier scans needed keeps the answer for later ones.
        track.forget_before(25 * MS);
        assert_eq!(track.len(), 3);
        assert!(close(
            &track.at(25 * MS).unwrap().pose,
            &Pose2::new(0.25, 0.0, 0.0)
        ));
    }

    #[test]
    fn missing_at_the_end_of_the_stream_extrapolates_a_bounded_way() {
        let mut track = OdometryTrack::new();
        push(&mut track, reading(0, 0.0, 0.0));
        push(&mut track, reading(100, 1.0, 0.1));
        assert!(!track.resolves(150 * MS));
        track.end();
        assert!(track.resolves(150 * MS));
        // Constant velocity past the last reading ...
        let near = track.at(150 * MS).unwrap();
        assert!(close(&near.pose, &Pose2::new(1.5, 0.0, 0.15)));
        // ... for at most MAX_EXTRAPOLATION_NS, with the last reading's covariance.
        let far = track.at(10_000 * MS).unwrap();
        let limit = 1.0 + MAX_EXTRAPOLATION_NS as f64 / (100 * MS) as f64;
        assert!(close(&far.pose, &Pose2::new(limit, 0.0, 0.1 * limit)));
        assert_eq!(far.covariance, Matrix3::identity());
        // Before the first reading, the same from the start.
        let early = {
            let mut track = OdometryTrack::new();
            push(&mut track, reading(100, 1.0, 0.0));
            push(&mut track, reading(200, 2.0, 0.0));
            track.at(50 * MS).unwrap()
        };
        assert!(close(&early.pose, &Pose2::new(0.5, 0.0, 0.0)));
    }

    #[test]
    fn empty_single_out_of_order_and_duplicate_readings() {
        let mut track = OdometryTrack::new();
        assert!(track.at(0).is_none());
        assert!(!track.resolves(0));
        push(&mut track, reading(10, 1.0, 0.0));
        let held = track.at(99 * MS).unwrap();
        assert!(close(&held.pose, &Pose2::new(1.0, 0.0, 0.0)));
        // A late or repeated reading could change the answer for a scan already paired:
        // refused, so the first word on an instant holds.
        push(&mut track, reading(30, 3.0, 0.0));
        let late = track.push(reading(20, 2.5, 0.0));
        assert_eq!(late, Err(RefusedReading::OutOfOrder));
        let repeated = track.push(reading(30, 2.0, 0.0));
        assert_eq!(repeated, Err(RefusedReading::Duplicate));
        assert_eq!(track.len(), 2);
        let first = track.at(30 * MS).unwrap();
        assert!(close(&first.pose, &Pose2::new(3.0, 0.0, 0.0)));
        let mut bad = reading(40, 1.0, 0.0);
        bad.pose.x = f64::NAN;
        assert_eq!(track.push(bad), Err(RefusedReading::NotFinite));
        assert_eq!(track.len(), 2);
    }
}
