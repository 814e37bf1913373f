//! `sandjumper hil`: one jump through the loop (SIL, PIL, the virtual F407 board or a real
//! board), reported like `sandjumper jump` plus the loop's own figures; `--out` writes the
//! acquisition log, the parameters, the summary and a figure; `--bench` repeats the run and
//! prints speed figures. A face over [`sandjumper_rig::hil_command`].

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use crate::command::args::{
    KindArg, ModelArg, parse_freq, parse_gain_lowering, parse_number, parse_phi, parse_tau,
};
use crate::command::progress::Bars;
use crate::command::resolve::{ParamsFile, resolve_params};
use crate::rig::face::{cli_error, watch};
use crate::rig::tool::{jump, replay};
use sandjumper_imaging::render::CameraModel;
use sandjumper_model::params::Params;
use sandjumper_output::{Progress, Silent, StagedDir};
use sandjumper_rig::hil::camera::read_camera;
pub use sandjumper_rig::hil::open::{FaultEntry, LinkArg, open_link, parse_link};
use sandjumper_rig::hil_command::{
    self as lib, BoardRecord, BoardRequest, HilJump, HilRequest, LoopRun, NamedStroke,
    with_jump_height,
};
use sandjumper_rig::stroke_table::StrokeTable;

fn parse_factor(s: &str) -> Result<f32, String> {
    parse_gain_lowering(s).map(|v| v as f32)
}
fn parse_noise(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (0.0..=1000.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "encoder noise {v} counts out of range (allowed: 0..=1000)"
        ))
    }
}
fn parse_rtol(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (1e-12..=1e-3).contains(&v) {
        Ok(v)
    } else {
        Err(format!(
            "plant rtol {v} out of range (allowed: 1e-12..=1e-3)"
        ))
    }
}
fn parse_fps(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if v <= 5000 => Ok(v),
        _ => Err(format!(
            "camera rate `{s}` not allowed (allowed: 0..=5000 frames/s, at most half the 10 kHz tick)"
        )),
    }
}
fn parse_repeats(s: &str) -> Result<u32, String> {
    match s.trim().parse::<u32>() {
        Ok(v) if (1..=1000).contains(&v) => Ok(v),
        _ => Err(format!("repetitions `{s}` not allowed (allowed: 1..=1000)")),
    }
}

/// `sandjumper hil`.
#[derive(Debug, Clone, Args)]
pub struct HilArgs {
    /// The live view.
    #[command(flatten)]
    pub live: crate::live::LiveArgs,
    /// Where the controller runs: `sil` (the core in this process), `pil` (the real firmware
    /// in QEMU mps2-an386, frames over semihosting FIFOs), `f407` (the F407 release ELF on the
    /// virtual board, the plant behind its pins: runs as `rig jump --link f407`), `serial:PATH`
    /// (a board in HIL mode on its USB CDC port).
    #[arg(long, value_name = "LINK", default_value = "sil", value_parser = parse_link)]
    pub link: LinkArg,
    /// Jump kind.
    #[arg(long, value_enum, required_unless_present = "stroke")]
    pub kind: Option<KindArg>,
    /// Forcing frequency f of the one-cycle sine, Hz.
    #[arg(long, value_name = "HZ", value_parser = parse_freq, required_unless_present = "stroke")]
    pub freq: Option<f64>,
    /// Run a stroke file instead of a one-cycle sine (`t_s,p_m` at a fixed rate, e.g.
    /// `sandjumper optimize`'s stroke.csv): uploaded into the controller's replay table and
    /// replayed. Refused before anything runs when it fails the rig's feasibility check.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["kind", "freq", "tau"])]
    pub stroke: Option<PathBuf>,
    /// Delay of the delayed stutter between its halves, s (required with --kind delayed).
    #[arg(long, value_name = "S", value_parser = parse_tau, required_if_eq("kind", "delayed"))]
    pub tau: Option<f64>,
    /// Gain-lowering damping during the delay: position gain times FACTOR (0 < FACTOR <= 1;
    /// 0.05 damps the ringing ~10x), velocity gain times 0.9.
    #[arg(long, value_name = "FACTOR", value_parser = parse_factor)]
    pub gain_lowering: Option<f32>,
    /// Ground model of the plant.
    #[arg(long, value_enum, default_value = "eq4")]
    pub model: ModelArg,
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi)]
    pub phi: f64,
    /// TOML file overriding any parameter (as for `sandjumper jump --params`), applied on top
    /// of the --phi preset.
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
    /// Relative tolerance of the plant's integration inside each control period (default
    /// 1e-6: a few hundredths of an encoder count).
    #[arg(long, value_name = "X", value_parser = parse_rtol)]
    pub rtol: Option<f64>,
    /// Camera frame rate, frames/s (200 rod tracking, 500 PIV; 0 none).
    #[arg(long, value_name = "FPS", default_value = "200", value_parser = parse_fps)]
    pub camera_fps: u32,
    /// Standard deviation of the encoder noise, counts (seeded, reproducible).
    #[arg(long, value_name = "COUNTS", default_value = "0", value_parser = parse_noise)]
    pub encoder_noise: f64,
    /// Firmware ELF for --link pil (built with --features board-qemu).
    #[arg(
        long,
        value_name = "ELF",
        default_value = sandjumper_rig::firmware_image::EMULATED_ELF
    )]
    pub firmware: PathBuf,
    /// The simulated rod camera (TOML, every key of `frames/camera.toml` optional): region
    /// size, scale, ball, exposure, lighting, noise, defocus, bits, seed.
    #[arg(long, value_name = "FILE.toml")]
    pub camera: Option<PathBuf>,
    /// Write acquisition.csv (the acquisition-log format), params.toml, summary.json,
    /// hil.png and hil.svg into DIR, and with a camera rate frames/ (the rendered rod-camera
    /// frames, frame_NNNNNN.png, and camera.toml).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// With --out, also write the acquisition log as acquisition.mcap (for Foxglove,
    /// Lichtblick and PlotJuggler; see `sandjumper log convert`).
    #[arg(long, requires = "out")]
    pub mcap: bool,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// Run the jump N times and print wall time and real-time factor (best and median).
    #[arg(long, value_name = "N", value_parser = parse_repeats)]
    pub bench: Option<u32>,
}

