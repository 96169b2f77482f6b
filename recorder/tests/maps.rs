//! Map snapshots are recorded at most once per MAP_PERIOD_NS of data time, and the run's
//! last one always: the file ends with the final map. Each recorded one is drawn as a scene.

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

    // Each recorded snapshot is drawn as a scene too, at its stamp.
    let scenes = summary
        .channels
        .iter()
        .find(|c| c.topic == "/slam/map_scene")
        .map_or(0, |c| c.messages);
    assert_eq!(scenes, maps);

    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let stamps = |topic: &str| -> Vec<u64> {
        mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| m.unwrap())
            .filter(|m| m.channel.topic == topic)
            .map(|m| m.log_time)
            .collect()
    };
    let period = MAP_PERIOD_NS;
    let expected = [0, period, 2 * period, 3 * period, 4 * period, 19 * half];
    assert_eq!(stamps("/slam/map"), expected);
    assert_eq!(stamps("/slam/map_scene"), expected);
    let _ = std::fs::remove_dir_all(&dir);
}
