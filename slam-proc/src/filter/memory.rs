//! How much memory a filter of N particles needs, and whether the machine has it.
//!
//! Each particle holds its own corner map and path, shared copy-on-write with its relatives
//! (a resampled particle copies only what it changes), so what a particle costs depends on
//! how far the maps diverge, which grows with the run. The figures below are measured, not
//! derived from the types: the steepest slope of slam-proc's peak resident size (VmHWM) per
//! particle over whole runs with one to thousands of particles, on the simulated office and
//! on the longest benchmark log (whose maps and paths diverge the most), rounded up. A much
//! longer live run may need more; the check refuses what cannot fit at all rather than
//! promise that what passes will.

use std::path::{Path, PathBuf};

/// Peak resident size of slam-proc with one particle (the process, its buffers, the
/// transport), measured on the office world and rounded up.
pub const BASE_BYTES: u64 = 16 << 20;
/// Peak resident size each particle adds, rounded up from the steepest measured slope (see
/// the module documentation).
pub const BYTES_PER_PARTICLE: u64 = 160 << 10;

/// The peak memory slam-proc is expected to reach with `particles` particles.
pub fn estimate_bytes(particles: usize) -> u64 {
    let particles = u64::try_from(particles).unwrap_or(u64::MAX);
    BASE_BYTES.saturating_add(particles.saturating_mul(BYTES_PER_PARTICLE))
}

/// The most particles whose estimate fits in `bytes`.
pub fn particles_fitting(bytes: u64) -> u64 {
    bytes.saturating_sub(BASE_BYTES) / BYTES_PER_PARTICLE
}

/// Where the figure of available memory comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MemorySource {
    /// `MemAvailable` in /proc/meminfo: what the kernel can give without swapping.
    MemAvailable,
    /// The memory cgroup's limit less what the cgroup uses (reclaimable page cache
    /// excepted): a container's limit, when it is below what the machine has free.
    Cgroup,
}

impl std::fmt::Display for MemorySource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::MemAvailable => "MemAvailable in /proc/meminfo",
            Self::Cgroup => "the memory cgroup's limit less its usage",
        })
    }
}

/// Memory this process could still use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Available {
    pub bytes: u64,
    pub source: MemorySource,
}

/// A filter that would not fit in the memory there is.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{particles} particles would need about {} MiB ({} MiB + {} KiB per particle, measured), \
     but {} MiB is available ({}); at most {fitting} particles fit",
    mib(*need),
    BASE_BYTES >> 20,
    BYTES_PER_PARTICLE >> 10,
    mib(available.bytes),
    available.source
)]
pub struct MemoryError {
    pub particles: usize,
    pub need: u64,
    pub available: Available,
    pub fitting: u64,
}

fn mib(bytes: u64) -> u64 {
    bytes >> 20
}

/// Refuses a particle count whose estimate exceeds the memory available now. Where no
/// figure can be read (not Linux, /proc not mounted), nothing is refused.
pub fn check(particles: usize) -> Result<(), MemoryError> {
    check_against(particles, available())
}

/// [`check`] against a given figure of available memory.
pub fn check_against(particles: usize, available: Option<Available>) -> Result<(), MemoryError> {
    let Some(available) = available else {
        return Ok(());
    };
    let need = estimate_bytes(particles);
    if need <= available.bytes {
        return Ok(());
    }
    Err(MemoryError {
        particles,
        need,
        available,
        fitting: particles_fitting(available.bytes),
    })
}

/// The smaller of `MemAvailable` and the cgroup's room, whichever can be read.
pub fn available() -> Option<Available> {
    let meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| mem_available(&text))
        .map(|bytes| Available {
            bytes,
            source: MemorySource::MemAvailable,
        });
    let cgroup = cgroup_room().map(|bytes| Available {
        bytes,
        source: MemorySource::Cgroup,
    });
    match (meminfo, cgroup) {
        (Some(m), Some(c)) => Some(if c.bytes < m.bytes { c } else { m }),
        (m, c) => m.or(c),
    }
}

/// `MemAvailable` of /proc/meminfo's text, in bytes.
pub fn mem_available(meminfo: &str) -> Option<u64> {
    meminfo.lines().find_map(|line| {
        let rest = line.strip_prefix("MemAvailable:")?;
        let kib: u64 = rest.trim().strip_suffix("kB")?.trim().parse().ok()?;
        kib.checked_mul(1024)
    })
}

/// A cgroup limit at or above this is "no limit" (v1 writes 2^63 rounded down to a page).
const UNLIMITED: u64 = 1 << 62;

/// Room under a cgroup limit: `limit - usage + reclaimable`, from the text of the limit
/// file (`max` or a number), the usage file and the memory.stat file; `None` without a
/// limit.
pub fn room_under_limit(
    limit: &str,
    usage: &str,
    stat: &str,
    reclaimable_key: &str,
) -> Option<u64> {
    let limit: u64 = limit.trim().parse().ok()?;
    if limit >= UNLIMITED {
        return None;
    }
    let usage: u64 = usage.trim().parse().ok()?;
    let reclaimable = stat
        .lines()
        .find_map(|line| {
            let (key, value) = line.split_once(' ')?;
            (key == reclaimable_key).then(|| value.trim().parse::<u64>().ok())?
        })
        .unwrap_or(0);
    Some(limit.saturating_sub(usage.saturating_sub(reclaimable)))
}

