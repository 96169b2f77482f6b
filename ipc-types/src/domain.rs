//! A run's own iceoryx2 domain, so two pipelines or two tests on one machine never cross.

use iceoryx2::config::Config;
use iceoryx2::prelude::*;

use crate::shm::SHM_DIR;

/// Characters a domain name may have: they become part of file names in /dev/shm.
const MAX_DOMAIN_LEN: usize = 40;
/// A domain with no live node whose files are this old is abandoned.
const ABANDONED_AFTER: std::time::Duration = std::time::Duration::from_secs(60);
/// Prefix of every file a domain leaves in /dev/shm and /tmp/iceoryx2.
pub const FILE_PREFIX: &str = "slam_";
/// The file a launcher keeps locked in /dev/shm while its run lives (see [`Domain::claim`]).
const OWNER_FILE: &str = "owner.lock";

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
    #[error("cannot create node '{name}' in domain '{domain}': {cause:?}")]
    Create {
        name: String,
        domain: String,
        cause: iceoryx2::node::NodeCreationFailure,
    },
}

/// Why a domain could not be claimed for a run.
#[derive(Debug, thiserror::Error)]
pub enum ClaimError {
    #[error("domain '{0}' belongs to another slam-launch that is still running")]
    InUse(String),
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

/// A run's domain: its name and the iceoryx2 configuration whose prefix keeps its shared
/// memory apart from every other run's.
#[derive(Debug, Clone)]
pub struct Domain {
    name: String,
    config: Config,
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
        Ok(Self {
            name: name.to_owned(),
            config,
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
        format!("{FILE_PREFIX}{name}_")
    }

    /// The iceoryx2 configuration of this domain.
    pub fn config(&self) -> &Config {
        &self.config
    }

    /// Creates a node in this domain. Signal handling is ours ([`crate::shutdown`]).
    pub fn node(&self, name: &str) -> Result<Node<ipc::Service>, NodeError> {
        let node_name = NodeName::new(name).map_err(|_| NodeError::BadName(name.to_owned()))?;
        NodeBuilder::new()
            .name(&node_name)
            .config(&self.config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|cause| NodeError::Create {
                name: name.to_owned(),
                domain: self.name.clone(),
                cause,
            })
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
        let file = std::fs::File::create_new(&temp).map_err(io)?;
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
                    if owner_at(&path).map_err(io)? == Owner::Alive {
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

    fn owner(&self) -> Owner {
        // Unreadable counts as alive: a run we cannot judge is left alone.
        owner_at(&self.owner_path()).unwrap_or(Owner::Alive)
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
            std::fs::metadata(path)
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

    /// Cleans up every domain in /dev/shm that no live process uses any more: dead nodes are
    /// removed and, where no node is alive, the domain's files too. Returns the domains
    /// cleaned. Run at start so crashed runs do not pile up shared memory. A domain claimed
    /// by a live launcher is left to it; one whose launcher died is cleaned at once, one
    /// never claimed once its files are a minute old.
    pub fn sweep_abandoned() -> Vec<String> {
        let Ok(entries) = std::fs::read_dir(SHM_DIR) else {
            return Vec::new();
        };
        let mut names: Vec<String> = entries
            .filter_map(|entry| entry.ok())
            .filter_map(|entry| {
                let file = entry.file_name().to_string_lossy().into_owned();
                let rest = file.strip_prefix(FILE_PREFIX)?;
                Some(rest.split('_').next()?.to_owned())
            })
            .collect();
        names.sort();
        names.dedup();
        let mut cleaned = Vec::new();
        for name in names {
            let Ok(domain) = Domain::new(&name) else {
                continue;
            };
            let owner = domain.owner();
            if owner == Owner::Alive {
                continue;
            }
            let dead = domain.cleanup_dead_nodes();
            // A pipeline starting right now has files but no node yet: leave young domains,
            // unless their launcher is known to be dead.
            if domain.alive_nodes() == 0
                && (owner == Owner::Gone || domain.is_older_than(ABANDONED_AFTER))
            {
                if domain.remove_leftovers().unwrap_or(0) > 0 || dead > 0 {
                    cleaned.push(name);
                }
            } else if dead > 0 {
                cleaned.push(name);
            }
        }
        cleaned
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

/// Who holds the owner file at `path`.
fn owner_at(path: &std::path::Path) -> std::io::Result<Owner> {
    let file = match std::fs::File::open(path) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Owner::None),
        Err(e) => return Err(e),
    };
    // Shared, so two sweeps looking at once do not take each other for the owner.
    match file.try_lock_shared() {
        Ok(()) => Ok(Owner::Gone),
        Err(std::fs::TryLockError::WouldBlock) => Ok(Owner::Alive),
        Err(std::fs::TryLockError::Error(e)) => Err(e),
    }
}
