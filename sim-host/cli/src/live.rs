//! `--live ADDR`: the live view of a run (`sandjumper_live`), as the commands use it: the bus
//! and its server started before the run (the URL printed first, on stderr), every control
//! period put on the bus and, for a simulated link, paced at real time (or `--pace`), then
//! the page kept up after the run until Ctrl-C or `--linger` passes.

use std::time::{Duration, Instant};

#[cfg(feature = "live")]
use sandjumper_live::LiveServer;
use sandjumper_live::{Event, LiveBus};
use sandjumper_output::CliError;
use sandjumper_rig::hil::PeriodView;
use sandjumper_rig::tool::session::ProgramView;

/// The jump view's channels: commanded and measured motor position, rod height, foot
/// position, the drive's force command and the spring force.
pub const JUMP_CHANNELS: [&str; 6] = [
    "p_cmd_mm",
    "p_mm",
    "rod_height_mm",
    "foot_mm",
    "drive_force_n",
    "spring_force_n",
];

/// The options every `--live` command shares.
#[derive(Debug, Clone, clap::Args)]
pub struct LiveArgs {
    /// Serve a live view of the run at http://ADDR/ (e.g. 127.0.0.1:8080, or 8080 for
    /// 127.0.0.1:8080; port 0: any free port), the same state at /state.json. The URL is
    /// printed first, on stderr.
    #[arg(long, value_name = "ADDR")]
    pub live: Option<String>,
    /// With --live, run a simulated link at this multiple of real time (default 1; 0: as
    /// fast as it can).
    #[arg(long, value_name = "X", requires = "live", value_parser = parse_pace)]
    pub pace: Option<f64>,
    /// With --live, the same streams on a Foxglove WebSocket server at HOST:PORT (typed JSON
    /// channels for Foxglove or Lichtblick panels; builds with `--features foxglove`).
    #[arg(long, value_name = "HOST:PORT", requires = "live")]
    pub foxglove: Option<String>,
    /// With --live, keep the page up this long after the run, s (default: until Ctrl-C).
    #[arg(long, value_name = "S", requires = "live", value_parser = parse_linger)]
    pub linger: Option<f64>,
}

fn parse_pace(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v == 0.0 || (0.01..=1000.0).contains(&v) => Ok(v),
        _ => Err(format!(
            "`{s}` is not a pace (allowed: 0, as fast as possible, or 0.01..=1000 times real time)"
        )),
    }
}

fn parse_linger(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (0.0..=86_400.0).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a linger time (allowed: 0..=86400 s)")),
    }
}

/// A live view for one command: its bus and server, and the run's pacing.
pub struct LiveView {
    bus: LiveBus,
    #[cfg(feature = "live")]
    server: LiveServer,
    pace: f64,
    linger: Option<f64>,
    wall_start: Option<(Instant, f64)>,
    last_state: Option<sandjumper_core::RigState>,
    fault_sent: bool,
}

impl LiveView {
    /// Start the view `a` asks for (`None` without `--live`); `channels` name the samples.
    pub fn start(a: &LiveArgs, channels: &[&str]) -> Result<Option<Self>, CliError> {
        let Some(addr) = &a.live else {
            return Ok(None);
        };
        #[cfg(not(feature = "live"))]
        {
            let _ = channels;
            Err(CliError::input(format!(
                "--live {addr}: this build has no live view (built with --no-default-features; build sandjumper-cli with its default features)"
            )))
        }
        #[cfg(feature = "live")]
        {
            Self::start_server(a, addr, channels).map(Some)
        }
    }

    #[cfg(feature = "live")]
    fn start_server(a: &LiveArgs, addr: &str, channels: &[&str]) -> Result<Self, CliError> {
        let (bus, feed) = sandjumper_live::channel(channels);
        let server = sandjumper_live::serve_with_foxglove(addr, feed, a.foxglove.as_deref())
            .map_err(CliError::input)?;
        eprintln!(
            "live view: {} (state: {}state.json)",
            server.url(),
            server.url()
        );
        if let (Some(port), Some(fg)) = (server.foxglove_port, &a.foxglove) {
            let host = fg.rsplit_once(':').map_or(fg.as_str(), |(h, _)| h);
            eprintln!("foxglove: ws://{host}:{port} (Foxglove, or Lichtblick after 1.21)");
        }
        Ok(Self {
            bus,
            server,
            pace: a.pace.unwrap_or(1.0),
            linger: a.linger,
            wall_start: None,
            last_state: None,
            fault_sent: false,
        })
    }

    /// Do not pace this run (a real board keeps its own time).
    pub fn unpaced(&mut self) {
        self.pace = 0.0;
    }

    /// The bus, for events of the command's own.
    pub fn bus(&mut self) -> &mut LiveBus {
        &mut self.bus
    }

    /// One control period of a jump through the loop.
    pub fn period(&mut self, v: &PeriodView) {
        let r = &v.row;
        let t = r.t_s;
        if v.started {
            self.bus.event(Event::Jump {
                t_s: t,
                phase: "start".into(),
            });
        }
        if let Some(st) = v.state {
            self.state_and_fault(t, st, v.fault);
        }
        self.bus.sample(
            t,
            &[
                1e3 * v.p_ref_m,
                1e3 * r.p_m,
                1e3 * r.rod_height_m,
                -1e3 * r.depth_m,
                r.drive_command_n,
                r.spring_force_n,
            ],
        );
        self.keep_pace(t);
    }

