//! Where the live view listens and who may read it: the address forms `--live` and
//! `--foxglove` both take (`PORT`, `IP:PORT`, `localhost:PORT`, `[::1]:PORT`), the refusal of a
//! bind beyond this machine unless the user says so (the page has no login), and the `Host`
//! names a request may carry (a page of another site that rebinds its DNS name to this
//! machine's loopback address sends its own name, and is refused).

use std::net::{IpAddr, Ipv4Addr, SocketAddr};

/// The forms an address may take, for errors.
pub const FORMS: &str = "PORT (on 127.0.0.1), IP:PORT, localhost:PORT or [IPv6]:PORT, e.g. 8080, 127.0.0.1:8080, localhost:8080, [::1]:8080";

/// `text` as a socket address: a bare `PORT` on 127.0.0.1, `localhost:PORT` on 127.0.0.1,
/// `IP:PORT` or `[IPv6]:PORT`. `flag` names the option for the error.
pub fn parse_listen(flag: &str, text: &str) -> Result<SocketAddr, String> {
    let bad = |why: &str| format!("{flag} {text}: {why} (allowed: {FORMS})");
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), port));
    }
    if let Some(port) = text.strip_prefix("localhost:") {
        let port = port.parse::<u16>().map_err(|_| bad("not a port"))?;
        return Ok(SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), port));
    }
    text.parse::<SocketAddr>().map_err(|_| {
        if text
            .rsplit_once(':')
            .is_some_and(|(h, _)| h.parse::<IpAddr>().is_err())
        {
            bad("a host name other than localhost (give its IP address)")
        } else {
            bad("not an address")
        }
    })
}

/// Refuse `addr` beyond this machine (not a loopback address) unless `public`: the page has
/// no login, so anyone who can reach the address could read it.
pub fn check_exposure(
    flag: &str,
    text: &str,
    addr: SocketAddr,
    public: bool,
) -> Result<(), String> {
    if addr.ip().is_loopback() || public {
        return Ok(());
    }
    Err(format!(
        "{flag} {text} listens beyond this machine ({}), and the page has no login: anyone who \
         can reach it could read the run (its faults, file paths, plan). Add --live-public to \
         mean it, or listen on 127.0.0.1 (a bare PORT)",
        if addr.ip().is_unspecified() {
            "every interface"
        } else {
            "a network interface"
        }
    ))
}

/// This machine's name (Linux's `/proc/sys/kernel/hostname`, else `HOSTNAME`).
pub fn host_name() -> Option<String> {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_ascii_lowercase())
        .filter(|h| !h.is_empty())
}

/// The `Host` names a request to a server bound at `bound` may carry: `localhost` and loopback
/// addresses always; with a bind beyond this machine, any IP address and this machine's name
/// (as the kernel has it, and its first label). A name of another site (DNS rebinding) never.
#[derive(Clone, Debug)]
pub struct AllowedHosts {
    port: u16,
    public: bool,
    machine: Option<String>,
    bound_ip: IpAddr,
}

impl AllowedHosts {
    /// The names allowed for a server bound at `bound`.
    pub fn for_bind(bound: SocketAddr) -> Self {
        Self {
            port: bound.port(),
            public: !bound.ip().is_loopback(),
            machine: host_name(),
            bound_ip: bound.ip(),
        }
    }

    /// Whether a request with this `Host` header is this server's own.
    pub fn allows(&self, host: &str) -> bool {
        self.own(host, false)
    }

    /// Whether `host` (of a browser `Origin`, `NAME:PORT`) names this server: as
    /// [`allows`](Self::allows), except that an IP address must be a loopback one or the one
    /// bound. A `Host` of any IP is no rebinding (a rebinding page sends its name), but an
    /// `Origin` of any IP is any site served from an IP address.
    pub fn names_this_server(&self, host: &str) -> bool {
        self.own(host, true)
    }

    /// Bound on every interface (`0.0.0.0`, `[::]`): whether `ip` is one of this machine's
    /// addresses (a socket can be bound to it).
    fn any_own(&self, ip: IpAddr) -> bool {
        self.bound_ip.is_unspecified()
            && !ip.is_unspecified()
            && std::net::UdpSocket::bind(SocketAddr::new(ip, 0)).is_ok()
    }

