use std::collections::BTreeSet;
use std::f64::consts::FRAC_PI_2;

use super::render::Values;
use super::*;
use crate::config::{RunConfig, SourceKind};

/// Every `(table, key)` of `table` whose value is not itself a table.
fn leaf_keys(table: &toml::Table, prefix: &str, out: &mut BTreeSet<(String, String)>) {
    for (key, value) in table {
        match value.as_table() {
            Some(inner) => {
                let path = if prefix.is_empty() {
                    key.clone()
                } else {
                    format!("{prefix}.{key}")
                };
                leaf_keys(inner, &path, out);
            }
            None => {
                out.insert((prefix.to_owned(), key.clone()));
            }
        }
    }
}

fn table_of(config: &RunConfig) -> toml::Table {
    toml::Table::try_from(config).unwrap()
}

/// `value` at `key` of `table` (created if missing) in `root`.
fn put(root: &mut toml::Table, table: &str, key: &str, value: toml::Value) {
    let mut current = root;
    for part in table.split('.').filter(|p| !p.is_empty()) {
        current = current
            .entry(part)
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .unwrap();
    }
    current.insert(key.to_owned(), value);
}

fn all_settings() -> impl Iterator<Item = (&'static str, &'static Setting)> {
    SECTIONS
        .iter()
        .flat_map(|section| section.settings.iter().map(move |s| (section.table, s)))
}

fn example_value(example: &str) -> toml::Value {
    let table: toml::Table = toml::from_str(&format!("v = {example}")).unwrap();
    table["v"].clone()
}

#[test]
fn every_key_has_its_line_and_every_line_names_a_key() {
    let mut defaults = BTreeSet::new();
    leaf_keys(&table_of(&RunConfig::default()), "", &mut defaults);
    let mut lines = BTreeSet::new();
    for (table, setting) in all_settings() {
        let entry = (table.to_owned(), setting.key.to_owned());
        assert!(lines.insert(entry.clone()), "{entry:?} has two lines");
        match setting.example {
            None => assert!(
                defaults.contains(&entry),
                "the reference has a line for {entry:?}, which the configuration does not have"
            ),
            Some(example) => {
                assert!(!defaults.contains(&entry), "{entry:?} is set by default");
                // An unknown key is refused (deny_unknown_fields): the key exists.
                let mut root = toml::Table::new();
                put(&mut root, table, setting.key, example_value(example));
                let read: Result<RunConfig, _> = root.try_into();
                assert!(read.is_ok(), "{entry:?} = {example}: {read:?}");
            }
        }
    }
    let missing: Vec<_> = defaults.difference(&lines).collect();
    assert!(
        missing.is_empty(),
        "settings without a line in the reference (launch/src/reference/): {missing:?}"
    );
}

#[test]
fn every_default_lies_in_its_stated_range() {
    let values = Values::of(&RunConfig::default()).unwrap();
    let mut checked = 0;
    for (table, setting) in all_settings() {
        let number = match values.get(table, setting.key) {
            Some(toml::Value::Float(v)) => *v,
            Some(toml::Value::Integer(v)) => *v as f64,
            _ => continue,
        };
        assert!(
            setting.range.contains(number),
            "[{table}] {} = {number} is outside its range {}",
            setting.key,
            setting.range.text()
        );
        checked += 1;
    }
    assert!(checked > 60, "{checked}");
}

/// A configuration that runs every check: a replay, so the replay's settings are checked.
fn probe_base() -> RunConfig {
    let mut config = RunConfig {
        source: SourceKind::Replay,
        ..RunConfig::default()
    };
    config.replay.file = Some("log.clf".into());
    config
}

/// The values just past each limit of `range`, of the type of `like`.
fn past_the_limits(range: &Range, like: &toml::Value) -> Vec<toml::Value> {
    let integer = like.is_integer();
    let step = |v: f64| {
        if integer {
            1.0
        } else {
            1e-6 * v.abs().max(1.0)
        }
    };
    let below = match range.low {
        Limit::None => None,
        Limit::Incl(v) => Some(v - step(v)),
        Limit::Excl(v) => Some(v),
    };
    let above = match range.high {
        Limit::None => None,
        Limit::Incl(v) => Some(v + step(v)),
        Limit::Excl(v) => Some(v),
    };
    let mut probes: Vec<toml::Value> = [below, above]
        .into_iter()
        .flatten()
        .map(|v| {
            if integer {
                toml::Value::Integer(v as i64)
            } else {
                toml::Value::Float(v)
            }
        })
        .collect();
    if !integer && !probes.is_empty() {
        probes.push(toml::Value::Float(f64::NAN));
    }
    probes
}

