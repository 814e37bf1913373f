//! `sandjumper rig status`: the controller's state, phase, latched fault and counters; a
//! face over [`sandjumper_rig::tool::status`].

use clap::Args;

use super::TargetArgs;
use crate::command::CliError;
use crate::command::progress::Bars;
use crate::live::{JUMP_CHANNELS, LiveView};
use crate::rig::face::watch as live_watch;
use sandjumper_output::Silent;
use sandjumper_rig::tool::status::{self as lib, WatchRequest, parse_watch_for};

/// `rig status`.
#[derive(Debug, Clone, Args)]
pub struct StatusArgs {
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Print one JSON object instead of text (watching: one line of JSON per change).
    #[arg(long)]
    pub json: bool,
    /// Keep polling the status (every 250 ms) and print a line whenever the state, phase or
    /// fault changes, until Ctrl-C (exit 0). `--live ADDR` watches on a page as well.
    #[arg(long)]
    pub watch: bool,
    /// Watch for this long, s, then stop (exit 0); implies --watch.
    #[arg(long, value_name = "S", value_parser = parse_watch_for)]
    pub watch_for: Option<f64>,
    /// The live view of the polled states and faults (implies --watch).
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
}

/// Run `rig status`.
pub fn run(a: &StatusArgs) -> Result<(), CliError> {
    if a.watch || a.watch_for.is_some() || a.live.live.is_some() {
        return watch(a);
    }
    let report = lib::status(&a.target.target(), &Silent)?;
    print!("{}", report.printed(a.json)?);
    Ok(())
}

/// `rig status --watch`: poll until Ctrl-C or `--watch-for`, a line per change, the live view
/// fed with every poll.
fn watch(a: &StatusArgs) -> Result<(), CliError> {
    let mut view = LiveView::start(&a.live, &JUMP_CHANNELS)?;
    crate::interrupt::catch();
    if let Some(v) = view.as_mut() {
        v.unpaced();
    }
    let request = WatchRequest {
        target: a.target.target(),
        watch_for_s: a.watch_for,
    };
    let session = lib::StatusWatch::open(&request)?;
    let result = session
        .run(
            &Bars::new(),
            &mut |line| line.printed(a.json).map(|text| println!("{text}")),
            live_watch(&mut view),
        )
        .map(|_| ())
        .map_err(CliError::from);
    crate::live::finish_as(view, &result, "stopped watching");
    result
}
