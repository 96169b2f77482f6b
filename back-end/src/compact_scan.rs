//! One scan's beams, kept compactly until the final path says where the scan was taken.
//!
//! The occupancy grid is traced from the final path, which slam-proc sends only at the end
//! of the run, so every scan must be kept until then. A beam costs 4 bytes here (its index
//! and its range in 2 mm steps) instead of the 4-byte `f32` of the message plus nothing for
//! its index, and beams that would add nothing to the grid are left out: a beam whose end
//! lies less than one grid cell from the end of the last beam kept traces (nearly) the same
//! cells. Near walls most beams of a dense scanner are such beams.

/// Range steps, metres: far below any grid resolution worth having, and 65534 steps reach
/// 131 m, beyond every scanner this pipeline reads.
const RANGE_STEP_M: f64 = 0.002;
/// The range code of a beam that returned nothing (REP 117 `+inf`).
const NO_RETURN: u16 = u16::MAX;

/// What a kept beam saw.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Beam {
    /// A return at this range, metres: the beam passed through free space up to it.
    Hit(f64),
    /// No return within the sensor's range: free space as far as the grid trusts it.
    NoReturn,
}

/// The beams of one scan worth tracing, in the sensor frame.
#[derive(Debug, Clone, PartialEq)]
pub struct CompactScan {
    angle_min: f64,
    angle_increment: f64,
    /// `index << 16 | range code`, in beam order.
    beams: Vec<u32>,
}

impl CompactScan {
    /// Keeps the beams of a scan that the grid can use: returns within
    /// `[range_min, range_max]` and no-returns (`+inf`); every other value (NaN, `-inf`, out
    /// of range) is a measurement error and says nothing about the world (REP 117). A beam
    /// is left out when the last beam kept is of the same kind (return or no-return) and
    /// their end points (a no-return's at `no_return_reach_m`) lie less than `spacing_m`
    /// apart.
    pub fn new(
        angle_min: f64,
        angle_increment: f64,
        range_min: f64,
        range_max: f64,
        ranges: &[f32],
        spacing_m: f64,
        no_return_reach_m: f64,
    ) -> Self {
        let mut beams = Vec::new();
        let mut last: Option<(bool, [f64; 2])> = None;
        // The packed index has 16 bits; the message holds at most MAX_BEAMS (8192) beams.
        for (i, &r) in ranges.iter().enumerate().take(1 << 16) {
            let r = f64::from(r);
            let (code, reach) = if r == f64::INFINITY {
                (NO_RETURN, no_return_reach_m)
            } else if r.is_finite() && r >= range_min && r <= range_max {
                let steps = (r / RANGE_STEP_M).round();
                if steps >= f64::from(NO_RETURN) {
                    continue;
                }
                (steps as u16, r)
            } else {
                continue;
            };
            let (s, c) = (angle_min + i as f64 * angle_increment).sin_cos();
            let end = [reach * c, reach * s];
            let hit = code != NO_RETURN;
            if let Some((last_hit, last_end)) = last
                && last_hit == hit
                && (end[0] - last_end[0]).hypot(end[1] - last_end[1]) < spacing_m
            {
                continue;
            }
            last = Some((hit, end));
            beams.push(((i as u32) << 16) | u32::from(code));
        }
        beams.shrink_to_fit();
        Self {
            angle_min,
            angle_increment,
            beams,
        }
    }

    /// The kept beams as `(bearing in the sensor frame, what it saw)`.
    pub fn beams(&self) -> impl Iterator<Item = (f64, Beam)> + '_ {
        self.beams.iter().map(|&packed| {
            let index = packed >> 16;
            let code = (packed & 0xffff) as u16;
            let bearing = self.angle_min + f64::from(index) * self.angle_increment;
            let beam = if code == NO_RETURN {
                Beam::NoReturn
            } else {
                Beam::Hit(f64::from(code) * RANGE_STEP_M)
            };
            (bearing, beam)
        })
    }

    /// Beams kept.
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }

    /// Heap and inline bytes this scan holds.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.beams.capacity() * std::mem::size_of::<u32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_beams_are_dropped_and_ranges_survive_to_a_millimetre() {
        let ranges = [
            1.0,
            f32::NAN,
            f32::NEG_INFINITY,
            0.01,
            40.0,
            2.5,
            f32::INFINITY,
        ];
        let scan = CompactScan::new(-1.0, 0.5, 0.1, 30.0, &ranges, 0.0, 5.0);
        let beams: Vec<(f64, Beam)> = scan.beams().collect();
        assert_eq!(beams.len(), 3, "{beams:?}");
        assert_eq!(beams[0].0, -1.0);
        assert!(matches!(beams[0].1, Beam::Hit(r) if (r - 1.0).abs() <= 1e-3));
        assert_eq!(beams[1].0, -1.0 + 5.0 * 0.5);
        assert!(matches!(beams[1].1, Beam::Hit(r) if (r - 2.5).abs() <= 1e-3));
        assert_eq!(beams[2], (-1.0 + 6.0 * 0.5, Beam::NoReturn));
    }

    #[test]
    fn beams_ending_within_a_cell_of_the_last_kept_one_are_left_out() {
        // 1081 beams at 0.25 degrees on a circle of 2 m: ends 8.7 mm apart, so one beam in
        // six ends 5 cm or more from the last one kept.
        let step = std::f64::consts::PI / 720.0;
        let ranges = vec![2.0_f32; 1081];
        let scan = CompactScan::new(0.0, step, 0.1, 30.0, &ranges, 0.05, 5.0);
        let expected = 1081_f64 / (0.05 / (2.0 * step)).ceil();
        assert!(
            (scan.len() as f64 - expected).abs() <= 2.0,
            "{} kept, about {expected} expected",
            scan.len()
        );
        // No-returns are thinned at their reach, and a change of kind is always kept.
        let mixed = [2.0, 2.0, f32::INFINITY, f32::INFINITY, 2.0];
        let scan = CompactScan::new(0.0, 1e-4, 0.1, 30.0, &mixed, 0.05, 5.0);
        let kinds: Vec<bool> = scan
            .beams()
            .map(|(_, b)| matches!(b, Beam::Hit(_)))
            .collect();
        assert_eq!(kinds, [true, false, true]);
    }
}
