//! `sandjumper hil` as one typed call: one jump through the loop on any link
//! ([`HilRequest`] -> [`run`] -> [`HilJump`]). On a lockstep link (sil, pil, a board in HIL
//! mode) the host plays the rig period by period ([`crate::hil::run`]); on the virtual F407
//! board (`LinkArg::F407`) the release binary runs the jump free on its own tick, the robot
//! behind its pins, as the rig tool's [`crate::tool::jump`] (or, for a stroke,
//! [`crate::tool::replay`]) runs it. Either way the outcome serialises with `jump_height_m`.

use std::fmt;
use std::path::PathBuf;

use serde::{Serialize, Serializer};

use sandjumper_acqlog::AcqLog;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_imaging::render::CameraModel;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::JumpSummary;
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::parse::parse_number;
use sandjumper_output::plot::save_figure;
use sandjumper_output::{Progress, StagedDir};

use crate::error::{RigError, to_json};
use crate::firmware_image::EMULATED_ELF;
use crate::hil::open::{FaultEntry, LinkArg, open_link};
use crate::hil::rig_model::RigModelConfig;
use crate::hil::run::{HilOutcome, HilSpec, run_jump_observed, trajectory};
use crate::hil::{camera, log};
use crate::stroke_table::{RigLimits, StrokeTable};
use crate::tool::jump::{JumpOutcome, JumpRequest};
use crate::tool::output::ProgramOutcome;
use crate::tool::replay::{ReplayOutcome, ReplayRequest};
use crate::tool::target::Target;
use crate::watch::RunWatch;

/// A stroke table to run instead of a sine, with the name messages and the summary give it
/// (the file's path as given).
#[derive(Clone, Debug, PartialEq)]
pub struct NamedStroke {
    /// Its name (a path, or any label for a table made in memory).
    pub name: String,
    /// The table (`t_s,p_m` at a fixed rate).
    pub table: StrokeTable,
}

impl NamedStroke {
    /// The stroke file at `path`, named by the path as given.
    pub fn read(path: &std::path::Path) -> Result<Self, RigError> {
        let table = StrokeTable::read_csv(path).map_err(RigError::Input)?;
        let name = path.display().to_string();
        Ok(Self { name, table })
    }
}

/// `sandjumper hil`: the jump, the link and the rig model.
#[derive(Clone, Debug)]
pub struct HilRequest {
    /// Where the controller runs (default sil).
    pub link: LinkArg,
    /// Jump kind (default single; unused with a stroke).
    pub kind: JumpKind,
    /// Forcing frequency f of the one-cycle sine, Hz (unused with a stroke).
    pub freq_hz: f64,
    /// Delay of the delayed stutter between its halves, s.
    pub tau_s: Option<f64>,
    /// A stroke table to upload and replay instead of the sine.
    pub stroke: Option<NamedStroke>,
    /// Gain-lowering damping during the delay: position gain times this (0 < X <= 1).
    pub gain_lowering: Option<f32>,
    /// Ground model of the plant (default eq4).
    pub model: ModelName,
    /// The parameters (default: the phi = 0.57 preset).
    pub params: Params,
    /// Relative tolerance of the plant's integration inside each period (`None`: 1e-6).
    pub rtol: Option<f64>,
    /// Camera frame rate, frames/s (default 200; 0 none).
    pub camera_fps: u32,
    /// Standard deviation of the encoder noise, counts (default 0).
    pub encoder_noise_counts: f64,
    /// Firmware ELF: the QEMU build for pil (default [`EMULATED_ELF`]); for f407 any other
    /// path is the F407 build to run (the default leaves the virtual board its own).
    pub firmware: PathBuf,
    /// The simulated rod camera the frames are rendered with.
    pub camera: CameraModel,
}

impl Default for HilRequest {
    fn default() -> Self {
        Self {
            link: LinkArg::Sil,
            kind: JumpKind::Single,
            freq_hz: 0.0,
            tau_s: None,
            stroke: None,
            gain_lowering: None,
            model: ModelName::Eq4,
            params: Params::default(),
            rtol: None,
            camera_fps: 200,
            encoder_noise_counts: 0.0,
            firmware: PathBuf::from(EMULATED_ELF),
            camera: CameraModel::default(),
        }
    }
}

