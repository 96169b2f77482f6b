//! A run's own iceoryx2 domain, so two pipelines or two tests on one machine never cross.
//!
//! A domain is also its user's: iceoryx2 keeps node and service files under one root
//! directory (`/tmp/iceoryx2/` by default, made by the first user with mode 0750, which
//! every other user then cannot write: "cannot create node ... InternalError") and its
//! shared memory in /dev/shm under a prefix. Each user gets a root of their own, made
//! owner-only, and a prefix with their uid, so runs of two users never share a file and
//! neither's sweep of abandoned runs touches the other's.

use std::os::unix::fs::{DirBuilderExt, MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::PathBuf;

use iceoryx2::config::Config;
use iceoryx2::prelude::*;

use crate::shm::SHM_DIR;
use crate::unblocked::{Links, kind_of, open_unblocked};

/// Characters a domain name may have: they become part of file names in /dev/shm.
const MAX_DOMAIN_LEN: usize = 40;
/// A domain with no live node whose files are this old is abandoned.
const ABANDONED_AFTER: std::time::Duration = std::time::Duration::from_secs(60);
/// Prefix of every file a domain leaves in /dev/shm and in its iceoryx2 root; the user's
/// uid follows (see [`user_prefix`]).
pub const FILE_PREFIX: &str = "slam_";
/// The file a launcher keeps locked in /dev/shm while its run lives (see [`Domain::claim`]).
const OWNER_FILE: &str = "owner.lock";
/// Mode of every file of a domain: its user's alone.
const OWNER_ONLY_FILE: u32 = 0o600;
/// Mode of the user's iceoryx2 root directory.
const OWNER_ONLY_DIR: u32 = 0o700;
/// Bits that let anyone but the owner in.
const GROUP_OTHER_BITS: u32 = 0o077;

/// Why a domain name was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DomainError {
    #[error("domain name is empty")]
    Empty,
    #[error("domain name '{0}' is longer than {MAX_DOMAIN_LEN} characters")]
    TooLong(String),
    #[error("domain name '{0}' may only contain ASCII letters, digits and '-'")]
    BadCharacter(String),
}

/// Why a node could not be created.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    #[error("node name '{0}' is not a valid iceoryx2 node name")]
    BadName(String),
    // The cause is the source, not part of the message: `{:#}` would print it twice.
    #[error("cannot prepare the iceoryx2 directory {}", path.display())]
    RootDir {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error(
        "the iceoryx2 directory {} is not this user's own (owner uid {owner}, mode \
         {mode:o}, a link: {link}); remove it, or run as its owner",
        path.display()
    )]
    RootNotPrivate {
        path: std::path::PathBuf,
        owner: u32,
        mode: u32,
        link: bool,
    },
    #[error("cannot make {} owner-only", path.display())]
    Restrict {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("cannot create node '{name}' in domain '{domain}'")]
    Create {
        name: String,
        domain: String,
        source: iceoryx2::node::NodeCreationFailure,
    },
}

/// A file in /dev/shm under this user's prefix that is not this user's regular file:
/// planted by someone else (a FIFO would block an open, a link redirect it), so it is
/// neither opened nor removed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{} is not this user's file ({kind}, owner uid {owner}); left alone", path.display())]
pub struct ForeignFile {
    pub path: PathBuf,
    pub kind: &'static str,
    pub owner: u32,
}

/// What a sweep of abandoned runs did.
#[derive(Debug, Default)]
pub struct Sweep {
    /// The domains cleaned up.
    pub cleaned: Vec<String>,
    /// Files under this user's prefix that are not this user's, whose domains were left.
    pub foreign: Vec<ForeignFile>,
}

/// Why a domain could not be claimed for a run.
#[derive(Debug, thiserror::Error)]
pub enum ClaimError {
    #[error("domain '{0}' belongs to another slam-launch that is still running")]
    InUse(String),
    #[error("cannot claim domain '{domain}'")]
    Foreign {
        domain: String,
        #[source]
        file: ForeignFile,
    },
    #[error("cannot claim domain '{domain}' with {path}: {source}")]
    Io {
        domain: String,
        path: std::path::PathBuf,
        source: std::io::Error,
    },
}

/// A launcher's hold on its domain, for as long as it lives: an exclusive lock on the
/// domain's owner file. The kernel drops the lock when the process dies however it dies
/// (SIGKILL included), so a domain whose owner file is not locked is known to be abandoned
/// at once, where a domain without one must first age (a pipeline starting right now has
/// files but no live node yet).
#[derive(Debug)]
pub struct Claim {
    _file: std::fs::File,
}

