//! `sandjumper rig status`: the controller's state, phase, latched fault and counters.

use clap::Args;
use serde::Serialize;

use super::session::query_status;
use super::{TargetArgs, link_failed};
use sandjumper_core::Status;
use sandjumper_output::CliError;
use sandjumper_rig::hil::rig_model::RigModelConfig;

/// `rig status`.
#[derive(Debug, Clone, Args)]
pub struct StatusArgs {
    /// The board (or a simulated controller).
    #[command(flatten)]
    pub target: TargetArgs,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The JSON of `rig status --json`.
#[derive(Debug, Serialize)]
pub struct StatusReport {
    /// The link.
    pub link: String,
    /// The controller's status.
    pub status: Status,
    /// The latched fault's stable code and name, if any.
    pub fault_code: Option<u8>,
    /// Name of the latched fault.
    pub fault_name: Option<&'static str>,
}

/// Human-readable status.
pub fn describe(s: &Status) -> String {
    let c = &s.counters;
    let fault = match s.fault {
        Some(f) => format!(
            "{} {} (latched at tick {})",
            f.code(),
            f.name(),
            s.fault_tick
        ),
        None => "none".into(),
    };
    let replay = match s.replay_checksum {
        Some(c) => format!("{c:#010x}"),
        None => "none".into(),
    };
    format!(
        "  state              {:?} (phase {:?})\n  fault              {fault}\n  \
         tick               {} (run tick {})\n  configured         {}\n  \
         replay table       {replay}\n  camera frames      {}\n  \
         samples            {} produced, {} dropped\n  \
         frames             {} ok, {} rejected, {} lockstep lost\n  \
         commands rejected  {}\n  faults after latch {}\n  max tick           {} cycles\n  \
         ticks missed       {}\n  frames dropped     {}\n  \
         last reset         {:?}{}\n  \
         drive calibration  zero code {}, {} codes/N\n",
        s.state,
        s.phase,
        s.tick,
        s.run_tick,
        s.configured,
        s.camera_frames,
        c.samples_produced,
        c.samples_dropped,
        c.frames_ok,
        c.frames_rejected,
        c.lockstep_frames_lost,
        c.commands_rejected,
        c.faults_after_latch,
        c.max_tick_cycles,
        c.ticks_missed,
        c.frames_dropped,
        s.reset_cause,
        if s.reset_acknowledged {
            ""
        } else {
            " (Arm refused until `rig acknowledge-reset`)"
        },
        s.drive_calibration.zero_code,
        s.drive_calibration.codes_per_newton,
    ) + &bed_line(s)
}

/// The bed apparatus: present with its inputs, or absent, which a user must know (its
/// emergency stop input is not monitored then).
fn bed_line(s: &Status) -> String {
    let b = &s.bed;
    if !b.present {
        return "  bed apparatus      absent: its limit switches and emergency stop input are not \
                read, and nothing of it can be switched on\n"
            .to_string();
    }
    format!(
        "  bed apparatus      e-stop {}, lift {}{}, blower {} V, shaker {}{}\n",
        if b.inputs.emergency_stop {
            "PRESSED"
        } else {
            "released"
        },
        if b.inputs.lift_down_limit {
            "down"
        } else if b.inputs.lift_up_limit {
            "up"
        } else {
            "between limits"
        },
        if b.outputs.lift_enable {
            " (moving)"
        } else {
            ""
        },
        b.outputs.blower_v,
        b.outputs.shaker_duty,
        if b.tripped {
            ", TRIPPED (clear the fault)"
        } else {
            ""
        },
    )
}

/// Run `rig status`.
pub fn run(a: &StatusArgs) -> Result<(), CliError> {
    let mut link = a.target.open(&RigModelConfig::default())?;
    let name = link.name();
    let status = query_status(link.as_mut()).map_err(|e| link_failed(&name, "status query", e))?;
    link.finish()
        .map_err(|e| link_failed(&name, "closing the session", e))?;
    if a.json {
        let report = StatusReport {
            link: name,
            status,
            fault_code: status.fault.map(|f| f.code()),
            fault_name: status.fault.map(|f| f.name()),
        };
        let json = serde_json::to_string_pretty(&report)
            .map_err(|e| CliError::internal(format!("cannot encode the status as JSON: {e}")))?;
        println!("{json}");
    } else {
        print!("controller on {name}\n{}", describe(&status));
    }
    Ok(())
}
