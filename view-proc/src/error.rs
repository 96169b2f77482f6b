//! Why the live view cannot serve.

/// An error of the live view: its address, or its server.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error(
        "'{0}' is not an address to serve the live view on: give HOST:PORT, e.g. 127.0.0.1:8765"
    )]
    NotAnAddress(String),
    #[error("cannot resolve the live view's host in '{address}': {source}")]
    Resolve {
        address: String,
        source: std::io::Error,
    },
    #[error(
        "cannot serve the live view on {address}: the port is in use (another Foxglove server, \
         or another run's view?); give another port, e.g. --foxglove 127.0.0.1:8766"
    )]
    PortInUse { address: String },
    #[error("cannot serve the live view on {address}: {source}")]
    Listen {
        address: String,
        source: std::io::Error,
    },
    #[error("cannot start the live view's server on {address}: {source}")]
    Server {
        address: String,
        source: foxglove::FoxgloveError,
    },
    #[error("cannot open the live view's channel {topic}: {source}")]
    Channel {
        topic: &'static str,
        source: foxglove::FoxgloveError,
    },
}
