//! Property tests of the decoders of a log's lines, CARMEN and seed-hall CSV: whatever the
//! bytes, the readers do not panic, yield no more than the input holds, and refuse a bad
//! line with a typed error naming a line that exists; a valid line decodes to its values,
//! and one with a field left out or repeated is refused.

use lidar_replay::seed_csv::{self, range_from_code};
use lidar_replay::{CarmenReader, LogRecord, ReadError, SeedCsvReader};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::Index;

/// Everything a reader yields for `bytes`, checked as it comes: only line errors (no I/O
/// error can come from a slice) on lines that exist, and records from lines that exist.
/// Returns the records and the line errors.
fn read_all(
    records: impl Iterator<Item = Result<LogRecord, ReadError>>,
    bytes: &[u8],
) -> Result<(Vec<LogRecord>, Vec<lidar_replay::LineError>), TestCaseError> {
    let lines = bytes.split(|&b| b == b'\n').count() as u64;
    let mut good = Vec::new();
    let mut bad = Vec::new();
    for (count, item) in records.enumerate() {
        // A line gives at most two records (a FLASER's odometry and scan) or one error.
        prop_assert!(count as u64 <= 2 * lines, "more items than the lines hold");
        match item {
            Ok(record) => {
                prop_assert!((1..=lines).contains(&record.line()));
                good.push(record);
            }
            Err(ReadError::Line(e)) => {
                prop_assert!((1..=lines).contains(&e.line), "{}", e);
                prop_assert!(!e.reason.is_empty());
                bad.push(e);
            }
            Err(e) => prop_assert!(false, "not a line error: {}", e),
        }
    }
    // Each range is a token of at least one byte and a separator: no more ranges than bytes.
    let beams: usize = good
        .iter()
        .map(|record| match record {
            LogRecord::Scan(scan) => scan.ranges.len() + scan.intensities.len(),
            LogRecord::Odometry(_) => 0,
        })
        .sum();
    prop_assert!(beams <= bytes.len());
    Ok((good, bad))
}

/// Words CARMEN lines are made of, valid and not, so random lines reach deep into the
/// parser rather than stopping at the record name.
const CARMEN_WORDS: &[&str] = &[
    "FLASER",
    "ROBOTLASER1",
    "ODOM",
    "PARAM",
    "SYNC",
    "#",
    "0",
    "1",
    "180",
    "181",
    "360",
    "361",
    "721",
    "9000",
    "-1",
    "0.5",
    "2.50",
    "81.91",
    "1e400",
    "nan",
    "inf",
    "-0",
    "x",
    "1058295543.123456",
    "1058295543",
    "1.2.3",
    "robot",
    "",
];

/// A valid FLASER line of `ranges` with the odometry `pose` and the stamp `stamp` seconds.
fn flaser(ranges: &[f32], pose: (f64, f64, f64), stamp: &str) -> Vec<String> {
    let mut tokens = vec!["FLASER".to_owned(), ranges.len().to_string()];
    tokens.extend(ranges.iter().map(|r| format!("{r:.2}")));
    let (x, y, yaw) = pose;
    for _ in 0..2 {
        tokens.extend([x, y, yaw].iter().map(|v| format!("{v:.3}")));
    }
    tokens.extend([stamp.to_owned(), "robot".to_owned(), "0.1".to_owned()]);
    tokens
}

/// How a valid line is spoiled.
#[derive(Debug, Clone, Copy)]
enum Spoil {
    /// A field left out.
    Drop,
    /// A field written twice.
    Repeat,
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_bytes_are_records_or_line_errors_in_either_format(
        bytes in vec(any::<u8>(), 0..2000),
    ) {
        read_all(CarmenReader::new(&bytes[..]), &bytes)?;
        read_all(SeedCsvReader::new(&bytes[..]), &bytes)?;
    }

    #[test]
    fn lines_of_carmen_words_are_records_or_line_errors(
        lines in vec(vec(prop::sample::select(CARMEN_WORDS), 0..40), 0..20),
    ) {
        let text: String = lines.iter().map(|words| words.join(" ") + "\n").collect();
        read_all(CarmenReader::new(text.as_bytes()), text.as_bytes())?;
    }

