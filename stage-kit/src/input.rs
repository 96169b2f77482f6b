//! Opening a file a run reads: its world, map, log, relations, settings or recording.
//!
//! Every such file is opened without blocking (a FIFO would hold the open, and Ctrl-C
//! with it), judged by what was opened (`fstat`): a regular file, never a device, a FIFO
//! or a directory, and no larger than the limit its kind of file has, which the refusal
//! names. Reading stops at that limit too, so a file that grows while it is read (or a
//! `/proc` file, whose size says nothing) cannot fill the memory. A link the user made is
//! followed: what it leads to is what is judged.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

pub use ipc_types::unblocked::Links;
use ipc_types::unblocked::{kind_of, open_unblocked};

/// A kind of input file and the most bytes one may have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InputKind {
    /// What the file is, for errors ("world file").
    pub what: &'static str,
    /// The limit's name, for errors (the constant that holds it).
    pub limit_name: &'static str,
    /// The most bytes such a file may have.
    pub max_bytes: u64,
}

/// Why an input file was refused.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("cannot open the {what} {path}")]
    Open {
        what: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("the {what} {path} is {kind}, not a regular file")]
    NotRegular {
        what: &'static str,
        path: PathBuf,
        kind: &'static str,
    },
    #[error(
        "the {what} {path} has {size} bytes or more, above the {max_bytes} a {what} may have \
         ({limit_name})"
    )]
    TooLarge {
        what: &'static str,
        path: PathBuf,
        size: u64,
        max_bytes: u64,
        limit_name: &'static str,
    },
    #[error("cannot read the {what} {path}")]
    Read {
        what: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl InputKind {
    /// Opens `path` as a file of this kind: without blocking, a regular file within the
    /// limit. The file reads blocking as usual (a regular file never blocks).
    pub fn open(&self, path: &Path, links: Links) -> Result<File, InputError> {
        let (file, metadata) = open_unblocked(path, links).map_err(|source| InputError::Open {
            what: self.what,
            path: path.to_owned(),
            source,
        })?;
        if !metadata.is_file() {
            return Err(InputError::NotRegular {
                what: self.what,
                path: path.to_owned(),
                kind: kind_of(&metadata),
            });
        }
        self.within_limit(path, metadata.len())?;
        Ok(file)
    }

    /// The whole file at `path`, checked as [`InputKind::open`] does.
    pub fn read(&self, path: &Path) -> Result<Vec<u8>, InputError> {
        let file = self.open(path, Links::Follow)?;
        let mut bytes = Vec::new();
        // One byte past the limit tells a file that grew beyond it from one that fits.
        file.take(self.max_bytes.saturating_add(1))
            .read_to_end(&mut bytes)
            .map_err(|source| InputError::Read {
                what: self.what,
                path: path.to_owned(),
                source,
            })?;
        self.within_limit(path, bytes.len() as u64)?;
        Ok(bytes)
    }

    /// The whole file at `path` as text, checked as [`InputKind::open`] does.
    pub fn read_to_string(&self, path: &Path) -> Result<String, InputError> {
        String::from_utf8(self.read(path)?).map_err(|e| InputError::Read {
            what: self.what,
            path: path.to_owned(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
        })
    }

    fn within_limit(&self, path: &Path, size: u64) -> Result<(), InputError> {
        if size > self.max_bytes {
            return Err(InputError::TooLarge {
                what: self.what,
                path: path.to_owned(),
                size,
                max_bytes: self.max_bytes,
                limit_name: self.limit_name,
            });
        }
        Ok(())
    }
}

/// A settings (TOML) file: a few hundred lines at most.
pub const SETTINGS_INPUT: InputKind = InputKind {
    what: "config file",
    limit_name: "stage_kit::input::SETTINGS_INPUT",
    max_bytes: 1 << 20,
};

#[cfg(test)]
mod tests {
    use super::*;

    const TINY: InputKind = InputKind {
        what: "test file",
        limit_name: "TINY",
        max_bytes: 8,
    };

    fn scratch(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "stage-kit-input-{tag}-{}-{}",
            std::process::id(),
            ipc_types::now_ns()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_device_a_directory_and_a_large_file_are_refused_by_name() {
        let error = TINY.read(Path::new("/dev/zero")).unwrap_err().to_string();
        assert_eq!(
            error,
            "the test file /dev/zero is a character device, not a regular file"
        );
        let dir = scratch("kinds");
        let error = TINY.read(&dir).unwrap_err().to_string();
        assert!(
            error.ends_with("is a directory, not a regular file"),
            "{error}"
        );
        let large = dir.join("large");
        std::fs::write(&large, b"123456789").unwrap();
        let error = TINY.read(&large).unwrap_err().to_string();
        assert!(
            error.ends_with("has 9 bytes or more, above the 8 a test file may have (TINY)"),
            "{error}"
        );
        let fits = dir.join("fits");
        std::fs::write(&fits, b"12345678").unwrap();
        assert_eq!(TINY.read_to_string(&fits).unwrap(), "12345678");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_link_to_a_device_is_judged_by_what_it_leads_to() {
        let dir = scratch("link");
        let link = dir.join("map.pgm");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let error = TINY.read(&link).unwrap_err().to_string();
        assert!(
            error.ends_with("is a character device, not a regular file"),
            "{error}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
