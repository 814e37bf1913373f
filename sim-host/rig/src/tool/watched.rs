//! A program run with a [`RunWatch`] shown every step, and the end every program shares.

use std::path::Path;

use super::output::FaultEntry;
use super::session::{Fixture, Program, ProgramView, RunRecord, run_program, run_program_observed};
use crate::error::RigError;
use crate::protocol::link::{LinkError, RigLink};
use crate::watch::RunWatch;

/// Run `program` through `link` (`fixture`: the rig the host plays in lockstep, if it does),
/// `watch` (if any) told `rig WHAT on LINK` and then every step; `p_cmd` gives the commanded
/// motor position at a rig time, when the host knows it.
pub fn run_watched(
    watch: Option<&mut dyn RunWatch>,
    what: &str,
    link: &mut dyn RigLink,
    fixture: Option<&mut dyn Fixture>,
    program: &Program,
    p_cmd: Option<&dyn Fn(f64) -> f64>,
    metres_per_count: f64,
) -> Result<RunRecord, LinkError> {
    let Some(w) = watch else {
        return run_program(link, fixture, program);
    };
    w.started(&format!("rig {what} on {}", link.name()), 0.0);
    let mut step = |v: &ProgramView<'_>| {
        w.program(v, p_cmd.map(|f| f(v.t_s)), metres_per_count);
    };
    run_program_observed(link, fixture, program, Some(&mut step))
}

/// The end of every program once its folder `dir` is written: an error (exit status 1) when
/// the controller did not complete the program `what` cleanly (a fault, or no `Done`).
pub fn completed_cleanly(
    what: &str,
    completed: bool,
    faults: &[FaultEntry],
    dir: &Path,
) -> Result<(), RigError> {
    if !faults.is_empty() || !completed {
        return Err(RigError::NotCompleted {
            what: what.to_string(),
            summary: dir.join("summary.json"),
        });
    }
    Ok(())
}
