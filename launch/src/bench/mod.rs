//! `slam-bench`'s library half: which seeds to run, what the runs add up to, the published
//! figures to compare with, and the table. The program itself (`src/bin/slam-bench.rs`)
//! runs slam-launch once per log and seed and reads each run's metrics.json.

pub mod published;
pub mod report;
pub mod seeds;
pub mod table;
