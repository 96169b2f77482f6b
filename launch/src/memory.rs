//! The peak resident memory of the run's processes: each stage's `VmHWM`, read from /proc
//! while it runs and told by the stage itself as it ends ([`ipc_types::peak_memory`]), and
//! slam-launch's own, written to `OUT/memory.json` at the end.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub use ipc_types::peak_memory::peak_resident_kib;

/// The file in the run's output directory.
pub const MEMORY_FILE: &str = "memory.json";

/// What `OUT/memory.json` holds.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct RunMemory {
    /// How often the stages' peaks were read while they ran, milliseconds. A stage also
    /// tells its own as it ends; only a stage that is killed can have its last moments'
    /// peak missed.
    pub sampled_every_ms: u64,
    /// Peak resident memory per process (slam-launch and each stage), KiB.
    pub peak_resident_kib: BTreeMap<String, u64>,
}

#[cfg(test)]
mod tests {
    use super::*;

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
