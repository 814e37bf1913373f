//! `rig status`: the controller's state, phase, latched fault and counters, once
//! ([`status`]) or watched until the caller stops it ([`watch`]).

use std::fmt;
use std::time::{Duration, Instant};

use serde::Serialize;

use sandjumper_core::{Phase, RigState, SampleRecord, Status};
use sandjumper_output::Progress;
use sandjumper_output::parse::number_within;

use super::session::ProgramView;
use super::target::Target;
use crate::error::RigError;
use crate::hil::rig_model::RigModelConfig;
use crate::protocol::query_status;
use crate::watch::RunWatch;

/// How often a watched status is polled.
pub const WATCH_INTERVAL: Duration = Duration::from_millis(250);

/// The JSON of `rig status --json`; its [`fmt::Display`] is the text `rig status` prints.
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

impl fmt::Display for StatusReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "controller on {}\n{}", self.link, describe(&self.status))
    }
}

/// Ask the controller of `target` for its status once.
pub fn status(target: &Target, _progress: &dyn Progress) -> Result<StatusReport, RigError> {
    let mut link = target.open(&RigModelConfig::default())?;
    let name = link.name();
    let status =
        query_status(link.as_mut()).map_err(|e| RigError::link(&name, "status query", e))?;
    link.finish()
        .map_err(|e| RigError::link(&name, "closing the session", e))?;
    Ok(StatusReport {
        link: name,
        status,
        fault_code: status.fault.map(|f| f.code()),
        fault_name: status.fault.map(|f| f.name()),
    })
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

/// One change of state, phase or fault while watching: its JSON is one line of `rig status
/// --watch --json`, its [`fmt::Display`] the text line.
#[derive(Debug, Serialize)]
pub struct WatchLine {
    /// The board's time: its tick since start-up over the control rate, s.
    pub t_s: f64,
    /// The controller's state (`Idle`, `Armed`, ...).
    pub state: String,
    /// Its phase.
    pub phase: String,
    /// The latched fault's name.
    pub fault: Option<&'static str>,
    /// The latched fault's stable code.
    pub fault_code: Option<u8>,
}

impl fmt::Display for WatchLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "t {:10.3} s  state {} (phase {})  fault {}",
            self.t_s,
            self.state,
            self.phase,
            match (self.fault_code, self.fault) {
                (Some(c), Some(n)) => format!("{c} {n}"),
                _ => "none".to_string(),
            }
        )
    }
}

/// `rig status --watch`: how long to watch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WatchRequest {
    /// The controller.
    pub target: Target,
    /// Stop after this long, s (`None`: until the caller's progress says cancelled).
    pub watch_for_s: Option<f64>,
}

/// What a watch did.
#[derive(Clone, Debug, PartialEq)]
pub struct Watched {
    /// The link's name.
    pub link: String,
    /// Wall time watched, s.
    pub watched_s: f64,
    /// Status polls.
    pub polls: u64,
}

/// A watch whose session is open ([`StatusWatch::open`]): a link that cannot be opened is
/// refused before the watch begins.
pub struct StatusWatch {
    link: Box<dyn crate::protocol::link::RigLink>,
    watch_for_s: Option<f64>,
}

impl StatusWatch {
    /// Open the session of `request`'s target.
    pub fn open(request: &WatchRequest) -> Result<Self, RigError> {
        Ok(Self {
            link: request.target.open(&RigModelConfig::default())?,
            watch_for_s: request.watch_for_s,
        })
    }

    /// Run the watch (see [`watch`]).
    pub fn run(
        self,
        progress: &dyn Progress,
        on_change: &mut dyn FnMut(&WatchLine) -> Result<(), RigError>,
        watch: Option<&mut dyn RunWatch>,
    ) -> Result<Watched, RigError> {
        poll(self, progress, on_change, watch)
    }
}