/// Whether a launcher owns a domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    /// No owner file: started by hand or by a test.
    None,
    /// An owner file nobody holds: its launcher has died.
    Gone,
    /// Held by a live launcher.
    Alive,
}

/// A run's domain: its name and the iceoryx2 configuration whose root and prefix keep its
/// files apart from every other run's and every other user's.
#[derive(Debug, Clone)]
pub struct Domain {
    name: String,
    config: Config,
    root: std::path::PathBuf,
}

impl Domain {
    /// A domain named `name` (ASCII letters, digits and '-', at most 40 characters).
    pub fn new(name: &str) -> Result<Self, DomainError> {
        if name.is_empty() {
            return Err(DomainError::Empty);
        }
        if name.len() > MAX_DOMAIN_LEN {
            return Err(DomainError::TooLong(name.to_owned()));
        }
        if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
            return Err(DomainError::BadCharacter(name.to_owned()));
        }
        let mut config = Config::default();
        // Validated above: letters, digits, '-' and '_' always make a valid file name.
        config.global.prefix = FileName::new(Self::prefix_of(name).as_bytes())
            .map_err(|_| DomainError::BadCharacter(name.to_owned()))?;
        let root = user_root();
        // Trailing '/' as iceoryx2's own default has it; the path is ASCII by construction.
        let root_text = format!("{}/", root.display());
        let root_path = iceoryx2::prelude::Path::new(root_text.as_bytes())
            .map_err(|_| DomainError::BadCharacter(name.to_owned()))?;
        config.global.set_root_path(&root_path);
        Ok(Self {
            name: name.to_owned(),
            config,
            root,
        })
    }

    /// The domain's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file-name prefix of every shared-memory resource of this domain.
    pub fn file_prefix(&self) -> String {
        Self::prefix_of(&self.name)
    }

    fn prefix_of(name: &str) -> String {
        // '_' cannot occur in a name, so the prefix of one domain is never the start of
        // another's.
        format!("{}{name}_", user_prefix())
    }

    /// The directory under which iceoryx2 keeps this domain's node and service files: the
    /// user's own.
    pub fn root(&self) -> &std::path::Path {
        &self.root
    }

    /// The iceoryx2 configuration of this domain.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Creates a node in this domain. Signal handling is ours ([`crate::shutdown`]). The
    /// user's iceoryx2 root is made first if need be (owner-only), and the domain's files in
    /// /dev/shm are owner-only once the node exists.
    pub fn node(&self, name: &str) -> Result<Node<ipc::Service>, NodeError> {
        let node_name = NodeName::new(name).map_err(|_| NodeError::BadName(name.to_owned()))?;
        prepare_private_dir(&self.root)?;
        let node = NodeBuilder::new()
            .name(&node_name)
            .config(&self.config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|source| NodeError::Create {
                name: name.to_owned(),
                domain: self.name.clone(),
                source,
            })?;
        self.restrict_shm_files()?;
        Ok(node)
    }

    /// Takes group and other access away from this user's files of the domain in /dev/shm.
    /// iceoryx2 0.10 makes one of them, the global management segment its first node
    /// creates, readable and writable by everyone (`enable_global_access(true)`, whatever
    /// the configuration says); the others it makes owner-only already.
    fn restrict_shm_files(&self) -> Result<(), NodeError> {
        let restrict = |path: std::path::PathBuf, source| NodeError::Restrict { path, source };
        let dir = std::path::Path::new(SHM_DIR);
        let files = self
            .leftovers_in(dir)
            .map_err(|e| restrict(dir.to_path_buf(), e))?;
        let uid = effective_uid();
        for path in files {
            let metadata = match std::fs::symlink_metadata(&path) {
                Ok(metadata) => metadata,
                // Removed meanwhile by the process that made it.
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(restrict(path, e)),
            };
            if metadata.uid() != uid || metadata.mode() & GROUP_OTHER_BITS == 0 {
                continue;
            }
            let mode = std::fs::Permissions::from_mode(metadata.mode() & !GROUP_OTHER_BITS);
            match std::fs::set_permissions(&path, mode) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(restrict(path, e)),
            }
        }
        Ok(())
    }

    fn owner_path(&self) -> std::path::PathBuf {
        std::path::Path::new(SHM_DIR).join(format!("{}{OWNER_FILE}", self.file_prefix()))
    }

    /// Claims this domain for the calling process until the returned [`Claim`] is dropped
    /// or the process ends; refused while another live process holds it. Its owner file
    /// lies with the domain's other files and goes with [`Domain::remove_leftovers`].
    pub fn claim(&self) -> Result<Claim, ClaimError> {
        let path = self.owner_path();
        let io = |source| ClaimError::Io {
            domain: self.name.clone(),
            path: path.clone(),
            source,
        };
        // Locked under a name of no domain before it takes its place, so a sweep never
        // finds the owner file of a live run unlocked.
        let temp = std::path::Path::new(SHM_DIR).join(format!(
            ".slam-claim-{}-{}",
            std::process::id(),
            crate::now_ns()
        ));
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(OWNER_ONLY_FILE)
            .open(&temp)
            .map_err(io)?;
        let claimed = file
            .try_lock()
            .map_err(|e| io(std::io::Error::other(e.to_string())))
            .and_then(|()| {
                // Twice at most: once more after removing the file of a dead owner.
                for _ in 0..2 {
                    match std::fs::hard_link(&temp, &path) {
                        Ok(()) => return Ok(()),
                        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                        Err(e) => return Err(io(e)),
                    }
                    let owner = owner_at(&path).map_err(|e| match e {
                        OwnerError::Io(source) => io(source),
                        OwnerError::Foreign(file) => ClaimError::Foreign {
                            domain: self.name.clone(),
                            file,
                        },
                    })?;
                    if owner == Owner::Alive {
                        return Err(ClaimError::InUse(self.name.clone()));
                    }
                    match std::fs::remove_file(&path) {
                        Ok(()) => {}
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                        Err(e) => return Err(io(e)),
                    }
                }
                // Another launcher claimed it between our removal and our link.
                Err(ClaimError::InUse(self.name.clone()))
            });
        let _ = std::fs::remove_file(&temp);
        claimed.map(|()| Claim { _file: file })
    }

    /// Who holds this domain; a foreign owner file is reported, not opened.
    fn owner(&self) -> Result<Owner, ForeignFile> {
        match owner_at(&self.owner_path()) {
            Ok(owner) => Ok(owner),
            Err(OwnerError::Foreign(file)) => Err(file),
            // Unreadable counts as alive: a run we cannot judge is left alone.
            Err(OwnerError::Io(_)) => Ok(Owner::Alive),
        }
    }

    /// This domain's files in /dev/shm that are not this user's regular files.
    fn foreign_files(&self) -> Vec<ForeignFile> {
        let Ok(files) = self.leftovers_in(std::path::Path::new(SHM_DIR)) else {
            return Vec::new();
        };
        files
            .into_iter()
            .filter_map(|path| {
                let metadata = std::fs::symlink_metadata(&path).ok()?;
                foreign(&path, &metadata)
            })
            .collect()
    }

    /// Deletes what iceoryx2 leaves of this domain in /dev/shm once every process of it has
    /// ended (its global management segment outlives the last node). Call it only when no
    /// process of the domain is alive. Returns the number of files removed.
    pub fn remove_leftovers(&self) -> std::io::Result<usize> {
        self.remove_leftovers_in(std::path::Path::new(SHM_DIR))
    }

    /// Files in `dir` that belong to this domain.
    pub fn leftovers_in(&self, dir: &std::path::Path) -> std::io::Result<Vec<std::path::PathBuf>> {
        let prefix = self.file_prefix();
        let mut found = Vec::new();
        for entry in std::fs::read_dir(dir)? {
            let entry = entry?;
            if entry.file_name().to_string_lossy().starts_with(&prefix) {
                found.push(entry.path());
            }
        }
        Ok(found)
    }

    fn remove_leftovers_in(&self, dir: &std::path::Path) -> std::io::Result<usize> {
        let mut removed = 0;
        for path in self.leftovers_in(dir)? {
            match std::fs::remove_file(&path) {
                Ok(()) => removed += 1,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(e),
            }
        }
        Ok(removed)
    }

    /// True when every file of this domain in /dev/shm is older than `age`.
    fn is_older_than(&self, age: std::time::Duration) -> bool {
        let Ok(files) = self.leftovers_in(std::path::Path::new(SHM_DIR)) else {
            return false;
        };
        files.iter().all(|path| {
            std::fs::symlink_metadata(path)
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|elapsed| elapsed >= age)
        })
    }

    /// Nodes of this domain whose processes are alive.
    pub fn alive_nodes(&self) -> usize {
        let mut alive = 0;
        // A listing error means there are no nodes yet.
        let _ = Node::<ipc::Service>::list(&self.config, |state| {
            if let NodeState::Alive(_) = state {
                alive += 1;
            }
            CallbackProgression::Continue
        });
        alive
    }

    /// Cleans up every domain of this user in /dev/shm that no live process uses any more:
    /// dead nodes are removed and, where no node is alive, the domain's files too. Run at
    /// start so crashed runs do not pile up shared memory. A domain claimed by a live
    /// launcher is left to it; one whose launcher died is cleaned at once, one never
    /// claimed once its files are a minute old. Other users' domains are theirs to clean,
    /// and a domain with a file under this user's prefix that is not this user's (anyone
    /// can create one in /dev/shm) is left as it is and the file reported.
    pub fn sweep_abandoned() -> Sweep {
        let mut sweep = Sweep::default();
        for name in Self::user_domain_names() {
            let Ok(domain) = Domain::new(&name) else {
                continue;
            };
            let foreign = domain.foreign_files();
            if !foreign.is_empty() {
                sweep.foreign.extend(foreign);
                continue;
            }
            let owner = match domain.owner() {
                Ok(owner) => owner,
                Err(file) => {
                    sweep.foreign.push(file);
                    continue;
                }
            };
            if owner != Owner::Alive && domain.sweep_one(owner) {
                sweep.cleaned.push(name);
            }
        }
        sweep
    }

    /// The names of this user's domains that have files in /dev/shm.
    fn user_domain_names() -> Vec<String> {
        let Ok(entries) = std::fs::read_dir(SHM_DIR) else {
            return Vec::new();
        };
        let prefix = user_prefix();
        let mut names: Vec<String> = entries
            .filter_map(|entry| entry.ok())
            .filter_map(|entry| {
                let file = entry.file_name().to_string_lossy().into_owned();
                let rest = file.strip_prefix(&prefix)?;
                Some(rest.split('_').next()?.to_owned())
            })
            .collect();
        names.sort();
        names.dedup();
        names
    }

    /// Cleans this unclaimed or orphaned domain; true when something was removed.
    fn sweep_one(&self, owner: Owner) -> bool {
        let dead = self.cleanup_dead_nodes();
        // A pipeline starting right now has files but no node yet: leave young domains,
        // unless their launcher is known to be dead.
        if self.alive_nodes() == 0 && (owner == Owner::Gone || self.is_older_than(ABANDONED_AFTER))
        {
            self.remove_leftovers().unwrap_or(0) > 0 || dead > 0
        } else {
            dead > 0
        }
    }

    /// Removes the resources of this domain's nodes whose processes died, so a killed
    /// subscriber no longer blocks a lossless publisher. Returns how many were removed.
    pub fn cleanup_dead_nodes(&self) -> usize {
        let mut removed = 0;
        // A listing error means there is nothing of this domain to clean yet.
        let _ = Node::<ipc::Service>::list(&self.config, |state| {
            if let NodeState::Dead(view) = state
                && view.try_remove_stale_resources().is_ok()
            {
                removed += 1;
            }
            CallbackProgression::Continue
        });
        removed
    }
}

