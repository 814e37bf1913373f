//! The best strokes re-run force-driven through the real controller: the stroke table is
//! uploaded into the controller's replay table and replayed in lockstep against the
//! force-driven plant (`hil --stroke`), in this process (`sil`) or as the firmware under QEMU
//! (`pil`, when its ELF and QEMU are there). A stroke the controller cannot follow shows here:
//! a lower height, tracking faults, a saturated drive.

use std::path::Path;

use serde::Serialize;

use sandjumper_model::params::{ModelName, Params};
use sandjumper_output::Silent;
use sandjumper_rig::hil::open::{LinkArg, open_link};
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::hil::run::{HilSpec, run_jump};
use sandjumper_rig::stroke_table::StrokeTable;
use sandjumper_rig::tool::replay::{ReplayOutcome, ReplayRequest, run as replay_run};
use sandjumper_rig::tool::target::Target;

use crate::evaluate::{Objective, Problem, SearchLimits};
use crate::family::MoveChain;
use crate::request::OptimizeRequest;

/// One stroke run through one link.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LinkRun {
    /// `sil` or `pil`.
    pub link: String,
    /// Why it did not run (the link is not available here), if so.
    pub skipped: Option<String>,
    /// Highest rod apex, m.
    pub jump_height_m: Option<f64>,
    /// Highest apex after the push-off begins, m.
    pub final_jump_height_m: Option<f64>,
    /// Highest rise of the robot's centre of mass, m (None where the link does not report it:
    /// the F407 board's replay).
    pub com_rise_m: Option<f64>,
    /// Most the spring was compressed below its free length, m (None where the link does not
    /// report it).
    pub max_spring_compression_m: Option<f64>,
    /// Faults the controller latched, by name.
    pub faults: Vec<String>,
    /// Largest |p_cmd - p| until the drive first saturated, m.
    pub tracking_error_max_m: Option<f64>,
    /// Periods the drive command sat at the peak force.
    pub saturated_periods: Option<usize>,
    /// The foot left the ground.
    pub lifted_off: bool,
    /// Largest |F_m p'| of the force-driven plant, W.
    pub peak_power_w: Option<f64>,
    /// Positive work of the motor, J.
    pub work_j: Option<f64>,
}

impl LinkRun {
    /// The objective's value of this run (None: skipped, or the controller latched a fault:
    /// a stroke it cannot follow within its tracking bound and stroke limit is worth
    /// nothing). A drive that saturates for a few periods (the Catmull-Rom feedforward at an
    /// acceleration step) is reported in `saturated_periods`, not disqualified: the paper's
    /// own fast strokes do it and track within a millimetre. `released_j` is the potential
    /// energy the stroke releases by ending lower than it starts (charged to the energy
    /// objective). A run past the robot's physical limits (`limits`: the rig's frame, the
    /// spring's compression) is worth nothing, as its kinematic jump would be.
    pub fn value(
        &self,
        objective: Objective,
        limits: &SearchLimits,
        released_j: f64,
    ) -> Option<f64> {
        if self.skipped.is_some() || !self.faults.is_empty() {
            return None;
        }
        let h = self.jump_height_m?;
        if h > limits.max_rise_m
            || self
                .max_spring_compression_m
                .is_some_and(|c| c > limits.max_spring_compression_m)
        {
            return None;
        }
        if objective.is_ratio() && (h < limits.min_height_m || !self.lifted_off) {
            return None;
        }
        let v = match objective {
            Objective::Height => h,
            Objective::FinalHeight => self.final_jump_height_m?,
            Objective::ComRise => self.com_rise_m?,
            Objective::HeightPerPeakPower => h / self.peak_power_w?,
            Objective::HeightPerEnergy => h / (self.work_j? + released_j),
        };
        v.is_finite().then_some(v)
    }

    /// A run through `link` that did not happen, and why.
    pub fn skipped(link: &LinkArg, why: String) -> Self {
        Self {
            link: link.to_string(),
            skipped: Some(why),
            jump_height_m: None,
            final_jump_height_m: None,
            com_rise_m: None,
            max_spring_compression_m: None,
            faults: Vec::new(),
            tracking_error_max_m: None,
            saturated_periods: None,
            lifted_off: false,
            peak_power_w: None,
            work_j: None,
        }
    }
}

/// `chain` through sil on every bed of `problem`: the nominal bed's run and the objective's
/// worst value over the beds (None when the run on any bed faulted or broke a limit).
pub fn through_sil_on_beds(
    problem: &Problem,
    chain: &MoveChain,
    firmware: &Path,
) -> Result<(LinkRun, Option<f64>), String> {
    let table = problem.table(chain);
    let released = problem.released_energy_j(chain);
    let value = |r: &LinkRun| r.value(problem.objective, &problem.limits, released);
    let nominal = run_through(
        &LinkArg::Sil,
        &problem.params,
        problem.model,
        &table,
        firmware,
    )?;
    let mut worst = value(&nominal);
    for bed in &problem.beds {
        if worst.is_none() {
            break;
        }
        let run = run_through(&LinkArg::Sil, bed, problem.model, &table, firmware)?;
        worst = match (worst, value(&run)) {
            (Some(w), Some(v)) => Some(w.min(v)),
            _ => None,
        };
    }
    Ok((nominal, worst))
}