/// `--gain-lowering FACTOR`: the position gain's factor during the delay (0 < FACTOR <= 1).
pub fn parse_gain_lowering(s: &str) -> Result<f32, String> {
    sandjumper_output::parse::parse_gain_lowering(s).map(|v| v as f32)
}

/// `--encoder-noise COUNTS`: the encoder noise's standard deviation, counts (0..=1000).
pub fn parse_encoder_noise(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (0.0..=1000.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "encoder noise {v} counts out of range (allowed: 0..=1000)"
        ))
    }
}

/// `--rtol X`: the plant's relative tolerance inside each control period (1e-12..=1e-3).
pub fn parse_rtol(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (1e-12..=1e-3).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "plant rtol {v} out of range (allowed: 1e-12..=1e-3)"
        ))
    }
}

/// `--camera-fps FPS`: the camera's frame rate, frames/s (0..=5000, half the 10 kHz tick).
pub fn parse_camera_fps(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if v <= 5000 => Ok(v),
        _ => Err(format!(
            "camera rate `{s}` not allowed (allowed: 0..=5000 frames/s, at most half the 10 kHz tick)"
        )),
    }
}

/// `--bench N`: how many runs to time (1..=1000).
pub fn parse_bench_runs(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=1000).contains(&v) => Ok(v),
        _ => Err(format!("repetitions `{s}` not allowed (allowed: 1..=1000)")),
    }
}

/// Refuse, before any file is read, what cannot be asked together: a live view (`live`) of
/// a timing run (`bench`: its number of runs), and on the virtual board a timing run and the
/// lockstep-only settings of `request` ([`HilRequest::refuse_lockstep_only`]).
pub fn refuse_early(request: &HilRequest, live: bool, bench: Option<u32>) -> Result<(), RigError> {
    if live && bench.is_some() {
        return Err(RigError::input(
            "--live shows one jump; --bench repeats it for timing (allowed: one of them)",
        ));
    }
    if request.link == LinkArg::F407 && bench.is_some() {
        return Err(lockstep_only("--bench"));
    }
    request.refuse_lockstep_only()
}

/// What `hil` says when it removes the virtual board's scratch folder (no `--out` given).
pub const SCRATCH_NOTE: &str =
    "(a scratch copy, removed now: give --out DIR to keep the log, summary and figure)";

/// The scratch folder of a run on the virtual board (whose program always writes a folder)
/// when no `out` is given, removed when it drops (then say [`SCRATCH_NOTE`]); else `None`.
pub fn scratch_dir(
    request: &HilRequest,
    out: Option<&std::path::Path>,
) -> Result<Option<tempfile::TempDir>, RigError> {
    if out.is_some() || request.link != LinkArg::F407 {
        return Ok(None);
    }
    tempfile::tempdir()
        .map(Some)
        .map_err(|e| RigError::internal(format!("cannot make a scratch directory: {e}")))
}

/// Where a run's folder goes: `out` when given, else `jump` in the `scratch` folder of
/// [`scratch_dir`], else nowhere.
pub fn run_dir(
    out: Option<&std::path::Path>,
    scratch: Option<&tempfile::TempDir>,
) -> Option<PathBuf> {
    out.map(std::path::Path::to_path_buf)
        .or_else(|| scratch.map(|d| d.path().join("jump")))
}

/// The refusal of a flag only a lockstep link has, on the virtual board.
pub fn lockstep_only(flag: &str) -> RigError {
    RigError::input(format!(
        "{flag} is not available with --link f407 (the virtual board runs the flashed binary \
         free on its own tick, the plant behind its pins; allowed there: --kind, --freq, --tau, \
         --model, --phi, --params, --camera-fps, --camera, --firmware, --out, --mcap, --json)"
    ))
}

