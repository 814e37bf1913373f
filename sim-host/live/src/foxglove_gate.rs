//! The gate in front of the Foxglove WebSocket: the `foxglove` crate's server checks neither
//! `Host` nor a browser's `Origin`, so it listens on a loopback port of its own and the user's
//! address is this gate's. Each connection's request head is read and checked before a byte
//! reaches the server: a `Host` that is not the gate's own name (DNS rebinding), or a browser
//! page of another site (an `Origin` other than the live page's and the Foxglove web app's),
//! gets 403 and is closed. What passes is relayed both ways unchanged.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::address::AllowedHosts;

/// The browser origins allowed besides the live page's own: Foxglove's web app.
pub const FOXGLOVE_APP_ORIGINS: [&str; 2] =
    ["https://app.foxglove.dev", "https://studio.foxglove.dev"];

/// The longest request head the gate reads, bytes.
const MAX_HEAD: usize = 16 * 1024;

/// How long a client has to send its whole request head.
const HEAD_TIME: Duration = Duration::from_secs(10);

/// Connections the gate holds at once (reading a head or relayed); more are refused (503).
pub const MAX_CONNECTIONS: usize = 64;

/// Ports browsers refuse to open (the Fetch standard's "bad ports", WebSocket included) that
/// an unprivileged process may bind: the Foxglove server itself listens on one of them, on
/// loopback, so that no web page can reach it around the gate. Those on the list longest
/// come first (10080 joined it in 2021, 4190 and 6679 in 2024: an older browser opens them).
pub const BROWSER_BLOCKED_PORTS: [u16; 19] = [
    6665, 6666, 6667, 6668, 6669, 6000, 2049, 4045, 1719, 1720, 1723, 3659, 5060, 5061, 6566, 6697,
    10080, 4190, 6679,
];

/// Who may connect: by `Host` (the gate's own names) and by browser `Origin`.
#[derive(Clone, Debug)]
pub struct OriginPolicy {
    /// The gate's own names.
    pub hosts: AllowedHosts,
    /// The live page's own names: a page loaded from it may connect.
    pub page: AllowedHosts,
}

impl OriginPolicy {
    /// Whether a request with these `Host` and `Origin` headers may reach the server; the
    /// reason when not. A web page's `Origin` is `http(s)://...` or `null` (a sandboxed or
    /// opaque page), set by the browser, not the page: those are refused unless they are the
    /// live page's own or Foxglove's web app. No `Origin` (a program: scripts, the SDKs) and an
    /// origin of another scheme (a desktop app's own pages, `file://`, `app://`: not a site)
    /// are allowed.
    pub fn check(&self, host: Option<&str>, origin: Option<&str>) -> Result<(), String> {
        let host = host.unwrap_or("");
        if !self.hosts.allows(host) {
            return Err(format!(
                "Host `{host}` is not this server's own name (open the address the command printed)"
            ));
        }
        let Some(origin) = origin.map(str::trim) else {
            return Ok(());
        };
        let own_page = origin
            .strip_prefix("http://")
            .is_some_and(|h| self.page.names_this_server(h));
        let lower = origin.to_ascii_lowercase();
        let web = lower == "null" || lower.starts_with("http://") || lower.starts_with("https://");
        if own_page || !web && !lower.is_empty() || FOXGLOVE_APP_ORIGINS.contains(&origin) {
            Ok(())
        } else {
            Err(format!(
                "a page of `{origin}` may not read this run (allowed: the live page's own, {})",
                FOXGLOVE_APP_ORIGINS.join(", ")
            ))
        }
    }
}