/// The effective uid of this process: the owner of every file it makes.
fn effective_uid() -> u32 {
    nix::unistd::geteuid().as_raw()
}

/// The start of every file name of this user's domains: [`FILE_PREFIX`], `u`, the uid, `_`.
pub fn user_prefix() -> String {
    format!("{FILE_PREFIX}u{}_", effective_uid())
}

/// This user's iceoryx2 root directory (see the module's documentation). In /tmp, where
/// iceoryx2's default is, and not under `$TMPDIR`: every process of a run must find the same
/// one whatever its environment.
pub fn user_root() -> std::path::PathBuf {
    std::path::PathBuf::from(format!("/tmp/slam-iceoryx2-{}", effective_uid()))
}

/// Makes `dir` (mode 0700) unless it exists, and checks that it is this user's own: a real
/// directory, owned by this user, open to nobody else. One that another user made first in a
/// shared /tmp could watch or disturb every run, so it is refused, not used.
fn prepare_private_dir(dir: &std::path::Path) -> Result<(), NodeError> {
    let io = |source| NodeError::RootDir {
        path: dir.to_path_buf(),
        source,
    };
    match std::fs::DirBuilder::new().mode(OWNER_ONLY_DIR).create(dir) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(io(e)),
    }
    let metadata = std::fs::symlink_metadata(dir).map_err(io)?;
    let link = metadata.file_type().is_symlink();
    if link || !metadata.is_dir() || metadata.uid() != effective_uid() {
        return Err(NodeError::RootNotPrivate {
            path: dir.to_path_buf(),
            owner: metadata.uid(),
            mode: metadata.mode() & 0o7777,
            link,
        });
    }
    // Ours, but perhaps made by an older version or under another umask: close it.
    if metadata.mode() & GROUP_OTHER_BITS != 0 {
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(OWNER_ONLY_DIR))
            .map_err(io)?;
    }
    Ok(())
}

