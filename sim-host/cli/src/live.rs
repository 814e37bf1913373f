//! `--live ADDR`: the live view of a run (`sandjumper_live`), as the commands use it: the bus
//! and its server started before the run (the URL printed first, on stderr), every control
//! period put on the bus and, for a simulated link, paced at real time (or `--pace`), then
//! the page kept up after the run until Ctrl-C or `--linger` passes.

use crate::command::CliError;
use sandjumper_live::{Event, LiveBus};
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

/// A live view for one command: [`sandjumper_live::LiveView`] (its bus, server and pacing)
/// and the rig's state as last shown.
pub struct LiveView {
    view: sandjumper_live::LiveView,
    last_state: Option<sandjumper_core::RigState>,
    fault_sent: bool,
}

impl LiveArgs {
    /// The view these options ask for (`None` without `--live`).
    pub fn config(&self) -> Option<sandjumper_live::LiveConfig> {
        self.live.as_ref().map(|addr| sandjumper_live::LiveConfig {
            addr: addr.clone(),
            pace: self.pace.unwrap_or(1.0),
            foxglove: self.foxglove.clone(),
            linger: self.linger,
        })
    }
}

impl LiveView {
    /// Start the view `a` asks for (`None` without `--live`); `channels` name the samples.
    pub fn start(a: &LiveArgs, channels: &[&str]) -> Result<Option<Self>, CliError> {
        let Some(config) = a.config() else {
            return Ok(None);
        };
        #[cfg(not(feature = "live"))]
        {
            let _ = channels;
            Err(CliError::input(format!(
                "--live {}: this build has no live view (built with --no-default-features; build sandjumper-cli with its default features)",
                config.addr
            )))
        }
        #[cfg(feature = "live")]
        {
            let view =
                sandjumper_live::LiveView::start(&config, channels).map_err(CliError::input)?;
            for line in view.addresses() {
                eprintln!("{line}");
            }
            Ok(Some(Self {
                view,
                last_state: None,
                fault_sent: false,
            }))
        }
    }

    /// Do not pace this run (a real board keeps its own time).
    pub fn unpaced(&mut self) {
        self.view.unpaced();
    }

    /// The bus, for events of the command's own.
    pub fn bus(&mut self) -> &mut LiveBus {
        self.view.bus()
    }

    /// One control period of a jump through the loop.
    pub fn period(&mut self, v: &PeriodView) {
        let r = &v.row;
        let t = r.t_s;
        if v.started {
            self.bus().event(Event::Jump {
                t_s: t,
                phase: "start".into(),
            });
        }
        if let Some(st) = v.state {
            self.state_and_fault(t, st, v.fault);
        }
        self.bus().sample(
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
            self.bus().event(Event::Jump {
                t_s: t,
                phase: "start".into(),
            });
        }
        self.state_and_fault(t, v.state, v.fault);
        let nan = f64::NAN;
        for (ts, r) in v.board_samples {
            self.bus().sample(
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
        self.bus().sample(
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
                self.bus().event(Event::Jump {
                    t_s: t,
                    phase: "end".into(),
                });
            }
            self.bus().event(Event::State {
                t_s: t,
                state: format!("{state:?}"),
            });
            self.last_state = Some(state);
        }
        if let Some(f) = fault
            && !self.fault_sent
        {
            self.fault_sent = true;
            self.bus().event(Event::Fault {
                t_s: t,
                fault: format!("{f:?}"),
            });
        }
    }

    /// Sleep so that rig time `t_s` is not ahead of the wall clock times the pace.
    pub fn keep_pace(&mut self, t_s: f64) {
        self.view.keep_pace(t_s);
    }

    /// The run is over: say how, send what is left, keep the page up until Ctrl-C or the
    /// linger time; returns whether Ctrl-C ended it.
    pub fn finish(mut self, t_s: f64, outcome: String, ok: bool) -> bool {
        self.view.end(t_s, outcome, ok);
        self.wait_on_the_page()
    }

    /// The run is over and the command ends now (the user stopped it): say how and send what
    /// is left, without keeping the page up.
    pub fn end_now(mut self, t_s: f64, outcome: String, ok: bool) {
        self.view.end(t_s, outcome, ok);
    }

    /// Keep the page up until Ctrl-C or the linger; whether Ctrl-C ended it.
    #[cfg(feature = "live")]
    fn wait_on_the_page(&self) -> bool {
        // The page's state has the end before the command says so.
        self.view.wait_until_shown();
        // Ctrl-C is caught before the page says it may be used: one sent right after the
        // message ends the wait, never the process.
        crate::interrupt::catch();
        match self.view.linger() {
            Some(s) => eprintln!(
                "live view: the run has ended; the page stays up for {s} s (Ctrl-C ends it sooner)"
            ),
            None => eprintln!("live view: the run has ended; the page stays up until Ctrl-C"),
        }
        self.view.linger_until(&crate::interrupt::interrupted)
    }

    #[cfg(not(feature = "live"))]
    fn wait_on_the_page(&self) -> bool {
        false // no page to keep up
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
