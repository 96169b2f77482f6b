//! A rate from the config file is checked as the source's `--rate` is, before any process
//! starts: out of range, the run is refused with the key and the range.

use tests::*;

#[test]
fn a_rate_out_of_range_in_the_config_is_refused_before_starting() {
    for (section, expected) in [
        (
            "[sim]\nrate = 1e-20\n",
            "[sim] rate (--rate) must be 0 (lockstep) or from 0.001 to 1000 scans per second, \
             not 1e-20",
        ),
        (
            "source = \"replay\"\n[replay]\nfile = \"log.clf\"\nrate = 1e-20\n",
            "[replay] rate (--rate) must be 0 (lockstep) or a speed factor from 0.001 to 1000",
        ),
    ] {
        let dir = scratch("rate-config");
        let config = dir.join("run.toml");
        std::fs::write(&config, section).unwrap();
        let out = dir.join("run");
        let output = launch(
            &domain("rate-config"),
            &out,
            &["--config", config.to_str().unwrap()],
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{section}: {stderr}");
        assert!(stderr.contains(expected), "{section}: {stderr}");
        assert!(!out.exists(), "refused before the run's directory was made");
    }
}