impl HilRequest {
    /// The jump as the loop runs it.
    pub fn spec(&self) -> HilSpec {
        let mut spec = HilSpec::new(
            self.kind,
            self.freq_hz,
            self.tau_s.unwrap_or(0.0),
            self.model,
        );
        spec.gain_lowering = self.gain_lowering.map(HilSpec::gain_lowering_factor);
        spec.camera_fps = self.camera_fps;
        spec.rtol = self.rtol.unwrap_or(spec.rtol);
        spec.stroke = self.stroke.as_ref().map(|s| s.table.clone());
        spec
    }

    /// The rig model (its encoder noise; the rest the defaults).
    pub fn model_config(&self) -> RigModelConfig {
        RigModelConfig {
            encoder_noise_counts: self.encoder_noise_counts,
            ..RigModelConfig::default()
        }
    }

    /// Refuse, before anything runs: a stroke the rig's feasibility check refuses (or whose
    /// rate does not divide the control rate), the lockstep-only settings on the virtual
    /// board, and there a sine the parameters cannot run.
    pub fn validate(&self) -> Result<(), RigError> {
        self.refuse_lockstep_only()?;
        if let Some(s) = &self.stroke {
            s.table
                .period_ticks(RigModelConfig::default().tick_hz)
                .map_err(|e| RigError::input(format!("{}: {e}", s.name)))?;
            s.table.check(&RigLimits::of(&self.params)).map_err(|e| {
                RigError::input(format!("{}: refused before anything ran: {e}", s.name))
            })?;
        } else if self.link == LinkArg::F407 {
            trajectory(&self.params, &self.spec()).map_err(|e| RigError::input(e.to_string()))?;
        }
        Ok(())
    }

    /// On the virtual board, refuse what only a lockstep link can do (encoder noise, a
    /// tolerance, gain lowering).
    pub fn refuse_lockstep_only(&self) -> Result<(), RigError> {
        if self.link != LinkArg::F407 {
            return Ok(());
        }
        let lockstep = [
            (self.encoder_noise_counts != 0.0, "--encoder-noise"),
            (self.rtol.is_some(), "--rtol"),
            (self.gain_lowering.is_some(), "--gain-lowering"),
        ];
        match lockstep.iter().find(|(set, _)| *set) {
            Some((_, flag)) => Err(lockstep_only(flag)),
            None => Ok(()),
        }
    }

    /// [`HilRequest::validate`], then the warning a setting that does nothing deserves
    /// (through `progress.note`).
    pub fn check(&self, progress: &dyn Progress) -> Result<(), RigError> {
        self.validate()?;
        if self.link != LinkArg::F407
            && self.stroke.is_none()
            && self.kind != JumpKind::DelayedStutter
            && self.gain_lowering.is_some()
        {
            progress.note("warning: --gain-lowering only acts during a delayed stutter's delay");
        }
        Ok(())
    }

    /// Whether the run reads the rod camera's model (not a stroke on the virtual board).
    pub fn uses_camera(&self) -> bool {
        self.link != LinkArg::F407 || self.stroke.is_none()
    }

    /// Whether the run keeps its own time (a board on a serial port): a live view does not
    /// pace it.
    pub fn keeps_own_time(&self) -> bool {
        matches!(self.link, LinkArg::Serial(_))
    }

    /// Whether a live view shows a failed run's error and stays up (a lockstep link; the
    /// virtual board's program ends its view with the command).
    pub fn shows_errors_live(&self) -> bool {
        self.link != LinkArg::F407
    }

    /// What runs, in words: `stutter at 10 Hz` or `stroke NAME`.
    pub fn describe(&self) -> String {
        match &self.stroke {
            Some(s) => format!("stroke {}", s.name),
            None => format!("{} at {} Hz", kind_name(self.kind), self.freq_hz),
        }
    }
}

