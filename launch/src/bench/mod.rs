//! `slam-bench`'s library half: which seeds to run, what the runs add up to, the published
//! figures to compare with, the table on the console and docs/RESULTS.md ([`markdown`]),
//! and when and at what commit it ran. The program itself (`src/bin/slam-bench.rs`) runs
//! slam-launch once per log (and simulated world) and seed and reads each run's
//! metrics.json and memory.json.

pub mod markdown;
pub mod provenance;
pub mod published;
pub mod report;
pub mod seeds;
pub mod table;
