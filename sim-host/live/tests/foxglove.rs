//! The Foxglove WebSocket server (`--features foxglove`): a client speaking the Foxglove
//! protocol (`foxglove.sdk.v1`, what Foxglove and Lichtblick send) is told the server's name
//! and our channels with their JSON schemas, and receives the samples and the state changes.
#![cfg(feature = "foxglove")]

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use sandjumper_live::{Event, channel, serve_with_foxglove};

/// One bridge at a time in this binary: the servers share a pool of ports (those browsers
/// refuse), and a test that checks a port is free after its bridge must not see another's.
static ONE_BRIDGE: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn one_bridge() -> std::sync::MutexGuard<'static, ()> {
    ONE_BRIDGE.lock().unwrap_or_else(|p| p.into_inner())
}

/// Read one WebSocket frame sent by the server (unmasked): (opcode, payload).
fn frame(s: &mut TcpStream) -> (u8, Vec<u8>) {
    let mut h = [0u8; 2];
    s.read_exact(&mut h).unwrap();
    let mut len = u64::from(h[1] & 0x7f);
    if len == 126 {
        let mut b = [0u8; 2];
        s.read_exact(&mut b).unwrap();
        len = u64::from(u16::from_be_bytes(b));
    } else if len == 127 {
        let mut b = [0u8; 8];
        s.read_exact(&mut b).unwrap();
        len = u64::from_be_bytes(b);
    }
    let mut p = vec![0u8; len as usize];
    s.read_exact(&mut p).unwrap();
    (h[0] & 0x0f, p)
}

/// A client frame (masked, as clients must): a JSON text message.
fn send_text(s: &mut TcpStream, text: &str) {
    let p = text.as_bytes();
    let mut f = vec![0x81u8];
    assert!(p.len() < 126);
    f.push(0x80 | p.len() as u8);
    let mask = [1u8, 2, 3, 4];
    f.extend_from_slice(&mask);
    f.extend(p.iter().enumerate().map(|(i, b)| b ^ mask[i % 4]));
    s.write_all(&f).unwrap();
}

#[test]
fn a_foxglove_client_sees_our_channels_and_receives_samples_and_states() {
    let _one = one_bridge();
    let (mut bus, feed) = channel(&["p_mm", "force_n"]);
    let server = serve_with_foxglove("127.0.0.1:0", feed, Some("127.0.0.1:0"), false).unwrap();
    let port = server.foxglove_port.unwrap();
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n"
    )
    .unwrap();
    // The 101 response, up to its blank line.
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n\r\n") {
        s.read_exact(&mut b).unwrap();
        head.push(b[0]);
    }
    let head = String::from_utf8_lossy(&head).to_lowercase();
    assert!(head.starts_with("http/1.1 101"), "{head}");
    assert!(
        head.contains("sec-websocket-protocol: foxglove.sdk.v1"),
        "{head}"
    );
    // serverInfo, then the channels advertised.
    let mut topics = std::collections::BTreeMap::new();
    let mut info = None;
    while topics.len() < 5 {
        let (op, p) = frame(&mut s);
        if op != 1 {
            continue;
        }
        let m: serde_json::Value = serde_json::from_slice(&p).unwrap();
        match m["op"].as_str() {
            Some("serverInfo") => info = Some(m),
            Some("advertise") => {
                for c in m["channels"].as_array().unwrap() {
                    topics.insert(c["topic"].as_str().unwrap().to_string(), c.clone());
                }
            }
            _ => {}
        }
    }
    assert_eq!(info.unwrap()["name"].as_str(), Some("sandjumper"));
    let samples = &topics["/sandjumper/samples"];
    assert_eq!(samples["encoding"].as_str(), Some("json"));
    assert_eq!(samples["schemaEncoding"].as_str(), Some("jsonschema"));
    let schema: serde_json::Value =
        serde_json::from_str(samples["schema"].as_str().unwrap()).unwrap();
    assert!(schema["properties"]["force_n"].is_object());
    for t in [
        "/sandjumper/state",
        "/sandjumper/fault",
        "/sandjumper/campaign",
        "/sandjumper/events",
    ] {
        assert!(topics.contains_key(t), "{t}");
    }
    // Subscribe to the samples and the states, then run.
    let id = |t: &str| topics[t]["id"].as_u64().unwrap();
    send_text(
        &mut s,
        &format!(
            r#"{{"op":"subscribe","subscriptions":[{{"id":1,"channelId":{}}},{{"id":2,"channelId":{}}}]}}"#,
            id("/sandjumper/samples"),
            id("/sandjumper/state")
        ),
    );
    std::thread::sleep(Duration::from_millis(200));
    bus.event(Event::State {
        t_s: 0.0,
        state: "Running".into(),
    });
    for k in 0..2_000u32 {
        bus.sample(f64::from(k) * 1e-4, &[1.0, 2.0]);
    }
    bus.flush_now();
    // Binary message data frames: op 1, subscription id (u32 LE), log time (u64), payload.
    let (mut got_sample, mut got_state) = (false, false);
    while !(got_sample && got_state) {
        let (op, p) = frame(&mut s);
        if op != 2 || p.first() != Some(&1) {
            continue;
        }
        let sub = u32::from_le_bytes(p[1..5].try_into().unwrap());
        let m: serde_json::Value = serde_json::from_slice(&p[13..]).unwrap();
        if sub == 1 {
            assert_eq!(m["force_n"].as_f64(), Some(2.0));
            got_sample = true;
        } else if sub == 2 {
            assert_eq!(m["state"].as_str(), Some("Running"));
            got_state = true;
        }
    }
}

