//! `--stroke FILE`: a stroke file read and checked as the rig checks it before anything moves
//! ([`sandjumper_study::jump::checked_stroke`], with the command line's errors).

use std::path::Path;

use crate::command::CliError;
use sandjumper_model::params::Params;
use sandjumper_rig::stroke_table::StrokeTable;

/// The stroke file `path`, checked by the rig's feasibility check for `params`' robot. Every
/// failure is an input error naming the file (exit status 2).
pub fn checked_stroke(path: &Path, params: &Params) -> Result<StrokeTable, CliError> {
    sandjumper_study::jump::checked_stroke(path, params).map_err(crate::study::cli_error)
}
