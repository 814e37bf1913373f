//! `sandjumper hil`: one jump through the loop (SIL, PIL or a real board), reported like
//! `sandjumper jump` plus the loop's own figures; `--out` writes the acquisition log, the
//! parameters, the summary and a figure; `--bench` repeats the run and prints speed figures.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use super::log;
use super::rig_model::RigModelConfig;
use super::run::{HilOutcome, HilSpec, PeriodView, run_jump_observed};
use crate::command::args::{
    KindArg, ModelArg, parse_freq, parse_gain_lowering, parse_number, parse_phi, parse_tau,
};
use crate::command::resolve::{ParamsFile, resolve_params};
use crate::command::stroke::checked_stroke;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_imaging::render::CameraModel;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::record::JumpSummary;
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::save_figure;
pub use sandjumper_rig::hil::open::{FaultEntry, LinkArg, open_link, parse_link};

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

/// The JSON object of `hil --json` and `summary.json`.
#[derive(Debug, Serialize)]
pub struct HilReport<'a> {
    /// The link.
    pub link: String,
    /// `single`, `stutter` or `delayed`.
    pub kind: &'static str,
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz (null for a stroke file).
    pub freq_hz: Option<f64>,
    /// Delay, s (null for a stroke file).
    pub tau_s: Option<f64>,
    /// The stroke file run instead of a sine.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stroke: Option<String>,
    /// Gain-lowering factor, if any.
    pub gain_lowering: Option<f32>,
    /// Jump metrics (times from the trajectory's start).
    #[serde(flatten)]
    pub summary: &'a JumpSummary,
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

fn spec_of(a: &HilArgs, params: &Params) -> Result<HilSpec, CliError> {
    let kind: JumpKind = a.kind.unwrap_or(KindArg::Single).into();
    let model: ModelName = a.model.into();
    let mut spec = HilSpec::new(kind, a.freq.unwrap_or(0.0), a.tau.unwrap_or(0.0), model);
    spec.gain_lowering = a.gain_lowering.map(HilSpec::gain_lowering_factor);
    spec.camera_fps = a.camera_fps;
    spec.rtol = a.rtol.unwrap_or(spec.rtol);
    if let Some(path) = &a.stroke {
        spec.stroke = Some(checked_stroke(path, params)?);
    }
    Ok(spec)
}

/// What runs, in words: `stutter at 10 Hz` or `stroke FILE`.
fn describe(a: &HilArgs, spec: &HilSpec) -> String {
    match &a.stroke {
        Some(path) => format!("stroke {}", path.display()),
        None => format!("{} at {} Hz", kind_name(spec.kind), spec.freq_hz),
    }
}

fn one_run(
    a: &HilArgs,
    params: &Params,
    spec: &HilSpec,
    model_config: RigModelConfig,
    observe: Option<&mut dyn FnMut(&PeriodView)>,
) -> Result<HilOutcome, CliError> {
    let mut link = open_link(&a.link, &model_config, &a.firmware)?;
    run_jump_observed(params, spec, model_config, link.as_mut(), observe).map_err(|e| {
        CliError::input(format!(
            "the run through the loop ({}) failed: {e}",
            link.name()
        ))
    })
}

/// One jump through the loop as `sandjumper hil` runs it: the resolved parameters, the
/// request, the outcome, the JSON object `hil --json` prints and its text summary.
pub struct HilRun {
    /// Parameters after the preset and the overrides.
    pub params: Params,
    /// The jump and the loop's settings.
    pub spec: HilSpec,
    /// The rig model (tick rate, encoder scale, noise).
    pub model_config: RigModelConfig,
    /// The run's outcome.
    pub outcome: HilOutcome,
    /// `hil --json`'s object, pretty-printed.
    pub json: String,
    /// The title of the summary and the figure.
    pub title: String,
    /// The human summary `hil` prints without `--json`.
    pub human: String,
}

impl HilRun {
    /// The acquisition log of the run (what `hil --out` writes as acquisition.csv).
    pub fn acquisition_log(&self) -> sandjumper_acqlog::AcqLog {
        log::acquisition_log(
            &self.outcome,
            &self.spec,
            self.model_config.tick_hz,
            self.model_config.metres_per_count,
            self.params.robot.stroke_amplitude_m,
            self.params.sand.packing_fraction,
        )
    }
}

