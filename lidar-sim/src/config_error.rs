//! A sensor or vehicle setting outside its meaningful range.

/// Names the offending setting, its value and what it should be.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field} = {value}: {reason}")]
pub struct ConfigError {
    pub field: &'static str,
    pub value: f64,
    pub reason: &'static str,
}

/// `Err` naming `field` unless `ok`.
pub(crate) fn check(
    field: &'static str,
    value: f64,
    ok: bool,
    reason: &'static str,
) -> Result<(), ConfigError> {
    if ok {
        Ok(())
    } else {
        Err(ConfigError {
            field,
            value,
            reason,
        })
    }
}
