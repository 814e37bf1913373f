//! `--stroke FILE`: a stroke file read and checked as the rig checks it before anything moves.

use std::path::Path;

use sandjumper_model::params::Params;
use sandjumper_output::CliError;
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable};

/// The stroke file `path`, checked by the rig's feasibility check for `params`' robot
/// ([`StrokeTable::check`]) with a table rate that divides the control rate. Every failure is
/// an input error naming the file (exit status 2).
pub fn checked_stroke(path: &Path, params: &Params) -> Result<StrokeTable, CliError> {
    let table = StrokeTable::read_csv(path).map_err(CliError::input)?;
    table
        .period_ticks(RigModelConfig::default().tick_hz)
        .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    table.check(&RigLimits::of(params)).map_err(|e| {
        CliError::input(format!(
            "{}: refused before anything ran: {e}",
            path.display()
        ))
    })?;
    Ok(table)
}
