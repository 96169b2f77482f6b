//! A recording reads back (streaming) into the very scans and odometry that were recorded,
//! bit for bit; a file cut short reads up to its last complete chunk and says so; a file
//! that is no recording is refused before anything is replayed, saying why.

use std::path::{Path, PathBuf};

use ipc_types::{Header, LaserScan, Odometry, Pose2, Zeroable};
use recorder::{
    McapFile, OpenRecordingError, PoseMessage, ReadError, Recorded, RecordingReader, ScanMessage,
    open_recording,
};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("recorder-replay-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// xorshift64*: reproducible bits without a dependency.
struct Bits(u64);

impl Bits {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Any finite f32, every exponent and mantissa alike.
    fn finite_f32(&mut self) -> f32 {
        loop {
            let x = f32::from_bits(self.next() as u32);
            if x.is_finite() {
                return x;
            }
        }
    }

    /// Any finite f64.
    fn finite_f64(&mut self) -> f64 {
        loop {
            let x = f64::from_bits(self.next());
            if x.is_finite() {
                return x;
            }
        }
    }
}

/// A scan of `beams` beams with arbitrary finite ranges and some of every invalid kind.
fn scan(bits: &mut Bits, seq: u64, beams: usize, intensities: bool) -> Box<LaserScan> {
    let mut scan = LaserScan::boxed_zeroed();
    scan.header = Header::new(seq, 1_134_864_629_000_000_000 + seq * 25_000_001, "laser");
    scan.header.sent_ns = 1_700_000_000_000_000_000 + seq;
    scan.angle_min = bits.finite_f32();
    scan.angle_increment = bits.finite_f32();
    scan.time_increment = bits.finite_f32();
    scan.scan_time = bits.finite_f32();
    scan.range_min = bits.finite_f32();
    scan.range_max = bits.finite_f32();
    // Now and then a scan its source re-stamped, its own stamp later.
    if seq % 5 == 3 {
        scan.source_stamp_offset_ns = 400_000_000 + seq as i64;
    }
    let mut ranges: Vec<f32> = (0..beams).map(|_| bits.finite_f32()).collect();
    for (i, invalid) in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0]
        .into_iter()
        .enumerate()
    {
        ranges[(i * 7 + seq as usize) % beams] = invalid;
    }
    let intensities: Vec<f32> = if intensities {
        (0..beams).map(|_| bits.finite_f32()).collect()
    } else {
        Vec::new()
    };
    scan.set_beams(&ranges, &intensities).unwrap();
    scan
}

fn odometry(bits: &mut Bits, seq: u64) -> Box<Odometry> {
    let mut odometry = Odometry::boxed_zeroed();
    odometry.header = Header::new(seq, 1_134_864_629_000_000_000 + seq * 25_000_001, "odom");
    odometry.header.sent_ns = 1_700_000_000_000_000_000 + seq;
    odometry.pose = Pose2::new(bits.finite_f64(), bits.finite_f64(), bits.finite_f64());
    odometry.covariance = std::array::from_fn(|_| bits.finite_f64());
    odometry.linear_velocity = bits.finite_f64();
    odometry.angular_velocity = bits.finite_f64();
    odometry
}

/// Equal bit for bit, NaN ranges (whose payload is not kept) aside.
fn assert_same_scan(read: &LaserScan, written: &LaserScan) {
    let bits = |scan: &LaserScan| -> Vec<u32> {
        scan.ranges()
            .iter()
            .map(|r| {
                if r.is_nan() {
                    f32::NAN.to_bits()
                } else {
                    r.to_bits()
                }
            })
            .collect()
    };
    assert_eq!(bits(read), bits(written));
    let mut read = *read;
    let mut written = *written;
    read.ranges = [0.0; ipc_types::MAX_BEAMS];
    written.ranges = [0.0; ipc_types::MAX_BEAMS];
    assert_eq!(read, written);
    for (a, b) in read.intensities().iter().zip(written.intensities()) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
}

fn write_scan(file: &mut McapFile, scan: &LaserScan) {
    let h = scan.header;
    file.write(&ScanMessage::new(scan), h.stamp_ns, h.sent_ns)
        .unwrap();
}

