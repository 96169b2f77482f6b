//! Opening a connection to the sensor, afresh after every loss.

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::Duration;

/// Why an address cannot be used.
#[derive(Debug, thiserror::Error)]
#[error("'{addr}' cannot be resolved to an address (HOST:PORT, e.g. 192.168.0.10:10940): {cause}")]
pub struct AddressError {
    pub addr: String,
    pub cause: String,
}

/// Resolves `addr` (`HOST:PORT`) now: a typo is refused at start, not retried for ever.
pub fn resolve(addr: &str) -> Result<Vec<SocketAddr>, AddressError> {
    let error = |cause: String| AddressError {
        addr: addr.to_owned(),
        cause,
    };
    let addrs: Vec<SocketAddr> = addr
        .to_socket_addrs()
        .map_err(|e| error(e.to_string()))?
        .collect();
    if addrs.is_empty() {
        return Err(error("no address".to_owned()));
    }
    Ok(addrs)
}

/// Something that opens a stream to the sensor.
pub trait Connect {
    type Stream: Read + Write;

    /// A new connection.
    fn connect(&mut self) -> io::Result<Self::Stream>;

    /// Where it connects to, for messages.
    fn describe(&self) -> String;
}

/// TCP to a Hokuyo Ethernet model (default `192.168.0.10:10940`).
#[derive(Debug, Clone)]
pub struct TcpConnector {
    addr: String,
    connect_timeout: Duration,
    poll: Duration,
}

impl TcpConnector {
    /// Connects to `addr` (`HOST:PORT`) giving up after `connect_timeout`; reads time out
    /// every `poll` so the client can check for a stop request.
    pub fn new(addr: &str, connect_timeout: Duration, poll: Duration) -> Self {
        Self {
            addr: addr.to_owned(),
            connect_timeout,
            poll,
        }
    }
}

impl Connect for TcpConnector {
    type Stream = TcpStream;

    fn connect(&mut self) -> io::Result<TcpStream> {
        let mut last_error = io::Error::new(
            io::ErrorKind::NotFound,
            format!("'{}' resolves to no address", self.addr),
        );
        for addr in self.addr.to_socket_addrs()? {
            match TcpStream::connect_timeout(&addr, self.connect_timeout) {
                Ok(stream) => {
                    stream.set_read_timeout(Some(self.poll))?;
                    // A sensor that stops reading must not block us for ever either.
                    stream.set_write_timeout(Some(self.connect_timeout))?;
                    // Commands are tiny and each waits for its reply: send them at once.
                    stream.set_nodelay(true)?;
                    return Ok(stream);
                }
                Err(e) => last_error = e,
            }
        }
        Err(last_error)
    }

    fn describe(&self) -> String {
        self.addr.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_port_is_an_error_not_a_hang() {
        let closed = test_child::closed_port();
        let mut connector = TcpConnector::new(
            closed.addr(),
            Duration::from_millis(500),
            Duration::from_millis(50),
        );
        assert!(connector.connect().is_err());
        assert!(
            TcpConnector::new("not an address", Duration::from_millis(10), Duration::ZERO)
                .connect()
                .is_err()
        );
    }

    #[test]
    fn addresses_that_cannot_be_resolved_are_refused() {
        assert_eq!(resolve("127.0.0.1:10940").unwrap().len(), 1);
        for bad in ["notanaddr", "127.0.0.1:notaport", "127.0.0.1", ""] {
            let error = resolve(bad).unwrap_err().to_string();
            assert!(
                error.starts_with(&format!("'{bad}' cannot be resolved to an address")),
                "{error}"
            );
        }
    }

    #[test]
    fn connected_streams_poll() {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let mut connector =
            TcpConnector::new(&addr, Duration::from_secs(1), Duration::from_millis(30));
        let stream = connector.connect().unwrap();
        // The kernel rounds the timeout to its tick.
        let timeout = stream.read_timeout().unwrap().unwrap();
        assert!(timeout >= Duration::from_millis(30) && timeout < Duration::from_millis(50));
        assert_eq!(connector.describe(), addr);
    }
}
