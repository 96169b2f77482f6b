//! The arguments every scan source (lidar-sim, lidar-replay, lidar-hokuyo) takes alike.

use std::time::Duration;

/// Where a source publishes and whom it waits for; `#[command(flatten)]` into its `Args`.
#[derive(Debug, Clone, clap::Args)]
pub struct SourceArgs {
    /// iceoryx2 domain of the run.
    #[arg(long, default_value = "default")]
    pub domain: String,
    /// Scan subscribers to wait for before the first scan (lockstep loses nothing at start;
    /// in real time the wait ends after 10 s, as a live sensor would not wait).
    #[arg(long, default_value_t = 1)]
    pub subscribers: usize,
}

impl SourceArgs {
    /// How long a real-time source waits for its scan subscribers: not long, as a live
    /// sensor would not wait at all.
    pub const REAL_TIME_WAIT: Duration = Duration::from_secs(10);
}