/// The JSON object of `hil --json` and `summary.json` on a lockstep link.
#[derive(Clone, Debug, Serialize)]
pub struct HilReport {
    /// The link.
    pub link: String,
    /// `single`, `stutter`, `delayed` or `stroke`.
    pub kind: &'static str,
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz (null for a stroke).
    pub freq_hz: Option<f64>,
    /// Delay, s (null for a stroke).
    pub tau_s: Option<f64>,
    /// The stroke run instead of a sine.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stroke: Option<String>,
    /// Gain-lowering factor, if any.
    pub gain_lowering: Option<f32>,
    /// Jump metrics (times from the trajectory's start; `jump_height_m` among them, m).
    #[serde(flatten)]
    pub summary: JumpSummary,
    /// What a final jump height that is not positive means, in words (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub final_jump_note: Option<&'static str>,
    /// Control periods simulated.
    pub ticks: u64,
    /// Frames lost (controller-side gaps + host-side undecodable).
    pub frames_lost: u32,
    /// Frames the controller rejected.
    pub frames_rejected: u32,
    /// Faults reported.
    pub faults: Vec<FaultEntry>,
    /// Camera frames taken.
    pub camera_frames: usize,
    /// Largest |p_cmd - p| until the force first saturated, m.
    pub tracking_error_max_m: f64,
    /// Wall-clock time, s.
    pub wall_time_s: f64,
    /// Simulated over wall time.
    pub realtime_factor: f64,
    /// Most instructions one control tick took (PIL).
    pub max_tick_instructions: Option<u32>,
    /// The firmware's exit status (PIL).
    pub exit_code: Option<i32>,
}

/// One jump through a lockstep link: the parameters, the request as run, the loop's outcome
/// and its report.
pub struct LoopRun {
    /// Parameters after the preset and the overrides.
    pub params: Params,
    /// The jump and the loop's settings.
    pub spec: HilSpec,
    /// The rig model (tick rate, encoder scale, noise).
    pub model_config: RigModelConfig,
    /// The loop's outcome (trace, samples, camera frames).
    pub outcome: HilOutcome,
    /// What `hil --json` prints.
    pub report: HilReport,
    /// The title of the summary and the figure.
    pub title: String,
    /// The camera model the frames are rendered with.
    pub camera: CameraModel,
}

impl LoopRun {
    /// The acquisition log of the run (acquisition.csv).
    pub fn acquisition_log(&self) -> AcqLog {
        log::acquisition_log(
            &self.outcome,
            &self.spec,
            self.model_config.tick_hz,
            self.model_config.metres_per_count,
            self.params.robot.stroke_amplitude_m,
            self.params.sand.packing_fraction,
        )
    }

    /// Write acquisition.csv (and with `mcap` acquisition.mcap), with a camera rate frames/,
    /// params.toml, summary.json, hil.png and hil.svg into `staged`, then commit it.
    pub fn write(&self, staged: StagedDir, mcap: bool) -> Result<PathBuf, RigError> {
        let log = self.acquisition_log();
        log.write_file(&staged.file("acquisition.csv"))
            .map_err(|e| RigError::internal(format!("cannot write acquisition.csv: {e}")))?;
        if mcap {
            log.write_mcap_file(&staged.file("acquisition.mcap"), None)
                .map_err(|e| RigError::internal(format!("cannot write acquisition.mcap: {e}")))?;
        }
        if self.spec.camera_fps > 0 {
            camera::write_frames(
                &self.outcome.camera_frames,
                &camera::heights_by_period(&self.outcome),
                &self.camera,
                1.0 / f64::from(self.model_config.tick_hz),
                &staged.file("frames"),
            )
            .map_err(RigError::internal)?;
        }
        staged.write_text("params.toml", &self.params.to_toml())?;
        staged.write_text(
            "summary.json",
            &format!("{}\n", to_json(&self.report, "the summary")?),
        )?;
        save_figure(
            &log::figure(&self.outcome, self.title.clone()),
            &staged.file("hil.png"),
            Some(&staged.file("hil.svg")),
        )?;
        Ok(staged.commit()?)
    }
}