impl HilArgs {
    /// The library's request with `params` (resolved from `phi` and the overrides by
    /// [`resolve_params`]); the stroke file read, the camera the default.
    pub fn request(&self, params: Params) -> Result<HilRequest, CliError> {
        let stroke = self
            .stroke
            .as_ref()
            .map(|path| {
                StrokeTable::read_csv(path).map(|table| NamedStroke {
                    name: path.display().to_string(),
                    table,
                })
            })
            .transpose()
            .map_err(CliError::input)?;
        Ok(HilRequest {
            link: self.link.clone(),
            kind: self.kind.unwrap_or(KindArg::Single).into(),
            freq_hz: self.freq.unwrap_or(0.0),
            tau_s: self.tau,
            stroke,
            gain_lowering: self.gain_lowering,
            model: self.model.into(),
            params,
            rtol: self.rtol,
            camera_fps: self.camera_fps,
            encoder_noise_counts: self.encoder_noise,
            firmware: self.firmware.clone(),
            camera: CameraModel::default(),
        })
    }

    fn resolve(&self) -> Result<Params, CliError> {
        let file = ParamsFile::read_opt(self.params.as_deref())?;
        resolve_params(self.phi, file.as_ref())
    }
}

/// One jump as `sandjumper hil` runs it (the Python module's entry): the outcome and the
/// JSON object `hil --json` prints.
pub struct HilRun {
    /// What the run did.
    pub jump: HilJump,
    /// `hil --json`'s object, pretty-printed.
    pub json: String,
}

impl HilRun {
    /// The acquisition log of the run (what `hil --out` writes as acquisition.csv).
    pub fn acquisition_log(&self) -> sandjumper_acqlog::AcqLog {
        match &self.jump {
            HilJump::Loop(run) => run.acquisition_log(),
            HilJump::Board(b) => match b {
                BoardRecord::Jump(j) => j.log.clone(),
                BoardRecord::Replay(r) => r.log.clone(),
            },
        }
    }
}

/// Run the jump `a` asks for through its link with `params` (resolved from `a.phi` and the
/// overrides by [`resolve_params`]; `a.params` is not read here).
pub fn simulate_run(a: &HilArgs, params: Params) -> Result<HilRun, CliError> {
    let request = a.request(params)?;
    request.validate()?;
    let jump = lib::run_checked(&request, &Silent, None)?;
    let json = jump.json()?;
    Ok(HilRun { jump, json })
}

