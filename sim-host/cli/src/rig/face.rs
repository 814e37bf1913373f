//! What `hil` and `rig` share as a face: errors to exit statuses, the live view as the
//! library's [`RunWatch`], and the end of every rig program's output.

use std::path::Path;

use crate::command::CliError;

use sandjumper_rig::hil::PeriodView;
use sandjumper_rig::hil::open::FaultEntry;
use sandjumper_rig::tool::session::ProgramView;
use sandjumper_rig::watch::RunWatch;

use crate::live::LiveView;

pub use crate::command::progress::cli_error;

impl RunWatch for LiveView {
    fn started(&mut self, title: &str, t_s: f64) {
        self.bus().event(sandjumper_live::Event::RunStarted {
            title: title.to_string(),
            t_s,
        });
    }
    fn period(&mut self, view: &PeriodView) {
        LiveView::period(self, view);
    }
    fn program(&mut self, view: &ProgramView<'_>, p_cmd_m: Option<f64>, metres_per_count: f64) {
        LiveView::program(self, view, p_cmd_m, metres_per_count);
    }
}

/// The live view as the watch a library run reports to.
pub fn watch(live: &mut Option<LiveView>) -> Option<&mut dyn RunWatch> {
    live.as_mut().map(|v| v as &mut dyn RunWatch)
}

/// The live view `live` asks for, started before anything else of the command (its URL
/// printed first; a bad address refused before a board or a virtual board is opened).
pub fn start_live(live: &crate::live::LiveArgs) -> Result<Option<LiveView>, CliError> {
    LiveView::start(live, &crate::live::JUMP_CHANNELS)
}

/// The end of every program once its folder `dir` is written: print `json` or `human`,
/// list the faults (unless JSON was asked for), say where the files went, and fail (exit 1)
/// with `check` when the controller did not complete the program cleanly.
pub fn conclude(
    (json, human): (String, String),
    faults: &[FaultEntry],
    dir: &Path,
    as_json: bool,
    check: Result<(), sandjumper_rig::RigError>,
) -> Result<(), CliError> {
    if as_json {
        println!("{json}");
    } else {
        print!("{human}");
        for f in faults {
            println!("  fault {} {} at tick {}", f.code, f.name, f.tick);
        }
    }
    eprintln!("wrote {}", dir.display());
    check.map_err(cli_error)
}