/// The room under this process's memory cgroup limit (v2, else v1), if it has one.
fn cgroup_room() -> Option<u64> {
    let membership = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let read = |path: PathBuf| std::fs::read_to_string(path).ok();
    let (v2, v1) = cgroup_dirs(&membership);
    // Each version's limit, usage and reclaimable page-cache counter, v2 first.
    let versions = [
        (v2, "memory.max", "memory.current", "inactive_file"),
        (
            v1,
            "memory.limit_in_bytes",
            "memory.usage_in_bytes",
            "total_inactive_file",
        ),
    ];
    for (dirs, limit_file, usage_file, inactive) in versions {
        for dir in dirs {
            if let (Some(limit), Some(usage)) =
                (read(dir.join(limit_file)), read(dir.join(usage_file)))
            {
                let stat = read(dir.join("memory.stat")).unwrap_or_default();
                return room_under_limit(&limit, &usage, &stat, inactive);
            }
        }
    }
    None
}

/// The directories where this process's memory cgroup may be mounted, v2 and v1: the path
/// /proc/self/cgroup names, then the mount's root (inside a container's cgroup namespace
/// the named path may not exist under the mount, whose root is the container's cgroup).
pub fn cgroup_dirs(membership: &str) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let root = Path::new("/sys/fs/cgroup");
    let mut v2 = Vec::new();
    let mut v1 = Vec::new();
    for line in membership.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let relative = path.trim_start_matches('/');
        if controllers.is_empty() {
            v2.push(root.join(relative));
            v2.push(root.to_path_buf());
        } else if controllers.split(',').any(|c| c == "memory") {
            v1.push(root.join("memory").join(relative));
            v1.push(root.join("memory"));
        }
    }
    (v2, v1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_estimate_grows_with_the_particles_and_names_what_fits() {
        assert_eq!(estimate_bytes(0), BASE_BYTES);
        assert_eq!(
            estimate_bytes(1000) - estimate_bytes(0),
            1000 * BYTES_PER_PARTICLE
        );
        assert_eq!(estimate_bytes(usize::MAX), u64::MAX);
        let fitting = particles_fitting(4 << 30);
        assert!(estimate_bytes(fitting as usize) <= 4 << 30);
        assert!(estimate_bytes(fitting as usize + 1) > 4 << 30);
    }

    #[test]
    fn a_million_particles_do_not_fit_in_four_gib() {
        let available = Available {
            bytes: 4 << 30,
            source: MemorySource::Cgroup,
        };
        assert_eq!(check_against(100, Some(available)), Ok(()));
        let error = check_against(1_000_000, Some(available)).unwrap_err();
        assert_eq!(error.need, estimate_bytes(1_000_000));
        let text = error.to_string();
        assert!(
            text.starts_with("1000000 particles would need about"),
            "{text}"
        );
        assert!(
            text.contains("but 4096 MiB is available (the memory cgroup's limit"),
            "{text}"
        );
        assert!(
            text.ends_with(&format!("at most {} particles fit", error.fitting)),
            "{text}"
        );
        // Nothing known, nothing refused.
        assert_eq!(check_against(1_000_000, None), Ok(()));
    }

    #[test]
    fn meminfo_and_cgroup_files_are_read() {
        let meminfo = "MemTotal:       24684000 kB\nMemFree:        20000000 kB\n\
                       MemAvailable:   23000000 kB\n";
        assert_eq!(mem_available(meminfo), Some(23_000_000 * 1024));
        assert_eq!(mem_available("MemFree: 1 kB\n"), None);
        assert_eq!(mem_available("MemAvailable: lots kB\n"), None);

        assert_eq!(room_under_limit("max\n", "100", "", "inactive_file"), None);
        assert_eq!(
            room_under_limit("9223372036854771712", "100", "", "total_inactive_file"),
            None
        );
        let stat = "anon 500\ninactive_file 300\nactive_file 10\n";
        assert_eq!(
            room_under_limit("1000\n", "800\n", stat, "inactive_file"),
            Some(500)
        );
        assert_eq!(
            room_under_limit("1000", "1200", "", "inactive_file"),
            Some(0)
        );

        let (v2, v1) = cgroup_dirs("0::/user.slice/run\n");
        assert_eq!(v2[0], Path::new("/sys/fs/cgroup/user.slice/run"));
        assert!(v1.is_empty());
        let (v2, v1) = cgroup_dirs("4:memory:/docker/abc\n3:cpu,cpuacct:/docker/abc\n0::/\n");
        assert_eq!(v1[0], Path::new("/sys/fs/cgroup/memory/docker/abc"));
        assert_eq!(v1[1], Path::new("/sys/fs/cgroup/memory"));
        assert_eq!(v2[0], Path::new("/sys/fs/cgroup"));
    }
}
