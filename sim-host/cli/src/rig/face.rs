//! What `hil` and `rig` share as a face: the live view as the library's [`RunWatch`], and the
//! end of every rig program's output.

use crate::command::CliError;
use crate::live::LiveView;
use sandjumper_output::StagedDir;
use sandjumper_rig::tool::output::ProgramOutcome;
use sandjumper_rig::watch::RunWatch;

pub use crate::command::progress::cli_error;

/// The live view as the watch a library run reports to.
pub fn watch(live: &mut Option<LiveView>) -> Option<&mut dyn RunWatch> {
    live.as_mut().map(|v| &mut v.0 as &mut dyn RunWatch)
}

/// The live view `live` asks for, started before anything else of the command (its URL
/// printed first; a bad address refused before a board or a virtual board is opened).
pub fn start_live(live: &crate::live::LiveArgs) -> Result<Option<LiveView>, CliError> {
    LiveView::start(live, &crate::live::JUMP_CHANNELS)
}

/// The end of every program: write its folder into `staged`, print its JSON (`json`) or its
/// summary and faults, say where the files went, and fail (exit 1) when the controller did
/// not complete the program cleanly.
pub fn conclude(
    outcome: &dyn ProgramOutcome,
    staged: StagedDir,
    mcap: bool,
    json: bool,
) -> Result<(), CliError> {
    let dir = outcome.write(staged, mcap)?;
    print!("{}", outcome.printed(json)?);
    eprintln!("wrote {}", dir.display());
    Ok(outcome.check(&dir)?)
}
