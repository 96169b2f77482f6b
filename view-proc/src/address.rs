//! The address the live view listens on, checked before a run starts.

use std::net::{SocketAddr, TcpListener, ToSocketAddrs};

use crate::error::ViewError;

/// Where the view listens unless told otherwise: this machine only, Foxglove's usual port.
pub const DEFAULT_ADDRESS: &str = "127.0.0.1:8765";

/// `HOST:PORT` to serve the live view on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ViewAddress {
    pub host: String,
    pub port: u16,
}

impl std::fmt::Display for ViewAddress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.host.contains(':') {
            write!(f, "[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{}:{}", self.host, self.port)
        }
    }
}

impl std::str::FromStr for ViewAddress {
    type Err = ViewError;

    /// `HOST:PORT`, an IPv6 host in brackets (`[::1]:8765`).
    fn from_str(text: &str) -> Result<Self, ViewError> {
        let bad = || ViewError::NotAnAddress(text.to_owned());
        let (host, port) = text.trim().rsplit_once(':').ok_or_else(bad)?;
        let host = host
            .strip_prefix('[')
            .and_then(|h| h.strip_suffix(']'))
            .unwrap_or(host);
        if host.is_empty() || (host.contains(':') && !text.contains('[')) {
            return Err(bad());
        }
        let port = port.parse().map_err(|_| bad())?;
        Ok(Self {
            host: host.to_owned(),
            port,
        })
    }
}

impl ViewAddress {
    /// The socket addresses the host names.
    pub fn resolve(&self) -> Result<Vec<SocketAddr>, ViewError> {
        let resolve_error = |cause| ViewError::Resolve {
            address: self.to_string(),
            cause,
        };
        let found: Vec<SocketAddr> = (self.host.as_str(), self.port)
            .to_socket_addrs()
            .map_err(resolve_error)?
            .collect();
        if found.is_empty() {
            return Err(resolve_error(std::io::Error::other("it names no address")));
        }
        Ok(found)
    }

    /// Checks that the view could listen there now: the host resolves, and the port is
    /// free. (Port 0, any free port, always is.) The view's server binds it again when it
    /// starts; this is for an error before the run does.
    pub fn check_free(&self) -> Result<(), ViewError> {
        let addresses = self.resolve()?;
        match TcpListener::bind(addresses.as_slice()) {
            Ok(_) => Ok(()),
            Err(source) => Err(self.listen_error(source)),
        }
    }

    /// The error of listening on this address failing with `source`.
    pub fn listen_error(&self, source: std::io::Error) -> ViewError {
        let address = self.to_string();
        if source.kind() == std::io::ErrorKind::AddrInUse {
            ViewError::PortInUse { address }
        } else {
            ViewError::Listen {
                address,
                cause: source,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_address_is_host_and_port() {
        let address: ViewAddress = "127.0.0.1:8765".parse().unwrap();
        assert_eq!(address.host, "127.0.0.1");
        assert_eq!(address.port, 8765);
        assert_eq!(address.to_string(), "127.0.0.1:8765");
        let v6: ViewAddress = "[::1]:9000".parse().unwrap();
        assert_eq!((v6.host.as_str(), v6.port), ("::1", 9000));
        assert_eq!(v6.to_string(), "[::1]:9000");
        assert_eq!(
            DEFAULT_ADDRESS.parse::<ViewAddress>().unwrap().to_string(),
            DEFAULT_ADDRESS
        );
        for bad in [
            "8765",
            "localhost",
            ":8765",
            "host:port",
            "host:70000",
            "::1:8765",
        ] {
            let error = bad.parse::<ViewAddress>().unwrap_err();
            assert!(error.to_string().contains(bad), "{error}");
        }
    }

    #[test]
    fn a_port_in_use_is_said_plainly() {
        let taken = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = taken.local_addr().unwrap().port();
        let address: ViewAddress = format!("127.0.0.1:{port}").parse().unwrap();
        let error = address.check_free().unwrap_err().to_string();
        assert!(error.contains("the port is in use"), "{error}");
        assert!(error.contains(&format!("127.0.0.1:{port}")), "{error}");
        drop(taken);
        address.check_free().unwrap();
    }
}