/// Run `table` through `link` on `model` with `params` (the rig's gains, as `hil` runs).
/// `firmware` is the emulated board's ELF for `pil`. A link that cannot open is reported as
/// skipped, with the reason; a run that fails is an error.
pub fn run_through(
    link: &LinkArg,
    params: &Params,
    model: ModelName,
    table: &StrokeTable,
    firmware: &Path,
) -> Result<LinkRun, String> {
    let model_config = RigModelConfig::default();
    let mut l = match open_link(link, &model_config, firmware) {
        Ok(l) => l,
        Err(e) => return Ok(LinkRun::skipped(link, e.to_string())),
    };
    let mut spec = HilSpec::new(
        sandjumper_core::trajectory::JumpKind::Single,
        0.0,
        0.0,
        model,
    );
    spec.gains = HilSpec::rig_gains(&params.robot);
    spec.camera_fps = 0;
    spec.stroke = Some(table.clone());
    let o = run_jump(params, &spec, model_config, l.as_mut())
        .map_err(|e| format!("the run through {link} failed: {e}"))?;
    let peak = params.drive.peak_force_n * (1.0 - 1e-6);
    Ok(LinkRun {
        link: link.to_string(),
        skipped: None,
        jump_height_m: Some(o.summary.jump_height_m),
        final_jump_height_m: Some(o.summary.final_jump_height_m),
        com_rise_m: Some(o.summary.com_rise_m),
        max_spring_compression_m: Some(o.summary.max_spring_compression_m),
        faults: o.faults.iter().map(|f| f.code.name().to_string()).collect(),
        tracking_error_max_m: Some(o.tracking_error_until_saturation().0),
        saturated_periods: Some(
            o.trace
                .iter()
                .filter(|r| r.drive_command_n.abs() >= peak)
                .count(),
        ),
        lifted_off: o.summary.liftoff_time_s.is_some(),
        peak_power_w: Some(o.summary.peak_motor_power_w),
        work_j: Some(o.summary.motor_work_j),
    })
}

/// The F407 release binary on the virtual board, as [`crate::run`] ([`VirtualBoard`]) and
/// [`crate::run_with_board`] reach it:
/// `table` replayed there (free-running on the board's own tick, not in lockstep) for the
/// request's model and parameters, its run as a [`LinkRun`] (skipped, with the reason, when
/// the board or the binary is not there).
pub trait StrokeOnBoard {
    /// Replay `table` on the board for `request`.
    fn replay(&self, request: &OptimizeRequest, table: &StrokeTable) -> LinkRun;
}

impl<F: Fn(&OptimizeRequest, &StrokeTable) -> LinkRun> StrokeOnBoard for F {
    fn replay(&self, request: &OptimizeRequest, table: &StrokeTable) -> LinkRun {
        self(request, table)
    }
}

/// The virtual F407 board ([`crate::run`]'s): `table` replayed on the F407 release binary as
/// `rig replay --stroke --link f407` replays it (the board runs free on its own tick, not in
/// lockstep), for the request's model and parameters. The board's program and the firmware
/// are the rig's defaults, relative to the current directory
/// (sim-host/virtual-f407/target/release/virtual-f407 and the F407 release ELF). Skipped, with
/// the reason, when the board or the binary is not there, or the replay fails.
#[derive(Clone, Copy, Debug, Default)]
pub struct VirtualBoard;

impl StrokeOnBoard for VirtualBoard {
    fn replay(&self, request: &OptimizeRequest, table: &StrokeTable) -> LinkRun {
        let replay = ReplayRequest {
            model: request.model,
            params: request.params.clone(),
            ..ReplayRequest::stroke(Target::on(LinkArg::F407), table.clone(), "stroke.csv")
        };
        match replay_run(&replay, &Silent) {
            Ok(o) => board_run(&o),
            Err(e) => LinkRun::skipped(&LinkArg::F407, e.to_string()),
        }
    }
}

/// A replay on the virtual board as a [`LinkRun`].
fn board_run(o: &ReplayOutcome) -> LinkRun {
    LinkRun {
        link: LinkArg::F407.to_string(),
        skipped: None,
        jump_height_m: o.simulated_jump_height_m,
        final_jump_height_m: None,
        com_rise_m: None,
        max_spring_compression_m: None,
        faults: o.fault_names().into_iter().map(str::to_string).collect(),
        tracking_error_max_m: Some(o.tracking_error_max_m),
        saturated_periods: None,
        lifted_off: o.simulated_jump_height_m.is_some_and(|h| h > 0.0),
        peak_power_w: None,
        work_j: None,
    }
}

/// No board: every F407 run is skipped, saying so (a run given it with
/// [`crate::run_with_board`], as tests do).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoBoard;

impl StrokeOnBoard for NoBoard {
    fn replay(&self, _: &OptimizeRequest, _: &StrokeTable) -> LinkRun {
        LinkRun::skipped(
            &LinkArg::F407,
            "no virtual board was given to this run (sandjumper_optimize::NoBoard)".into(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sandjumper_model::Params;
    use sandjumper_rig::stroke_table::RigLimits;

    /// A run through the controller past the robot's physical limits is worth nothing, as its
    /// kinematic jump would be: the rig's frame and the spring's compression.
    #[test]
    fn a_run_past_the_frame_or_the_springs_limit_is_worth_nothing() {
        let limits = SearchLimits {
            rig: RigLimits::of(&Params::default()),
            table_rate_hz: 1000,
            max_duration_s: 2.0,
            min_height_m: 0.02,
            max_spring_compression_m: 0.05,
            max_rise_m: 0.3,
        };
        let run = |h: f64, c: f64| LinkRun {
            jump_height_m: Some(h),
            max_spring_compression_m: Some(c),
            lifted_off: true,
            skipped: None,
            ..LinkRun::skipped(&LinkArg::Sil, String::new())
        };
        assert_eq!(
            run(0.2, 0.04).value(Objective::Height, &limits, 0.0),
            Some(0.2)
        );
        assert_eq!(run(0.31, 0.04).value(Objective::Height, &limits, 0.0), None);
        assert_eq!(run(0.2, 0.06).value(Objective::Height, &limits, 0.0), None);
    }
}
