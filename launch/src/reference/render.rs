//! The reference as a TOML file to copy (`slam-launch --print-config`) and as
//! docs/CONFIG.md (`slam-launch --print-config markdown`).

use std::fmt::Write;

use super::{Limit, SECTIONS, Section, Setting};
use crate::config::RunConfig;

/// The command that writes docs/CONFIG.md.
pub const REGENERATE: &str = "target/release/slam-launch --print-config markdown > docs/CONFIG.md";

/// The values of `config`, table by table, as TOML values.
pub(super) struct Values(pub(super) toml::Table);

impl Values {
    pub(super) fn of(config: &RunConfig) -> Result<Self, toml::ser::Error> {
        toml::Table::try_from(config).map(Self)
    }

    /// The value of `key` in `table` (`slam.localize`, or empty for the top), if set.
    pub(super) fn get(&self, table: &str, key: &str) -> Option<&toml::Value> {
        let mut current = &self.0;
        for part in table.split('.').filter(|p| !p.is_empty()) {
            current = current.get(part)?.as_table()?;
        }
        current.get(key).filter(|value| !value.is_table())
    }
}

/// The unit and range of a setting in words, e.g. ` Unit m; range [0.005, 5].`; empty when
/// there is nothing to say.
fn unit_and_range(setting: &Setting) -> String {
    let range = setting.range.text();
    let numbers = setting.range.low != Limit::None || setting.range.high != Limit::None;
    let range = match (range.as_str(), numbers) {
        ("any", _) => None,
        (_, true) => Some(format!("range {range}")),
        (_, false) => Some(format!("values: {range}")),
    };
    match (setting.unit, range) {
        ("", None) => String::new(),
        ("", Some(range)) => format!(" {}{}.", range[..1].to_uppercase(), &range[1..]),
        (unit, None) => format!(" Unit {unit}."),
        (unit, Some(range)) => format!(" Unit {unit}; {range}."),
    }
}

/// `config` as a TOML file: every key with its value and a comment line above it saying
/// what it means; a key that is unset appears commented out with an example value.
pub fn toml_file(config: &RunConfig) -> Result<String, toml::ser::Error> {
    let values = Values::of(config)?;
    let mut text = String::from(
        "# slam-launch's configuration: every key with its value (slam-launch --print-config).\n\
         # Keep the keys you change, drop the rest, and pass the file with --config FILE;\n\
         # options on the command line override it. docs/CONFIG.md has the same as tables.\n",
    );
    for section in &SECTIONS {
        text.push('\n');
        if !section.table.is_empty() {
            let _ = writeln!(text, "[{}]", section.table);
        }
        let _ = writeln!(text, "# {}", section.about);
        for setting in section.settings {
            let _ = writeln!(text, "# {}{}", setting.meaning, unit_and_range(setting));
            match values.get(section.table, setting.key) {
                Some(value) => {
                    let _ = writeln!(text, "{} = {value}", setting.key);
                }
                None => {
                    let example = setting.example.unwrap_or("...");
                    let _ = writeln!(text, "# {} = {example}  (unset)", setting.key);
                }
            }
        }
    }
    Ok(text)
}

/// docs/CONFIG.md: the defaults as tables, one per section.
pub fn markdown() -> Result<String, toml::ser::Error> {
    let values = Values::of(&RunConfig::default())?;
    let mut text = format!(
        "# Configuration reference\n\n\
         Generated from the settings types; do not edit by hand (a test compares this file \
         with what the code generates). To regenerate it: `{REGENERATE}`.\n\n\
         Every setting can be given in a TOML file passed with `slam-launch --config FILE`; \
         every key is optional (a key left out keeps its default), a key a section does not \
         know or a value out of its range stops the run before anything starts, and the \
         options on the command line override the file. `slam-launch --print-config` prints \
         the same settings as a TOML file to start from (with `--config` and options, the \
         values they give). Each process reads its own section, which slam-launch hands it \
         as a file of its own (`OUT/config/`); the effective configuration of a run is \
         `OUT/config.toml`.\n"
    );
    for section in &SECTIONS {
        section_table(&mut text, section, &values);
    }
    Ok(text)
}

fn section_table(text: &mut String, section: &Section, values: &Values) {
    let heading = if section.table.is_empty() {
        "Top-level keys".to_owned()
    } else {
        format!("`[{}]`", section.table)
    };
    let _ = write!(
        text,
        "\n## {heading}\n\n{}\n\n| key | default | unit | range | meaning |\n|---|---|---|---|---|\n",
        section.about
    );
    for setting in section.settings {
        let default = values
            .get(section.table, setting.key)
            .map_or_else(|| "unset".to_owned(), |v| format!("`{v}`"));
        let cells = [
            format!("`{}`", setting.key),
            default,
            setting.unit.to_owned(),
            setting.range.text(),
            setting.meaning.to_owned(),
        ];
        let cells: Vec<String> = cells.iter().map(|c| c.replace('|', "\\|")).collect();
        let _ = writeln!(text, "| {} |", cells.join(" | "));
    }
}
