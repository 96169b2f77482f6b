//! A recorder that dies leaves a file readable up to its last complete chunk: the chunks
//! reach the disk as they close, by size or at least once a second.

use std::path::PathBuf;

use ipc_types::{Header, LaserScan, Zeroable};
use recorder::{FLUSH_PERIOD, McapFile, ScanMessage};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("recorder-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 1081-beam scan whose ranges change from scan to scan, as a real one's do.
fn scan(seq: u64) -> Box<LaserScan> {
    let mut scan = LaserScan::boxed_zeroed();
    scan.header = Header::new(seq, seq * 25_000_000, "laser");
    scan.angle_min = -2.356;
    scan.angle_increment = 0.004_363;
    scan.range_max = 30.0;
    let ranges: Vec<f32> = (0..1081)
        .map(|i| 1.0 + ((i as u64 * 7919 + seq * 104_729) % 10_007) as f32 * 1.234_567e-3)
        .collect();
    scan.set_beams(&ranges, &[]).unwrap();
    scan
}

fn write(file: &mut McapFile, seq: u64) {
    let scan = scan(seq);
    file.write(&ScanMessage::new(&scan), scan.header.stamp_ns, 0)
        .unwrap();
}

/// A new file in a scratch directory of its own (`name`), with scans 0 .. `scans` in it.
fn file_with_scans(name: &str, scans: u64) -> (PathBuf, McapFile) {
    let path = scratch(name).join("run.mcap");
    let mut file = McapFile::create(&path).unwrap();
    for seq in 0..scans {
        write(&mut file, seq);
    }
    (path, file)
}

/// The messages a reader gets from the file before it finds it cut off.
fn readable(path: &std::path::Path) -> Vec<u64> {
    let bytes = std::fs::read(path).unwrap();
    let mut stamps = Vec::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        match message {
            Ok(message) => stamps.push(message.log_time),
            Err(_) => break,
        }
    }
    stamps
}

#[test]
fn a_file_never_finished_reads_up_to_its_last_full_chunk() {
    let (path, file) = file_with_scans("cut", 300);
    // Dies here: no last chunk, no summary, no footer.
    std::mem::forget(file);
    let stamps = readable(&path);
    // About a hundred of these scans fill a chunk: the full chunks are there, in order, and
    // the open one is not.
    assert!(
        stamps.len() >= 200 && stamps.len() < 300,
        "{}",
        stamps.len()
    );
    let expected: Vec<u64> = (0..stamps.len() as u64).map(|s| s * 25_000_000).collect();
    assert_eq!(stamps, expected);
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}

#[test]
fn a_slow_run_is_on_disk_within_the_flush_period() {
    let (path, mut file) = file_with_scans("slow", 5);
    std::thread::sleep(FLUSH_PERIOD + std::time::Duration::from_millis(100));
    // The first message after the period closes the chunk with it.
    write(&mut file, 5);
    std::mem::forget(file);
    assert_eq!(readable(&path).len(), 6);
    let _ = std::fs::remove_dir_all(path.parent().unwrap());
}