impl fmt::Display for LoopRun {
    /// The summary `hil` prints without `--json`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.report;
        let s = &r.summary;
        let mm = |v: f64| format!("{:.2} mm", 1e3 * v);
        writeln!(f, "{}", self.title)?;
        writeln!(
            f,
            "  jump height        {}  (apex at t = {:.4} s)",
            mm(s.jump_height_m),
            s.apex_time_s
        )?;
        writeln!(f, "  final jump height  {}", mm(s.final_jump_height_m))?;
        if let Some(note) = s.final_height_note() {
            writeln!(f, "                     {note}")?;
        }
        writeln!(f, "  max depth          {}", mm(s.max_depth_m))?;
        writeln!(
            f,
            "  tracking error     {} (max until the force first saturated)",
            mm(r.tracking_error_max_m)
        )?;
        writeln!(f, "  ticks              {}", r.ticks)?;
        writeln!(
            f,
            "  frames lost        {} (rejected {})",
            r.frames_lost, r.frames_rejected
        )?;
        let faults: Vec<String> = r
            .faults
            .iter()
            .map(|f| format!("{} {} at tick {}", f.code, f.name, f.tick))
            .collect();
        let faults = if faults.is_empty() {
            "none".to_string()
        } else {
            faults.join(", ")
        };
        writeln!(f, "  faults             {faults}")?;
        writeln!(f, "  camera frames      {}", r.camera_frames)?;
        writeln!(
            f,
            "  wall time          {:.3} s ({:.1}x real time)",
            r.wall_time_s, r.realtime_factor
        )?;
        if let Some(n) = r.max_tick_instructions {
            writeln!(
                f,
                "  max tick cost      {n} instructions (Cortex-M4, QEMU -icount)"
            )?;
        }
        if let Some(c) = r.exit_code {
            writeln!(f, "  firmware exit      {c}")?;
        }
        Ok(())
    }
}

/// The rig tool's record of a jump on the virtual board.
pub enum BoardRecord {
    /// A sine jump (`rig jump --link f407`).
    Jump(Box<JumpOutcome>),
    /// A stroke (`rig replay --stroke --link f407`).
    Replay(Box<ReplayOutcome>),
}

/// What `hil` did on one link.
pub enum HilJump {
    /// A lockstep link (sil, pil, serial).
    Loop(Box<LoopRun>),
    /// The virtual F407 board: the rig tool's record.
    Board(BoardRecord),
}

impl HilJump {
    /// The jump height, m (the simulated rig's on the board; `None` when it has none).
    pub fn jump_height_m(&self) -> Option<f64> {
        match self {
            Self::Loop(r) => Some(r.report.summary.jump_height_m),
            Self::Board(b) => match b {
                BoardRecord::Jump(j) => j.simulated_jump_height_m,
                BoardRecord::Replay(r) => r.simulated_jump_height_m,
            },
        }
    }

    /// The faults reported, in order.
    pub fn faults(&self) -> &[FaultEntry] {
        match self {
            Self::Loop(r) => &r.report.faults,
            Self::Board(b) => match b {
                BoardRecord::Jump(j) => &j.faults,
                BoardRecord::Replay(r) => &r.faults,
            },
        }
    }

    /// `hil --json`'s text (pretty JSON, no newline).
    pub fn json(&self) -> Result<String, RigError> {
        to_json(self, "the summary")
    }

    /// The acquisition log of the run (what `hil --out` writes as acquisition.csv).
    pub fn acquisition_log(&self) -> AcqLog {
        match self {
            Self::Loop(run) => run.acquisition_log(),
            Self::Board(BoardRecord::Jump(j)) => j.log.clone(),
            Self::Board(BoardRecord::Replay(r)) => r.log.clone(),
        }
    }

    /// How a live view of the run ends: the rig time of its end, s, the line it shows and
    /// whether it went well (`error`: the command's error after the run, if any; `None`: the
    /// view closes with the command, as a lockstep run's does after an error).
    pub fn live_end(&self, error: Option<&str>) -> Option<(f64, String, bool)> {
        let Self::Loop(run) = self else {
            return Some(match error {
                None => (f64::NAN, "completed".to_string(), true),
                Some(e) => (f64::NAN, e.to_string(), false),
            });
        };
        if error.is_some() {
            return None;
        }
        let t_end = run.outcome.trace.last().map_or(0.0, |r| r.t_s);
        let faults = run.outcome.faults.len();
        let line = format!(
            "jump height {:.2} mm, {} fault{}",
            1e3 * run.outcome.summary.jump_height_m,
            faults,
            if faults == 1 { "" } else { "s" }
        );
        Some((t_end, line, faults == 0))
    }
}

