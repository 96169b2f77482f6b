//! Property tests of the decoders of what a SCIP peer sends: replies, scans, parameters (the
//! client reading a whole handshake off the wire is `sensor`'s own). Whatever the bytes: no panic, a
//! typed error, and output no larger than what was asked for; and a valid scan, changed in
//! one byte or cut short, is refused rather than decoded into wrong ranges.

use lidar_hokuyo::scip::{DataKind, Reply, ScipError, SensorParams, Status, scan_body};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::Index;

const KINDS: [DataKind; 3] = [
    DataKind::Ranges2,
    DataKind::Ranges3,
    DataKind::RangesIntensities,
];

/// Every decoder a reply can go through; the scans must have the length asked for.
fn decode_everything(reply: &Reply, beams: usize) -> Result<(), TestCaseError> {
    if let Ok(info) = reply.information() {
        let _ = SensorParams::from_information(&info);
    }
    let _ = reply.time();
    for kind in KINDS {
        if let Ok(scan) = reply.scan(kind, beams) {
            prop_assert_eq!(scan.ranges.len(), beams);
            prop_assert!(scan.intensities.is_empty() || scan.intensities.len() == beams);
        }
    }
    Ok(())
}

/// A valid scan: its kind, ranges, intensities (for `ME`) and time stamp.
fn valid_scan() -> impl Strategy<Value = (DataKind, Vec<u32>, Vec<u32>, u32)> {
    // Up to 300 beams: several 64-character lines, with values cut across line ends.
    (prop::sample::select(KINDS.to_vec()), 1usize..300).prop_flat_map(|(kind, beams)| {
        let largest = match kind {
            DataKind::Ranges2 => 1u32 << 12,
            _ => 1 << 18,
        };
        let intensities = match kind {
            DataKind::RangesIntensities => beams,
            _ => 0,
        };
        (
            Just(kind),
            vec(0..largest, beams),
            vec(0u32..1 << 18, intensities),
            0u32..1 << 24,
        )
    })
}

/// The lines of a scan reply as a sensor sends them (echo, status, body).
fn scan_lines(kind: DataKind, ranges: &[u32], intensities: &[u32], stamp: u32) -> Vec<Vec<u8>> {
    let mut lines = vec![b"MD0000108001000".to_vec(), b"99b".to_vec()];
    lines.extend(scan_body(kind, stamp, ranges, intensities).expect("a valid scan"));
    lines
}

/// The scan a reply's lines decode to, if they decode.
fn decode_scan(lines: Vec<Vec<u8>>, kind: DataKind, beams: usize) -> Result<Vec<u32>, ScipError> {
    let reply = Reply::parse(lines)?;
    Ok(reply.scan(kind, beams)?.ranges)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_lines_are_a_reply_or_a_typed_error(
        lines in vec(vec(any::<u8>(), 0..80), 0..8),
        beams in 0usize..2000,
    ) {
        match Reply::parse(lines.clone()) {
            Ok(reply) => {
                prop_assert_eq!(&reply.echo, &lines[0]);
                prop_assert!(reply.body.len() <= lines.len());
                decode_everything(&reply, beams)?;
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }

    #[test]
    fn lines_of_scip_characters_are_a_reply_or_a_typed_error(
        // The data alphabet only, so checksums and encodings are what is tested.
        lines in vec(vec(0x30u8..0x70, 0..70), 0..8),
        beams in 0usize..100,
    ) {
        if let Ok(reply) = Reply::parse(lines) {
            decode_everything(&reply, beams)?;
        }
    }

    #[test]
    fn information_lines_give_parameters_or_a_typed_error(
        entries in vec(("[A-Z]{4}", "[ -~]{0,20}"), 0..12),
    ) {
        let mut lines = vec![b"PP".to_vec(), b"00P".to_vec()];
        for (name, value) in &entries {
            lines.push(lidar_hokuyo::scip::information_line(name, value));
        }
        let reply = Reply::parse(lines).expect("well-formed lines");
        let info = reply.information().expect("information lines with their checksums");
        match SensorParams::from_information(&info) {
            Ok(params) => prop_assert!(params.amin <= params.amax),
            Err(e) => {
                // (prop_assert! quotes its condition in a format string: no braces there.)
                let typed = matches!(
                    e,
                    ScipError::MissingParameter(_) | ScipError::BadParameter { .. }
                );
                prop_assert!(typed, "{}", e);
            }
        }
    }

    #[test]
    fn a_valid_scan_decodes_to_its_values((kind, ranges, intensities, stamp) in valid_scan()) {
        let reply = Reply::parse(scan_lines(kind, &ranges, &intensities, stamp)).unwrap();
        prop_assert_eq!(reply.status, Status::SCAN);
        let scan = reply.scan(kind, ranges.len()).unwrap();
        prop_assert_eq!(scan.timestamp_ms, stamp);
        prop_assert_eq!(scan.ranges, ranges);
        prop_assert_eq!(scan.intensities, intensities);
    }
}

/// How one body line (the time stamp or data) of a valid scan is spoiled.
#[derive(Debug, Clone)]
enum Damage {
    /// One byte changed to any other byte but LF.
    Byte { at: Index, byte: u8 },
    /// Cut short.
    Cut { keep: Index },
    /// Left out.
    Drop,
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        (any::<Index>(), any::<u8>()).prop_map(|(at, byte)| Damage::Byte { at, byte }),
        any::<Index>().prop_map(|keep| Damage::Cut { keep }),
        Just(Damage::Drop),
    ]
}

proptest! {
    // Three kinds of damage, each as often as a property of its own.
    #![proptest_config(ProptestConfig::with_cases(3 * 512))]

    #[test]
    fn a_scan_spoiled_in_one_line_is_refused(
        (kind, ranges, intensities, stamp) in valid_scan(),
        line in any::<Index>(),
        damage in damage(),
    ) {
        let mut lines = scan_lines(kind, &ranges, &intensities, stamp);
        let line = 2 + line.index(lines.len() - 2);
        match damage {
            Damage::Byte { at, byte } => {
                let at = at.index(lines[line].len());
                prop_assume!(byte != lines[line][at] && byte != b'\n');
                lines[line][at] = byte;
            }
            Damage::Cut { keep } => {
                let keep = keep.index(lines[line].len());
                lines[line].truncate(keep);
            }
            Damage::Drop => {
                lines.remove(line);
            }
        }
        let decoded = decode_scan(lines, kind, ranges.len());
        prop_assert!(decoded.is_err(), "decoded {:?}", decoded);
    }
}