#[test]
fn a_value_past_a_stated_limit_is_refused_naming_its_key() {
    let base = probe_base();
    base.validate().unwrap();
    let defaults = table_of(&base);
    let mut probed = 0;
    for (table, setting) in all_settings() {
        let like = match setting.example {
            Some(example) => example_value(example),
            None => Values(defaults.clone())
                .get(table, setting.key)
                .cloned()
                .unwrap_or_else(|| panic!("[{table}] {} has no value", setting.key)),
        };
        for probe in past_the_limits(&setting.range, &like) {
            let mut root = defaults.clone();
            put(&mut root, table, setting.key, probe.clone());
            // A value its type cannot hold (a negative count) is refused as it is read.
            let Ok(config) = root.try_into::<RunConfig>() else {
                continue;
            };
            let refusal = config.validate().err().map(|e| e.to_string());
            assert!(
                refusal.as_ref().is_some_and(|m| m.contains(setting.key)),
                "[{table}] {} = {probe} (range {}): {refusal:?}",
                setting.key,
                setting.range.text()
            );
            probed += 1;
        }
    }
    assert!(probed > 120, "{probed}");
}

#[test]
fn the_toml_file_reads_back_as_the_configuration() {
    let mut config = RunConfig {
        relations: Some("aces.relations".into()),
        ..RunConfig::default()
    };
    config.slam.filter.particles = 7;
    config.slam.filter.localize.initial_sigma_yaw = 0.25;
    for config in [RunConfig::default(), config] {
        let text = toml_file(&config).unwrap();
        assert_eq!(
            toml::from_str::<RunConfig>(&text).unwrap(),
            config,
            "{text}"
        );
        for (_, setting) in all_settings() {
            assert!(
                text.contains(&format!("\n{} = ", setting.key))
                    || text.contains(&format!("\n# {} = ", setting.key)),
                "{}",
                setting.key
            );
        }
    }
    let text = toml_file(&RunConfig::default()).unwrap();
    assert!(text.contains(
        "# Edge of a grid cell (--resolution). Unit m; range [0.005, 5].\nresolution = 0.05\n"
    ));
    assert!(text.contains("# relations = \"aces.relations\"  (unset)\n"));
}

#[test]
fn docs_config_md_is_the_generated_reference() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/CONFIG.md");
    let written = std::fs::read_to_string(&path).unwrap_or_default();
    let generated = markdown().unwrap();
    assert!(
        written == generated,
        "docs/CONFIG.md is not what the settings types generate; regenerate it with `{}`",
        render::REGENERATE
    );
    assert!(generated.contains(
        "| `resolution` | `0.05` | m | [0.005, 5] | Edge of a grid cell (--resolution). |"
    ));
}

#[test]
fn ranges_read_as_written() {
    assert_eq!(Range::ANY.text(), "any");
    assert_eq!(Range::POSITIVE.text(), "> 0");
    assert_eq!(Range::NON_NEGATIVE.text(), ">= 0");
    assert_eq!(Range::PROBABILITY.text(), "(0, 1)");
    assert_eq!(Range::closed(0.005, 5.0).text(), "[0.005, 5]");
    assert_eq!(
        Range::new(Limit::Excl(0.0), Limit::Incl(FRAC_PI_2)).text(),
        "(0, pi/2]"
    );
    assert_eq!(
        Range::new(Limit::None, Limit::Excl(std::f64::consts::PI)).text(),
        "< pi"
    );
    assert_eq!(
        Range::at_least(1.0).and("at least min_particles").text(),
        ">= 1, at least min_particles"
    );
    assert_eq!(
        Range::words("sim, replay or hokuyo").text(),
        "sim, replay or hokuyo"
    );
    assert!(Range::PROBABILITY.contains(0.5));
    assert!(!Range::PROBABILITY.contains(1.0));
    assert!(Range::FRACTION.contains(1.0));
}
