//! The peak resident memory of the run's processes: each stage's `VmHWM`, read from /proc
//! while it runs, and slam-launch's own, written to `OUT/memory.json` at the end.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// The file in the run's output directory.
pub const MEMORY_FILE: &str = "memory.json";

/// What `OUT/memory.json` holds.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunMemory {
    /// How often the stages' peaks were read while they ran, milliseconds: a peak reached
    /// in a stage's last moments, after the last reading, is missed.
    pub sampled_every_ms: u64,
    /// Peak resident memory per process (slam-launch and each stage), KiB.
    pub peak_resident_kib: BTreeMap<String, u64>,
}

/// The peak resident memory so far (`VmHWM`) of process `pid`, or of this process for
/// `None`, KiB; `None` where /proc does not tell (another system, a process that ended).
pub fn peak_resident_kib(pid: Option<u32>) -> Option<u64> {
    let path = match pid {
        Some(pid) => format!("/proc/{pid}/status"),
        None => "/proc/self/status".to_owned(),
    };
    parse_vm_hwm(&std::fs::read_to_string(path).ok()?)
}

/// `VmHWM` of a /proc status file, KiB.
fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_high_water_mark_is_read_from_the_status_file() {
        let status = "Name:\tmap-sink\nVmPeak:\t  200000 kB\nVmHWM:\t   45120 kB\nVmRSS:\t 1 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(45_120));
        assert_eq!(parse_vm_hwm("Name:\tx\n"), None);
        // This process has one.
        assert!(peak_resident_kib(None).is_some_and(|kib| kib > 0));
    }

    #[test]
    fn the_file_reads_back() {
        let memory = RunMemory {
            sampled_every_ms: 50,
            peak_resident_kib: [("slam-proc".to_owned(), 96_000)].into(),
        };
        let text = serde_json::to_string(&memory).unwrap();
        assert_eq!(serde_json::from_str::<RunMemory>(&text).unwrap(), memory);
    }
}