/// The rig model `a` asks for (its encoder noise; the rest the defaults).
fn rig_model_config(a: &HilArgs) -> RigModelConfig {
    RigModelConfig {
        encoder_noise_counts: a.encoder_noise,
        ..RigModelConfig::default()
    }
}

/// Run the jump `a` asks for through its link with `params` (resolved from `a.phi` and the
/// overrides by [`resolve_params`]; `a.params` is not read here). Errors are the CLI's.
pub fn simulate_run(a: &HilArgs, params: Params) -> Result<HilRun, CliError> {
    simulate_run_observed(a, params, None)
}

/// [`simulate_run`], calling `observe` after every control period.
pub fn simulate_run_observed(
    a: &HilArgs,
    params: Params,
    observe: Option<&mut dyn FnMut(&PeriodView)>,
) -> Result<HilRun, CliError> {
    let spec = spec_of(a, &params)?;
    let model_config = rig_model_config(a);
    let outcome = one_run(a, &params, &spec, model_config, observe)?;
    let phi = params.sand.packing_fraction;
    let report = HilReport {
        link: outcome.link_name.clone(),
        kind: if spec.stroke.is_some() {
            "stroke"
        } else {
            kind_name(spec.kind)
        },
        model: spec.model.as_str(),
        phi,
        freq_hz: spec.stroke.is_none().then_some(spec.freq_hz),
        tau_s: spec.stroke.is_none().then_some(spec.tau_s),
        stroke: a.stroke.as_ref().map(|p| p.display().to_string()),
        gain_lowering: a.gain_lowering,
        summary: &outcome.summary,
        final_jump_note: outcome.summary.final_height_note(),
        ticks: outcome.ticks,
        frames_lost: outcome.frames_lost,
        frames_rejected: outcome.frames_rejected,
        faults: outcome
            .faults
            .iter()
            .map(|f| FaultEntry {
                code: f.code.code(),
                name: f.code.name(),
                tick: f.tick,
            })
            .collect(),
        camera_frames: outcome.camera_frames.len(),
        tracking_error_max_m: outcome.tracking_error_until_saturation().0,
        wall_time_s: outcome.wall_time_s,
        realtime_factor: outcome.realtime_factor,
        max_tick_instructions: outcome.link.max_tick_instructions,
        exit_code: outcome.link.exit_code,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    let title = format!(
        "{} through {}{}, model {}, φ = {phi}",
        match &a.stroke {
            Some(p) => format!("stroke {}", p.display()),
            None => kind_name(spec.kind).to_string(),
        },
        outcome.link_name,
        if spec.stroke.is_some() {
            String::new()
        } else if spec.kind == JumpKind::DelayedStutter {
            format!(", f = {} Hz, τ = {} s", spec.freq_hz, spec.tau_s)
        } else {
            format!(", f = {} Hz", spec.freq_hz)
        },
        spec.model
    );
    let human = human(&title, &report);
    Ok(HilRun {
        params,
        spec,
        model_config,
        outcome,
        json,
        title,
        human,
    })
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
    let file = ParamsFile::read_opt(a.params.as_deref())?;
    let params = resolve_params(a.phi, file.as_ref())?;
    let spec = spec_of(a, &params)?;
    if spec.kind != JumpKind::DelayedStutter && a.gain_lowering.is_some() {
        eprintln!("warning: --gain-lowering only acts during a delayed stutter's delay");
    }
    if let Some(n) = a.bench {
        return bench(a, &params, &spec, rig_model_config(a), n);
    }
    let camera = read_camera(a.camera.as_deref())?;
    let staged = a.out.as_deref().map(StagedDir::create).transpose()?;
    let mut live = crate::live::LiveView::start(&a.live, &crate::live::JUMP_CHANNELS)?;
    if let (Some(v), LinkArg::Serial(_)) = (live.as_mut(), &a.link) {
        // A board runs at its own pace.
        v.unpaced();
    }
    if let Some(v) = live.as_mut() {
        v.bus().event(sandjumper_live::Event::RunStarted {
            title: format!(
                "hil --link {}: {}, {}, phi {}",
                a.link,
                describe(a, &spec),
                spec.model.as_str(),
                params.sand.packing_fraction
            ),
            t_s: -spec.settle_s,
        });
    }
    let result = match live.as_mut() {
        Some(v) => simulate_run_observed(a, params, Some(&mut |p| v.period(p))),
        None => simulate_run(a, params),
    };
    let run = match (result, live.take()) {
        (Ok(run), v) => {
            live = v;
            run
        }
        (Err(e), Some(v)) => {
            eprintln!("error: {}", e.message);
            v.finish(0.0, e.message.clone(), false);
            return Err(e);
        }
        (Err(e), None) => return Err(e),
    };
    if let Some(staged) = staged {
        write_outputs(a, staged, &camera, &run)?;
    }
    if a.json {
        println!("{}", run.json);
    } else {
        print!("{}", run.human);
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

/// `hil --out`: the acquisition log (and MCAP), frames, parameters, summary and figure.
fn write_outputs(
    a: &HilArgs,
    staged: StagedDir,
    camera: &CameraModel,
    run: &HilRun,
) -> Result<(), CliError> {
    let log = run.acquisition_log();
    log.write_file(&staged.file("acquisition.csv"))
        .map_err(|e| CliError::internal(format!("cannot write acquisition.csv: {e}")))?;
    if a.mcap {
        log.write_mcap_file(&staged.file("acquisition.mcap"), None)
            .map_err(|e| CliError::internal(format!("cannot write acquisition.mcap: {e}")))?;
    }
    if a.camera_fps > 0 {
        sandjumper_rig::hil::camera::write_frames(
            &run.outcome.camera_frames,
            &sandjumper_rig::hil::camera::heights_by_period(&run.outcome),
            camera,
            1.0 / f64::from(run.model_config.tick_hz),
            &staged.file("frames"),
        )
        .map_err(CliError::internal)?;
    }
    staged.write_text("params.toml", &run.params.to_toml())?;
    staged.write_text("summary.json", &format!("{}\n", run.json))?;
    save_figure(
        &log::figure(&run.outcome, run.title.clone()),
        &staged.file("hil.png"),
        Some(&staged.file("hil.svg")),
    )?;
    let dir = staged.commit()?;
    eprintln!("wrote {}", dir.display());
    Ok(())
}

/// The camera model of `--camera` (the defaults when absent).
pub fn read_camera(path: Option<&std::path::Path>) -> Result<CameraModel, CliError> {
    path.map_or(Ok(CameraModel::default()), |p| {
        CameraModel::from_toml_file(p).map_err(|e| CliError::input(format!("--camera {e}")))
    })
}

fn human(title: &str, r: &HilReport<'_>) -> String {
    let s = r.summary;
    let mm = |v: f64| format!("{:.2} mm", 1e3 * v);
    let mut t = format!("{title}\n");
    t += &format!(
        "  jump height        {}  (apex at t = {:.4} s)\n",
        mm(s.jump_height_m),
        s.apex_time_s
    );
    t += &format!("  final jump height  {}\n", mm(s.final_jump_height_m));
    if let Some(note) = s.final_height_note() {
        t += &format!("                     {note}\n");
    }
    t += &format!("  max depth          {}\n", mm(s.max_depth_m));
    t += &format!(
        "  tracking error     {} (max until the force first saturated)\n",
        mm(r.tracking_error_max_m)
    );
    t += &format!("  ticks              {}\n", r.ticks);
    t += &format!(
        "  frames lost        {} (rejected {})\n",
        r.frames_lost, r.frames_rejected
    );
    let faults: Vec<String> = r
        .faults
        .iter()
        .map(|f| format!("{} {} at tick {}", f.code, f.name, f.tick))
        .collect();
    t += &format!(
        "  faults             {}\n",
        if faults.is_empty() {
            "none".into()
        } else {
            faults.join(", ")
        }
    );
    t += &format!("  camera frames      {}\n", r.camera_frames);
    t += &format!(
        "  wall time          {:.3} s ({:.1}x real time)\n",
        r.wall_time_s, r.realtime_factor
    );
    if let Some(n) = r.max_tick_instructions {
        t += &format!("  max tick cost      {n} instructions (Cortex-M4, QEMU -icount)\n");
    }
    if let Some(c) = r.exit_code {
        t += &format!("  firmware exit      {c}\n");
    }
    t
}

fn bench(
    a: &HilArgs,
    params: &Params,
    spec: &HilSpec,
    model_config: RigModelConfig,
    n: u32,
) -> Result<(), CliError> {
    let mut factors = Vec::new();
    let mut last = None;
    for _ in 0..n {
        let o = one_run(a, params, spec, model_config, None)?;
        factors.push((o.wall_time_s, o.realtime_factor));
        last = Some(o);
    }
    factors.sort_by(|x, y| x.0.total_cmp(&y.0));
    let Some(o) = last else { return Ok(()) };
    let (best, median) = (factors[0], factors[factors.len() / 2]);
    println!(
        "hil bench: link {} {} tau {} s model {}: {} runs of {:.3} s simulated ({} ticks at {} Hz)",
        o.link_name,
        describe(a, spec),
        spec.tau_s,
        spec.model,
        n,
        o.simulated_time_s,
        o.ticks,
        model_config.tick_hz
    );
    println!(
        "  wall time best {:.4} s ({:.0}x real time), median {:.4} s ({:.0}x real time)",
        best.0, best.1, median.0, median.1
    );
    println!(
        "  plant: {} rhs evaluations, {} steps ({} rejected): {:.1} rhs per tick",
        o.summary.rhs_evaluations,
        o.summary.steps_accepted,
        o.summary.steps_rejected,
        o.summary.rhs_evaluations as f64 / o.ticks as f64
    );
    if let Some(m) = o.link.max_tick_instructions {
        println!("  max tick cost {m} instructions");
    }
    Ok(())
}

/// `hil --link f407`: the F407 release binary on the virtual board runs the jump free on its own
/// tick, the robot coupled through its peripherals, so the jump goes the way `rig jump` runs it
/// on a board (the same program, log, summary and figure; `--out` optional here). What only a
/// lockstep link can do is refused.
fn run_on_the_virtual_board(a: &HilArgs) -> Result<(), CliError> {
    let lockstep_only = [
        (a.bench.is_some(), "--bench"),
        (a.encoder_noise != 0.0, "--encoder-noise"),
        (a.rtol.is_some(), "--rtol"),
        (a.gain_lowering.is_some(), "--gain-lowering"),
    ];
    if let Some((_, flag)) = lockstep_only.iter().find(|(set, _)| *set) {
        return Err(CliError::input(format!(
            "{flag} is not available with --link f407 (the virtual board runs the flashed binary \
             free on its own tick, the plant behind its pins; allowed there: --kind, --freq, --tau, \
             --model, --phi, --params, --camera-fps, --camera, --firmware, --out, --mcap, --json)"
        )));
    }
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
    let emulated = PathBuf::from(sandjumper_rig::firmware_image::EMULATED_ELF);
    let target = crate::rig::tool::TargetArgs {
        controller: crate::rig::tool::ControllerArgs {
            port: None,
            link: Some(crate::rig::tool::SimLink::F407),
        },
        // hil's default is the QEMU build's ELF: the virtual board takes the F407 build's.
        firmware: (a.firmware != emulated).then(|| a.firmware.clone()),
        virtual_board: None,
        board_pace: None,
        drive_calibration: None,
    };
    let rig = crate::rig::tool::RigParamArgs {
        model: a.model,
        phi: a.phi,
        params: a.params.clone(),
    };
    if let Some(stroke) = &a.stroke {
        // A stroke runs on the board as `rig replay --stroke` does, at the file's own rate.
        let file = ParamsFile::read_opt(a.params.as_deref())?;
        let params = resolve_params(a.phi, file.as_ref())?;
        let table = checked_stroke(stroke, &params)?;
        let replay = crate::rig::tool::replay::ReplayArgs {
            live: a.live.clone(),
            log: None,
            stroke: Some(stroke.clone()),
            target,
            scale: 1.0,
            time_stretch: 1.0,
            clip: None,
            table_rate: Some(table.rate_hz),
            allow_gaps: false,
            rig,
            out,
            mcap: a.mcap,
            json: a.json,
        };
        let result = crate::rig::tool::replay::run(&replay);
        if scratch.is_some() {
            eprintln!(
                "(a scratch copy, removed now: give --out DIR to keep the log, summary and figure)"
            );
        }
        return result;
    }
    let jump = crate::rig::tool::jump::JumpArgs {
        live: a.live.clone(),
        target,
        kind: a.kind.unwrap_or(KindArg::Single),
        freq: a.freq.unwrap_or(0.0),
        tau: a.tau,
        camera_fps: a.camera_fps,
        rig,
        camera: a.camera.clone(),
        out,
        mcap: a.mcap,
        json: a.json,
    };
    let result = crate::rig::tool::jump::run(&jump);
    if scratch.is_some() {
        eprintln!(
            "(a scratch copy, removed now: give --out DIR to keep the log, summary and figure)"
        );
    }
    result
}
