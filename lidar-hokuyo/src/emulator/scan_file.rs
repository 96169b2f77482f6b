//! Recorded scans: a CSV file, one scan a line, one integer per step in millimetres (the
//! sensor's raw values, error codes included), as in `seed-hall/scans.csv`.

use std::path::{Path, PathBuf};

/// Why a scan file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum ScanFileError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}: value {field} ({text:?}) is not a range in millimetres")]
    Value {
        path: PathBuf,
        line: usize,
        field: usize,
        text: String,
    },
    #[error("{path}:{line}: {len} values, but the first scan has {expected}")]
    Ragged {
        path: PathBuf,
        line: usize,
        len: usize,
        expected: usize,
    },
    #[error("{path} holds no scans")]
    Empty { path: PathBuf },
}

/// Reads every scan of `path`; all must have the same number of values.
pub fn load_scans(path: &Path) -> Result<Vec<Vec<u32>>, ScanFileError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScanFileError::Read {
        path: path.to_owned(),
        source,
    })?;
    parse_scans(&text, path)
}

/// Parses the text of a scan file (`path` names it in errors).
pub fn parse_scans(text: &str, path: &Path) -> Result<Vec<Vec<u32>>, ScanFileError> {
    let mut scans: Vec<Vec<u32>> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let scan = line
            .split(',')
            .enumerate()
            .map(|(field, value)| {
                value
                    .trim()
                    .parse::<u32>()
                    .map_err(|_| ScanFileError::Value {
                        path: path.to_owned(),
                        line: i + 1,
                        field: field + 1,
                        text: value.to_owned(),
                    })
            })
            .collect::<Result<Vec<u32>, _>>()?;
        if let Some(first) = scans.first()
            && first.len() != scan.len()
        {
            return Err(ScanFileError::Ragged {
                path: path.to_owned(),
                line: i + 1,
                len: scan.len(),
                expected: first.len(),
            });
        }
        scans.push(scan);
    }
    if scans.is_empty() {
        return Err(ScanFileError::Empty {
            path: path.to_owned(),
        });
    }
    Ok(scans)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_lines_of_integers() {
        let scans = parse_scans("1,2,3\n4, 5 ,6\n\n", Path::new("x.csv")).unwrap();
        assert_eq!(scans, vec![vec![1, 2, 3], vec![4, 5, 6]]);
    }

    #[test]
    fn bad_files_are_named_errors() {
        let path = Path::new("x.csv");
        assert!(matches!(
            parse_scans("1,2\n1,2,3\n", path),
            Err(ScanFileError::Ragged { line: 2, .. })
        ));
        assert!(matches!(
            parse_scans("1,-2\n", path),
            Err(ScanFileError::Value {
                line: 1,
                field: 2,
                ..
            })
        ));
        assert!(matches!(
            parse_scans("\n", path),
            Err(ScanFileError::Empty { .. })
        ));
        let missing = load_scans(Path::new("/nonexistent/scans.csv")).unwrap_err();
        assert!(missing.to_string().contains("/nonexistent/scans.csv"));
    }
}