/// A running gate; dropping it stops accepting and closes the connections it relays.
pub struct Gate {
    /// The address it listens on.
    pub addr: SocketAddr,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Gate {
    /// Listen at `at` for connections to relay to `server` (a loopback port), checked by
    /// the policy `policy_for` gives for the bound address.
    pub fn start(
        at: SocketAddr,
        server: SocketAddr,
        policy_for: impl FnOnce(SocketAddr) -> OriginPolicy,
    ) -> Result<Self, String> {
        let listener = TcpListener::bind(at)
            .map_err(|e| format!("--foxglove {at}: cannot listen there ({e})"))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| format!("--foxglove {at}: {e}"))?;
        let addr = listener
            .local_addr()
            .map_err(|e| format!("--foxglove {at}: {e}"))?;
        let policy = Arc::new(policy_for(addr));
        let stop = Arc::new(AtomicBool::new(false));
        let stopped = stop.clone();
        let open = Arc::new(AtomicUsize::new(0));
        let thread = std::thread::Builder::new()
            .name("foxglove-gate".into())
            .spawn(move || {
                while !stopped.load(Ordering::Relaxed) {
                    match listener.accept() {
                        Ok((mut client, _)) => {
                            if open.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
                                open.fetch_sub(1, Ordering::SeqCst);
                                let _ = client.set_nonblocking(false);
                                refuse(
                                    &mut client,
                                    "503 Service Unavailable",
                                    "too many connections",
                                );
                                continue;
                            }
                            let (policy, held, stopped) =
                                (policy.clone(), open.clone(), stopped.clone());
                            let slot = Slot(held);
                            // A thread that cannot start drops its closure, and the slot.
                            let _ = std::thread::Builder::new()
                                .name("foxglove-conn".into())
                                .spawn(move || {
                                    let _slot = slot;
                                    serve(client, server, &policy, &stopped);
                                });
                        }
                        Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                            std::thread::sleep(Duration::from_millis(20));
                        }
                        Err(_) => std::thread::sleep(Duration::from_millis(20)),
                    }
                }
            })
            .map_err(|e| format!("cannot start the Foxglove gate's thread: {e}"))?;
        Ok(Self {
            addr,
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for Gate {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One of the gate's [`MAX_CONNECTIONS`], given back when dropped (however its thread ends).
struct Slot(Arc<AtomicUsize>);

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

/// The value of header `name` (case-insensitive) in a request head.
fn header<'a>(head: &'a str, name: &str) -> Option<&'a str> {
    head.lines().skip(1).find_map(|l| {
        let (k, v) = l.split_once(':')?;
        k.trim().eq_ignore_ascii_case(name).then(|| v.trim())
    })
}

/// One connection: read its head (within [`HEAD_TIME`] in all), check it, refuse it or
/// relay it until either side closes or the gate stops.
fn serve(mut client: TcpStream, server: SocketAddr, policy: &OriginPolicy, stopped: &AtomicBool) {
    let _ = client.set_nonblocking(false);
    let deadline = Instant::now() + HEAD_TIME;
    let mut head = Vec::new();
    let mut buf = [0u8; 4096];
    let end = loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || client.set_read_timeout(Some(left)).is_err() {
            return;
        }
        match client.read(&mut buf) {
            Ok(0) | Err(_) => return,
            Ok(n) => head.extend_from_slice(&buf[..n]),
        }
        if let Some(at) = head.windows(4).position(|w| w == b"\r\n\r\n") {
            break at + 4;
        }
        if head.len() > MAX_HEAD {
            refuse(
                &mut client,
                "431 Request Header Fields Too Large",
                "the request head is too long",
            );
            return;
        }
    };
    if stopped.load(Ordering::Relaxed) {
        return; // the gate is gone: its server's port may be another run's by now
    }
    let text = String::from_utf8_lossy(&head[..end]);
    if let Err(why) = policy.check(header(&text, "host"), header(&text, "origin")) {
        refuse(&mut client, "403 Forbidden", &why);
        return;
    }
    let Ok(mut upstream) = TcpStream::connect(server) else {
        refuse(
            &mut client,
            "502 Bad Gateway",
            "the Foxglove server is gone",
        );
        return;
    };
    let _ = client.set_read_timeout(None);
    if upstream.write_all(&head).is_err() {
        return;
    }
    let (Ok(mut client_r), Ok(mut upstream_w)) = (client.try_clone(), upstream.try_clone()) else {
        return;
    };
    let (Ok(client_end), Ok(upstream_end)) = (client.try_clone(), upstream.try_clone()) else {
        return;
    };
    let Ok(up) = std::thread::Builder::new().spawn(move || {
        let _ = std::io::copy(&mut client_r, &mut upstream_w);
        let _ = upstream_w.shutdown(Shutdown::Write);
    }) else {
        return;
    };
    let Ok(down) = std::thread::Builder::new().spawn(move || {
        let _ = std::io::copy(&mut upstream, &mut client);
        let _ = client.shutdown(Shutdown::Write);
    }) else {
        let _ = client_end.shutdown(Shutdown::Both);
        let _ = upstream_end.shutdown(Shutdown::Both);
        let _ = up.join();
        return;
    };
    // Both directions end when either side closes; the gate's stop closes both.
    while !(up.is_finished() && down.is_finished()) {
        if stopped.load(Ordering::Relaxed) {
            let _ = client_end.shutdown(Shutdown::Both);
            let _ = upstream_end.shutdown(Shutdown::Both);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = up.join();
    let _ = down.join();
}

fn refuse(client: &mut TcpStream, status: &str, why: &str) {
    let body = format!("{status}: {why}\n");
    let _ = write!(
        client,
        "HTTP/1.1 {status}\r\nContent-Type: text/plain\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    let _ = client.shutdown(Shutdown::Both);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy() -> OriginPolicy {
        OriginPolicy {
            hosts: AllowedHosts::for_bind("127.0.0.1:8765".parse().unwrap()),
            page: AllowedHosts::for_bind("127.0.0.1:8080".parse().unwrap()),
        }
    }

    #[test]
    fn the_page_the_foxglove_app_and_programs_may_connect_other_sites_may_not() {
        let p = policy();
        let host = Some("127.0.0.1:8765");
        for ok in [
            None,
            Some("http://127.0.0.1:8080"),
            Some("http://localhost:8080"),
            Some("https://app.foxglove.dev"),
            Some("file://"),
            Some("app://foxglove"),
        ] {
            p.check(host, ok).unwrap_or_else(|e| panic!("{ok:?}: {e}"));
        }
        for bad in [
            "https://evil.example",
            "http://127.0.0.1:9999",
            "http://rebound.example:8080",
            "https://app.foxglove.dev.evil.example",
            "null",
            "HTTPS://EVIL.EXAMPLE",
            "",
        ] {
            let e = p.check(host, Some(bad)).unwrap_err();
            assert!(e.contains("may not read this run"), "{bad}: {e}");
        }
        // A foreign Host (DNS rebinding) is refused whatever the Origin.
        let e = p.check(Some("rebound.example:8765"), None).unwrap_err();
        assert!(e.contains("not this server's own name"), "{e}");
        assert!(p.check(None, None).is_err());
    }

    /// Bound beyond this machine, a `Host` of any IP address is the server's own (no
    /// rebinding sends one), but an `Origin` of any IP address is any site served from one:
    /// only loopback, the bound address and the machine's name are the page's.
    #[test]
    fn on_a_public_bind_a_page_of_another_ip_address_may_not_connect() {
        let p = OriginPolicy {
            hosts: AllowedHosts::for_bind("0.0.0.0:8765".parse().unwrap()),
            page: AllowedHosts::for_bind("192.0.2.10:8080".parse().unwrap()),
        };
        let host = Some("198.51.100.7:8765");
        p.check(host, None).unwrap();
        p.check(host, Some("http://192.0.2.10:8080")).unwrap();
        p.check(host, Some("http://127.0.0.1:8080")).unwrap();
        if let Some(m) = crate::address::host_name() {
            p.check(host, Some(&format!("http://{m}:8080"))).unwrap();
        }
        let e = p.check(host, Some("http://198.51.100.7:8080")).unwrap_err();
        assert!(e.contains("may not read this run"), "{e}");
    }

    #[test]
    fn headers_are_found_whatever_their_case() {
        let head = "GET / HTTP/1.1\r\nhOsT: a:1\r\nORIGIN:  https://x \r\n\r\n";
        assert_eq!(header(head, "host"), Some("a:1"));
        assert_eq!(header(head, "origin"), Some("https://x"));
        assert_eq!(header(head, "cookie"), None);
    }
}
