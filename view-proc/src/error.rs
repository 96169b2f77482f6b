//! Why the live view cannot serve.

/// An error of the live view: its address, or its server.
///
/// The underlying error is named `cause`, not `source`, and is part of the message: the
/// message is complete on its own, and `{:#}` does not repeat it.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error(
        "'{0}' is not an address to serve the live view on: give HOST:PORT, e.g. 127.0.0.1:8765"
    )]
    NotAnAddress(String),
    #[error("cannot resolve the live view's host in '{address}': {cause}")]
    Resolve {
        address: String,
        cause: std::io::Error,
    },
    #[error(
        "cannot serve the live view on {address}: the port is in use (another Foxglove server, \
         or another run's view?); give another port: --foxglove HOST:PORT"
    )]
    PortInUse { address: String },
    #[error("cannot serve the live view on {address}: {cause}")]
    Listen {
        address: String,
        cause: std::io::Error,
    },
    #[error("cannot start the live view's server on {address}: {cause}")]
    Server {
        address: String,
        cause: foxglove::FoxgloveError,
    },
    #[error("cannot open the live view's channel {topic}: {cause}")]
    Channel {
        topic: &'static str,
        cause: foxglove::FoxgloveError,
    },
}
