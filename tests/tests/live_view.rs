//! `slam-launch --foxglove` (issue 48): clients of Foxglove's WebSocket protocol, one
//! offering it under the SDK's name and one under its first name, connect to a live office
//! run; each sees the channels of the scan, the frames, the grid and the paths
//! advertised under Foxglove's schemas, subscribes to the scan and receives scans while the
//! run goes on, and one receives a whole grid of the back end's; Ctrl-C ends the run and the view within seconds. A lockstep run with the
//! view and no client is the same run, bit for bit; a port in use is refused before a run
//! starts.

use std::net::{TcpListener, TcpStream};
use std::process::Stdio;
use std::time::{Duration, Instant};

use tests::*;
use tungstenite::client::IntoClientRequest;
use tungstenite::http::HeaderValue;
use tungstenite::{Message, WebSocket};

/// Generous for a loaded 2-core machine.
const LIMIT: Duration = Duration::from_secs(120);
/// How long a stopped run may take to end: a few seconds, with room for a loaded machine.
const STOP_LIMIT: Duration = Duration::from_secs(15);
/// The schemas a person's Foxglove layout needs, as run.mcap has them.
const SCHEMAS: [&str; 4] = [
    "foxglove.LaserScan",
    "foxglove.FrameTransform",
    "foxglove.Grid",
    "foxglove.PosesInFrame",
];
/// The protocol's name in the SDK (the Foxglove app offers it).
const SDK_NAME: &str = "foxglove.sdk.v1";
/// Its first name, the only one older Foxglove apps and Lichtblick offer.
const FIRST_NAME: &str = "foxglove.websocket.v1";

/// A port free now on the loopback (the system's choice), for the view to listen on.
fn free_port() -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").expect("a free port");
    listener.local_addr().expect("its address").port()
}

/// Connects to the view at `addr` once it listens, offering the subprotocol `name`, and
/// checks that the view chose it; panics when the launcher ends first or `limit` passes.
fn connect(
    addr: &str,
    name: &'static str,
    launcher: &mut std::process::Child,
    limit: Duration,
) -> WebSocket<TcpStream> {
    let deadline = Instant::now() + limit;
    loop {
        if let Some(status) = launcher.try_wait().expect("poll slam-launch") {
            panic!("slam-launch ended before its view listened: {status}");
        }
        assert!(
            Instant::now() < deadline,
            "the view did not listen within {limit:?}"
        );
        let Ok(stream) = TcpStream::connect(addr) else {
            // Not listening yet: the view starts with the run.
            std::thread::sleep(Duration::from_millis(50));
            continue;
        };
        stream
            .set_read_timeout(Some(Duration::from_secs(5)))
            .expect("a read timeout");
        let mut request = format!("ws://{addr}")
            .into_client_request()
            .expect("a request");
        request
            .headers_mut()
            .insert("Sec-WebSocket-Protocol", HeaderValue::from_static(name));
        let (socket, response) = tungstenite::client(request, stream).expect("the handshake");
        assert_eq!(
            response.headers().get("Sec-WebSocket-Protocol"),
            Some(&HeaderValue::from_static(name))
        );
        return socket;
    }
}

/// Reads the server's `advertise` messages until every schema of [`SCHEMAS`] is among
/// them; returns the channels advertised (id, topic, schema name).
fn read_advertised(
    socket: &mut WebSocket<TcpStream>,
    limit: Duration,
) -> Vec<(u64, String, String)> {
    let deadline = Instant::now() + limit;
    let mut channels = Vec::new();
    while !SCHEMAS
        .iter()
        .all(|schema| channels.iter().any(|(_, _, s)| s == schema))
    {
        assert!(Instant::now() < deadline, "advertised only {channels:?}");
        let Message::Text(text) = socket.read().expect("a message from the view") else {
            continue;
        };
        let message: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        if message["op"] != "advertise" {
            continue;
        }
        for channel in message["channels"].as_array().expect("channels") {
            assert_eq!(channel["encoding"], "json", "{channel}");
            assert_eq!(channel["schemaEncoding"], "jsonschema", "{channel}");
            channels.push((
                channel["id"].as_u64().expect("an id"),
                channel["topic"].as_str().expect("a topic").to_owned(),
                channel["schemaName"].as_str().expect("a schema").to_owned(),
            ));
        }
    }
    channels
}

/// Waits for a binary message-data frame (opcode 1) of subscription `id`; returns its
/// payload.
fn read_message_data(socket: &mut WebSocket<TcpStream>, id: u32, limit: Duration) -> Vec<u8> {
    let deadline = Instant::now() + limit;
    loop {
        assert!(
            Instant::now() < deadline,
            "no message data within {limit:?}"
        );
        let Message::Binary(frame) = socket.read().expect("a message from the view") else {
            continue;
        };
        // opcode 1, subscription id (u32 LE), log time (u64 LE), the message.
        if frame.len() > 13 && frame[0] == 1 && frame[1..5] == id.to_le_bytes() {
            return frame[13..].to_vec();
        }
    }
}

/// Subscribes to the advertised channel of `(topic, schema)` as subscription `id`.
fn subscribe(
    socket: &mut WebSocket<TcpStream>,
    channels: &[(u64, String, String)],
    (topic, schema): (&str, &str),
    id: u32,
) {
    let channel = channels
        .iter()
        .find(|(_, t, s)| t == topic && s == schema)
        .unwrap_or_else(|| panic!("no {topic} of {schema} in {channels:?}"));
    let subscribe = serde_json::json!({
        "op": "subscribe",
        "subscriptions": [{"id": id, "channelId": channel.0}],
    });
    socket
        .send(Message::text(subscribe.to_string()))
        .expect("subscribe");
}