impl fmt::Display for HilJump {
    /// The summary `hil` prints without `--json`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Loop(run) => run.fmt(f),
            Self::Board(BoardRecord::Jump(j)) => j.fmt(f),
            Self::Board(BoardRecord::Replay(r)) => r.fmt(f),
        }
    }
}

impl ProgramOutcome for HilJump {
    fn json(&self) -> Result<String, RigError> {
        HilJump::json(self)
    }
    fn faults(&self) -> &[FaultEntry] {
        HilJump::faults(self)
    }
    fn write(&self, staged: StagedDir, mcap: bool) -> Result<PathBuf, RigError> {
        match self {
            Self::Loop(run) => run.write(staged, mcap),
            Self::Board(BoardRecord::Jump(j)) => j.write(staged, mcap),
            Self::Board(BoardRecord::Replay(r)) => r.write(staged, mcap),
        }
    }
    fn check(&self, dir: &std::path::Path) -> Result<(), RigError> {
        match self {
            Self::Loop(_) => Ok(()),
            Self::Board(BoardRecord::Jump(j)) => j.check(dir),
            Self::Board(BoardRecord::Replay(r)) => r.check(dir),
        }
    }
    /// A lockstep run ends as the loop ran it: its summary lists its faults.
    fn completed_cleanly(&self) -> bool {
        match self {
            Self::Loop(_) => true,
            Self::Board(BoardRecord::Jump(j)) => j.completed_cleanly(),
            Self::Board(BoardRecord::Replay(r)) => r.completed_cleanly(),
        }
    }
    fn acquisition_log(&self) -> AcqLog {
        HilJump::acquisition_log(self)
    }
    /// A lockstep run's summary lists its faults itself.
    fn printed(&self, as_json: bool) -> Result<String, RigError> {
        match self {
            Self::Loop(run) if !as_json => Ok(run.to_string()),
            _ => crate::tool::output::printed(self, as_json),
        }
    }
}

/// The JSON of a board's record (a [`JumpOutcome`] or a [`ReplayOutcome`]) as `hil --json`
/// prints it: its own keys, then `jump_height_m` (m; the value of its
/// `simulated_jump_height_m`).
pub fn with_jump_height<R: Serialize>(
    record: &R,
    jump_height_m: Option<f64>,
) -> Result<String, RigError> {
    to_json(
        &WithJumpHeight {
            record,
            jump_height_m,
        },
        "the summary",
    )
}

/// A board's record with `jump_height_m` added after its own keys.
#[derive(Serialize)]
struct WithJumpHeight<'a, R: Serialize> {
    #[serde(flatten)]
    record: &'a R,
    jump_height_m: Option<f64>,
}

impl Serialize for HilJump {
    /// The lockstep report, or the board's record with `jump_height_m` (the same value as its
    /// `simulated_jump_height_m`) added: `hil --json` has that key on every link.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let jump_height_m = self.jump_height_m();
        match self {
            Self::Loop(r) => r.report.serialize(s),
            Self::Board(b) => match b {
                BoardRecord::Jump(j) => WithJumpHeight {
                    record: j,
                    jump_height_m,
                }
                .serialize(s),
                BoardRecord::Replay(r) => WithJumpHeight {
                    record: r,
                    jump_height_m,
                }
                .serialize(s),
            },
        }
    }
}

/// Run `hil`: [`HilRequest::check`], then [`run_checked`] without a watch.
pub fn run(request: &HilRequest, progress: &dyn Progress) -> Result<HilJump, RigError> {
    request.check(progress)?;
    run_checked(request, progress, None)
}

/// Run a checked request ([`HilRequest::check`]), `watch` shown the title and every period.
pub fn run_checked(
    request: &HilRequest,
    progress: &dyn Progress,
    watch: Option<&mut dyn RunWatch>,
) -> Result<HilJump, RigError> {
    if request.link == LinkArg::F407 {
        return on_the_board(request, progress, watch).map(HilJump::Board);
    }
    run_loop(request, watch).map(|r| HilJump::Loop(Box::new(r)))
}