    fn own(&self, host: &str, strict_ip: bool) -> bool {
        let host = host.trim().to_ascii_lowercase();
        // Split off the port: `[v6]:port`, `name:port`, or no port (80).
        let (name, port) = if let Some(rest) = host.strip_prefix('[') {
            let Some((v6, after)) = rest.split_once(']') else {
                return false;
            };
            let port = match after.strip_prefix(':') {
                Some(p) => p.parse::<u16>().ok(),
                None if after.is_empty() => Some(80),
                None => None,
            };
            (v6.to_string(), port)
        } else {
            match host.rsplit_once(':') {
                Some((n, p)) => (n.to_string(), p.parse::<u16>().ok()),
                None => (host.clone(), Some(80)),
            }
        };
        if port != Some(self.port) {
            return false;
        }
        if name == "localhost" {
            return true;
        }
        if let Ok(ip) = name.parse::<IpAddr>() {
            return ip.is_loopback()
                || self.public && (!strict_ip || ip == self.bound_ip || self.any_own(ip));
        }
        self.public
            && self
                .machine
                .as_ref()
                .is_some_and(|m| name == *m || name == m.split('.').next().unwrap_or(m))
    }

    /// The page's address for the user: the machine's name for a bind beyond it (the
    /// unspecified address 0.0.0.0 opens nowhere), else the bound address.
    pub fn url(&self, bound: SocketAddr) -> String {
        match (&self.machine, bound.ip().is_unspecified()) {
            (Some(m), true) => format!("http://{m}:{}/", bound.port()),
            _ => format!("http://{bound}/"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_address_form_parses_and_others_are_refused_saying_which_forms() {
        let v4 = |s: &str| parse_listen("--live", s).unwrap();
        assert_eq!(v4("8080"), "127.0.0.1:8080".parse().unwrap());
        assert_eq!(v4("localhost:8080"), "127.0.0.1:8080".parse().unwrap());
        assert_eq!(v4("[::1]:8080"), "[::1]:8080".parse().unwrap());
        assert_eq!(v4("0.0.0.0:80"), "0.0.0.0:80".parse().unwrap());
        for bad in ["example.org:80", "localhost:http", "8080:", "", "70000"] {
            let e = parse_listen("--foxglove", bad).unwrap_err();
            assert!(
                e.starts_with("--foxglove") && e.contains("allowed:"),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn a_bind_beyond_this_machine_needs_the_word_public() {
        let any: SocketAddr = "0.0.0.0:8080".parse().unwrap();
        let e = check_exposure("--live", "0.0.0.0:8080", any, false).unwrap_err();
        assert!(
            e.contains("every interface") && e.contains("--live-public"),
            "{e}"
        );
        check_exposure("--live", "0.0.0.0:8080", any, true).unwrap();
        check_exposure("--live", "8080", "127.0.0.1:8080".parse().unwrap(), false).unwrap();
        check_exposure("--live", "[::1]:1", "[::1]:1".parse().unwrap(), false).unwrap();
    }

    #[test]
    fn only_this_servers_own_names_are_allowed() {
        let local = AllowedHosts::for_bind("127.0.0.1:8080".parse().unwrap());
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LOCALHOST:8080",
            "[::1]:8080",
            "127.0.0.2:8080",
        ] {
            assert!(local.allows(ok), "{ok}");
        }
        for no in [
            "evil.example:8080",
            "127.0.0.1:9090",
            "10.0.0.5:8080",
            "localhost",
            "[::1]",
            "localhost.evil.example:8080",
            "",
        ] {
            assert!(!local.allows(no), "{no}");
        }
        let public = AllowedHosts {
            port: 80,
            public: true,
            machine: Some("node07.cluster.example".into()),
            bound_ip: "10.0.0.5".parse().unwrap(),
        };
        for ok in [
            "10.0.0.5",
            "node07",
            "node07.cluster.example:80",
            "localhost:80",
        ] {
            assert!(public.allows(ok), "{ok}");
        }
        // An Origin's address must be loopback or the one bound (any IP is any site).
        assert!(public.names_this_server("10.0.0.5:80"));
        assert!(public.names_this_server("node07:80"));
        assert!(!public.names_this_server("10.0.0.6:80"));
        assert!(public.allows("10.0.0.6:80"));
        // Bound on every interface: an address of this machine is the page's, another not.
        let every = AllowedHosts {
            bound_ip: "0.0.0.0".parse().unwrap(),
            ..public.clone()
        };
        assert!(every.names_this_server("127.0.0.1:80"));
        let own = std::net::UdpSocket::bind("0.0.0.0:0")
            .and_then(|s| s.connect("192.0.2.1:9").map(|()| s))
            .and_then(|s| s.local_addr())
            .map(|a| a.ip());
        if let Some(ip) = own
            .ok()
            .filter(|ip| !ip.is_loopback() && !ip.is_unspecified())
        {
            assert!(every.names_this_server(&format!("{ip}:80")), "{ip}");
        }
        assert!(!every.names_this_server("198.51.100.7:80"));
        assert!(!public.allows("evil.example"));
        assert!(!public.allows("node08:80"));
        assert!(!public.allows("node07.evil.example:80"));
        assert_eq!(
            public.url("0.0.0.0:80".parse().unwrap()),
            "http://node07.cluster.example:80/"
        );
    }
}
