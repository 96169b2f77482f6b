//! # ipc-types
//!
//! The message contract of the lidar SLAM pipeline: fixed-layout `#[repr(C)]` messages that
//! cross process boundaries over iceoryx2 shared memory without copies, the topics they travel
//! on, and the small transport layer every process uses.
//!
//! * Every message is [`ZeroCopySend`](iceoryx2::prelude::ZeroCopySend) with an explicit,
//!   versioned type name, so processes built from different versions refuse to connect
//!   instead of misreading memory.
//! * Capacities are fixed ([`MAX_BEAMS`], [`MAX_MAP_CORNERS`], ...); only the used prefix of an
//!   array is meaningful and only it is serialised.
//! * Every topic lives inside a run's [`Domain`] (an iceoryx2 prefix chosen on the command
//!   line), so two pipelines on one machine never cross.
//! * Each message round-trips through serde; big ones serialise as a compact record
//!   ([`LaserScanRecord`], ...) and rebuild with `from_record`. The serde form leaves out
//!   the padding and names the frame as text, so it is also what a recording holds: with
//!   the `json-schema` feature the types the recorder writes as they are derive their JSON
//!   schema too.
//!
//! ```no_run
//! use ipc_types::prelude::*;
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! ipc_types::shutdown::install()?;
//! let domain = Domain::new("example")?;
//! let node = domain.node("scanner")?;
//! let scans = Outlet::create(&domain, &node, topic::SCAN, Delivery::Latest, 0)?;
//! scans.publish(|scan| {
//!     scan.header = Header::new(0, 0, "laser");
//!     scan.angle_min = -2.356;
//!     scan.angle_increment = 0.004_363;
//!     scan.range_min = 0.1;
//!     scan.range_max = 30.0;
//!     let _ = scan.set_beams(&[1.0, 2.0, f32::INFINITY], &[]);
//! })?;
//! # Ok(())
//! # }
//! ```

mod capacity;
mod domain;
mod header;
mod layout;
pub mod losses;
mod message;
pub mod messages;
pub mod peak_memory;
pub mod progress;
pub mod shm;
pub mod shutdown;
pub mod topic;
mod transport;
pub mod unblocked;
mod zeroed;

pub use capacity::{
    CapacityError, MAX_BEAMS, MAX_CLOUD_CHUNK_PARTICLES, MAX_FEATURE_CORNERS, MAX_GRID_CHUNK_CELLS,
    MAX_LINES, MAX_MAP_CORNERS, MAX_PATH_CHUNK_POSES, MAX_WORLD_CORNERS,
};
pub use domain::{
    Claim, ClaimError, Domain, DomainError, FILE_PREFIX, ForeignFile, NodeError, Sweep,
    user_prefix, user_root,
};
pub use header::{FLAG_END_OF_STREAM, FLAG_FINAL, FRAME_ID_LEN, Header, now_ns};
pub use message::Message;
pub use messages::*;
pub use topic::Topic;
pub use transport::{
    Delivery, Inlet, LATEST_QUEUE, LOSSLESS_QUEUE, LOSSY_READER, OpenError, OpenFailure, Outlet,
    PublishError, PublishFailure, ReceiveError, WaitError, Wake, Wakeable, wait_any,
    wait_for_topic, wait_loop,
};
pub use zeroed::Zeroable;

/// Everything a process shell needs.
pub mod prelude {
    pub use crate::messages::*;
    pub use crate::{
        Delivery, Domain, Header, Inlet, Message, Outlet, Wake, Zeroable, now_ns, topic, wait_any,
        wait_for_topic,
    };
}
