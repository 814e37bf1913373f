//! What `hil` and `rig` share as a face: the live view as the library's [`RunWatch`], and the
//! end of every rig program's output.

use crate::command::CliError;
use std::path::Path;

use crate::command::progress::Bars;
use crate::live::{JUMP_CHANNELS, LiveArgs, LiveView};
use sandjumper_output::StagedDir;
use sandjumper_rig::tool::output::{ProgramOutcome, ProgramRequest};
use sandjumper_rig::watch::RunWatch;

/// The live view as the watch a library run reports to.
pub fn watch(live: &mut Option<LiveView>) -> Option<&mut dyn RunWatch> {
    live.as_mut().map(|v| &mut v.0 as &mut dyn RunWatch)
}

/// Run a rig program's `request` into `out` (`mcap`: also acquisition.mcap; `json`: print
/// JSON) with the live view `live` asks for, started once the request and the output are
/// checked (its URL printed first; a bad address refused before a board or a virtual board is
/// opened); a failure after that ends the page with it, kept for the linger.
pub fn run_program<R: ProgramRequest>(
    request: &R,
    live: &LiveArgs,
    (out, mcap, json): (&Path, bool, bool),
) -> Result<(), CliError> {
    let checked = request.check()?;
    // Bad input (an output that cannot be written) is refused before the page starts.
    let staged = StagedDir::create(out)?;
    let mut view = LiveView::start(live, &JUMP_CHANNELS)?;
    // Whatever fails once the page is up is shown on it, and the page kept for the linger.
    let result = request
        .run_checked(checked, &Bars::new(), watch(&mut view))
        .map_err(CliError::from)
        .and_then(|outcome| conclude(&outcome, Some(staged), (mcap, json), false));
    crate::live::finish_as(view, &result, "completed");
    result
}

/// The end of every program: write its folder into `staged` (if any), print its JSON
/// (`json`) or its summary and faults, say where the files went (before the printing with
/// `wrote_first`, as `hil` on a lockstep link always has; after it, as the rig tool does), and
/// fail (exit 1) when the controller did not complete the program cleanly.
pub fn conclude(
    outcome: &dyn ProgramOutcome,
    staged: Option<StagedDir>,
    (mcap, json): (bool, bool),
    wrote_first: bool,
) -> Result<(), CliError> {
    let dir = staged.map(|s| outcome.write(s, mcap)).transpose()?;
    let wrote = || {
        if let Some(dir) = &dir {
            eprintln!("wrote {}", dir.display());
        }
    };
    if wrote_first {
        wrote();
    }
    print!("{}", outcome.printed(json)?);
    if !wrote_first {
        wrote();
    }
    let Some(dir) = dir else { return Ok(()) };
    Ok(outcome.check(&dir)?)
}