    #[test]
    fn a_flaser_line_decodes_to_its_values(
        // Returns only: 0 (an error) and 50 m on (no return) become REP 117 codes, as the
        // reader's own tests show.
        ranges in prop::sample::select(vec![180usize, 181, 360, 361, 721])
            .prop_flat_map(|n| vec(0.01f32..49.0, n)),
        pose in (-100.0..100.0, -100.0..100.0, -3.0..3.0),
        seconds in 1_000_000_000u64..2_000_000_000,
        micros in 0u64..1_000_000,
    ) {
        let stamp = format!("{seconds}.{micros:06}");
        let text = flaser(&ranges, pose, &stamp).join(" ") + "\n";
        let (records, errors) = read_all(CarmenReader::new(text.as_bytes()), text.as_bytes())?;
        prop_assert!(errors.is_empty(), "{:?}", errors);
        prop_assert_eq!(records.len(), 2);
        let LogRecord::Scan(scan) = &records[1] else {
            return Err(TestCaseError::fail("the second record is not the scan"));
        };
        prop_assert_eq!(scan.stamp_ns, seconds * 1_000_000_000 + micros * 1_000);
        // The ranges as written (two decimals), straight to f32.
        let written: Vec<f32> = ranges.iter().map(|r| format!("{r:.2}").parse().unwrap()).collect();
        prop_assert_eq!(&scan.ranges, &written);
    }

    #[test]
    fn a_flaser_line_with_a_field_left_out_or_repeated_is_refused(
        ranges in prop::sample::select(vec![180usize, 181, 361]).prop_flat_map(|n| vec(0.0f32..49.0, n)),
        field in any::<Index>(),
        spoil in prop_oneof![Just(Spoil::Drop), Just(Spoil::Repeat)],
    ) {
        let mut tokens = flaser(&ranges, (1.0, 2.0, 0.5), "1058295543.123456");
        // A field after the record name (dropping the name makes another kind of line).
        let at = 1 + field.index(tokens.len() - 1);
        match spoil {
            Spoil::Drop => {
                tokens.remove(at);
            }
            Spoil::Repeat => {
                let token = tokens[at].clone();
                tokens.insert(at, token);
            }
        }
        let text = tokens.join(" ") + "\n";
        let (records, errors) = read_all(CarmenReader::new(text.as_bytes()), text.as_bytes())?;
        prop_assert!(records.is_empty(), "{:?} read from {:?} field {}", spoil, text, at);
        prop_assert_eq!(errors.len(), 1);
        prop_assert_eq!(errors[0].line, 1);
    }

    #[test]
    fn lines_of_csv_fields_are_scans_or_line_errors(
        lines in vec(
            vec(prop::sample::select(vec!["0", "1", "19", "20", "14029", "60000", "99999999999", "-1", "x", " 5", ""]), 0..1200),
            0..4,
        ),
    ) {
        let text: String = lines.iter().map(|fields| fields.join(",") + "\n").collect();
        let (records, _) = read_all(SeedCsvReader::new(text.as_bytes()), text.as_bytes())?;
        for record in records {
            let LogRecord::Scan(scan) = record else {
                return Err(TestCaseError::fail("seed-csv has no odometry"));
            };
            prop_assert_eq!(scan.ranges.len(), seed_csv::BEAMS);
        }
    }

    #[test]
    fn a_csv_line_decodes_to_its_values_and_a_field_more_or_less_is_refused(
        codes in vec(0u32..100_000, seed_csv::BEAMS),
        field in any::<Index>(),
        spoil in prop::option::of(prop_oneof![Just(Spoil::Drop), Just(Spoil::Repeat)]),
    ) {
        let mut fields: Vec<String> = codes.iter().map(u32::to_string).collect();
        let at = field.index(fields.len());
        match spoil {
            None => {}
            Some(Spoil::Drop) => {
                fields.remove(at);
            }
            Some(Spoil::Repeat) => {
                let field = fields[at].clone();
                fields.insert(at, field);
            }
        }
        let text = fields.join(",") + "\n";
        let (records, errors) = read_all(SeedCsvReader::new(text.as_bytes()), text.as_bytes())?;
        if spoil.is_some() {
            prop_assert!(records.is_empty());
            prop_assert_eq!(errors.len(), 1);
            return Ok(());
        }
        prop_assert!(errors.is_empty(), "{:?}", errors);
        let LogRecord::Scan(scan) = &records[0] else {
            return Err(TestCaseError::fail("not a scan"));
        };
        prop_assert_eq!(scan.stamp_ns, 0);
        for (range, &code) in scan.ranges.iter().zip(&codes) {
            let expected = range_from_code(code);
            prop_assert!(
                range.to_bits() == expected.to_bits(),
                "{} mm read as {}, expected {}", code, range, expected
            );
        }
    }
}