fn write_odometry(file: &mut McapFile, odometry: &Odometry) {
    let h = odometry.header;
    file.write(odometry, h.stamp_ns, h.sent_ns).unwrap();
}

#[test]
fn scans_and_odometry_read_back_bit_for_bit_in_file_order() {
    let dir = scratch("exact");
    let mut bits = Bits(0x9e37_79b9_7f4a_7c15);
    let mut file = McapFile::create(&dir.join("run.mcap")).unwrap();
    let mut written = Vec::new();
    for seq in 0..300 {
        let odometry = odometry(&mut bits, seq);
        write_odometry(&mut file, &odometry);
        written.push(Recorded::Odometry(odometry));
        let scan = scan(&mut bits, seq, 1081, seq % 2 == 0);
        write_scan(&mut file, &scan);
        written.push(Recorded::Scan(scan));
        // Topics a replay passes over.
        let mut pose = ipc_types::PoseEstimate::boxed_zeroed();
        pose.header = Header::new(seq, 0, "map");
        file.write(&PoseMessage::new(&pose), 0, 0).unwrap();
    }
    file.finish().unwrap();

    let (mut reader, info) = open_recording(&dir.join("run.mcap")).unwrap();
    assert!(info.has_odometry);
    let Recorded::Scan(first) = &written[1] else {
        unreachable!()
    };
    assert_eq!(info.first_scan_ns, first.header.stamp_ns);
    let mut count = 0;
    for (read, written) in reader.by_ref().zip(&written) {
        match (read.unwrap(), written) {
            (Recorded::Scan(read), Recorded::Scan(written)) => assert_same_scan(&read, written),
            (Recorded::Odometry(read), Recorded::Odometry(written)) => {
                // Every f64 field as bits: PartialEq would let -0.0 pass for 0.0.
                let fields = |o: &Odometry| -> Vec<u64> {
                    [
                        o.pose.x,
                        o.pose.y,
                        o.pose.yaw,
                        o.linear_velocity,
                        o.angular_velocity,
                    ]
                    .into_iter()
                    .chain(o.covariance)
                    .map(f64::to_bits)
                    .collect()
                };
                assert_eq!(fields(&read), fields(written));
                assert_eq!(read.header, written.header);
            }
            (read, written) => panic!("{read:?} where {written:?} was written"),
        }
        count += 1;
    }
    assert_eq!(count, written.len());
    assert!(reader.next().is_none());
    assert_eq!(reader.messages_read(), 900);
    assert_eq!(reader.passed_over().get("/slam/pose"), Some(&300));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_f32_range_survives_its_shortest_decimal_form() {
    // The JSON holds each range in its shortest decimal form, read back through an f64:
    // no double rounding may move it, over a million arbitrary values.
    let mut bits = Bits(42);
    for _ in 0..1_000_000 {
        let x = bits.finite_f32();
        let text = serde_json::to_string(&x).unwrap();
        let back: f32 = serde_json::from_str(&text).unwrap();
        assert_eq!(back.to_bits(), x.to_bits(), "{x:e} written as {text}");
    }
}

#[test]
fn zero_intensities_are_not_written_and_come_back_as_zeros() {
    let mut scan = LaserScan::boxed_zeroed();
    scan.set_beams(&[1.0, 2.0, 3.0], &[]).unwrap();
    let json = serde_json::to_value(ScanMessage::new(&scan)).unwrap();
    assert_eq!(json["intensities"], serde_json::json!([]));
    let text = json.to_string();
    let Recorded::Scan(read) = recorder::ReplayedChannel::Scan
        .decode(text.as_bytes())
        .unwrap()
    else {
        unreachable!()
    };
    assert_eq!(read.intensities(), [0.0; 3]);
    assert_same_scan(&read, &scan);
}

/// A recording of `scans` scans whose recorder died before finishing it.
fn unfinished(path: &Path, scans: u64) {
    let mut bits = Bits(7);
    let mut file = McapFile::create(path).unwrap();
    for seq in 0..scans {
        write_scan(&mut file, &scan(&mut bits, seq, 1081, false));
    }
    std::mem::forget(file);
}

#[test]
fn a_recording_cut_short_reads_up_to_its_last_chunk_and_says_so() {
    let dir = scratch("cut");
    let path = dir.join("run.mcap");
    unfinished(&path, 300);
    let (reader, _) = open_recording(&path).unwrap();
    let mut scans = 0;
    let mut end = None;
    for next in reader {
        match next {
            Ok(Recorded::Scan(scan)) => {
                assert_eq!(scan.header.seq, scans, "in order, none missing");
                scans += 1;
            }
            Ok(other) => panic!("{other:?}"),
            Err(e) => end = Some(e),
        }
    }
    assert!((100..300).contains(&scans), "{scans} scans read");
    match end {
        Some(ReadError::Cut { messages, .. }) => assert_eq!(messages, scans),
        other => panic!("the cut is not reported: {other:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn refusal(path: &Path) -> String {
    match open_recording(path) {
        Ok(_) => panic!("{} was not refused", path.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn what_is_no_recording_is_refused_naming_the_problem() {
    let dir = scratch("refused");

    let text = dir.join("scans.mcap");
    std::fs::write(&text, "14029,14083\n".repeat(100)).unwrap();
    assert!(
        matches!(
            open_recording(&text),
            Err(OpenRecordingError::NotMcap { .. })
        ),
        "{}",
        refusal(&text)
    );
    assert!(refusal(&text).contains("is not an MCAP file"));

    let empty = dir.join("empty.mcap");
    std::fs::write(&empty, "").unwrap();
    let reason = refusal(&empty);
    assert!(reason.contains("empty.mcap"), "{reason}");

    let missing = dir.join("missing.mcap");
    assert!(
        refusal(&missing).starts_with(&format!("cannot open the recording {}", missing.display()))
    );

    // An MCAP file with no scans: a run recorded without a source, or someone else's.
    let foreign = dir.join("foreign.mcap");
    let mut file = McapFile::create(&foreign).unwrap();
    file.write(
        &PoseMessage::new(&ipc_types::PoseEstimate::boxed_zeroed()),
        0,
        0,
    )
    .unwrap();
    file.finish().unwrap();
    let reason = refusal(&foreign);
    assert!(
        reason.ends_with(
            "is not a recording of slam-record: no scan it can replay in its 1 messages; \
             topics in it: /slam/pose x1"
        ),
        "{reason}"
    );

    // Cut inside its first chunk: nothing can be replayed.
    let cut = dir.join("cut.mcap");
    unfinished(&cut, 300);
    let bytes = std::fs::read(&cut).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len().min(5_000)]).unwrap();
    let reason = refusal(&cut);
    assert!(
        reason.contains("is damaged before its first scan (after 0 messages)"),
        "{reason}"
    );

    // A byte flipped in the first chunk: its CRC refuses it rather than giving wrong data.
    let damaged = dir.join("damaged.mcap");
    unfinished(&damaged, 300);
    let mut bytes = std::fs::read(&damaged).unwrap();
    bytes[20_000] ^= 0x55;
    std::fs::write(&damaged, &bytes).unwrap();
    let reason = refusal(&damaged);
    assert!(
        reason.contains("is damaged before its first scan"),
        "{reason}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_damaged_chunk_later_on_ends_the_reading_there() {
    let dir = scratch("damaged-later");
    let path = dir.join("run.mcap");
    unfinished(&path, 300);
    let mut bytes = std::fs::read(&path).unwrap();
    // Well inside the second of the two or so complete chunks.
    let at = bytes.len() * 3 / 4;
    bytes[at] ^= 0x55;
    std::fs::write(&path, &bytes).unwrap();
    let reader = RecordingReader::new(std::fs::File::open(&path).unwrap());
    let results: Vec<_> = reader.collect();
    let scans = results.iter().filter(|r| r.is_ok()).count();
    assert!(scans > 0 && scans < 300, "{scans}");
    assert!(
        matches!(results.last(), Some(Err(ReadError::Cut { .. }))),
        "{:?}",
        results.last().map(|r| r.as_ref().err())
    );
    let _ = std::fs::remove_dir_all(&dir);
}
