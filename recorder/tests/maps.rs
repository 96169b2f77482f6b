//! Map snapshots are recorded at most once per MAP_PERIOD_NS of data time, and the run's
//! last one always: the file ends with the final map.

use ipc_types::{Header, MapSnapshot, Zeroable};
use recorder::{MAP_PERIOD_NS, Recording};

#[test]
fn maps_are_thinned_to_one_a_period_and_the_last_is_kept() {
    let dir = std::env::temp_dir().join(format!("recorder-maps-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut recording = Recording::create(&dir).unwrap();
    // A snapshot every half second for ten seconds: 0.0, 0.5, ... 9.5 s.
    let half = MAP_PERIOD_NS / 4;
    for i in 0..20 {
        let mut map = MapSnapshot::boxed_zeroed();
        map.header = Header::new(i, i * half, "map");
        recording.map(&map).unwrap();
    }
    let summary = recording.finish().unwrap();
    let maps = summary
        .channels
        .iter()
        .find(|c| c.topic == "/slam/map")
        .map_or(0, |c| c.messages);
    // 0, 2, 4, 6, 8 s, and the last (9.5 s).
    assert_eq!(maps, 6);
    assert_eq!(summary.maps_left_out, 14);

    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let stamps: Vec<u64> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap().log_time)
        .collect();
    let period = MAP_PERIOD_NS;
    assert_eq!(
        stamps,
        [0, period, 2 * period, 3 * period, 4 * period, 19 * half]
    );
    let _ = std::fs::remove_dir_all(&dir);
}
