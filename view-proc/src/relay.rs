//! The view's front door: it listens on the address the user gave and passes each
//! connection on to the SDK's server, which listens on the loopback only, renaming the
//! subprotocol in the handshake for clients that know the protocol by its first name
//! ([`crate::subprotocol`]). After the handshake it copies bytes both ways, unchanged.

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::thread;
use std::time::Duration;

use crate::subprotocol::{head_end, rename_request, rename_response};

/// The longest handshake head passed on; a WebSocket handshake is well under 1 KiB.
const MAX_HEAD: usize = 16 * 1024;
/// How long a client or the server may take to send its handshake head.
const HANDSHAKE_TIME: Duration = Duration::from_secs(5);
/// How long the door waits after a failed accept before the next.
const ACCEPT_BACKOFF: Duration = Duration::from_millis(50);

/// Accepts connections on `listener` and relays each to `server`, in threads of their own,
/// for as long as the process lives (the server closing its connections ends theirs).
pub fn start(listener: TcpListener, server: SocketAddr) -> io::Result<()> {
    thread::Builder::new()
        .name("view-door".into())
        .spawn(move || {
            for client in listener.incoming() {
                let Ok(client) = client else {
                    // Out of descriptors or memory, for now: back off rather than spin.
                    thread::sleep(ACCEPT_BACKOFF);
                    continue;
                };
                // A connection the relay cannot serve is closed; the client may try again.
                let _ = thread::Builder::new()
                    .name("view-relay".into())
                    .spawn(move || relay(client, server));
            }
        })?;
    Ok(())
}

/// Passes one connection's handshake on, renamed where it needs to be, then its bytes.
fn relay(client: TcpStream, server: SocketAddr) -> io::Result<()> {
    client.set_read_timeout(Some(HANDSHAKE_TIME))?;
    let (request, early) = read_head(&client)?;
    let renamed = std::str::from_utf8(&request).ok().and_then(rename_request);
    let upstream = TcpStream::connect(server)?;
    upstream.set_read_timeout(Some(HANDSHAKE_TIME))?;
    (&upstream).write_all(renamed.as_ref().map_or(&request[..], |r| r.as_bytes()))?;
    (&upstream).write_all(&early)?;

    let (response, early) = read_head(&upstream)?;
    let response = match (&renamed, std::str::from_utf8(&response)) {
        (Some(_), Ok(head)) => rename_response(head).into_bytes(),
        _ => response,
    };
    (&client).write_all(&response)?;
    (&client).write_all(&early)?;

    for stream in [&client, &upstream] {
        stream.set_read_timeout(None)?;
        stream.set_nodelay(true)?;
    }
    splice(client, upstream)
}

/// Reads from `stream` until an HTTP head is complete; returns the head and what came
/// after it.
fn read_head(mut stream: &TcpStream) -> io::Result<(Vec<u8>, Vec<u8>)> {
    let mut bytes = Vec::new();
    let mut chunk = [0u8; 2048];
    loop {
        if let Some(end) = head_end(&bytes) {
            let rest = bytes.split_off(end);
            return Ok((bytes, rest));
        }
        if bytes.len() > MAX_HEAD {
            return Err(io::Error::other("a handshake head longer than 16 KiB"));
        }
        match stream.read(&mut chunk)? {
            0 => return Err(io::ErrorKind::UnexpectedEof.into()),
            n => bytes.extend_from_slice(&chunk[..n]),
        }
    }
}

/// Copies bytes both ways until either side closes, then closes both: a WebSocket ends
/// with its close frames, which have passed by then.
fn splice(client: TcpStream, upstream: TcpStream) -> io::Result<()> {
    let (client_back, upstream_back) = (client.try_clone()?, upstream.try_clone()?);
    let back = thread::Builder::new()
        .name("view-relay-back".into())
        .spawn(move || pipe(upstream_back, client_back))?;
    pipe(client, upstream);
    let _ = back.join();
    Ok(())
}

/// Copies `from` to `to` until either fails or `from` ends; then shuts both down, which
/// also ends the copy the other way.
fn pipe(mut from: TcpStream, mut to: TcpStream) {
    let _ = io::copy(&mut from, &mut to);
    let _ = from.shutdown(Shutdown::Both);
    let _ = to.shutdown(Shutdown::Both);
}
