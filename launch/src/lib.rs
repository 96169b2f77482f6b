//! # slam-launch
//!
//! Starts the pipeline's processes in a fresh iceoryx2 domain of their own, watches them,
//! shows progress and stops them cleanly:
//!
//! * consumers first (`map-sink`, `slam-proc`, `feature-proc`), the scan publisher last; each
//!   prints `ready` once its ports are connected, and a lossless publisher waits for its
//!   subscribers before it streams, so nothing is lost at start;
//! * a child that dies is named with its exit status and the tail of its stderr, its dead
//!   node is cleaned up at once (a dead subscriber would otherwise stall a lossless
//!   publisher), the others are stopped and the run fails;
//! * Ctrl-C or SIGTERM stops every child and waits for map-sink to write its results; a
//!   killed launcher takes its children with it (a parent-death signal, SIGTERM, so
//!   map-sink still writes), and its domain's lock tells the next start at once that the
//!   shared memory it left is abandoned;
//! * a stage that makes no progress is named on the console after `--stall-warning` and
//!   fails the run after `--stall-limit` ([`stall`] explains how the stage is found);
//! * given ground-truth relations (or finding them beside a replayed log, see
//!   [`relations::relations_beside`]), it checks they parse before anything starts and has
//!   map-sink score the run with them;
//! * a stage's closing summary on stderr (`<stage>: summary ...` and the indented lines
//!   after it, e.g. what lidar-replay could not publish) is shown when the run ends, and
//!   then one block of every count of skipped or lost data, per stage ([`losses`]);
//! * shared memory of crashed earlier runs is cleaned up at start, the run's own is checked
//!   against the room left in /dev/shm before anything starts ([`shm_room`]; a stage that
//!   dies of SIGBUS all the same is reported with that room), and nothing of this run is
//!   left in /dev/shm at the end;
//! * `--foxglove [ADDR]` adds `slam-view`, which serves the run live to Foxglove: it reads
//!   lossy (no publisher waits for it), is started first and stopped once the others have
//!   ended, and a run goes on without it if it dies ([`view`]);
//! * a particle count slam-proc's memory estimate does not fit in the memory available is
//!   refused before anything starts (`slam_proc::memory`).

pub mod bench;
pub mod cli;
pub mod closing;
pub mod config;
pub mod losses;
pub mod memory;
pub mod record;
pub mod reference;
pub mod relations;
pub mod shm_room;
pub mod stage;
pub mod stall;
pub mod status;
pub mod supervisor;
pub mod topology;
pub mod view;
