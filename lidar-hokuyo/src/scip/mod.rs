//! The SCIP 2.0 protocol of Hokuyo scanners, without any I/O: command builders, the reply
//! parser, the 2-, 3- and 4-character encodings and the line checksum.
//!
//! SCIP is line based ASCII. The host sends a command line; the sensor answers with the
//! command's echo, a status with its checksum, the body, and an empty line. After a
//! continuous ranging command (`MD`, `ME`, `MS`) it keeps sending one such reply per scan,
//! with status `99`, until `QT`.

mod checksum;
mod command;
mod encoding;
mod error;
mod params;
mod reply;

pub use checksum::{checksum, verify, verify_information};
pub use command::{Command, DataKind, MAX_CLUSTER, MAX_STEP, Ranging, TimeMode};
pub use encoding::{MAX_WIDTH, OFFSET, decode, decode_values, encode, encode_into, max_value};
pub use error::ScipError;
pub use params::SensorParams;
pub use reply::{
    DATA_LINE, Information, Reply, ScanData, Status, data_line, information_line, scan_body,
};
