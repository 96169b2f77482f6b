//! The odometry at a scan's stamp, as a function of the streams' contents alone
//! (docs/CONVENTIONS.md, "Joining streams").
//!
//! Odometry and scans travel on separate topics, so which of them a process sees first
//! depends on scheduling. The rule here does not: the pose at a stamp is interpolated between
//! the last reading at or before it and the first one after it, so it is final only once
//! the buffer holds a reading at or after the stamp, or the odometry stream has ended; until
//! then [`OdometryBuffer::at`] answers [`OdometryAt::NotYet`]. Beyond the ends of the
//! readings the pose is extrapolated from the two readings nearest to that end, for at most
//! [`MAX_EXTRAPOLATION_NS`].

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

impl From<&ipc_types::Odometry> for OdometryReading {
    /// The reading an odometry message carries, stamped with its header's stamp.
    fn from(message: &ipc_types::Odometry) -> Self {
        Self {
            stamp_ns: message.header.stamp_ns,
            pose: message.pose.into(),
            covariance: ipc_types::covariance_from_row_major(&message.covariance),
        }
    }
}

impl From<&OdometryReading> for ipc_types::OdometryAtScan {
    /// The reading as a features message carries it beside its scan (the scan's stamp).
    fn from(reading: &OdometryReading) -> Self {
        Self {
            pose: reading.pose.into(),
            covariance: ipc_types::covariance_to_row_major(&reading.covariance),
        }
    }
}

/// Why [`OdometryBuffer::push`] refused a reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RefusedReading {
    #[error("the odometry reading is not finite")]
    NotFinite,
    #[error("the odometry reading is older than one already received")]
    OutOfOrder,
    #[error("an odometry reading with this stamp was already received")]
    Duplicate,
}

/// The odometry at a stamp, as [`OdometryBuffer::at`] answers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdometryAt {
    /// The pose at the stamp, final: no reading still to come changes it.
    Final(OdometryReading),
    /// A reading still to come may change the pose: none at or after the stamp has come
    /// yet, or the stamp is before the first reading and the second (which the
    /// extrapolation back needs) has not come. `so_far` is the pose from the readings held
    /// (`None` without any), for a consumer that cannot wait longer.
    NotYet { so_far: Option<OdometryReading> },
    /// The stream has ended without a single reading.
    NoReadings,
}

impl OdometryAt {
    /// Whether the answer is final.
    pub fn is_final(&self) -> bool {
        !matches!(self, OdometryAt::NotYet { .. })
    }

    /// The pose, final or so far; `None` without readings.
    pub fn reading(self) -> Option<OdometryReading> {
        match self {
            OdometryAt::Final(reading) => Some(reading),
            OdometryAt::NotYet { so_far } => so_far,
            OdometryAt::NoReadings => None,
        }
    }
}

/// The odometry readings received so far, in stamp order, and whether their stream ended.
#[derive(Debug, Clone, Default)]
pub struct OdometryBuffer {
    readings: VecDeque<OdometryReading>,
    ended: bool,
}

