//! Foxglove's `time`: a stamp as whole seconds and nanoseconds.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A stamp in Foxglove's form (`{sec, nsec}`, `nsec` below 1e9). Our stamps are
/// nanoseconds in a `u64`, so the split is exact both ways.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct Time {
    pub sec: u64,
    #[schemars(range(max = 999_999_999))]
    pub nsec: u32,
}

impl Time {
    pub fn from_ns(ns: u64) -> Self {
        Self {
            sec: ns / 1_000_000_000,
            // Below 1e9, so it fits.
            nsec: (ns % 1_000_000_000) as u32,
        }
    }

    /// The stamp in nanoseconds, or `None` for a `nsec` of a second or more, or a stamp
    /// beyond `u64` (not what [`Time::from_ns`] makes).
    pub fn to_ns(self) -> Option<u64> {
        if self.nsec >= 1_000_000_000 {
            return None;
        }
        self.sec
            .checked_mul(1_000_000_000)?
            .checked_add(u64::from(self.nsec))
    }
}
