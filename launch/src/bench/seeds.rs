//! The list of seeds a benchmark runs: `1-5`, `1,2,3`, or both mixed (`1-3,7`).

/// Why a seed list was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SeedsError {
    #[error("'{0}' is not a seed or a range of seeds (e.g. 4 or 1-5)")]
    Item(String),
    #[error("the range {0}-{1} runs backwards")]
    Backwards(u64, u64),
    #[error("seed {0} is given twice")]
    Repeated(u64),
}

/// Parses a comma-separated list of seeds and inclusive ranges `A-B`, in the order given;
/// a seed given twice is refused (it would count twice in the spread over seeds).
pub fn parse_seeds(text: &str) -> Result<Vec<u64>, SeedsError> {
    let mut seeds = Vec::new();
    for item in text.split(',').map(str::trim) {
        let number = |s: &str| {
            s.trim()
                .parse::<u64>()
                .map_err(|_| SeedsError::Item(item.to_owned()))
        };
        let (first, last) = match item.split_once('-') {
            Some((a, b)) => (number(a)?, number(b)?),
            None => {
                let seed = number(item)?;
                (seed, seed)
            }
        };
        if last < first {
            return Err(SeedsError::Backwards(first, last));
        }
        for seed in first..=last {
            if seeds.contains(&seed) {
                return Err(SeedsError::Repeated(seed));
            }
            seeds.push(seed);
        }
    }
    // Splitting never yields nothing, and an empty item is refused: the list is not empty.
    Ok(seeds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_lists_and_both() {
        assert_eq!(parse_seeds("1"), Ok(vec![1]));
        assert_eq!(parse_seeds("1-5"), Ok(vec![1, 2, 3, 4, 5]));
        assert_eq!(parse_seeds("1,2,3"), Ok(vec![1, 2, 3]));
        assert_eq!(parse_seeds("7, 1-3"), Ok(vec![7, 1, 2, 3]));
        assert_eq!(parse_seeds("4-4"), Ok(vec![4]));
    }

    #[test]
    fn mistakes_are_named() {
        assert_eq!(parse_seeds("5-1"), Err(SeedsError::Backwards(5, 1)));
        assert_eq!(parse_seeds("1-3,2"), Err(SeedsError::Repeated(2)));
        assert_eq!(parse_seeds("1,,2"), Err(SeedsError::Item(String::new())));
        assert_eq!(parse_seeds("x"), Err(SeedsError::Item("x".into())));
        assert_eq!(parse_seeds("-3"), Err(SeedsError::Item("-3".into())));
        assert_eq!(parse_seeds("1-"), Err(SeedsError::Item("1-".into())));
        assert_eq!(parse_seeds("1-2-3"), Err(SeedsError::Item("1-2-3".into())));
        assert_eq!(parse_seeds(""), Err(SeedsError::Item(String::new())));
    }
}
