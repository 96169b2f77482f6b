//! Stale wheel readings: some odometry reaches the scans late by a varying delay (a log that
//! attaches to each scan the reading last received), so now and then a step falls short of the
//! motion, down to none at all, and a later one makes up for it. Along a corridor the scan
//! cannot tell, and a front end that believed them would stand still for a scan and then
//! jump. A wheel step is judged against the wheels' own recent believed steps, not against
//! the fits: those may wander along a corridor by centimetres a scan, and judging the wheels
//! by them would feed a fit's error back as the robot's pace.

use std::collections::VecDeque;

use nalgebra::Vector2;
use slam_geom::Pose2;

/// Readings are judged stale for at most this long after the last one believed,
/// nanoseconds: odometry late by longer is rather wheels that did stop (a robot that hit
/// something), and their steps since that reading are believed again, all at once.
pub(crate) const STALE_WINDOW_NS: u64 = 1_000_000_000;

/// The pace is the mean velocity of the last believed steps over at least this long,
/// seconds: at a fast scanner's rate one step's few millimetres of encoder noise would be
/// a change of pace of their own.
const PACE_SPAN_S: f64 = 0.2;

/// The wheels' recent pace.
#[derive(Debug, Clone, Default)]
pub(crate) struct WheelPace {
    /// The last believed steps, oldest first: their translation (each in the robot frame
    /// it started from, metres) and their duration (seconds), covering at least
    /// [`PACE_SPAN_S`] when they can.
    steps: VecDeque<(Vector2<f64>, f64)>,
    /// Their total duration, seconds.
    span: f64,
}

impl WheelPace {
    /// A wheel step `increment` over `dt` seconds was believed.
    pub fn believe(&mut self, increment: &Pose2, dt: f64) {
        self.steps
            .push_back((Vector2::new(increment.x, increment.y), dt));
        self.span += dt;
        while let Some(&(_, oldest)) = self.steps.front() {
            if self.span - oldest < PACE_SPAN_S {
                break;
            }
            self.steps.pop_front();
            self.span -= oldest;
        }
    }

    /// The wheels' pace is unknown again (a start, a stretch without odometry, a catch-up).
    pub fn forget(&mut self) {
        self.steps.clear();
        self.span = 0.0;
    }

    /// The acceleration, m/s^2, a wheel step `increment` over `dt` seconds would take from
    /// the pace, when beyond `max_acceleration` (with `slack` metres for the readings'
    /// quantisation and timing); `None` when within it or when the pace is unknown. The
    /// pace is a mean over its span, so the speed may have changed since its middle, half
    /// a span and half a step before this step's.
    pub fn broken_by(
        &self,
        increment: &Pose2,
        dt: f64,
        max_acceleration: f64,
        slack: f64,
    ) -> Option<f64> {
        if self.steps.is_empty() || self.span <= 0.0 {
            return None;
        }
        let velocity = self.steps.iter().map(|(t, _)| t).sum::<Vector2<f64>>() / self.span;
        let expected = velocity * dt;
        let change = (increment.x - expected.x).hypot(increment.y - expected.y);
        let apart = 0.5 * (self.span + dt);
        (change > max_acceleration * dt * apart + slack).then(|| change / (dt * apart))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn forward(metres: f64) -> Pose2 {
        Pose2::new(metres, 0.0, 0.0)
    }

    #[test]
    fn an_unknown_pace_judges_nothing() {
        let mut pace = WheelPace::default();
        assert_eq!(pace.broken_by(&forward(5.0), 0.2, 3.0, 0.005), None);
        pace.believe(&forward(0.26), 0.21);
        assert!(pace.broken_by(&forward(5.0), 0.2, 3.0, 0.005).is_some());
        pace.forget();
        assert_eq!(pace.broken_by(&forward(5.0), 0.2, 3.0, 0.005), None);
    }

    #[test]
    fn a_stalled_reading_breaks_the_pace_and_a_steady_one_does_not() {
        let mut pace = WheelPace::default();
        pace.believe(&forward(0.26), 0.21);
        // 1.24 m/s; 3 m/s^2 over 0.21 s allows 0.13 m (+ 5 mm) of change.
        assert_eq!(pace.broken_by(&forward(0.27), 0.21, 3.0, 0.005), None);
        assert_eq!(pace.broken_by(&forward(0.15), 0.21, 3.0, 0.005), None);
        let stalled = pace.broken_by(&forward(0.0), 0.21, 3.0, 0.005);
        assert!(stalled.is_some_and(|a| (a - 0.26 / (0.21 * 0.21)).abs() < 1e-9));
        assert!(pace.broken_by(&forward(0.54), 0.21, 3.0, 0.005).is_some());
        // Sideways as much as ahead: a holonomic base's pace is a velocity, not a speed.
        assert!(
            pace.broken_by(&Pose2::new(0.26, 0.2, 0.0), 0.21, 3.0, 0.005)
                .is_some()
        );
        // A robot setting off from standing still is within the bound.
        pace.forget();
        pace.believe(&forward(0.0), 0.2);
        assert_eq!(pace.broken_by(&forward(0.1), 0.2, 3.0, 0.005), None);
    }

    #[test]
    fn at_a_fast_rate_the_pace_is_a_mean_and_one_step_s_noise_keeps_it() {
        let mut pace = WheelPace::default();
        // 1 m/s at 40 Hz, each step a few millimetres off, alternately.
        for k in 0..20 {
            let noise = if k % 2 == 0 { 0.004 } else { -0.004 };
            pace.believe(&forward(0.025 + noise), 0.025);
        }
        // The last 0.2 s only (8 or 9 steps), their mean 1 m/s.
        assert!(pace.span >= PACE_SPAN_S && pace.span < PACE_SPAN_S + 0.025 + 1e-9);
        assert_eq!(
            pace.broken_by(&forward(0.025 - 0.008), 0.025, 3.0, 0.005),
            None
        );
        // A reading a whole step late stands still: stale.
        assert!(pace.broken_by(&forward(0.0), 0.025, 3.0, 0.005).is_some());
    }
}
