//! How well a saved map explains a run's scans: the share of the beams it can judge that
//! end on one of its walls. Localizing on a map, or mapping on top of one, believes the
//! map, and a map of another building is localized on as readily as the right one: the
//! particles converge wherever its walls fit a few scans best. The beams tell which: on the
//! right map nearly every beam ends on a mapped wall, on another one only those that happen
//! to.
//!
//! Each valid beam is judged from the estimate, by the saved grid's cells (slam-proc's
//! `FitField`):
//! * **explained** when it ends within [`MAP_FIT_WITHIN_M`] of a mapped (occupied) cell;
//! * **contradicting** when it ends in space the map saw free, or passes through one of
//!   its walls (into a wall's cells and out beyond their reach) short of its end;
//! * **not judged** when it ends where the map never looked (unknown cells, off the grid)
//!   without crossing a wall: a room the map leaves out says nothing against it.
//!
//! slam-proc counts the beams (localizing: at the scans that weight the converged
//! particles; mapping on a saved grid: at the filter's updates, from the best particle),
//! map-sink reports the counts in `metrics.json`, and below [`MAP_FIT_FLOOR`] the map does
//! not fit. A share of beams, not a likelihood: it means the same whatever the scanner's
//! beam count and range.

use serde::{Deserialize, Serialize};

/// A beam is explained when it ends this close to a mapped wall's cell, metres: the
/// localizer calls a cloud converged once it is within 0.15 m (slam-proc's
/// `CONVERGED_SIGMA_XY`), and a map's walls are blurred by a cell (0.05 m by default). What a right map misses beyond it
/// is not in the map (people, clutter, glass), not error.
pub const MAP_FIT_WITHIN_M: f64 = 0.2;

/// The least share of judged beams a map must explain to be believed: as many for it as
/// against it. Below that the scans, seen from where the map put them, say more against the
/// map than for it. Right maps score far above (measured: 0.99 on the simulated worlds,
/// 0.92-0.94 on the aces and MIT logs, 0.72-0.77 on intel, whose localization loses its way
/// for a third of the log), maps of other buildings far below (0.01-0.39); the figures are
/// in docs/localization.md.
pub const MAP_FIT_FLOOR: f64 = 0.5;

/// Beams of a scan judged at most, spread evenly over its valid ones: a scan's share is as
/// well estimated from them, a scanner of a thousand beams costs no more than one of a few
/// hundred, and the beams a verdict waits for are as many scans on either.
pub const MAP_FIT_BEAMS_PER_SCAN: usize = 360;

/// Beams judged before there is a verdict: tens of scans, so that a stretch of clutter or a
/// start the map holds poorly decides nothing (mapping the intel log on its own map, the
/// first 5000 beams explain only a third; after 10000, over half).
pub const MAP_FIT_MIN_BEAMS: u64 = 10_000;

/// Beams counted against a saved map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct MapFit {
    /// Beams whose ends the map could judge.
    pub beams_judged: u64,
    /// Of them, those that ended within [`MAP_FIT_WITHIN_M`] of a mapped wall.
    pub beams_explained: u64,
}

/// What the counts say of the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitVerdict {
    /// Fewer than [`MAP_FIT_MIN_BEAMS`] judged: nothing to say.
    TooFewBeams,
    /// At least [`MAP_FIT_FLOOR`] of the judged beams explained.
    Fits,
    /// Fewer than that.
    DoesNotFit,
}

impl MapFit {
    /// The share of judged beams explained; `None` before any was judged.
    pub fn share(&self) -> Option<f64> {
        (self.beams_judged > 0).then(|| self.beams_explained as f64 / self.beams_judged as f64)
    }

    /// The verdict on the counts so far.
    pub fn verdict(&self) -> FitVerdict {
        match self.share() {
            Some(share) if self.beams_judged >= MAP_FIT_MIN_BEAMS => {
                if share >= MAP_FIT_FLOOR {
                    FitVerdict::Fits
                } else {
                    FitVerdict::DoesNotFit
                }
            }
            _ => FitVerdict::TooFewBeams,
        }
    }

    /// What `metrics.json` keeps of the counts.
    pub fn summary(&self) -> MapFitSummary {
        MapFitSummary {
            beams_judged: self.beams_judged,
            beams_explained: self.beams_explained,
            explained_share: self.share(),
            floor: MAP_FIT_FLOOR,
            within_m: MAP_FIT_WITHIN_M,
            verdict: self.verdict(),
        }
    }
}

/// How well the saved map explained the run's scans, as `metrics.json` gives it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapFitSummary {
    pub beams_judged: u64,
    pub beams_explained: u64,
    /// `beams_explained / beams_judged`; `null` when none was judged.
    pub explained_share: Option<f64>,
    /// The least share a map must explain ([`MAP_FIT_FLOOR`]).
    pub floor: f64,
    /// A beam is explained within this many metres of a mapped wall ([`MAP_FIT_WITHIN_M`]).
    pub within_m: f64,
    pub verdict: FitVerdict,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_verdict_waits_for_enough_beams_then_compares_the_share_with_the_floor() {
        let fit = |judged, explained| MapFit {
            beams_judged: judged,
            beams_explained: explained,
        };
        assert_eq!(fit(0, 0).share(), None);
        assert_eq!(fit(0, 0).verdict(), FitVerdict::TooFewBeams);
        assert_eq!(
            fit(MAP_FIT_MIN_BEAMS - 1, 0).verdict(),
            FitVerdict::TooFewBeams
        );
        let judged = MAP_FIT_MIN_BEAMS * 10;
        let at_floor = (judged as f64 * MAP_FIT_FLOOR).ceil() as u64;
        assert_eq!(fit(judged, at_floor).verdict(), FitVerdict::Fits);
        assert_eq!(fit(judged, at_floor - 1).verdict(), FitVerdict::DoesNotFit);
        let summary = fit(judged, at_floor).summary();
        assert_eq!(summary.verdict, FitVerdict::Fits);
        let json = serde_json::to_value(summary).unwrap();
        assert_eq!(json["verdict"], "fits");
        assert_eq!(json["floor"], MAP_FIT_FLOOR);
    }
}
