//! `sandjumper hil`: one jump through the loop (SIL, PIL, the virtual F407 board or a real
//! board), reported like `sandjumper jump` plus the loop's own figures; `--out` writes the
//! acquisition log, the parameters, the summary and a figure; `--bench` repeats the run and
//! prints speed figures. A face over [`sandjumper_rig::hil_command`].

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use crate::command::args::{KindArg, ModelArg, parse_freq, parse_phi, parse_tau};
use crate::command::progress::Bars;
use crate::command::resolve::{ParamsFile, resolve_params};
use crate::live::{JUMP_CHANNELS, LiveView};
use crate::rig::face::{conclude, watch};
use sandjumper_model::params::Params;
use sandjumper_output::StagedDir;
use sandjumper_rig::hil::camera::read_camera;
use sandjumper_rig::hil::open::{LinkArg, parse_link};
use sandjumper_rig::hil_command::{
    self as lib, HilRequest, NamedStroke, parse_bench_runs as parse_repeats,
    parse_camera_fps as parse_fps, parse_encoder_noise as parse_noise,
    parse_gain_lowering as parse_factor, parse_rtol,
};

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
        Ok(HilRequest {
            params,
            stroke: self.stroke.as_deref().map(NamedStroke::read).transpose()?,
            ..self.flags()
        })
    }

    /// The request as the flags give it, no file read (the parameters the default).
    fn flags(&self) -> HilRequest {
        HilRequest {
            link: self.link.clone(),
            kind: self.kind.unwrap_or(KindArg::Single).into(),
            freq_hz: self.freq.unwrap_or(0.0),
            tau_s: self.tau,
            gain_lowering: self.gain_lowering,
            model: self.model.into(),
            rtol: self.rtol,
            camera_fps: self.camera_fps,
            encoder_noise_counts: self.encoder_noise,
            firmware: self.firmware.clone(),
            ..HilRequest::default()
        }
    }
}

/// Run `hil`.
pub fn run(a: &HilArgs) -> Result<(), CliError> {
    let flags = a.flags();
    lib::refuse_early(&flags, a.live.live.is_some(), a.bench)?;
    let scratch = lib::scratch_dir(&flags, a.out.as_deref())?;
    let result = jump(a, lib::run_dir(a.out.as_deref(), scratch.as_ref()));
    if scratch.is_some() {
        eprintln!("{}", lib::SCRATCH_NOTE);
    }
    result
}

/// The jump `a` asks for, its folder written into `out` (if any).
fn jump(a: &HilArgs, out: Option<PathBuf>) -> Result<(), CliError> {
    let progress = Bars::new();
    let file = ParamsFile::read_opt(a.params.as_deref())?;
    let mut request = a.request(resolve_params(a.phi, file.as_ref())?)?;
    request.check(&progress)?;
    if let Some(n) = a.bench {
        print!("{}", lib::bench(&request, n, &progress)?);
        return Ok(());
    }
    if request.uses_camera() {
        request.camera = read_camera(a.camera.as_deref())?;
    }
    // Every run claims its folder before the live view starts, as the rig tool does: an
    // output that cannot be written is refused before the page is up.
    let lockstep = request.link != LinkArg::F407;
    let staged = out.as_deref().map(StagedDir::create).transpose()?;
    let mut live = LiveView::start(&a.live, &JUMP_CHANNELS)?;
    if let Some(v) = live.as_mut().filter(|_| request.keeps_own_time()) {
        v.unpaced();
    }
    let jump = match lib::run_checked(&request, &progress, watch(&mut live)) {
        Ok(jump) => jump,
        Err(e) => {
            let e = CliError::from(e);
            if let Some(v) = live.filter(|_| request.shows_errors_live()) {
                eprintln!("error: {}", e.message);
                v.finish(0.0, e.message.clone(), false);
            }
            return Err(e);
        }
    };
    let result = conclude(&jump, staged, (a.mcap, a.json), lockstep);
    let error = result.as_ref().err().map(|e| e.message.as_str());
    if let (Some(v), Some((t_end, line, ok))) = (live, jump.live_end(error)) {
        v.finish(t_end, line, ok);
    }
    result
}
