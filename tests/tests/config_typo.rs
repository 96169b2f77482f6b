//! A typo in the config file is refused before any process starts, wherever it is: at the
//! top, or in the section of a process (which the launcher reads as that process's own
//! settings), with the file and the key, and the same exit status.

use tests::*;

#[test]
fn a_typo_in_a_process_s_section_is_refused_before_starting() {
    let refusal = |name: &str, text: &str| {
        let dir = scratch(name);
        let config = dir.join("run.toml");
        std::fs::write(&config, text).unwrap();
        let out = dir.join("run");
        let output = launch(&domain(name), &out, &["--config", config.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
        assert!(!output.status.success(), "{text}: {stderr}");
        assert!(
            stderr.contains(&format!("config file {}", config.display())),
            "{text}: {stderr}"
        );
        assert!(
            !out.exists(),
            "{text}: refused before the run's directory was made"
        );
        assert!(
            !stderr.contains("ready") && !stderr.contains("slam-proc:"),
            "{text}: no stage started: {stderr}"
        );
        (output.status.code(), stderr)
    };
    let (top_status, top) = refusal("typo-top", "[simulation]\nframes = 3\n");
    assert!(top.contains("simulation"), "{top}");
    for (text, key) in [
        ("[slam]\nparticles = 20\npartcles = 10\n", "partcles"),
        ("[slam.localize]\nmax_partcles = 10\n", "max_partcles"),
        ("[features]\nmax_rnge = 15\n", "max_rnge"),
        ("[front_end]\nvoxel = 0.1\n", "voxel"),
        ("[sim.vehicle]\nmax_acel = 1\n", "max_acel"),
    ] {
        let (status, stderr) = refusal("typo-section", text);
        assert!(
            stderr.contains(&format!("unknown field `{key}`")),
            "{text}: {stderr}"
        );
        assert_eq!(status, top_status, "{text}: as a typo at the top");
    }
}
