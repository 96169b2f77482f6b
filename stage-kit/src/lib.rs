//! # stage-kit
//!
//! What every process of the pipeline does the same way, so that each `main.rs` is its
//! ports and its loop:
//!
//! - [`run_stage`]: the whole opening of a stage's `main`: parses its arguments, installs
//!   the Ctrl-C/SIGTERM flag ([`shutdown`]), runs the stage and turns its error into one
//!   `name: error` line on stderr (the whole source chain, `{:#}`) and a failing exit status;
//!   [`run_tool`] the same for a command-line tool that has no loop to stop.
//! - [`launcher_watch`]: a process started by a launcher gets SIGTERM when the launcher
//!   dies ([`run_stage`] and [`run_tool`] ask for it), so nothing outlives its launcher.
//! - [`shutdown`]: the latched Ctrl-C/SIGTERM flag every loop polls. It is defined in
//!   ipc-types because the transport's blocking waits end on it too; a stage reads it here.
//! - [`say`] and [`say_err`]: console lines that are dropped, not a panic, when the reader
//!   of the pipe has gone (slam-launch killed while a stage writes its results).
//! - [`input`]: opening a file a run reads: without blocking, a regular file, within a
//!   size limit its kind names ([`InputKind`]).
//! - [`settings`]: a TOML settings file read into a library's config struct, with one error
//!   type naming the file; [`SettingError`] and [`check`] for the range checks of those
//!   structs.
//! - [`odometry_buffer`]: the odometry at a scan's stamp, interpolated between the readings
//!   around it, with a typed answer while it may still change.
//! - [`odometry_covariance`]: the covariance a source without one sends with its odometry,
//!   grown along the motion.
//! - [`SourceArgs`]: the arguments every scan source takes (domain, subscribers).
//! - [`pacing`]: a source's `--rate` (lockstep or real time) and the clock it publishes
//!   by, with sleeps sliced so that a stop is not held up.
//!
//! ```no_run
//! use std::process::ExitCode;
//!
//! /// My stage.
//! #[derive(clap::Parser)]
//! struct Args {
//!     /// Scans to take.
//!     #[arg(long, default_value_t = 10)]
//!     frames: u64,
//! }
//!
//! fn main() -> ExitCode {
//!     stage_kit::run_stage("my-stage", run)
//! }
//!
//! fn run(args: Args) -> anyhow::Result<()> {
//!     for _ in 0..args.frames {
//!         if stage_kit::shutdown::requested() {
//!             break;
//!         }
//!     }
//!     stage_kit::say("status: done");
//!     Ok(())
//! }
//! ```

mod console;
mod exit;
pub mod held_scans;
pub mod input;
pub mod launcher_watch;
pub mod odometry_buffer;
pub mod odometry_covariance;
pub mod pacing;
pub mod settings;
mod source_args;

pub use console::{say, say_err};
pub use exit::{run_stage, run_tool};
pub use input::{InputError, InputKind};
pub use ipc_types::shutdown;
pub use settings::{SettingError, SettingsFileError, check};
pub use source_args::SourceArgs;