    /// One step of a `rig` program: a lockstep period (samples: the commanded position when
    /// the host knows it, the plant when simulated, else the encoder; the drive's command)
    /// or a free-running board's status poll (its state and faults, and the samples it
    /// streamed since the previous poll: commanded position, encoder, drive force).
    pub fn program(&mut self, v: &ProgramView<'_>, p_cmd_m: Option<f64>, metres_per_count: f64) {
        let t = v.t_s;
        if v.started {
            self.bus.event(Event::Jump {
                t_s: t,
                phase: "start".into(),
            });
        }
        self.state_and_fault(t, v.state, v.fault);
        let nan = f64::NAN;
        for (ts, r) in v.board_samples {
            self.bus.sample(
                *ts,
                &[
                    1e3 * f64::from(r.commanded_position_m),
                    1e3 * r.encoder_count as f64 * metres_per_count,
                    nan,
                    nan,
                    f64::from(r.force_n),
                    nan,
                ],
            );
        }
        let Some(a) = v.actuator else {
            return;
        };
        let encoder_m = v.sensor.map_or(nan, |s| {
            f64::from(s.encoder_count as i32) * metres_per_count
        });
        let (p, rod, foot, spring) = v.plant.map_or((encoder_m, nan, nan, nan), |pl| {
            (pl.p_m, pl.rod_height_m, -pl.depth_m, pl.spring_force_n)
        });
        self.bus.sample(
            t,
            &[
                1e3 * p_cmd_m.unwrap_or(nan),
                1e3 * p,
                1e3 * rod,
                1e3 * foot,
                f64::from(a.force_n),
                spring,
            ],
        );
        self.keep_pace(t);
    }

    /// Events for a state (on change) and the first fault; names are formatted only then,
    /// not every control period.
    fn state_and_fault(
        &mut self,
        t: f64,
        state: sandjumper_core::RigState,
        fault: Option<sandjumper_core::fault::FaultCode>,
    ) {
        if self.last_state != Some(state) {
            if state == sandjumper_core::RigState::Done {
                self.bus.event(Event::Jump {
                    t_s: t,
                    phase: "end".into(),
                });
            }
            self.bus.event(Event::State {
                t_s: t,
                state: format!("{state:?}"),
            });
            self.last_state = Some(state);
        }
        if let Some(f) = fault
            && !self.fault_sent
        {
            self.fault_sent = true;
            self.bus.event(Event::Fault {
                t_s: t,
                fault: format!("{f:?}"),
            });
        }
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

    /// The run is over: say how, send what is left, keep the page up until Ctrl-C or the
    /// linger time; returns whether Ctrl-C ended it.
    pub fn finish(mut self, t_s: f64, outcome: String, ok: bool) -> bool {
        // The last samples first (waiting for the lock is free now), then the end.
        self.bus.flush_and_wait();
        self.bus.event(Event::RunEnded { t_s, outcome, ok });
        self.wait_on_the_page()
    }

    /// The run is over and the command ends now (the user stopped it): say how and send what
    /// is left, without keeping the page up.
    pub fn end_now(mut self, t_s: f64, outcome: String, ok: bool) {
        self.bus.flush_and_wait();
        self.bus.event(Event::RunEnded { t_s, outcome, ok });
    }

    /// Keep the page up until Ctrl-C or the linger; whether Ctrl-C ended it.
    #[cfg(feature = "live")]
    fn wait_on_the_page(&self) -> bool {
        // The page's state has the end before the command says so (the server reads the bus
        // every 25 ms).
        let asked = Instant::now();
        while self.server.snapshot().ended.is_none() && asked.elapsed() < Duration::from_secs(2) {
            std::thread::sleep(Duration::from_millis(5));
        }
        // Ctrl-C is caught before the page says it may be used: one sent right after the
        // message ends the wait, never the process.
        crate::interrupt::catch();
        match self.linger {
            Some(s) => eprintln!(
                "live view: the run has ended; the page stays up for {s} s (Ctrl-C ends it sooner)"
            ),
            None => eprintln!("live view: the run has ended; the page stays up until Ctrl-C"),
        }
        let until = self
            .linger
            .map(|s| Instant::now() + Duration::from_secs_f64(s));
        while until.is_none_or(|u| Instant::now() < u) {
            if crate::interrupt::interrupted() {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        crate::interrupt::interrupted()
    }

    #[cfg(not(feature = "live"))]
    fn wait_on_the_page(&self) -> bool {
        let _ = self.linger; // no page to keep up
        false
    }
}

/// End `live` (if any) with how the command ended: the summary line or the error.
pub fn finish(live: Option<LiveView>, result: &Result<(), CliError>) {
    if let Some(v) = live {
        let (outcome, ok) = match result {
            Ok(()) => ("completed".to_string(), true),
            Err(e) => (e.message.clone(), false),
        };
        v.finish(f64::NAN, outcome, ok);
    }
}
