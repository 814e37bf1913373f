//! `--live ADDR`: the live view of a run (`sandjumper_live`), as the commands use it: the bus
//! and its server started before the run (the URL printed first, on stderr), every control
//! period put on the bus and, for a simulated link, paced at real time (or `--pace`), then
//! the page kept up after the run until Ctrl-C or `--linger` passes.

use crate::command::CliError;
use sandjumper_live::LiveBus;
pub use sandjumper_rig::live::JUMP_CHANNELS;
use sandjumper_rig::live::{RigLiveView, parse_linger, parse_pace};

/// The options every `--live` command shares.
#[derive(Debug, Clone, clap::Args)]
pub struct LiveArgs {
    /// Serve a live view of the run at http://ADDR/ (PORT on 127.0.0.1, IP:PORT,
    /// localhost:PORT or `[::1]:PORT`; port 0: any free port), the same state at /state.json.
    /// The URL is printed first, on stderr. The page has no login: an address beyond this
    /// machine needs --live-public.
    #[arg(long, value_name = "ADDR")]
    pub live: Option<String>,
    /// With --live (and --foxglove), allow an address beyond this machine (0.0.0.0:PORT, a
    /// network interface's IP): anyone who can reach it can read the page.
    #[arg(long, requires = "live")]
    pub live_public: bool,
    /// With --live, run a simulated link at this multiple of real time (default 1; 0: as
    /// fast as it can).
    #[arg(long, value_name = "X", requires = "live", value_parser = parse_pace)]
    pub pace: Option<f64>,
    /// With --live, the same streams on a Foxglove WebSocket server at ADDR (the forms of
    /// --live; typed JSON channels for Foxglove or Lichtblick panels; builds with `--features
    /// foxglove`). Pages of other sites are refused (their Origin): docs/live.md says who
    /// can read it.
    #[arg(long, value_name = "ADDR", requires = "live")]
    pub foxglove: Option<String>,
    /// With --live, keep the page up this long after the run, s (default: until Ctrl-C at a
    /// terminal; 5 s when standard input is not one, so a script or a batch job ends).
    #[arg(long, value_name = "S", requires = "live", value_parser = parse_linger)]
    pub linger: Option<f64>,
}

/// How long the page stays up after the run when no terminal can send Ctrl-C, s.
pub const NO_TERMINAL_LINGER_S: f64 = 5.0;

/// A live view for one command: [`RigLiveView`] (its bus, server, pacing, and the rig runs
/// it shows).
pub struct LiveView(pub RigLiveView);

impl LiveArgs {
    /// The view these options ask for (`None` without `--live`).
    pub fn config(&self) -> Option<sandjumper_live::LiveConfig> {
        self.live.as_ref().map(|addr| sandjumper_live::LiveConfig {
            addr: addr.clone(),
            pace: self.pace.unwrap_or(1.0),
            foxglove: self.foxglove.clone(),
            linger: self.linger.or_else(|| {
                use std::io::IsTerminal;
                (!std::io::stdin().is_terminal()).then_some(NO_TERMINAL_LINGER_S)
            }),
            public: self.live_public,
        })
    }
}

impl LiveView {
    /// Start the view `a` asks for (`None` without `--live`); `channels` name the samples.
    pub fn start(a: &LiveArgs, channels: &[&str]) -> Result<Option<Self>, CliError> {
        let Some(config) = a.config() else {
            return Ok(None);
        };
        let view = sandjumper_live::LiveView::start(&config, channels).map_err(CliError::input)?;
        for line in view.addresses() {
            eprintln!("{line}");
        }
        Ok(Some(Self(RigLiveView::new(view))))
    }

    /// Do not pace this run (a real board keeps its own time).
    pub fn unpaced(&mut self) {
        self.0.view_mut().unpaced();
    }

    /// The bus, for events of the command's own.
    pub fn bus(&mut self) -> &mut LiveBus {
        self.0.bus()
    }

    /// The run is over: say how, send what is left, keep the page up until Ctrl-C or the
    /// linger time; returns whether Ctrl-C ended it.
    pub fn finish(mut self, t_s: f64, outcome: String, ok: bool) -> bool {
        self.0.end(t_s, outcome, ok);
        self.wait_on_the_page()
    }

    /// Keep the page up until Ctrl-C or the linger; whether Ctrl-C ended it.
    fn wait_on_the_page(&self) -> bool {
        // The page's state has the end before the command says so.
        self.0.view().wait_until_shown();
        // Ctrl-C is caught before the page says it may be used: one sent right after the
        // message ends the wait, never the process.
        crate::interrupt::catch();
        eprintln!("{}", self.0.view().lingering());
        self.0.view().linger_until(&crate::interrupt::interrupted)
    }
}

/// End `live` (if any) with how the command ended: `done` or the error; after Ctrl-C
/// (caught by a command that runs until stopped) the page closes with the command.
pub fn finish_as(live: Option<LiveView>, result: &Result<(), CliError>, done: &str) {
    if let Some(mut v) = live {
        let (outcome, ok) = match result {
            Ok(()) => (done.to_string(), true),
            Err(e) => (e.message.clone(), false),
        };
        if crate::interrupt::interrupted() {
            v.0.end(f64::NAN, outcome, ok);
        } else {
            v.finish(f64::NAN, outcome, ok);
        }
    }
}