/// The WebSocket handshake with `host` and `origin` (if any): the response's status line.
fn handshake(port: u16, host: &str, origin: Option<&str>) -> String {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let origin = origin
        .map(|o| format!("Origin: {o}\r\n"))
        .unwrap_or_default();
    write!(
        s,
        "GET / HTTP/1.1\r\nHost: {host}\r\n{origin}Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n"
    )
    .unwrap();
    let mut head = Vec::new();
    let mut b = [0u8; 1];
    while !head.ends_with(b"\r\n") && s.read_exact(&mut b).is_ok() {
        head.push(b[0]);
    }
    String::from_utf8_lossy(&head).trim().to_string()
}

/// DNS rebinding and cross-site pages, at the WebSocket: a page of another site (its browser
/// `Origin`) or under another site's name (its `Host`) gets 403 before a byte reaches the
/// Foxglove server; the live page's own pages, Foxglove's web app, a desktop app's own pages
/// and programs (no `Origin`) connect.
#[test]
fn a_page_of_another_site_cannot_open_the_foxglove_websocket() {
    let _one = one_bridge();
    let (_bus, feed) = channel(&["p_mm"]);
    let server = serve_with_foxglove("127.0.0.1:0", feed, Some("127.0.0.1:0"), false).unwrap();
    let port = server.foxglove_port.unwrap();
    let page = server.url().trim_end_matches('/').to_string();
    let own = format!("127.0.0.1:{port}");
    for origin in [
        None,
        Some(page.as_str()),
        Some("https://app.foxglove.dev"),
        Some("file://"),
    ] {
        let status = handshake(port, &own, origin);
        assert!(status.starts_with("HTTP/1.1 101"), "{origin:?}: {status}");
    }
    for origin in ["https://evil.example", "null", "http://127.0.0.1:1"] {
        let status = handshake(port, &own, Some(origin));
        assert!(status.starts_with("HTTP/1.1 403"), "{origin}: {status}");
    }
    let status = handshake(port, &format!("rebound.example:{port}"), None);
    assert!(status.starts_with("HTTP/1.1 403"), "{status}");
}

/// A bridge of its own (no live page: its page's address is only for the Origin policy).
fn bridge_alone() -> sandjumper_live::foxglove_bridge::FoxgloveBridge {
    sandjumper_live::foxglove_bridge::FoxgloveBridge::start(
        "127.0.0.1:0".parse().unwrap(),
        "127.0.0.1:8080".parse().unwrap(),
        &["p_mm".to_string()],
    )
    .unwrap()
}

/// [`handshake`] with `host` and no Origin, again every 50 ms (5 s at most) until its status
/// line starts with `status`: the last status line.
fn handshake_until(port: u16, host: &str, status: &str) -> String {
    let mut last = String::new();
    for _ in 0..100 {
        last = handshake(port, host, None);
        if last.starts_with(status) {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    last
}

/// The Foxglove server behind the gate listens on a loopback port that every browser refuses
/// to open (the Fetch standard's bad ports): a page cannot reach it around the gate. The
/// bridge gone, neither port answers.
#[test]
fn the_server_behind_the_gate_is_on_a_port_no_browser_opens_and_stops_with_the_bridge() {
    let _one = one_bridge();
    use sandjumper_live::foxglove_gate::BROWSER_BLOCKED_PORTS;
    let bridge = bridge_alone();
    let (gate, server) = (bridge.port, bridge.server_port);
    assert!(
        BROWSER_BLOCKED_PORTS.contains(&server),
        "the server listens on {server}"
    );
    assert!(handshake(gate, &format!("127.0.0.1:{gate}"), None).starts_with("HTTP/1.1 101"));
    drop(bridge);
    std::thread::sleep(Duration::from_millis(300));
    for port in [gate, server] {
        assert!(
            TcpStream::connect(("127.0.0.1", port)).is_err(),
            "port {port} still answers after the bridge is gone"
        );
    }
}

/// A client that opens connections and sends nothing holds at most the gate's cap of them:
/// the next connection is answered 503 at once, and the gate goes on serving once they close.
#[test]
fn the_gate_holds_a_bounded_number_of_connections() {
    let _one = one_bridge();
    use sandjumper_live::foxglove_gate::MAX_CONNECTIONS;
    let bridge = bridge_alone();
    let gate = bridge.port;
    let idle: Vec<TcpStream> = (0..MAX_CONNECTIONS)
        .map(|_| TcpStream::connect(("127.0.0.1", gate)).unwrap())
        .collect();
    // The gate takes them in turn (it polls its listener): wait until all are held.
    let own = format!("127.0.0.1:{gate}");
    let refused = handshake_until(gate, &own, "HTTP/1.1 503");
    assert!(refused.starts_with("HTTP/1.1 503"), "{refused}");
    drop(idle);
    let again = handshake_until(gate, &own, "HTTP/1.1 101");
    assert!(again.starts_with("HTTP/1.1 101"), "{again}");
}
