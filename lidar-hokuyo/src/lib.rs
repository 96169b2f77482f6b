//! # lidar-hokuyo
//!
//! A live `LaserScan` source for the pipeline: a driver for Hokuyo's Ethernet lidars
//! (UTM-30LX-EW, UST-10LX/20LX, ...), which speak SCIP 2.0 over TCP (by default at
//! `192.168.0.10:10940`), and an emulator of such a sensor serving recorded scans.
//!
//! * [`scip`]: the protocol without I/O: commands, replies, the 2/3/4-character encodings
//!   and the line checksum.
//! * [`Sensor`]: a client over any `Read + Write` stream: identify (`VV`, `PP`, `II`),
//!   sync the clock (`TM0/1/2`), range (`MD` or `ME`), stop (`QT`).
//! * [`SensorClock`]: the sensor's 24-bit millisecond counter in host time.
//! * [`RangingPlan`]: the ranging command and the `LaserScan` angles and timing for an
//!   angular window and cluster size on a given sensor.
//! * [`ranges`]: millimetres to metres, error codes to REP 117.
//! * [`Driver`]: the loop that publishes, reconnecting with back-off; what it cannot
//!   reach is shown on the console, rate-limited ([`ConnectionNotices`]).
//! * [`emulator`]: the sensor emulator the tests (and `hokuyo-emulator`) use.

pub mod backoff;
pub mod connector;
pub mod decoded_scan;
pub mod emulator;
pub mod geometry;
pub mod notices;
pub mod publisher;
pub mod ranges;
pub mod scip;
pub mod sensor;
pub mod text_lines;
pub mod time_sync;

#[cfg(test)]
mod test_stream;

pub use backoff::Backoff;
pub use connector::{AddressError, Connect, TcpConnector, resolve};
pub use decoded_scan::DecodedScan;
pub use geometry::{GeometryError, RangingPlan, ScanRequest};
pub use notices::ConnectionNotices;
pub use publisher::{Driver, DriverConfig, DriverError, DriverStats, Finish, ScanSink};
pub use sensor::{Identity, Sensor, SensorError};
pub use time_sync::{ClockSample, SensorClock, TimeSyncError};
