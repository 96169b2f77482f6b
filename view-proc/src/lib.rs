//! # view-proc
//!
//! A live view of a run: `slam-view` reads the pipeline's topics as they go by and serves
//! them over Foxglove's WebSocket protocol, so the Foxglove app, connected to
//! `ws://HOST:PORT`, shows the scan, the pose and its frames, the particle cloud, the map's
//! corners, the back end's grid and path while the run goes on.
//!
//! The messages are the recording's (crate `recorder`): the same conversion
//! ([`recorder::Recording`]), the same topics, schemas and frames as `run.mcap`, so a
//! Foxglove layout made for one works for the other; only the output differs
//! ([`LiveChannels`], a [`recorder::Output`] that logs on the Foxglove SDK's channels
//! instead of writing a file).
//!
//! Clients may offer the protocol under its first name, `foxglove.websocket.v1` (older
//! Foxglove apps, Lichtblick) or the SDK's, `foxglove.sdk.v1`: the view listens itself and
//! renames the subprotocol in the handshake for the first ([`relay`], [`subprotocol`]).
//!
//! The view never holds the pipeline up: it reads lossy ([`ipc_types::Inlet::open_lossy`]:
//! no publisher waits for it, and in lockstep it loses what arrives while it is busy), it
//! encodes a message only while a client subscribes to its channel, and a slow client loses
//! messages in the server's queue (the SDK's backlog drops the oldest), never the pipeline's.

mod address;
mod error;
mod live;
mod relay;
mod server;
mod subprotocol;

pub use address::{DEFAULT_ADDRESS, ViewAddress};
pub use error::ViewError;
pub use live::LiveChannels;
pub use server::{SHUTDOWN_GRACE, ViewServer};