/// Why an owner file could not be judged.
#[derive(Debug)]
enum OwnerError {
    Io(std::io::Error),
    Foreign(ForeignFile),
}

/// `Some` when `metadata` (of `path`, not followed) is not this user's regular file.
fn foreign(path: &std::path::Path, metadata: &std::fs::Metadata) -> Option<ForeignFile> {
    (metadata.uid() != effective_uid() || !metadata.is_file()).then(|| ForeignFile {
        path: path.to_path_buf(),
        kind: kind_of(metadata),
        owner: metadata.uid(),
    })
}

/// Who holds the owner file at `path`. It is opened without following a link or blocking,
/// and judged by what was opened: another user's file or a FIFO is reported, not locked.
fn owner_at(path: &std::path::Path) -> Result<Owner, OwnerError> {
    let (file, metadata) = match open_unblocked(path, Links::Refuse) {
        Ok(opened) => opened,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Owner::None),
        Err(e) if e.raw_os_error() == Some(nix::libc::ELOOP) => {
            let metadata = std::fs::symlink_metadata(path).map_err(OwnerError::Io)?;
            return Err(OwnerError::Foreign(ForeignFile {
                path: path.to_path_buf(),
                kind: kind_of(&metadata),
                owner: metadata.uid(),
            }));
        }
        Err(e) => return Err(OwnerError::Io(e)),
    };
    if let Some(file) = foreign(path, &metadata) {
        return Err(OwnerError::Foreign(file));
    }
    // Shared, so two sweeps looking at once do not take each other for the owner.
    match file.try_lock_shared() {
        Ok(()) => Ok(Owner::Gone),
        Err(std::fs::TryLockError::WouldBlock) => Ok(Owner::Alive),
        Err(std::fs::TryLockError::Error(e)) => Err(OwnerError::Io(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "ipc-types-root-{tag}-{}-{}",
            std::process::id(),
            crate::now_ns()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn the_root_is_made_owner_only_and_an_open_one_of_ours_is_closed() {
        let base = scratch("ours");
        let made = base.join("made");
        prepare_private_dir(&made).unwrap();
        let mode = std::fs::metadata(&made).unwrap().mode() & 0o777;
        assert_eq!(mode, OWNER_ONLY_DIR);
        std::fs::set_permissions(&made, std::fs::Permissions::from_mode(0o755)).unwrap();
        prepare_private_dir(&made).unwrap();
        assert_eq!(
            std::fs::metadata(&made).unwrap().mode() & 0o777,
            OWNER_ONLY_DIR
        );
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn a_link_a_file_or_another_user_s_directory_is_refused() {
        let base = scratch("refused");
        let target = base.join("target");
        std::fs::create_dir(&target).unwrap();
        let link = base.join("link");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let error = prepare_private_dir(&link).unwrap_err();
        assert!(
            matches!(error, NodeError::RootNotPrivate { link: true, .. }),
            "{error}"
        );
        let file = base.join("file");
        std::fs::write(&file, b"").unwrap();
        assert!(matches!(
            prepare_private_dir(&file),
            Err(NodeError::RootNotPrivate { link: false, .. })
        ));
        // Only root can give a directory away.
        if effective_uid() == 0 {
            let theirs = base.join("theirs");
            std::fs::create_dir(&theirs).unwrap();
            std::os::unix::fs::chown(&theirs, Some(65534), Some(65534)).unwrap();
            let error = prepare_private_dir(&theirs).unwrap_err().to_string();
            assert!(
                error.contains("is not this user's own (owner uid 65534"),
                "{error}"
            );
        }
        std::fs::remove_dir_all(&base).unwrap();
    }
}