/// Poll the status every [`WATCH_INTERVAL`] until `progress.cancelled()` or the request's
/// time is up; `on_change` gets a line whenever the state, phase or fault changes, `watch` every
/// poll (its time, the board's tick). Says "watched LINK for S s (N polls)" through
/// `progress.note` at the end, failed or not.
pub fn watch(
    request: &WatchRequest,
    progress: &dyn Progress,
    on_change: &mut dyn FnMut(&WatchLine) -> Result<(), RigError>,
    watch: Option<&mut dyn RunWatch>,
) -> Result<Watched, RigError> {
    StatusWatch::open(request)?.run(progress, on_change, watch)
}

fn poll(
    session: StatusWatch,
    progress: &dyn Progress,
    on_change: &mut dyn FnMut(&WatchLine) -> Result<(), RigError>,
    mut watch: Option<&mut dyn RunWatch>,
) -> Result<Watched, RigError> {
    let config = RigModelConfig::default();
    let StatusWatch {
        mut link,
        watch_for_s,
    } = session;
    let name = link.name();
    let hz = f64::from(config.tick_hz);
    if let Some(w) = watch.as_deref_mut() {
        w.started(&format!("rig status on {name}"), 0.0);
    }
    let began = Instant::now();
    let mut last: Option<(RigState, Phase, Option<u8>)> = None;
    let mut polls = 0u64;
    let result = loop {
        let status = match query_status(link.as_mut()) {
            Ok(s) => s,
            // Ctrl-C in a terminal also stops a simulated board's process (same process
            // group): a query that fails then is the end of the watch, not an error.
            Err(_) if progress.cancelled() => break Ok(()),
            Err(e) => break Err(RigError::link(&name, "status query", e)),
        };
        polls += 1;
        let t = f64::from(status.tick) / hz;
        // What the board streams while it is watched (its samples, every tick) is taken at
        // every poll: shown on the page on its own ticks, never piling up in the link.
        let streamed: Vec<(f64, SampleRecord)> = link
            .take_samples()
            .into_iter()
            .map(|r| (f64::from(r.tick) / hz, r))
            .collect();
        let _ = link.take_faults();
        if let Some(w) = watch.as_deref_mut() {
            w.program(
                &ProgramView {
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
            on_change(&WatchLine {
                t_s: t,
                state: format!("{:?}", status.state),
                phase: format!("{:?}", status.phase),
                fault: status.fault.map(|f| f.name()),
                fault_code: status.fault.map(|f| f.code()),
            })?;
        }
        let done =
            progress.cancelled() || watch_for_s.is_some_and(|s| began.elapsed().as_secs_f64() >= s);
        if done {
            break Ok(());
        }
        std::thread::sleep(WATCH_INTERVAL);
        if progress.cancelled() {
            break Ok(());
        }
    };
    let closed = link
        .finish()
        .map_err(|e| RigError::link(&name, "closing the session", e));
    let result = result.and(closed.map(|_| ()));
    let watched_s = began.elapsed().as_secs_f64();
    progress.note(&format!(
        "watched {name} for {watched_s:.1} s ({polls} polls)"
    ));
    result.map(|()| Watched {
        link: name,
        watched_s,
        polls,
    })
}

/// `--watch-for S`: how long to watch, s (more than 0, up to 30 days).
pub fn parse_watch_for(s: &str) -> Result<f64, String> {
    number_within(s, |v| v > 0.0 && v <= 30.0 * 86_400.0)
        .ok_or_else(|| format!("`{s}` is not a watch time (allowed: more than 0 s, up to 30 days)"))
}

impl StatusReport {
    /// What `rig status` prints: its JSON and a newline (`json`) or its text.
    pub fn printed(&self, json: bool) -> Result<String, RigError> {
        if json {
            return Ok(format!("{}\n", crate::error::to_json(self, "the status")?));
        }
        Ok(self.to_string())
    }
}

impl WatchLine {
    /// The line `rig status --watch` prints (no newline): its JSON (`json`) or its text.
    pub fn printed(&self, json: bool) -> Result<String, RigError> {
        if !json {
            return Ok(self.to_string());
        }
        serde_json::to_string(self)
            .map_err(|e| RigError::internal(format!("cannot encode the status as JSON: {e}")))
    }
}
