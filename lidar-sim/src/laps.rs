//! How many times the vehicle drives its world's route in a row (`lidar-sim --laps`,
//! `[sim] laps` in slam-launch's config).

/// The most laps a run may ask for: over a day of driving the office (a lap is about 100 s
/// and 4000 scans), far past any soak or test, while a typo of a few zeros is refused rather
/// than left running.
pub const MAX_LAPS: u32 = 1000;

/// A lap count from 1 to [`MAX_LAPS`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Laps(u32);

impl Laps {
    /// The route once, as a run without `--laps` drives it.
    pub const ONE: Laps = Laps(1);

    /// `laps`, if it is from 1 to [`MAX_LAPS`]; the error says the range.
    pub fn new(laps: i64) -> Result<Laps, String> {
        u32::try_from(laps)
            .ok()
            .filter(|n| (1..=MAX_LAPS).contains(n))
            .map(Laps)
            .ok_or_else(|| format!("must be from 1 to {MAX_LAPS} laps, not {laps}"))
    }

    pub fn get(self) -> u32 {
        self.0
    }
}

impl Default for Laps {
    fn default() -> Self {
        Laps::ONE
    }
}

/// `--laps`'s parser: a whole number that [`Laps::new`] takes.
pub fn parse_laps(text: &str) -> Result<Laps, String> {
    let laps: i64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a whole number of laps"))?;
    Laps::new(laps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_out_of_range_are_refused_with_the_range() {
        assert_eq!(parse_laps("3"), Ok(Laps(3)));
        assert_eq!(parse_laps(" 1000 "), Ok(Laps(MAX_LAPS)));
        for (text, error) in [
            ("0", "must be from 1 to 1000 laps, not 0"),
            ("-2", "must be from 1 to 1000 laps, not -2"),
            ("1001", "must be from 1 to 1000 laps, not 1001"),
            (
                "99999999999",
                "must be from 1 to 1000 laps, not 99999999999",
            ),
            ("2.5", "'2.5' is not a whole number of laps"),
            ("", "'' is not a whole number of laps"),
        ] {
            assert_eq!(parse_laps(text), Err(error.to_owned()), "{text:?}");
        }
        assert_eq!(Laps::default(), Laps::ONE);
    }
}
