//! The WebSocket server the Foxglove app connects to.

use std::net::{Ipv4Addr, SocketAddr, TcpListener};
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

use foxglove::{Context, WebSocketServer, WebSocketServerHandle};

use crate::address::ViewAddress;
use crate::error::ViewError;
use crate::relay;

/// How long a stopping server has to close its clients' connections cleanly; the process
/// ends after it all the same, so a stuck client cannot hold up the end of a run.
pub const SHUTDOWN_GRACE: Duration = Duration::from_secs(1);

/// Messages the server queues for each client; a client that reads slower loses the oldest
/// (the SDK's own policy), never the pipeline's. About two seconds of every live channel.
const CLIENT_BACKLOG: usize = 512;

/// A running server and the context whose channels it advertises.
#[derive(Debug)]
pub struct ViewServer {
    context: Arc<Context>,
    handle: WebSocketServerHandle,
    address: ViewAddress,
}

impl ViewServer {
    /// Listens on `address`: the view's front door ([`crate::relay`]) there, the SDK's
    /// server (its own tokio runtime, in threads of its own) on a loopback port behind it.
    pub fn start(address: &ViewAddress) -> Result<Self, ViewError> {
        let listener = TcpListener::bind(address.resolve()?.as_slice())
            .map_err(|source| address.listen_error(source))?;
        let door = listener
            .local_addr()
            .map_err(|source| address.listen_error(source))?;
        let context = Context::new();
        let handle = WebSocketServer::new()
            .name("slam-view")
            .bind(Ipv4Addr::LOCALHOST.to_string(), 0)
            .context(&context)
            .message_backlog_size(CLIENT_BACKLOG)
            .start_blocking()
            .map_err(|cause| ViewError::Server {
                address: address.to_string(),
                cause,
            })?;
        let server = SocketAddr::from((Ipv4Addr::LOCALHOST, handle.port()));
        relay::start(listener, server).map_err(|source| address.listen_error(source))?;
        let address = ViewAddress {
            host: address.host.clone(),
            port: door.port(),
        };
        Ok(Self {
            context,
            handle,
            address,
        })
    }

    /// The context to open the live channels in.
    pub fn context(&self) -> &Arc<Context> {
        &self.context
    }

    /// Where it listens (with the port the system chose for port 0).
    pub fn address(&self) -> &ViewAddress {
        &self.address
    }

    /// Clients connected now.
    pub fn clients(&self) -> usize {
        self.handle.client_count()
    }

    /// Closes the connections and stops, waiting at most [`SHUTDOWN_GRACE`]; returns
    /// whether it stopped within it.
    pub fn stop(self) -> bool {
        let shutdown = self.handle.stop();
        let (done, stopped) = mpsc::channel();
        std::thread::spawn(move || {
            shutdown.wait_blocking();
            let _ = done.send(());
        });
        stopped.recv_timeout(SHUTDOWN_GRACE).is_ok()
    }
}
