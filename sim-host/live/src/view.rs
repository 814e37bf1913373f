//! A live view for one run: its bus and (with `server`) its page, the run kept at a pace of
//! real time, and the page kept up after the run. What a command puts on the bus (a jump's
//! control periods, a campaign's points) is its own.

use std::time::{Duration, Instant};

use super::bus::{Event, LiveBus};

/// Where and how to show a run.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveConfig {
    /// The page's address: HOST:PORT, or a bare PORT on 127.0.0.1 (port 0: any free port).
    pub addr: String,
    /// A simulated run's pace, times real time (1: real time; 0: as fast as it can).
    pub pace: f64,
    /// The same streams on a Foxglove WebSocket server at HOST:PORT (the `foxglove` feature).
    pub foxglove: Option<String>,
    /// How long to keep the page up after the run, s (`None`: until the caller says stop).
    pub linger: Option<f64>,
    /// The user asked for an address beyond this machine (`--live-public`): without it one is
    /// refused, the page having no login.
    pub public: bool,
}

impl Default for LiveConfig {
    fn default() -> Self {
        Self {
            addr: "127.0.0.1:0".into(),
            pace: 1.0,
            foxglove: None,
            linger: None,
            public: false,
        }
    }
}

/// A live view for one run: its bus and server, and the run's pacing.
pub struct LiveView {
    bus: LiveBus,
    #[cfg(feature = "server")]
    server: super::server::LiveServer,
    #[cfg(feature = "server")]
    foxglove: Option<String>,
    #[cfg(feature = "server")]
    public: bool,
    pace: f64,
    linger: Option<f64>,
    wall_start: Option<(Instant, f64)>,
}

impl LiveView {
    /// Start the view's server at `config.addr`; `channels` name the samples. Fails (a
    /// message saying what and where) if the address cannot be served.
    #[cfg(feature = "server")]
    pub fn start(config: &LiveConfig, channels: &[&str]) -> Result<Self, String> {
        let (bus, feed) = super::bus::channel(channels);
        let server = super::server::serve_with_foxglove(
            &config.addr,
            feed,
            config.foxglove.as_deref(),
            config.public,
        )?;
        Ok(Self {
            bus,
            server,
            foxglove: config.foxglove.clone(),
            public: config.public,
            pace: config.pace,
            linger: config.linger,
            wall_start: None,
        })
    }

    /// Without the `server` feature there is no page: the refusal of `--live ADDR`.
    #[cfg(not(feature = "server"))]
    pub fn start(config: &LiveConfig, channels: &[&str]) -> Result<Self, String> {
        let _ = channels;
        Err(format!(
            "--live {}: this build has no live view (built with --no-default-features; build sandjumper-cli with its default features)",
            config.addr
        ))
    }

    /// Where the page and its streams are, one line each, for the user to read.
    #[cfg(feature = "server")]
    pub fn addresses(&self) -> Vec<String> {
        let url = self.server.url();
        let mut lines = vec![format!("live view: {url} (state: {url}state.json)")];
        if self.public {
            lines.push(
                "live view: the page has no login: anyone who can reach this machine's port can \
                 read it (--live-public)"
                    .into(),
            );
        }
        if let (Some(port), Some(fg)) = (self.server.foxglove_port, &self.foxglove) {
            let host = fg.rsplit_once(':').map_or("127.0.0.1", |(h, _)| h);
            lines.push(format!(
                "foxglove: ws://{host}:{port} (Foxglove, or Lichtblick after 1.21)"
            ));
        }
        lines
    }

    /// Without the `server` feature: no page, no address.
    #[cfg(not(feature = "server"))]
    pub fn addresses(&self) -> Vec<String> {
        Vec::new()
    }

    /// What to tell the user once the run has ended and the page stays up.
    pub fn lingering(&self) -> String {
        match self.linger {
            Some(s) => format!(
                "live view: the run has ended; the page stays up for {s} s (Ctrl-C ends it sooner)"
            ),
            None => "live view: the run has ended; the page stays up until Ctrl-C".to_string(),
        }
    }

    /// Do not pace this run (a real board keeps its own time).
    pub fn unpaced(&mut self) {
        self.pace = 0.0;
    }

    /// The bus.
    pub fn bus(&mut self) -> &mut LiveBus {
        &mut self.bus
    }

    /// How long the page stays up after the run, s (`None`: until the caller says stop).
    pub fn linger(&self) -> Option<f64> {
        self.linger
    }

    /// Sleep so that rig time `t_s` is not ahead of the wall clock times the pace (checked
    /// every period, slept in steps of at least 2 ms).
    pub fn keep_pace(&mut self, t_s: f64) {
        if self.pace <= 0.0 {
            return;
        }
        let (w0, t0) = *self.wall_start.get_or_insert((Instant::now(), t_s));
        let due = (t_s - t0) / self.pace;
        let now = w0.elapsed().as_secs_f64();
        if due - now > 0.002 {
            std::thread::sleep(Duration::from_secs_f64(due - now));
        }
    }

    /// The run is over at rig time `t_s`, s: send what is left, then how it ended.
    pub fn end(&mut self, t_s: f64, outcome: String, ok: bool) {
        // The last samples first (waiting for the lock is free now), then the end.
        self.bus.flush_and_wait();
        self.bus.event(Event::RunEnded { t_s, outcome, ok });
    }

    /// Wait (up to 2 s) until the page's state has the run's end: the server reads the bus
    /// every 25 ms.
    #[cfg(feature = "server")]
    pub fn wait_until_shown(&self) {
        let asked = Instant::now();
        while self.server.snapshot().ended.is_none() && asked.elapsed() < Duration::from_secs(2) {
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// Without the `server` feature there is no page to wait for.
    #[cfg(not(feature = "server"))]
    pub fn wait_until_shown(&self) {}

    /// Keep the page up for the linger time, or until `stop` says so when there is none (or
    /// sooner); whether `stop` ended it.
    pub fn linger_until(&self, stop: &dyn Fn() -> bool) -> bool {
        let until = self
            .linger
            .map(|s| Instant::now() + Duration::from_secs_f64(s));
        while until.is_none_or(|u| Instant::now() < u) {
            if stop() {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        stop()
    }
}
