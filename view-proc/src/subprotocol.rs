//! The protocol's first name: Foxglove's WebSocket protocol was `foxglove.websocket.v1`
//! before the SDK renamed it `foxglove.sdk.v1`, the same protocol under a new name. Older
//! Foxglove apps, Lichtblick and the ws-protocol libraries still offer only the first name,
//! and the SDK's server refuses them at the handshake; the view's front door
//! ([`crate::relay`]) renames the subprotocol in the two handshake heads for them.

/// The name older clients offer.
pub const FIRST_NAME: &str = "foxglove.websocket.v1";
/// The SDK's name for the same protocol, which its server accepts.
const SDK_NAME: &str = "foxglove.sdk.v1";
/// Every name the SDK's server accepts: a client offering one of them needs no renaming.
const SDK_NAMES: [&str; 2] = [SDK_NAME, "foxglove.sdk.v1.1"];
/// The header that carries the offered (request) and the chosen (response) subprotocols.
const HEADER: &str = "sec-websocket-protocol";

/// Where the HTTP head in `bytes` ends (just after its blank line), once it is complete.
pub fn head_end(bytes: &[u8]) -> Option<usize> {
    bytes
        .windows(4)
        .position(|window| window == b"\r\n\r\n")
        .map(|at| at + 4)
}

/// The client's handshake request with the protocol offered under the SDK's name, when the
/// client offered it only under its first name; `None` when the request needs no renaming.
pub fn rename_request(head: &str) -> Option<String> {
    let offered: Vec<&str> = header_values(head)
        .flat_map(|value| value.split(','))
        .map(str::trim)
        .collect();
    let first_only =
        offered.contains(&FIRST_NAME) && !offered.iter().any(|name| SDK_NAMES.contains(name));
    first_only.then(|| with_header(head, SDK_NAME))
}

/// The server's handshake response with the subprotocol it chose named as the client
/// offered it (a client refuses a subprotocol it did not offer).
pub fn rename_response(head: &str) -> String {
    with_header(head, FIRST_NAME)
}

/// The values of the subprotocol header lines of `head` (after its first line).
fn header_values(head: &str) -> impl Iterator<Item = &str> {
    head.split("\r\n").skip(1).filter_map(|line| {
        let (name, value) = line.split_once(':')?;
        name.trim().eq_ignore_ascii_case(HEADER).then_some(value)
    })
}

/// `head` with every subprotocol header line's value replaced by `value`.
fn with_header(head: &str, value: &str) -> String {
    head.split("\r\n")
        .enumerate()
        .map(|(at, line)| match line.split_once(':') {
            Some((name, _)) if at > 0 && name.trim().eq_ignore_ascii_case(HEADER) => {
                format!("{name}: {value}")
            }
            _ => line.to_owned(),
        })
        .collect::<Vec<_>>()
        .join("\r\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(protocols: &str) -> String {
        format!(
            "GET / HTTP/1.1\r\nHost: 127.0.0.1:8765\r\nUpgrade: websocket\r\n\
             Sec-WebSocket-Protocol: {protocols}\r\nSec-WebSocket-Key: x3JJHMbDL1EzLkh9GBhXDw==\r\n\r\n"
        )
    }

    #[test]
    fn a_client_offering_only_the_first_name_is_offered_under_the_sdks() {
        let renamed = rename_request(&request("foxglove.websocket.v1")).expect("renamed");
        assert_eq!(renamed, request("foxglove.sdk.v1"));
        assert_eq!(head_end(renamed.as_bytes()), Some(renamed.len()));
        // Header names are case-insensitive; other offers may come along.
        let lower = request("foo, foxglove.websocket.v1").replace("Sec-WebSocket", "sec-websocket");
        let renamed = rename_request(&lower).expect("renamed");
        assert!(
            renamed.contains("sec-websocket-Protocol: foxglove.sdk.v1\r\n"),
            "{renamed}"
        );
        assert!(renamed.contains("sec-websocket-Key: x3JJHMbDL1EzLkh9GBhXDw==\r\n"));
    }

    #[test]
    fn a_client_the_sdk_accepts_or_that_offers_neither_is_passed_as_it_came() {
        for offer in [
            "foxglove.sdk.v1",
            "foxglove.websocket.v1, foxglove.sdk.v1",
            "foxglove.sdk.v1.1,foxglove.websocket.v1",
            "something.else",
            "foxglove.websocket.v10",
        ] {
            assert_eq!(rename_request(&request(offer)), None, "{offer}");
        }
        assert_eq!(rename_request("GET / HTTP/1.1\r\nHost: x\r\n\r\n"), None);
    }

    #[test]
    fn the_servers_choice_is_named_as_the_client_offered_it() {
        let response = "HTTP/1.1 101 Switching Protocols\r\nSec-WebSocket-Protocol: foxglove.sdk.v1\r\n\
                        Sec-WebSocket-Accept: HSmrc0sMlYUkAGmm5OPpG2HaGWk=\r\n\r\n";
        assert_eq!(
            rename_response(response),
            response.replace("foxglove.sdk.v1", "foxglove.websocket.v1")
        );
        assert_eq!(head_end(b"HTTP/1.1 101\r\n\r\n\x81\x00"), Some(16));
        assert_eq!(head_end(b"HTTP/1.1 101\r\nX: y\r\n"), None);
    }
}
