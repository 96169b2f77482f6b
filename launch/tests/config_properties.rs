//! Property tests of the TOML configuration, as slam-launch loads the run's file and as each
//! process loads its section (`toml::from_str` into its config type, then `validate`):
//! whatever the bytes, nothing panics, and a refusal is a typed error that names the
//! problem: the file, and the key or the line at fault. Inputs are bounded (a few KiB), so
//! memory is; nested arrays deep enough to exhaust a recursive parser's stack are fed too.

use std::fmt::Display;
use std::path::Path;

use launch::config::{ConfigError, RunConfig};
use proptest::collection::vec;
use proptest::prelude::*;
use serde::de::DeserializeOwned;
use stage_kit::SettingsFileError;

/// The keys a config type knows, from the error for one it does not (every section refuses
/// unknown keys and lists the ones it takes).
fn known_keys<T: DeserializeOwned + std::fmt::Debug>() -> Vec<String> {
    let error = toml::from_str::<T>("no_such_key_anywhere = 1").expect_err("unknown key refused");
    let text = error.to_string();
    let list = text.split("expected one of").nth(1).unwrap_or_default();
    list.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

/// Values of every kind TOML has, in range and out of it.
const VALUES: &[&str] = &[
    "0",
    "-1",
    "1",
    "0.5",
    "3",
    "100",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "inf",
    "-inf",
    "9223372036854775807",
    "18446744073709551616",
    "\"x\"",
    "\"\"",
    "true",
    "false",
    "[]",
    "[1, 2]",
    "{}",
    "1979-05-27",
    "0x10",
    "1_000",
    "+",
    "",
];

/// `key = value` lines from the known keys, a misspelt one and the values above.
fn near_valid_lines(keys: Vec<String>) -> impl Strategy<Value = Vec<(String, String)>> {
    let mut keys = keys;
    keys.push("misspelt_key".to_owned());
    vec(
        (
            prop::sample::select(keys),
            prop::sample::select(VALUES).prop_map(str::to_owned),
        ),
        0..8,
    )
}

fn text_of(lines: &[(String, String)]) -> String {
    lines
        .iter()
        .map(|(key, value)| format!("{key} = {value}\n"))
        .collect()
}

/// A section's text as its process loads it: a refusal must name a key of the section or
/// the line of a syntax error.
fn check_section<T, E>(
    text: &str,
    validate: impl Fn(&T) -> Result<(), E>,
) -> Result<(), TestCaseError>
where
    T: DeserializeOwned + std::fmt::Debug,
    E: Display,
{
    let keys = known_keys::<T>();
    let names_problem = |message: &str| {
        message.contains("line")
            || keys
                .iter()
                .chain(std::iter::once(&"misspelt_key".to_owned()))
                .any(|key| message.contains(key.as_str()))
    };
    match toml::from_str::<T>(text) {
        Err(e) => {
            let message = e.to_string();
            prop_assert!(names_problem(&message), "{text}: {message}");
        }
        Ok(config) => {
            if let Err(e) = validate(&config) {
                let message = e.to_string();
                prop_assert!(
                    keys.iter().any(|key| message.contains(key.as_str())),
                    "{text}: {message}"
                );
            }
        }
    }
    Ok(())
}

/// Each process's section as its process loads it: slam-proc's, feature-proc's, the front
/// end's, and the simulator's sensor and vehicle, in that order.
fn check_every_section(texts: [&str; 5]) -> Result<(), TestCaseError> {
    let [slam, features, front_end, sensor, vehicle] = texts;
    check_section::<slam_proc::SlamConfig, _>(slam, |c| c.validate())?;
    check_section::<feature_proc::FeatureConfig, _>(features, |c| c.validate())?;
    check_section::<scan_match::FrontEndConfig, _>(front_end, |c| c.validate())?;
    check_section::<lidar_sim::SensorConfig, _>(sensor, |c| c.validate())?;
    check_section::<lidar_sim::VehicleConfig, _>(vehicle, |c| c.validate())?;
    Ok(())
}

/// The run's file as slam-launch loads and checks it; a refusal names the file.
fn check_run(text: &str) -> Result<(), TestCaseError> {
    let path = Path::new("run.toml");
    match RunConfig::parse(text, path) {
        Err(e) => {
            let parse_error = matches!(e, ConfigError::File(SettingsFileError::Parse { .. }));
            prop_assert!(parse_error, "{}", e);
            let message = format!("{:#}", anyhow::Error::new(e));
            prop_assert!(message.starts_with("config file run.toml: "), "{message}");
            prop_assert!(message.len() > "config file run.toml: ".len());
        }
        Ok(config) => {
            if let Err(e) = config.validate() {
                let invalid = matches!(e, ConfigError::Invalid(_));
                prop_assert!(invalid, "{}", e);
                prop_assert!(!e.to_string().is_empty());
            }
        }
    }
    Ok(())
}

/// Sections of the run's file and the keys the launcher itself reads in them.
const RUN_SECTIONS: &[(&str, &[&str])] = &[
    ("", &["source", "relations", "stall_warning", "stall_limit"]),
    ("sim", &["world", "frames", "rate", "seed", "odometry"]),
    (
        "replay",
        &[
            "file",
            "format",
            "rate",
            "odometry",
            "frames",
            "reorder_window",
        ],
    ),
    ("hokuyo", &["addr"]),
    ("slam", &["particles", "seed", "view_range"]),
    ("features", &["max_range"]),
    ("front_end", &["voxel_size"]),
];

fn run_file() -> impl Strategy<Value = String> {
    let section = (0..RUN_SECTIONS.len()).prop_flat_map(|index| {
        let (name, keys) = RUN_SECTIONS[index];
        let mut keys: Vec<String> = keys.iter().map(|k| (*k).to_owned()).collect();
        keys.push("source".to_owned());
        near_valid_lines(keys).prop_map(move |lines| {
            let head = if name.is_empty() {
                String::new()
            } else {
                format!("[{name}]\n")
            };
            head + &text_of(&lines)
        })
    });
    vec(section, 0..5).prop_map(|sections| sections.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn arbitrary_bytes_as_the_run_file_are_a_config_or_a_named_error(
        bytes in vec(any::<u8>(), 0..2000),
    ) {
        check_run(&String::from_utf8_lossy(&bytes))?;
    }

    #[test]
    fn near_valid_run_files_are_a_config_or_a_named_error(text in run_file()) {
        check_run(&text)?;
    }

    #[test]
    fn arbitrary_bytes_as_a_section_are_a_config_or_a_named_error(
        bytes in vec(any::<u8>(), 0..2000),
    ) {
        let text = String::from_utf8_lossy(&bytes);
        check_every_section([&text; 5])?;
    }

    #[test]
    fn near_valid_sections_are_a_config_or_a_named_error(
        slam in near_valid_lines(known_keys::<slam_proc::SlamConfig>()),
        features in near_valid_lines(known_keys::<feature_proc::FeatureConfig>()),
        front_end in near_valid_lines(known_keys::<scan_match::FrontEndConfig>()),
        sensor in near_valid_lines(known_keys::<lidar_sim::SensorConfig>()),
        vehicle in near_valid_lines(known_keys::<lidar_sim::VehicleConfig>()),
    ) {
        check_every_section([
            &text_of(&slam),
            &text_of(&features),
            &text_of(&front_end),
            &text_of(&sensor),
            &text_of(&vehicle),
        ])?;
    }

    #[test]
    fn deeply_nested_values_are_refused_without_exhausting_the_stack(
        depth in 1usize..20_000,
        key in prop::sample::select(vec!["particles", "slam", "stall_limit"]),
    ) {
        let text = format!("{key} = {}{}", "[".repeat(depth), "]".repeat(depth));
        check_run(&text)?;
        check_section::<slam_proc::SlamConfig, _>(&text, |c| c.validate())?;
    }
}

#[test]
fn the_key_lists_are_read_from_the_types() {
    let keys = known_keys::<slam_proc::SlamConfig>();
    assert!(keys.contains(&"particles".to_owned()), "{keys:?}");
    assert!(known_keys::<scan_match::FrontEndConfig>().contains(&"voxel_size".to_owned()));
    assert!(known_keys::<RunConfig>().contains(&"stall_limit".to_owned()));
}