impl OdometryBuffer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a reading, or says why it is refused. Readings must come in stamp order: one
    /// older than the newest held, or with its stamp, is refused. A scan is paired as soon as
    /// a reading at or after its stamp is held, so a later reading at or before that stamp
    /// would change the pairing depending on when the scan happened to be paired; refusing it
    /// makes the buffer a function of its own stream's order alone.
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

    /// The odometry at `stamp_ns`: [`OdometryAt::Final`] once a reading at or after it is
    /// held or the stream has ended, else [`OdometryAt::NotYet`]. A stamp before the first
    /// reading is extrapolated from the first two, so it waits for the second: with one
    /// alone the pose would depend on whether the next had come yet.
    pub fn at(&self, stamp_ns: u64) -> OdometryAt {
        let before_first = self
            .readings
            .front()
            .is_some_and(|first| stamp_ns < first.stamp_ns);
        let reaches = self
            .readings
            .back()
            .is_some_and(|last| last.stamp_ns >= stamp_ns);
        let held = self.pose_at(stamp_ns);
        match held {
            None if self.ended => OdometryAt::NoReadings,
            Some(reading) if self.ended || (reaches && !(before_first && self.len() < 2)) => {
                OdometryAt::Final(reading)
            }
            so_far => OdometryAt::NotYet { so_far },
        }
    }

    /// The pose at `stamp_ns` from the readings held: interpolated between the two around
    /// it, extrapolated (for at most [`MAX_EXTRAPOLATION_NS`]) from the two nearest an end,
    /// the one reading itself if there is only one; `None` without readings. The covariance
    /// is blended like the pose (a convex combination keeps it positive definite) and held
    /// at the end's value when extrapolating.
    fn pose_at(&self, stamp_ns: u64) -> Option<OdometryReading> {
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

    /// Prunes the readings no stamp at or after `stamp_ns` needs: it keeps the last two at
    /// or before it (the bracket and the extrapolation at the start need no more).
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
    use proptest::prelude::*;

    const MS: u64 = 1_000_000;

    fn reading(stamp_ms: u64, x: f64, yaw: f64) -> OdometryReading {
        OdometryReading {
            stamp_ns: stamp_ms * MS,
            pose: Pose2::new(x, 0.0, yaw),
            covariance: Matrix3::identity() * x.abs().max(0.01),
        }
    }

    #[test]
    fn a_reading_comes_from_its_message_and_goes_beside_its_scan_unchanged() {
        let mut message = <ipc_types::Odometry as ipc_types::Zeroable>::boxed_zeroed();
        message.header.stamp_ns = 42 * MS;
        message.pose = Pose2::new(1.0, -2.0, 0.5).into();
        message.covariance = [0.1, 0.01, 0.0, 0.01, 0.2, 0.0, 0.0, 0.0, 0.03];
        let reading = OdometryReading::from(&*message);
        assert_eq!(reading.stamp_ns, 42 * MS);
        assert_eq!(reading.pose, Pose2::new(1.0, -2.0, 0.5));
        assert_eq!(reading.covariance[(0, 1)], 0.01);
        assert_eq!(reading.covariance[(2, 2)], 0.03);
        let at_scan = ipc_types::OdometryAtScan::from(&reading);
        assert_eq!(at_scan.pose, message.pose);
        assert_eq!(at_scan.covariance, message.covariance);
    }

    fn push(buffer: &mut OdometryBuffer, reading: OdometryReading) {
        buffer.push(reading).expect("an in-order, finite reading");
    }

    fn final_pose(buffer: &OdometryBuffer, stamp_ns: u64) -> OdometryReading {
        match buffer.at(stamp_ns) {
            OdometryAt::Final(reading) => reading,
            other => panic!("not final at {stamp_ns}: {other:?}"),
        }
    }

    fn close(a: &Pose2, b: &Pose2) -> bool {
        (a.x - b.x).abs() < 1e-12 && (a.y - b.y).abs() < 1e-12 && (a.yaw - b.yaw).abs() < 1e-12
    }

    #[test]
    fn a_stamp_before_the_first_reading_waits_for_the_second() {
        let mut buffer = OdometryBuffer::new();
        push(&mut buffer, reading(100, 1.0, 0.0));
        // One reading would answer with itself; two extrapolate back from both. Answering
        // early would make the answer depend on when the second came.
        assert_eq!(
            buffer.at(90 * MS),
            OdometryAt::NotYet {
                so_far: Some(reading(100, 1.0, 0.0).with_stamp(90 * MS))
            }
        );
        assert!(buffer.at(100 * MS).is_final());
        push(&mut buffer, reading(110, 2.0, 0.0));
        let at = final_pose(&buffer, 90 * MS);
        push(&mut buffer, reading(120, 3.0, 0.0));
        assert_eq!(
            final_pose(&buffer, 90 * MS),
            at,
            "later readings change nothing"
        );
        let mut ended = OdometryBuffer::new();
        push(&mut ended, reading(100, 1.0, 0.0));
        ended.end();
        assert!(ended.at(90 * MS).is_final(), "nothing more will come");
    }

    #[test]
    fn odometry_after_its_scan_is_waited_for_then_interpolated() {
        let mut buffer = OdometryBuffer::new();
        push(&mut buffer, reading(0, 0.0, 0.0));
        // The scan at 25 ms arrives before the reading at 50 ms: not final yet, the reading
        // held is the best so far.
        let waiting = buffer.at(25 * MS);
        assert!(!waiting.is_final());
        assert_eq!(
            waiting.reading().map(|r| r.pose),
            Some(Pose2::new(0.0, 0.0, 0.0))
        );
        push(&mut buffer, reading(50, 1.0, 0.2));
        let at = final_pose(&buffer, 25 * MS);
        assert!(close(&at.pose, &Pose2::new(0.5, 0.0, 0.1)));
        assert_eq!(at.stamp_ns, 25 * MS);
        assert!((at.covariance[(0, 0)] - 0.505).abs() < 1e-12);
    }

    #[test]
    fn odometry_before_its_scan_and_at_its_stamp() {
        let mut buffer = OdometryBuffer::new();
        for (t, x) in [(0, 0.0), (10, 0.1), (20, 0.2), (30, 0.3)] {
            push(&mut buffer, reading(t, x, 0.0));
        }
        // Everything already there: final at once, the same answer whatever came first.
        assert!(close(
            &final_pose(&buffer, 20 * MS).pose,
            &Pose2::new(0.2, 0.0, 0.0)
        ));
        assert!(close(
            &final_pose(&buffer, 15 * MS).pose,
            &Pose2::new(0.15, 0.0, 0.0)
        ));
        // Pruning what earlier scans needed keeps the answer for later ones.
        buffer.forget_before(25 * MS);
        assert_eq!(buffer.len(), 3);
        assert!(close(
            &final_pose(&buffer, 25 * MS).pose,
            &Pose2::new(0.25, 0.0, 0.0)
        ));
    }

    #[test]
    fn missing_at_the_end_of_the_stream_extrapolates_a_bounded_way() {
        let mut buffer = OdometryBuffer::new();
        push(&mut buffer, reading(0, 0.0, 0.0));
        push(&mut buffer, reading(100, 1.0, 0.1));
        assert!(!buffer.at(150 * MS).is_final());
        buffer.end();
        // Constant velocity past the last reading ...
        let near = final_pose(&buffer, 150 * MS);
        assert!(close(&near.pose, &Pose2::new(1.5, 0.0, 0.15)));
        // ... for at most MAX_EXTRAPOLATION_NS, with the last reading's covariance.
        let far = final_pose(&buffer, 10_000 * MS);
        let limit = 1.0 + MAX_EXTRAPOLATION_NS as f64 / (100 * MS) as f64;
        assert!(close(&far.pose, &Pose2::new(limit, 0.0, 0.1 * limit)));
        assert_eq!(far.covariance, Matrix3::identity());
        // Before the first reading, the same from the start.
        let early = {
            let mut buffer = OdometryBuffer::new();
            push(&mut buffer, reading(100, 1.0, 0.0));
            push(&mut buffer, reading(200, 2.0, 0.0));
            final_pose(&buffer, 50 * MS)
        };
        assert!(close(&early.pose, &Pose2::new(0.5, 0.0, 0.0)));
    }

    #[test]
    fn empty_single_out_of_order_and_duplicate_readings() {
        let mut buffer = OdometryBuffer::new();
        assert_eq!(buffer.at(0), OdometryAt::NotYet { so_far: None });
        let mut ended = buffer.clone();
        ended.end();
        assert_eq!(ended.at(0), OdometryAt::NoReadings);
        assert_eq!(ended.at(0).reading(), None);
        push(&mut buffer, reading(10, 1.0, 0.0));
        let held = buffer.at(99 * MS).reading().expect("one reading");
        assert!(close(&held.pose, &Pose2::new(1.0, 0.0, 0.0)));
        // A late or repeated reading could change the answer for a scan already paired:
        // refused, so the first word on an instant holds.
        push(&mut buffer, reading(30, 3.0, 0.0));
        let late = buffer.push(reading(20, 2.5, 0.0));
        assert_eq!(late, Err(RefusedReading::OutOfOrder));
        let repeated = buffer.push(reading(30, 2.0, 0.0));
        assert_eq!(repeated, Err(RefusedReading::Duplicate));
        assert_eq!(buffer.len(), 2);
        let first = final_pose(&buffer, 30 * MS);
        assert!(close(&first.pose, &Pose2::new(3.0, 0.0, 0.0)));
        let mut bad = reading(40, 1.0, 0.0);
        bad.pose.x = f64::NAN;
        assert_eq!(buffer.push(bad), Err(RefusedReading::NotFinite));
        assert_eq!(buffer.len(), 2);
    }

    /// In-order readings: increasing stamps (ms) with poses along a path.
    fn readings() -> impl Strategy<Value = Vec<OdometryReading>> {
        prop::collection::vec((1u64..50, -1.0f64..1.0, -0.3f64..0.3), 1..12).prop_map(|steps| {
            let mut stamp = 0;
            let mut x = 0.0;
            let mut yaw = 0.0;
            steps
                .into_iter()
                .map(|(dt, dx, dyaw)| {
                    stamp += dt;
                    x += dx;
                    yaw = slam_geom::wrap_angle(yaw + dyaw);
                    reading(stamp, x, yaw)
                })
                .collect()
        })
    }

    proptest! {
        /// A final answer is the answer: readings that come later, the stream's end and
        /// pruning before the stamp leave it bit for bit as it was.
        #[test]
        fn a_final_answer_never_changes(
            all in readings(),
            split in 0usize..12,
            stamp_ms in 0u64..700,
        ) {
            let split = split.min(all.len());
            let mut buffer = OdometryBuffer::new();
            all[..split].iter().for_each(|r| push(&mut buffer, *r));
            let stamp_ns = stamp_ms * MS;
            let early = buffer.at(stamp_ns);
            all[split..].iter().for_each(|r| push(&mut buffer, *r));
            buffer.forget_before(stamp_ns);
            if early.is_final() {
                prop_assert_eq!(buffer.at(stamp_ns), early);
            }
            buffer.end();
            let late = buffer.at(stamp_ns);
            prop_assert!(late.is_final());
            if early.is_final() {
                prop_assert_eq!(late, early);
            }
        }

        /// At a reading's own stamp the answer is that reading; between two it lies on the
        /// segment between them.
        #[test]
        fn readings_are_met_and_gaps_interpolated(all in readings()) {
            let mut buffer = OdometryBuffer::new();
            all.iter().for_each(|r| push(&mut buffer, *r));
            for pair in all.windows(2) {
                prop_assert_eq!(final_pose(&buffer, pair[1].stamp_ns), pair[1]);
                let middle = final_pose(&buffer, (pair[0].stamp_ns + pair[1].stamp_ns) / 2);
                let (lo, hi) = (pair[0].pose.x.min(pair[1].pose.x), pair[0].pose.x.max(pair[1].pose.x));
                prop_assert!(middle.pose.x >= lo - 1e-12 && middle.pose.x <= hi + 1e-12);
            }
        }
    }
}