/// Waits for the scan channel among the advertised ones, subscribes to it as subscription
/// `id` and reads two scans, so the second came while the client was subscribed; returns
/// the channels advertised.
fn watch_scans(socket: &mut WebSocket<TcpStream>, id: u32) -> Vec<(u64, String, String)> {
    let channels = read_advertised(socket, LIMIT);
    subscribe(socket, &channels, ("/lidar/scan", "foxglove.LaserScan"), id);
    for _ in 0..2 {
        let payload = read_message_data(socket, id, LIMIT);
        let scan: serde_json::Value = serde_json::from_slice(&payload).expect("a JSON scan");
        assert!(
            !scan["ranges"].as_array().expect("ranges").is_empty(),
            "{scan}"
        );
        assert_eq!(scan["frame_id"], "laser", "the recording's frame");
    }
    channels
}

/// Subscribes to the back end's grid as subscription `id` and waits for one, whole.
fn watch_grid(socket: &mut WebSocket<TcpStream>, channels: &[(u64, String, String)], id: u32) {
    subscribe(socket, channels, ("/graph/grid", "foxglove.Grid"), id);
    let payload = read_message_data(socket, id, LIMIT);
    let grid: serde_json::Value = serde_json::from_slice(&payload).expect("a JSON grid");
    let rows = grid["row_count"].as_u64().expect("rows");
    let row_stride = grid["row_stride"].as_u64().expect("a row stride");
    let data = grid["data"].as_str().expect("base64 cells");
    let padding = data.bytes().rev().take_while(|&b| b == b'=').count() as u64;
    // Every row of cells is there (base64: 3 bytes in 4 characters).
    assert!(rows > 0 && row_stride > 0, "{rows} {row_stride}");
    assert_eq!(data.len() as u64 / 4 * 3 - padding, rows * row_stride);
}

#[test]
fn foxglove_clients_watch_a_live_office_run_until_ctrl_c() {
    let addr = format!("127.0.0.1:{}", free_port());
    let out = scratch("live-view");
    let args = ["--world", "office", "--rate", "40", "--foxglove", &addr];
    let mut launcher = spawn_launch(&domain("live-view"), &out, &args, Stdio::piped());
    let console = read_console(&mut launcher);
    // Today's Foxglove app, and an older app or Lichtblick, at once.
    let mut sockets = [SDK_NAME, FIRST_NAME].map(|name| connect(&addr, name, &mut launcher, LIMIT));
    for (socket, id) in sockets.iter_mut().zip([7, 8]) {
        let channels = watch_scans(socket, id);
        if id == 7 {
            // The back end publishes its grid every few seconds of the run.
            watch_grid(socket, &channels, 9);
        }
    }
    assert!(
        launcher.try_wait().expect("poll slam-launch").is_none(),
        "the run goes on"
    );

    send(pid_of(&launcher), Signal::SIGINT);
    let stopped_at = Instant::now();
    let status = wait_within(&mut launcher, STOP_LIMIT);
    if status.is_none() {
        stop(&mut launcher);
    }
    let console = console.join().expect("the console");
    let status =
        status.unwrap_or_else(|| panic!("not ended {STOP_LIMIT:?} after Ctrl-C\n{console}"));
    assert_eq!(status.code(), Some(130), "interrupted\n{console}");
    assert!(!console.contains("killed"), "{console}");
    assert!(!console.contains("slam-view died"), "{console}");
    // The view closed the connections as it stopped.
    for socket in &mut sockets {
        let closed = loop {
            match socket.read() {
                Ok(Message::Close(_)) | Err(_) => break stopped_at.elapsed(),
                Ok(_) => {}
            }
        };
        assert!(closed < STOP_LIMIT, "a connection stayed open {closed:?}");
    }
    let log = std::fs::read_to_string(out.join("logs/slam-view.log")).expect("slam-view's log");
    assert!(log.contains("messages served"), "{log}");
}

#[test]
fn a_lockstep_run_with_the_view_and_no_client_is_the_same_run() {
    let args = [
        "--world", "office", "--seed", "1", "--frames", "200", "--rate", "0",
    ];
    let addr = format!("127.0.0.1:{}", free_port());
    let viewed = launched(
        "live-view-lockstep",
        &[&args[..], &["--foxglove", &addr]].concat(),
    );
    let plain = launched("live-view-plain", &args);
    for file in ["trajectory.tum", "trajectory_online.tum", "map_corners.csv"] {
        assert_eq!(
            std::fs::read(viewed.out.join(file)).expect("the viewed run's file"),
            std::fs::read(plain.out.join(file)).expect("the plain run's file"),
            "{file} differs with --foxglove"
        );
    }
    let log = std::fs::read_to_string(viewed.out.join("logs/slam-view.log")).expect("its log");
    assert!(
        log.contains("0 messages served"),
        "no client, nothing encoded: {log}"
    );
    let _ = std::fs::remove_dir_all(&plain.out);
}

#[test]
fn a_port_in_use_is_refused_before_the_run_starts() {
    let taken = TcpListener::bind("127.0.0.1:0").expect("a port");
    let addr = taken.local_addr().expect("its address").to_string();
    let out = scratch("live-view-port");
    let started = Instant::now();
    let output = launch(
        &domain("live-view-port"),
        &out,
        &["--world", "office", "--frames", "5", "--foxglove", &addr],
    );
    let console = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{console}");
    assert!(console.contains("the port is in use"), "{console}");
    assert!(console.contains(&addr), "{console}");
    assert!(!out.join("logs/lidar-sim.log").exists(), "no stage started");
    assert!(started.elapsed() < LIMIT);
    drop(taken);
}