/// Run `hil`.
pub fn run(a: &HilArgs) -> Result<(), CliError> {
    if a.live.live.is_some() && a.bench.is_some() {
        return Err(CliError::input(
            "--live shows one jump; --bench repeats it for timing (allowed: one of them)",
        ));
    }
    if a.link == LinkArg::F407 {
        return run_on_the_virtual_board(a);
    }
    let progress = Bars::new();
    let mut request = a.request(a.resolve()?)?;
    request.check(&progress)?;
    if let Some(n) = a.bench {
        print!("{}", lib::bench(&request, n, &progress)?);
        return Ok(());
    }
    request.camera = read_camera(a.camera.as_deref())?;
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let mut live = crate::live::LiveView::start(&a.live, &crate::live::JUMP_CHANNELS)?;
    if let (Some(v), LinkArg::Serial(_)) = (live.as_mut(), &a.link) {
        // A board runs at its own pace.
        v.unpaced();
    }
    let run = match lib::run_checked(&request, &progress, watch(&mut live)) {
        Ok(HilJump::Loop(run)) => run,
        Ok(HilJump::Board(_)) => {
            return Err(CliError::internal("a board's run on a lockstep link"));
        }
        Err(e) => {
            let e = cli_error(e);
            if let Some(v) = live {
                eprintln!("error: {}", e.message);
                v.finish(0.0, e.message.clone(), false);
            }
            return Err(e);
        }
    };
    finish_loop(a, &run, staged, live)
}

/// Write, print and end the live view of a lockstep run.
fn finish_loop(
    a: &HilArgs,
    run: &LoopRun,
    staged: Option<StagedDir>,
    live: Option<crate::live::LiveView>,
) -> Result<(), CliError> {
    if let Some(staged) = staged {
        let dir = run.write(staged, a.mcap)?;
        eprintln!("wrote {}", dir.display());
    }
    if a.json {
        println!(
            "{}",
            sandjumper_rig::error::to_json(&run.report, "the summary")?
        );
    } else {
        print!("{run}");
    }
    if let Some(v) = live {
        let t_end = run.outcome.trace.last().map_or(0.0, |r| r.t_s);
        let faults = run.outcome.faults.len();
        let line = format!(
            "jump height {:.2} mm, {} fault{}",
            1e3 * run.outcome.summary.jump_height_m,
            faults,
            if faults == 1 { "" } else { "s" }
        );
        v.finish(t_end, line, faults == 0);
    }
    Ok(())
}

/// `hil --link f407`: the F407 release binary on the virtual board runs the jump free on its own
/// tick, the robot coupled through its peripherals, so the jump goes the way `rig jump` runs it
/// on a board (the same program, log, summary and figure; `--out` optional here; `--json`
/// adds `jump_height_m`). What only a lockstep link can do is refused.
fn run_on_the_virtual_board(a: &HilArgs) -> Result<(), CliError> {
    if a.bench.is_some() {
        return Err(cli_error(lib::lockstep_only("--bench")));
    }
    let flags = HilRequest {
        link: LinkArg::F407,
        encoder_noise_counts: a.encoder_noise,
        rtol: a.rtol,
        gain_lowering: a.gain_lowering,
        ..HilRequest::default()
    };
    flags.refuse_lockstep_only()?;
    let scratch = match &a.out {
        Some(_) => None,
        None => Some(
            tempfile::tempdir()
                .map_err(|e| CliError::internal(format!("cannot make a scratch directory: {e}")))?,
        ),
    };
    let out = a
        .out
        .clone()
        .or_else(|| scratch.as_ref().map(|d| d.path().join("jump")))
        .ok_or_else(|| CliError::internal("no output directory"))?;
    let result = on_the_board(a, &out, &Bars::new());
    if scratch.is_some() {
        eprintln!(
            "(a scratch copy, removed now: give --out DIR to keep the log, summary and figure)"
        );
    }
    result
}

/// The jump (or the stroke's replay) on the virtual board, as the rig tool runs it.
fn on_the_board(
    a: &HilArgs,
    out: &std::path::Path,
    progress: &dyn Progress,
) -> Result<(), CliError> {
    let request = a.request(a.resolve()?)?;
    request.check(progress)?;
    let outputs = (out, a.mcap, a.json);
    match lib::board_request(&request) {
        BoardRequest::Jump(j) => {
            jump::run_request(j, &a.live, a.camera.as_deref(), outputs, &|o| {
                with_jump_height(o, o.simulated_jump_height_m)
            })
        }
        BoardRequest::Replay(r) => replay::run_request(r, &a.live, outputs, &|o| {
            with_jump_height(o, o.simulated_jump_height_m)
        }),
    }
}
