//! What the emulated sensor reports for a ranging command, given one recorded scan.

use crate::scip::{DataKind, Ranging, SensorParams, max_value};

/// Reported for steps outside the recording: nothing was measured there.
const NOTHING: u32 = crate::ranges::NO_RETURN;

/// The intensity the emulator reports with a range: the recordings have none, so it is
/// made up, reproducibly (0 for error codes).
pub fn intensity_of(value_mm: u32, dmin_mm: u32) -> u32 {
    if value_mm < dmin_mm {
        0
    } else {
        1000 + value_mm % 7000
    }
}

/// The values of one scan for `ranging`: `recorded` holds one value per step from `AMIN`.
///
/// A cluster reports the shortest valid range of its steps, as the specification says, or,
/// when none is valid, the smallest error code. A 2-character range (`MS`) above 4095 mm
/// cannot be sent and is reported as error code 0.
pub fn measure(recorded: &[u32], params: &SensorParams, ranging: &Ranging) -> (Vec<u32>, Vec<u32>) {
    let dmin = params.dmin_mm;
    let value_at = |step: usize| {
        step.checked_sub(params.amin as usize)
            .and_then(|i| recorded.get(i))
            .copied()
            .unwrap_or(NOTHING)
    };
    let start = usize::from(ranging.start);
    let end = usize::from(ranging.end);
    let cluster = ranging.cluster_size();
    let widest = max_value(ranging.kind.width()).unwrap_or(u32::MAX);
    let ranges: Vec<u32> = (start..=end)
        .step_by(cluster)
        .map(|first| {
            let steps = first..=(first + cluster - 1).min(end);
            let valid = steps.clone().map(value_at).filter(|&v| v >= dmin).min();
            let value = valid.unwrap_or_else(|| steps.map(value_at).min().unwrap_or(NOTHING));
            if value > widest { 0 } else { value }
        })
        .collect();
    let intensities = if ranging.kind == DataKind::RangesIntensities {
        ranges.iter().map(|&r| intensity_of(r, dmin)).collect()
    } else {
        Vec::new()
    };
    (ranges, intensities)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SensorParams {
        SensorParams {
            amin: 2,
            amax: 7,
            ..SensorParams::utm_30lx()
        }
    }

    #[test]
    fn steps_map_onto_the_recording() {
        let recorded = [100, 200, 300, 400, 500, 600];
        let ranging = Ranging::new(DataKind::Ranges3, 0, 9, 1, 0, 0).unwrap();
        let (ranges, intensities) = measure(&recorded, &params(), &ranging);
        assert_eq!(ranges, [1, 1, 100, 200, 300, 400, 500, 600, 1, 1]);
        assert!(intensities.is_empty());
    }

    #[test]
    fn clusters_report_their_shortest_valid_range() {
        let recorded = [100, 1, 300, 19, 1, 50];
        let ranging = Ranging::new(DataKind::RangesIntensities, 2, 7, 2, 0, 0).unwrap();
        let (ranges, intensities) = measure(&recorded, &params(), &ranging);
        // Pairs (100, 1), (300, 19), (1, 50).
        assert_eq!(ranges, [100, 300, 50]);
        assert_eq!(intensities, [1100, 1300, 1050]);
        let ranging = Ranging::new(DataKind::Ranges3, 3, 7, 3, 0, 0).unwrap();
        // (1, 300, 19) and the short last cluster (1, 50).
        let (ranges, _) = measure(&recorded, &params(), &ranging);
        assert_eq!(ranges, [300, 50]);
        let all_errors = [19, 1, 5, 5, 5, 5];
        let ranging = Ranging::new(DataKind::Ranges3, 2, 3, 2, 0, 0).unwrap();
        assert_eq!(measure(&all_errors, &params(), &ranging).0, [1]);
    }

    #[test]
    fn two_character_ranges_saturate_to_an_error() {
        let recorded = [4095, 4096, 300, 3, 3, 3];
        let ranging = Ranging::new(DataKind::Ranges2, 2, 4, 1, 0, 0).unwrap();
        assert_eq!(measure(&recorded, &params(), &ranging).0, [4095, 0, 300]);
    }
}
