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

fn parse_watch_for(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 30.0 * 86_400.0 => Ok(v),
        _ => Err(format!(
            "`{s}` is not a watch time (allowed: more than 0 s, up to 30 days)"
        )),
    }
}

/// How often a watched status is polled.
pub const WATCH_INTERVAL: std::time::Duration = std::time::Duration::from_millis(250);

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
    ) + &estop_line(s)
        + &bed_line(s)
}

/// The board's own emergency-stop loop, where it has one.
fn estop_line(s: &Status) -> String {
    let e = &s.emergency_stop;
    if !e.fitted {
        return String::new();
    }
    let state = match (e.open, e.closed_since_reset) {
        (false, _) => "closed",
        (true, false) => {
            "OPEN since reset (Arm refused until it reads closed: wire the stop, or a jumper plug on its connector)"
        }
        (true, true) => "OPEN (pressed, a wire broken or its connector out)",
    };
    format!("  emergency stop     loop {state}\n")
}

/// The bed apparatus: present with its inputs, or absent, which a user must know (its limit
/// switches are not read then; on a board with an emergency-stop loop of its own, the stop is).
fn bed_line(s: &Status) -> String {
    let b = &s.bed;
    if !b.present {
        return if s.emergency_stop.fitted {
            "  bed apparatus      absent: its limit switches are not read, and nothing of it can \
             be switched on\n"
        } else {
            "  bed apparatus      absent: its limit switches and emergency stop input are not \
             read, and nothing of it can be switched on\n"
        }
        .to_string();
    }
    format!(
        "  bed apparatus      {}, lift {}{}, blower {} V, shaker {}{}\n",
        match (s.emergency_stop.fitted, b.inputs.emergency_stop) {
            (true, true) => "harness LOST (a stop)",
            (true, false) => "harness connected",
            (false, true) => "e-stop PRESSED",
            (false, false) => "e-stop released",
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
    if a.watch || a.watch_for.is_some() || a.live.live.is_some() {
        return watch(a);
    }
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

/// The JSON line of one change while watching.
#[derive(Debug, Serialize)]
struct WatchLine<'a> {
    /// The board's time: its tick since start-up over the control rate, s.
    t_s: f64,
    state: String,
    phase: String,
    fault: Option<&'a str>,
    fault_code: Option<u8>,
}

/// `rig status --watch`: poll until Ctrl-C or `--watch-for`, a line per change, the live view
/// fed with every poll.
fn watch(a: &StatusArgs) -> Result<(), CliError> {
    let mut view = crate::live::LiveView::start(&a.live, &crate::live::JUMP_CHANNELS)?;
    crate::interrupt::catch();
    let config = RigModelConfig::default();
    let mut link = a.target.open(&config)?;
    let name = link.name();
    let hz = f64::from(config.tick_hz);
    if let Some(v) = view.as_mut() {
        v.unpaced();
        v.bus().event(sandjumper_live::Event::RunStarted {
            title: format!("rig status on {name}"),
            t_s: 0.0,
        });
    }
    let began = std::time::Instant::now();
    let mut last: Option<(
        sandjumper_core::RigState,
        sandjumper_core::Phase,
        Option<u8>,
    )> = None;
    let mut polls = 0u64;
    let result = loop {
        let status = match query_status(link.as_mut()) {
            Ok(s) => s,
            // Ctrl-C in a terminal also stops a simulated board's process (same process
            // group): a query that fails then is the end of the watch, not an error.
            Err(_) if crate::interrupt::interrupted() => break Ok(()),
            Err(e) => break Err(link_failed(&name, "status query", e)),
        };
        polls += 1;
        let t = f64::from(status.tick) / hz;
        // What the board streams while it is watched (its samples, every tick) is taken at
        // every poll: shown on the page on its own ticks, never piling up in the link.
        let streamed: Vec<(f64, sandjumper_core::SampleRecord)> = link
            .take_samples()
            .into_iter()
            .map(|r| (f64::from(r.tick) / hz, r))
            .collect();
        let _ = link.take_faults();
        if let Some(v) = view.as_mut() {
            v.program(
                &super::session::ProgramView {
                    t_s: t,
                    state: status.state,
                    fault: status.fault,
                    actuator: None,
                    sensor: None,
                    plant: None,
                    started: false,
                    board_samples: &streamed,
                },
                None,
                config.metres_per_count,
            );
        }
        let key = (status.state, status.phase, status.fault.map(|f| f.code()));
        if last != Some(key) {
            last = Some(key);
            if a.json {
                let line = WatchLine {
                    t_s: t,
                    state: format!("{:?}", status.state),
                    phase: format!("{:?}", status.phase),
                    fault: status.fault.map(|f| f.name()),
                    fault_code: status.fault.map(|f| f.code()),
                };
                let json = serde_json::to_string(&line).map_err(|e| {
                    CliError::internal(format!("cannot encode the status as JSON: {e}"))
                })?;
                println!("{json}");
            } else {
                println!(
                    "t {t:10.3} s  state {:?} (phase {:?})  fault {}",
                    status.state,
                    status.phase,
                    status.fault.map_or("none".to_string(), |f| format!(
                        "{} {}",
                        f.code(),
                        f.name()
                    ))
                );
            }
        }
        let done = crate::interrupt::interrupted()
            || a.watch_for
                .is_some_and(|s| began.elapsed().as_secs_f64() >= s);
        if done {
            break Ok(());
        }
        std::thread::sleep(WATCH_INTERVAL);
        if crate::interrupt::interrupted() {
            break Ok(());
        }
    };
    let closed = link
        .finish()
        .map_err(|e| link_failed(&name, "closing the session", e));
    let result = result.and(closed.map(|_| ()));
    eprintln!(
        "watched {name} for {:.1} s ({polls} polls)",
        began.elapsed().as_secs_f64()
    );
    if let Some(v) = view {
        let (outcome, ok) = match &result {
            Ok(()) => ("stopped watching".to_string(), true),
            Err(e) => (e.message.clone(), false),
        };
        // Ctrl-C has ended the watch: the page closes with the command.
        if crate::interrupt::interrupted() {
            v.end_now(f64::NAN, outcome, ok);
        } else {
            v.finish(f64::NAN, outcome, ok);
        }
    }
    result
}