/// The jump through a lockstep link.
fn run_loop(
    request: &HilRequest,
    mut watch: Option<&mut dyn RunWatch>,
) -> Result<LoopRun, RigError> {
    let spec = request.spec();
    let params = &request.params;
    if let Some(w) = watch.as_deref_mut() {
        w.started(
            &format!(
                "hil --link {}: {}, {}, phi {}",
                request.link,
                request.describe(),
                spec.model.as_str(),
                params.sand.packing_fraction
            ),
            -spec.settle_s,
        );
    }
    let model_config = request.model_config();
    let outcome = match watch {
        Some(w) => one_run(request, &spec, model_config, Some(&mut |p| w.period(p))),
        None => one_run(request, &spec, model_config, None),
    };
    let outcome = outcome?;
    let report = report(request, &spec, &outcome);
    let title = title(request, &spec, &outcome.link_name);
    Ok(LoopRun {
        params: params.clone(),
        spec,
        model_config,
        outcome,
        report,
        title,
        camera: request.camera.clone(),
    })
}

/// One run through the loop.
fn one_run(
    request: &HilRequest,
    spec: &HilSpec,
    model_config: RigModelConfig,
    observe: Option<&mut dyn FnMut(&crate::hil::run::PeriodView)>,
) -> Result<HilOutcome, RigError> {
    let mut link = open_link(&request.link, &model_config, &request.firmware)?;
    run_jump_observed(&request.params, spec, model_config, link.as_mut(), observe).map_err(|e| {
        RigError::input(format!(
            "the run through the loop ({}) failed: {e}",
            link.name()
        ))
    })
}

fn report(request: &HilRequest, spec: &HilSpec, outcome: &HilOutcome) -> HilReport {
    HilReport {
        link: outcome.link_name.clone(),
        kind: if spec.stroke.is_some() {
            "stroke"
        } else {
            kind_name(spec.kind)
        },
        model: spec.model.as_str(),
        phi: request.params.sand.packing_fraction,
        freq_hz: spec.stroke.is_none().then_some(spec.freq_hz),
        tau_s: spec.stroke.is_none().then_some(spec.tau_s),
        stroke: request.stroke.as_ref().map(|s| s.name.clone()),
        gain_lowering: request.gain_lowering,
        summary: outcome.summary.clone(),
        final_jump_note: outcome.summary.final_height_note(),
        ticks: outcome.ticks,
        frames_lost: outcome.frames_lost,
        frames_rejected: outcome.frames_rejected,
        faults: outcome.faults.iter().map(FaultEntry::of).collect(),
        camera_frames: outcome.camera_frames.len(),
        tracking_error_max_m: outcome.tracking_error_until_saturation().0,
        wall_time_s: outcome.wall_time_s,
        realtime_factor: outcome.realtime_factor,
        max_tick_instructions: outcome.link.max_tick_instructions,
        exit_code: outcome.link.exit_code,
    }
}

fn title(request: &HilRequest, spec: &HilSpec, link_name: &str) -> String {
    format!(
        "{} through {link_name}{}, model {}, φ = {}",
        match &request.stroke {
            Some(s) => format!("stroke {}", s.name),
            None => kind_name(spec.kind).to_string(),
        },
        if spec.stroke.is_some() {
            String::new()
        } else if spec.kind == JumpKind::DelayedStutter {
            format!(", f = {} Hz, τ = {} s", spec.freq_hz, spec.tau_s)
        } else {
            format!(", f = {} Hz", spec.freq_hz)
        },
        spec.model,
        request.params.sand.packing_fraction
    )
}

/// The virtual board's target for `request`: hil's default firmware is the QEMU build's
/// ELF, so only another path is handed to the board (which takes the F407 build's).
pub fn board_target(request: &HilRequest) -> Target {
    Target {
        firmware: (request.firmware.as_path() != std::path::Path::new(EMULATED_ELF))
            .then(|| request.firmware.clone()),
        ..Target::on(LinkArg::F407)
    }
}

