//! Only the live view's own user can read it: a request under another site's name (a page
//! whose DNS name was rebound to this machine's loopback address) is refused (403) and gets
//! none of the state; the server's own names are answered; an address beyond this machine
//! is refused without the word `public`.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::Duration;

use sandjumper_live::{Event, channel, serve, serve_with_foxglove};

/// `GET path` with `Host: host` to the server at `port`: (status, body).
fn get(port: u16, path: &str, host: &str) -> (u16, String) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut text = String::new();
    s.read_to_string(&mut text).unwrap();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = text
        .split_once("\r\n\r\n")
        .map_or("", |(_, b)| b)
        .to_string();
    (status, body)
}

#[test]
fn a_foreign_host_gets_nothing_and_the_servers_own_names_get_the_state() {
    let (bus, feed) = channel(&["p_mm"]);
    bus.event(Event::Fault {
        t_s: 0.1,
        fault: "a fault text with /home/user/secret/path".into(),
    });
    let server = serve("127.0.0.1:0", feed).unwrap();
    let port = server.addr.port();
    // The state has the fault once the bus was read.
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    loop {
        let (status, body) = get(port, "/state.json", &format!("127.0.0.1:{port}"));
        assert_eq!(status, 200);
        if body.contains("secret") {
            break;
        }
        assert!(std::time::Instant::now() < deadline, "{body}");
        std::thread::sleep(Duration::from_millis(20));
    }
    for own in [format!("localhost:{port}"), format!("[::1]:{port}")] {
        let (status, body) = get(port, "/state.json", &own);
        assert_eq!(status, 200, "{own}");
        assert!(body.contains("secret"), "{own}");
    }
    for foreign in [
        format!("evil.example:{port}"),
        format!("localhost.evil.example:{port}"),
        "127.0.0.1:1".to_string(),
    ] {
        for path in ["/state.json", "/", "/events"] {
            let (status, body) = get(port, path, &foreign);
            assert_eq!(status, 403, "{foreign}{path}");
            assert!(!body.contains("secret"), "{foreign}{path}: {body}");
        }
    }
}

#[test]
fn every_interface_needs_the_word_public_and_the_address_forms_are_one_set() {
    let (_bus, feed) = channel(&["p_mm"]);
    let e = serve_with_foxglove("0.0.0.0:0", feed, None, false)
        .err()
        .expect("refused");
    assert!(
        e.contains("--live-public") && e.contains("every interface"),
        "{e}"
    );
    let (_bus, feed) = channel(&["p_mm"]);
    let e = serve("example.org:80", feed).err().expect("refused");
    assert!(
        e.contains("allowed:") && e.contains("localhost:PORT"),
        "{e}"
    );
    let (_bus, feed) = channel(&["p_mm"]);
    let s = serve("localhost:0", feed).unwrap();
    assert!(s.addr.ip().is_loopback());
    let (_bus, feed) = channel(&["p_mm"]);
    let public = serve_with_foxglove("0.0.0.0:0", feed, None, true).unwrap();
    // The URL names the machine, not 0.0.0.0 (which opens nowhere).
    assert!(!public.url().contains("0.0.0.0"), "{}", public.url());
}
