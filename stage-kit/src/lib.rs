//! # stage-kit
//!
//! What every process of the pipeline does the same way, so that each `main.rs` is its
//! ports and its loop:
//!
//! - [`main`]: runs the process's `run` and turns its error into one `name: error` line on
//!   stderr (the whole source chain, `{:#}`) and a failing exit status.
//! - [`say`] and [`say_err`]: console lines that are dropped, not a panic, when the reader
//!   of the pipe has gone (slam-launch killed while a stage writes its results).
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
//! fn main() -> ExitCode {
//!     stage_kit::main("my-stage", run)
//! }
//!
//! fn run() -> anyhow::Result<()> {
//!     stage_kit::say("status: running");
//!     Ok(())
//! }
//! ```

mod console;
mod exit;
pub mod odometry_buffer;
pub mod odometry_covariance;
pub mod pacing;
pub mod settings;
mod source_args;

pub use console::{say, say_err};
pub use exit::main;
pub use settings::{SettingError, SettingsFileError, check};
pub use source_args::SourceArgs;
