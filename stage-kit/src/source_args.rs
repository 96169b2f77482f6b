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
    /// Odometry subscribers to wait for before the first odometry reading, when the source
    /// publishes odometry (in lockstep all of them, so none misses a reading; in real time
    /// at most 10 s). A reader looks for the odometry once it has found the scans, so
    /// without this wait its first readings would be lost, and which ones would depend on
    /// timing.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub odometry_subscribers: usize,
}

impl SourceArgs {
    /// How long a real-time source waits for its subscribers: not long, as a live sensor
    /// would not wait at all.
    pub const REAL_TIME_WAIT: Duration = Duration::from_secs(10);

    /// How long a source waits for its subscribers: in lockstep until they have all come
    /// (`None`: nothing is lost), in real time at most [`SourceArgs::REAL_TIME_WAIT`].
    pub fn subscriber_wait(lockstep: bool) -> Option<Duration> {
        (!lockstep).then_some(Self::REAL_TIME_WAIT)
    }
}
