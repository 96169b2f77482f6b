//! The configuration reference: every key of slam-launch's config file with its unit, its
//! range and one line of meaning, beside the defaults read from the settings types.
//!
//! The lines live here, one table per TOML section ([`SECTIONS`]); the defaults are
//! [`RunConfig::default`] serialized, so they cannot drift. The tests hold the rest to the
//! types: every key of the serialized configuration has its line and every line names a
//! key that exists, each default lies in its stated range, and a value just outside a
//! stated bound is refused by [`RunConfig::validate`] naming the key.
//!
//! `slam-launch --print-config` prints it as a TOML file to copy (the effective settings,
//! a comment line above each); `slam-launch --print-config markdown` prints
//! `docs/CONFIG.md`.

mod pipeline;
mod render;
mod run;
mod slam;

use std::f64::consts::{FRAC_PI_2, PI, TAU};

pub use render::{markdown, toml_file};

/// One bound of a range of numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Limit {
    /// No bound on this side.
    None,
    /// The bound itself is allowed.
    Incl(f64),
    /// The bound itself is not allowed.
    Excl(f64),
}

/// What values a setting takes: numbers between two limits, and a note in words for what
/// the limits cannot say (another setting, a special value, a choice of names).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub low: Limit,
    pub high: Limit,
    pub note: &'static str,
}

impl Range {
    /// Any value of the setting's type.
    pub const ANY: Self = Self::new(Limit::None, Limit::None);
    /// Finite and above zero.
    pub const POSITIVE: Self = Self::new(Limit::Excl(0.0), Limit::None);
    /// Finite and not below zero.
    pub const NON_NEGATIVE: Self = Self::new(Limit::Incl(0.0), Limit::None);
    /// A probability strictly between 0 and 1.
    pub const PROBABILITY: Self = Self::new(Limit::Excl(0.0), Limit::Excl(1.0));
    /// A fraction from 0 to 1, both included.
    pub const FRACTION: Self = Self::new(Limit::Incl(0.0), Limit::Incl(1.0));

    pub const fn new(low: Limit, high: Limit) -> Self {
        Self {
            low,
            high,
            note: "",
        }
    }

    /// From `low` to `high`, both included.
    pub const fn closed(low: f64, high: f64) -> Self {
        Self::new(Limit::Incl(low), Limit::Incl(high))
    }

    /// At least `low`.
    pub const fn at_least(low: f64) -> Self {
        Self::new(Limit::Incl(low), Limit::None)
    }

    /// Only a note in words: what the values are is not a range of numbers.
    pub const fn words(note: &'static str) -> Self {
        Self::ANY.and(note)
    }

    /// The same limits with a note added.
    pub const fn and(self, note: &'static str) -> Self {
        Self { note, ..self }
    }

    /// Whether `value` lies within the limits (the note is not checked).
    pub fn contains(&self, value: f64) -> bool {
        let above = match self.low {
            Limit::None => true,
            Limit::Incl(low) => value >= low,
            Limit::Excl(low) => value > low,
        };
        let below = match self.high {
            Limit::None => true,
            Limit::Incl(high) => value <= high,
            Limit::Excl(high) => value < high,
        };
        above && below
    }

    /// The range as the reference writes it: `> 0`, `[0, 1]`, `(0, pi/2]`, with the note.
    pub fn text(&self) -> String {
        // Each side as (bracket, inequality, number).
        let low = match self.low {
            Limit::None => None,
            Limit::Incl(a) => Some(('[', ">=", a)),
            Limit::Excl(a) => Some(('(', ">", a)),
        };
        let high = match self.high {
            Limit::None => None,
            Limit::Incl(b) => Some((']', "<=", b)),
            Limit::Excl(b) => Some((')', "<", b)),
        };
        let limits = match (low, high) {
            (None, None) => String::new(),
            (Some((_, op, a)), None) | (None, Some((_, op, a))) => {
                format!("{op} {}", number_text(a))
            }
            (Some((open, _, a)), Some((close, _, b))) => {
                format!("{open}{}, {}{close}", number_text(a), number_text(b))
            }
        };
        match (limits.is_empty(), self.note.is_empty()) {
            (true, true) => "any".to_owned(),
            (true, false) => self.note.to_owned(),
            (false, true) => limits,
            (false, false) => format!("{limits}, {}", self.note),
        }
    }
}

/// A number as a person reads it: multiples of pi by name, others as Rust prints them.
fn number_text(value: f64) -> String {
    for (constant, name) in [(PI, "pi"), (TAU, "2 pi"), (FRAC_PI_2, "pi/2")] {
        if value == constant {
            return name.to_owned();
        }
        if value == -constant {
            return format!("-{name}");
        }
    }
    format!("{value}")
}

/// One key of a section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setting {
    pub key: &'static str,
    /// `m`, `rad`, `s`, `m^2/m`, ...; empty for a count, a flag or a name.
    pub unit: &'static str,
    pub range: Range,
    pub meaning: &'static str,
    /// For a key that is unset by default: a value it could take, shown commented out.
    pub example: Option<&'static str>,
}

/// A key that has a default.
pub const fn set(
    key: &'static str,
    unit: &'static str,
    range: Range,
    meaning: &'static str,
) -> Setting {
    Setting {
        key,
        unit,
        range,
        meaning,
        example: None,
    }
}

/// A key that is unset by default, with a value it could take.
pub const fn unset(
    key: &'static str,
    unit: &'static str,
    range: Range,
    example: &'static str,
    meaning: &'static str,
) -> Setting {
    Setting {
        example: Some(example),
        ..set(key, unit, range, meaning)
    }
}

/// One table of the config file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// The TOML table, e.g. `slam.localize`; empty for the keys at the top.
    pub table: &'static str,
    /// Who reads it, in one line.
    pub about: &'static str,
    pub settings: &'static [Setting],
}

/// Every section, in the order the config file has them.
pub const SECTIONS: [Section; 14] = [
    run::RUN,
    run::SIM,
    run::SIM_SENSOR,
    run::SIM_VEHICLE,
    run::SIM_VEHICLE_ODOMETRY,
    run::REPLAY,
    run::HOKUYO,
    pipeline::FEATURES,
    pipeline::FRONT_END,
    slam::SLAM,
    slam::LOCALIZE,
    run::GRID,
    run::RECORD,
    run::FOXGLOVE,
];

#[cfg(test)]
mod tests;
