//! Settings files and the range checks of settings.
//!
//! Every library keeps its settings in a serde struct (`#[serde(default,
//! deny_unknown_fields)]`, so a typo is an error rather than a default silently kept); a
//! process reads one from a TOML file with [`load`] and checks it with the library's
//! `validate`, built from [`check`].

use std::borrow::Cow;
use std::ops::{Bound, RangeBounds};
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// Why a settings file was refused.
#[derive(Debug, thiserror::Error)]
pub enum SettingsFileError {
    #[error(transparent)]
    Read(#[from] crate::InputError),
    #[error("config file {path}")]
    Parse {
        path: PathBuf,
        #[source]
        source: Box<toml::de::Error>,
    },
}

/// The settings in the TOML file at `path`, or their defaults without one.
pub fn load<T: Default + DeserializeOwned>(path: Option<&Path>) -> Result<T, SettingsFileError> {
    match path {
        Some(path) => load_file(path),
        None => Ok(T::default()),
    }
}

/// The settings in the TOML file at `path`.
pub fn load_file<T: DeserializeOwned>(path: &Path) -> Result<T, SettingsFileError> {
    let text = crate::input::SETTINGS_INPUT.read_to_string(path)?;
    parse(&text, path)
}

/// The settings in `text`, read from the file at `path` (named in the error).
pub fn parse<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, SettingsFileError> {
    toml::from_str(text).map_err(|source| SettingsFileError::Parse {
        path: path.to_owned(),
        source: Box::new(source),
    })
}

/// A setting outside its meaningful range: names it, its value and what it should be.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field} = {value}: {reason}")]
pub struct SettingError {
    /// The offending setting.
    pub field: &'static str,
    /// Its value (counts converted to `f64`).
    pub value: f64,
    /// What it should be.
    pub reason: Cow<'static, str>,
}

/// `Err` naming `field`, `value` and `reason` unless `ok`.
pub fn check(
    field: &'static str,
    value: f64,
    ok: bool,
    reason: &'static str,
) -> Result<(), SettingError> {
    if ok {
        Ok(())
    } else {
        Err(SettingError {
            field,
            value,
            reason: reason.into(),
        })
    }
}

/// Checks that every `(field, value)` is finite and above zero.
pub fn check_positive(fields: &[(&'static str, f64)]) -> Result<(), SettingError> {
    fields.iter().try_for_each(|&(field, value)| {
        check(
            field,
            value,
            value.is_finite() && value > 0.0,
            "must be finite and > 0",
        )
    })
}

/// Checks that every `(field, value)` is finite and not below zero.
pub fn check_non_negative(fields: &[(&'static str, f64)]) -> Result<(), SettingError> {
    fields.iter().try_for_each(|&(field, value)| {
        check(
            field,
            value,
            value.is_finite() && value >= 0.0,
            "must be finite and >= 0",
        )
    })
}

/// Checks that every `(field, value)` lies in `range` (so finite); the error names the
/// range in `unit` ("m", "m^2/m"), which is what keeps the work a setting asks for bounded.
pub fn check_within(
    fields: &[(&'static str, f64)],
    range: std::ops::RangeInclusive<f64>,
    unit: &str,
) -> Result<(), SettingError> {
    fields.iter().try_for_each(|&(field, value)| {
        if range.contains(&value) {
            return Ok(());
        }
        Err(SettingError {
            field,
            value,
            reason: format!("must be from {} to {} {unit}", range.start(), range.end()).into(),
        })
    })
}

/// Checks that every count `(field, value)` lies in `range` (`lo..=hi`, `lo..` or `..=hi`);
/// the error says which range.
pub fn check_counts(
    fields: &[(&'static str, usize)],
    range: impl RangeBounds<usize>,
) -> Result<(), SettingError> {
    fields.iter().try_for_each(|&(field, value)| {
        if range.contains(&value) {
            return Ok(());
        }
        let reason = match (range.start_bound(), range.end_bound()) {
            (Bound::Included(lo), Bound::Included(hi)) => format!("must be in {lo}..={hi}"),
            (Bound::Included(lo), _) => format!("must be >= {lo}"),
            (_, Bound::Included(hi)) => format!("must be <= {hi}"),
            _ => "is out of range".to_owned(),
        };
        Err(SettingError {
            field,
            value: value as f64,
            reason: reason.into(),
        })
    })
}

/// The setting a configuration is refused for once `spoil` has changed its defaults (`None`
/// if it passes `validate`): what the tests of a config's range checks ask.
pub fn refused_field<T: Default>(
    spoil: impl FnOnce(&mut T),
    validate: impl Fn(&T) -> Result<(), SettingError>,
) -> Option<&'static str> {
    let mut config = T::default();
    spoil(&mut config);
    validate(&config).err().map(|e| e.field)
}

/// The named fields of a config as `[(name, value), ...]`, for [`check_positive`],
/// [`check_non_negative`] (`f64` fields) and [`check_counts`] (`usize` fields): each field is written once and its name is its spelling, with a
/// prefix for a nested section's (`named_fields!(self, "localize."; sigma_hit)`).
#[macro_export]
macro_rules! named_fields {
    ($config:expr, $prefix:literal; $($field:ident),+ $(,)?) => {
        [$((concat!($prefix, stringify!($field)), $config.$field)),+]
    };
    ($config:expr; $($field:ident),+ $(,)?) => {
        [$((stringify!($field), $config.$field)),+]
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Default, PartialEq, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    struct Sample {
        gain: f64,
        count: u32,
    }

    #[test]
    fn no_file_is_the_defaults_and_a_file_fills_in_the_rest() {
        assert_eq!(load::<Sample>(None).unwrap(), Sample::default());
        let read: Sample = parse("gain = 2.5", Path::new("x.toml")).unwrap();
        assert_eq!(
            read,
            Sample {
                gain: 2.5,
                count: 0
            }
        );
    }

    #[test]
    fn errors_name_the_file_and_the_key() {
        let error = parse::<Sample>("gian = 2.5", Path::new("run.toml")).unwrap_err();
        let refused = check_within(&[("reach", 1e9)], 0.0..=100.0, "m").unwrap_err();
        assert_eq!(
            refused.to_string(),
            "reach = 1000000000: must be from 0 to 100 m"
        );
        let shown = format!("{:#}", anyhow::Error::new(error));
        assert!(shown.starts_with("config file run.toml: "), "{shown}");
        assert!(shown.contains("unknown field `gian`"), "{shown}");
        let missing = load::<Sample>(Some(Path::new("/nonexistent/run.toml"))).unwrap_err();
        assert!(matches!(missing, SettingsFileError::Read(_)));
        assert!(missing.to_string().contains("/nonexistent/run.toml"));
    }

    #[test]
    fn a_failed_check_names_the_setting() {
        assert!(check("gain", 1.0, true, "must be positive").is_ok());
        let error = check("gain", -1.0, false, "must be positive").unwrap_err();
        assert_eq!(error.to_string(), "gain = -1: must be positive");
        let fields = [("a", 1.0), ("b", 0.0), ("c", f64::NAN)];
        assert_eq!(check_positive(&fields).unwrap_err().field, "b");
        assert_eq!(check_non_negative(&fields).unwrap_err().field, "c");
        assert!(check_non_negative(&fields[..2]).is_ok());
    }

    #[test]
    fn counts_out_of_range_name_the_range() {
        let counts = [("beams", 0), ("keyframes", 50)];
        assert!(check_counts(&counts[1..], 1..=64).is_ok());
        let refused = |range: (Bound<usize>, Bound<usize>)| {
            check_counts(&counts, range).unwrap_err().to_string()
        };
        use Bound::{Included, Unbounded};
        assert_eq!(
            refused((Included(1), Included(64))),
            "beams = 0: must be in 1..=64"
        );
        assert_eq!(refused((Included(1), Unbounded)), "beams = 0: must be >= 1");
        assert_eq!(
            check_counts(&counts, ..=10).unwrap_err().to_string(),
            "keyframes = 50: must be <= 10"
        );
    }

    #[test]
    fn a_spoilt_default_is_refused_for_its_field() {
        let validate = |s: &Sample| check("gain", s.gain, s.gain >= 0.0, "must be >= 0");
        assert_eq!(refused_field(|_: &mut Sample| {}, validate), None);
        assert_eq!(
            refused_field(|s: &mut Sample| s.gain = -1.0, validate),
            Some("gain")
        );
    }

    #[test]
    fn named_fields_are_checked_under_their_own_names() {
        struct Gains {
            gain: f64,
            floor: f64,
        }
        let gains = Gains {
            gain: 2.0,
            floor: -1.0,
        };
        assert_eq!(
            named_fields!(gains; gain, floor),
            [("gain", 2.0), ("floor", -1.0)]
        );
        assert_eq!(
            check_non_negative(&named_fields!(gains, "section."; gain, floor)),
            Err(SettingError {
                field: "section.floor",
                value: -1.0,
                reason: "must be finite and >= 0".into(),
            })
        );
    }
}