/// The rig tool's request for the board: a replay of the stroke at its own rate, or the jump.
pub enum BoardRequest {
    /// `rig jump --link f407`.
    Jump(JumpRequest),
    /// `rig replay --stroke --link f407`.
    Replay(ReplayRequest),
}

/// What the virtual board runs for `request`.
pub fn board_request(request: &HilRequest) -> BoardRequest {
    let target = board_target(request);
    match &request.stroke {
        Some(s) => BoardRequest::Replay(ReplayRequest {
            table_rate_hz: Some(s.table.rate_hz),
            model: request.model,
            params: request.params.clone(),
            ..ReplayRequest::stroke(target, s.table.clone(), s.name.clone())
        }),
        None => BoardRequest::Jump(JumpRequest {
            tau_s: request.tau_s,
            camera_fps: request.camera_fps,
            model: request.model,
            params: request.params.clone(),
            camera: request.camera.clone(),
            ..JumpRequest::new(target, request.kind, request.freq_hz)
        }),
    }
}

fn on_the_board(
    request: &HilRequest,
    progress: &dyn Progress,
    watch: Option<&mut dyn RunWatch>,
) -> Result<BoardRecord, RigError> {
    Ok(match board_request(request) {
        BoardRequest::Jump(j) => BoardRecord::Jump(Box::new(crate::tool::jump::run_watching(
            &j, progress, watch,
        )?)),
        BoardRequest::Replay(r) => {
            let plan = r.plan()?;
            BoardRecord::Replay(Box::new(crate::tool::replay::run_planned(
                &r, plan, progress, watch,
            )?))
        }
    })
}

/// Timing of `hil --bench`: the last run and every run's wall time and real-time factor.
pub struct Bench {
    /// The request's description (`single at 10 Hz`).
    pub describe: String,
    /// The jump as run.
    pub spec: HilSpec,
    /// The control rate, Hz.
    pub tick_hz: u32,
    /// `(wall time s, real-time factor)` of each run, fastest first.
    pub runs: Vec<(f64, f64)>,
    /// The last run.
    pub last: HilOutcome,
}

/// Run the checked request `n` times (at least once) on its lockstep link, for timing.
pub fn bench(request: &HilRequest, n: u32, _progress: &dyn Progress) -> Result<Bench, RigError> {
    let spec = request.spec();
    let model_config = request.model_config();
    let mut runs = Vec::new();
    let mut last = None;
    for _ in 0..n.max(1) {
        let o = one_run(request, &spec, model_config, None)?;
        runs.push((o.wall_time_s, o.realtime_factor));
        last = Some(o);
    }
    runs.sort_by(|x, y| x.0.total_cmp(&y.0));
    let last = last.ok_or_else(|| RigError::internal("no run"))?;
    Ok(Bench {
        describe: request.describe(),
        spec,
        tick_hz: model_config.tick_hz,
        runs,
        last,
    })
}

impl fmt::Display for Bench {
    /// What `hil --bench` prints.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let o = &self.last;
        let (best, median) = (self.runs[0], self.runs[self.runs.len() / 2]);
        writeln!(
            f,
            "hil bench: link {} {} tau {} s model {}: {} runs of {:.3} s simulated ({} ticks at {} Hz)",
            o.link_name,
            self.describe,
            self.spec.tau_s,
            self.spec.model,
            self.runs.len(),
            o.simulated_time_s,
            o.ticks,
            self.tick_hz
        )?;
        writeln!(
            f,
            "  wall time best {:.4} s ({:.0}x real time), median {:.4} s ({:.0}x real time)",
            best.0, best.1, median.0, median.1
        )?;
        writeln!(
            f,
            "  plant: {} rhs evaluations, {} steps ({} rejected): {:.1} rhs per tick",
            o.summary.rhs_evaluations,
            o.summary.steps_accepted,
            o.summary.steps_rejected,
            o.summary.rhs_evaluations as f64 / o.ticks as f64
        )?;
        if let Some(m) = o.link.max_tick_instructions {
            writeln!(f, "  max tick cost {m} instructions")?;
        }
        Ok(())
    }
}
