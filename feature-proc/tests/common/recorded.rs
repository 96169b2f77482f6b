//! The real recording (shared data, seed-hall) as the extractor takes it.

use feature_proc::ScanInput;
use test_data::ScanRecord;

/// A scan of `test_data::seed_hall_scans` (read as `lidar-replay` publishes it, with the
/// sensor's geometry) as the extractor's input.
pub fn scan_input(scan: &ScanRecord) -> ScanInput<'_> {
    ScanInput {
        geometry: scan.geometry,
        ranges: &scan.ranges,
    }
}
