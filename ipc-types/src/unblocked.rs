//! Opening a file without following a link or blocking, and judging it by what was opened.
//!
//! A path can be swapped between a look at it (`stat`) and its open; a FIFO blocks an open
//! for reading until a writer comes, and a signal does not end that wait. So a file is
//! opened first, without blocking (and, in a directory others can write, without following
//! a link), and what it is and whose it is is asked of the open file (`fstat`).

use std::fs::{File, Metadata};
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

use nix::fcntl::OFlag;

/// Whether a link at the path itself is followed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Links {
    /// A link is refused (`ELOOP`): the path lies in a directory others can write.
    Refuse,
    /// A link is followed: a path the user named, whose links are theirs.
    Follow,
}

/// Opens `path` for reading without blocking (a FIFO opens at once) and, with
/// [`Links::Refuse`], without following a link; returns the file and its `fstat`.
pub fn open_unblocked(path: &Path, links: Links) -> std::io::Result<(File, Metadata)> {
    let mut flags = OFlag::O_NONBLOCK | OFlag::O_NOCTTY;
    if links == Links::Refuse {
        flags |= OFlag::O_NOFOLLOW;
    }
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(flags.bits())
        .open(path)?;
    let metadata = file.metadata()?;
    Ok((file, metadata))
}

/// What kind of file `metadata` describes, in words for an error.
pub fn kind_of(metadata: &Metadata) -> &'static str {
    let kind = metadata.file_type();
    if kind.is_file() {
        "a regular file"
    } else if kind.is_dir() {
        "a directory"
    } else if kind.is_fifo() {
        "a FIFO"
    } else if kind.is_char_device() {
        "a character device"
    } else if kind.is_block_device() {
        "a block device"
    } else if kind.is_socket() {
        "a socket"
    } else if kind.is_symlink() {
        "a symbolic link"
    } else {
        "of an unknown kind"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "ipc-types-unblocked-{tag}-{}-{}",
            std::process::id(),
            crate::now_ns()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_fifo_opens_at_once_and_says_what_it_is() {
        let dir = scratch("fifo");
        let fifo = dir.join("fifo");
        nix::unistd::mkfifo(&fifo, nix::sys::stat::Mode::from_bits_truncate(0o600)).unwrap();
        let (_file, metadata) = open_unblocked(&fifo, Links::Follow).unwrap();
        assert_eq!(kind_of(&metadata), "a FIFO");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_link_is_refused_or_followed_as_asked() {
        let dir = scratch("link");
        let target = dir.join("target");
        std::fs::write(&target, b"x").unwrap();
        let link = dir.join("link");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let refused = open_unblocked(&link, Links::Refuse).unwrap_err();
        assert_eq!(refused.raw_os_error(), Some(nix::libc::ELOOP));
        let (_file, metadata) = open_unblocked(&link, Links::Follow).unwrap();
        assert_eq!(kind_of(&metadata), "a regular file");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
