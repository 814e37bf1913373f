//! The rig tool from Python: `rig_status`, `rig_jump`, `rig_intrude`, `rig_replay`,
//! `rig_calibrate_drive`, `rig_acknowledge_reset` and `rig_flash`, each a call of
//! `sandjumper_rig::tool` with the command line's defaults and checks, on the controller a
//! `link` (or a `port`) names; and [`RunNotCompleted`], what a program the controller did not
//! complete cleanly raises (the command line's exit status 1).

use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::resolve::resolve_params;
use sandjumper_output::parse::check_phi;
use sandjumper_rig::RigError;
use sandjumper_rig::hil::open::{LinkArg, parse_link};
use sandjumper_rig::tool::output::{ProgramOutcome, ProgramRequest};
use sandjumper_rig::tool::target::{Target, parse_board_pace};

use crate::call::long_call;
use crate::convert::{claim_out, opt_path, params_source, path_arg, summary_to_py};
use crate::errors::{checked, checked_number, choice, lib_err};
use crate::simulate::{HilResult, models};
use crate::typed;

create_exception!(
    sandjumper,
    RunNotCompleted,
    PyRuntimeError,
    "A rig program the controller did not complete cleanly (a fault, or the program cut \
     short): the command line's exit status 1. Its `result` is what the run recorded (its \
     folder is written first when `out` was given)."
);

/// The command-line flags of the target, as the Python arguments that carry them.
const TARGET_NAMES: [(&str, &str); 6] = [
    ("--link", "link"),
    ("--port", "port"),
    ("--firmware", "firmware"),
    ("--virtual-board", "virtual_board"),
    ("--board-pace", "board_pace"),
    ("--drive-calibration", "drive_calibration"),
];

/// The controller a call talks to, as `rig`'s `--link`/`--port`, `--firmware`,
/// `--virtual-board`, `--board-pace` and `--drive-calibration` give it: `link` is `"sil"`
/// (the default), `"pil"`, `"f407"` or `"serial:PATH"`; `port` (a board's serial port)
/// instead of a link.
fn target(
    (link, port): (Option<String>, Option<String>),
    (firmware, virtual_board): (Option<&Bound<'_, PyAny>>, Option<&Bound<'_, PyAny>>),
    board_pace: Option<f64>,
    drive_calibration: Option<&Bound<'_, PyAny>>,
) -> PyResult<Target> {
    let link = match (link, port) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "the argument 'link' cannot be used with 'port'",
            ));
        }
        (None, Some(port)) => LinkArg::Serial(port),
        (Some(link), None) => checked("link", link, parse_link)?,
        (None, None) => LinkArg::Sil,
    };
    Ok(Target {
        link,
        firmware: opt_path("firmware", firmware)?,
        virtual_board: opt_path("virtual_board", virtual_board)?,
        board_pace: board_pace
            .map(|p| checked("board_pace", p, parse_board_pace))
            .transpose()?,
        drive_calibration: opt_path("drive_calibration", drive_calibration)?,
    })
}

/// The simulated rig's ground model and parameters (`model`, `phi`, `params`), as `rig`'s
/// `--model`, `--phi` and `--params` give them.
fn rig_params(
    model: &str,
    phi: f64,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<(ModelName, Params)> {
    let model = choice("model", model, &models())?;
    let phi = checked_number("phi", phi, check_phi)?;
    let file = params_source("params", params)?;
    let params =
        resolve_params(phi, file.as_ref()).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((model, params))
}

/// A table of columns (name, values) a program measured besides its log.
pub type Table = (&'static str, Vec<(&'static str, Vec<f64>)>);

/// Run the rig program `request` as the command line does: checked before anything opens,
/// `out` claimed, run with the GIL released (progress to `progress`), the folder written into
/// `out` (`mcap`: acquisition.mcap too). Returns its summary, acquisition log and the `tables`
/// it measured; a run the controller did not complete cleanly raises [`RunNotCompleted`]
/// (`what`: "jump", "intrusion", "replay") with that result, after the folder is written.
#[allow(clippy::too_many_arguments)]
pub fn run_program<R>(
    py: Python<'_>,
    what: &str,
    request: &R,
    out: Option<&Bound<'_, PyAny>>,
    mcap: bool,
    progress: Option<Py<PyAny>>,
    names: &[(&str, &str)],
    tables: fn(&R::Outcome) -> Vec<Table>,
) -> PyResult<HilResult>
where
    R: ProgramRequest + Sync,
    R::Checked: Send,
    R::Outcome: Send,
{
    let checked = request.check().map_err(|e| lib_err(e, names))?;
    mcap_needs_out(mcap, out)?;
    let staged = claim_out(out)?;
    let (json, log, tables, clean, dir) = long_call(py, progress, |progress| {
        let outcome = request.run_checked(checked, progress, None)?;
        let dir = staged.map(|s| outcome.write(s, mcap)).transpose()?;
        Ok((
            outcome.json()?,
            outcome.acquisition_log(),
            tables(&outcome),
            outcome.completed_cleanly(),
            dir,
        ))
    })?
    .map_err(|e: RigError| lib_err(e, names))?;
    let result = HilResult::with_tables(py, &json, &log, tables)?;
    concluded(py, what, result, clean, dir)
}

/// `mcap=True` without `out`: refused, as the command line refuses `--mcap` without `--out`
/// (acquisition.mcap is written into the run's folder).
pub fn mcap_needs_out(mcap: bool, out: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    if mcap && out.is_none_or(|o| o.is_none()) {
        return Err(PyValueError::new_err(
            "mcap needs out (acquisition.mcap is written into the run's folder)",
        ));
    }
    Ok(())
}

/// `result` as the call's return when the controller completed the program cleanly (`clean`),
/// else [`RunNotCompleted`] carrying it (`what`: "jump", "intrusion", "replay"; `dir`: the
/// folder written, named in the message).
pub fn concluded(
    py: Python<'_>,
    what: &str,
    result: HilResult,
    clean: bool,
    dir: Option<std::path::PathBuf>,
) -> PyResult<HilResult> {
    if clean {
        return Ok(result);
    }
    let seen = dir.map_or(String::new(), |d| {
        format!(" (see {})", d.join("summary.json").display())
    });
    let e = RunNotCompleted::new_err(format!("the {what} did not complete cleanly{seen}"));
    e.value(py).setattr("result", Py::new(py, result)?)?;
    Err(e)
}

/// The controller's state, phase, latched fault and counters, as `sandjumper rig status
/// --json` prints them, from the controller `link` (or `port`) names.
#[pyfunction]
#[pyo3(signature = (link = None, port = None, firmware = None, virtual_board = None, board_pace = None, drive_calibration = None))]
pub fn rig_status(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    firmware: Option<&Bound<'_, PyAny>>,
    virtual_board: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::board_pace)] board_pace: Option<f64>,
    drive_calibration: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let target = target(
        (link, port),
        (firmware, virtual_board),
        board_pace,
        drive_calibration,
    )?;
    let report = py
        .detach(|| sandjumper_rig::tool::status::status(&target, &sandjumper_output::Silent))
        .map_err(|e| lib_err(e, &TARGET_NAMES))?;
    Ok(summary_to_py(py, &report)?.unbind())
}

/// One jump through the rig tool, as `sandjumper rig jump` does: the robot's program on `link`
/// (`"sil"`, `"pil"`, `"f407"`: the F407 release binary on the virtual board, or
/// `"serial:PATH"`; or a board's `port`), the plant (or the rig) answering, the acquisition log
/// recorded. `out`: also write the run's folder (`mcap`: acquisition.mcap too). Returns
/// `summary` (the dict `rig jump --json` prints, with `jump_height_m`), `log` and
/// `log_metadata`, as [`HilResult`]; a jump with a fault raises [`RunNotCompleted`].
#[pyfunction]
#[pyo3(signature = (kind, freq_hz, link = None, tau_s = None, model = "eq4".to_string(), phi = 0.57, params = None, camera_fps = 200, firmware = None, out = None, progress = None, port = None, virtual_board = None, board_pace = None, drive_calibration = None, mcap = false, camera = None))]
#[allow(clippy::too_many_arguments)]
pub fn rig_jump(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::kind)] kind: String,
    #[pyo3(from_py_with = typed::freq_hz)] freq_hz: f64,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = typed::tau_s)] tau_s: Option<f64>,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::camera_fps)] camera_fps: i64,
    firmware: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    virtual_board: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::board_pace)] board_pace: Option<f64>,
    drive_calibration: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::mcap)] mcap: bool,
    camera: Option<&Bound<'_, PyAny>>,
) -> PyResult<HilResult> {
    use sandjumper_rig::tool::jump::JumpRequest;
    let target = target(
        (link, port),
        (firmware, virtual_board),
        board_pace,
        drive_calibration,
    )?;
    let (kind, freq_hz, tau_s) =
        crate::simulate::sine("kind", "freq_hz", Some(kind), Some(freq_hz), tau_s, false)?;
    let (model, params) = rig_params(&model, phi, params)?;
    let mut names = TARGET_NAMES.to_vec();
    names.extend([("--tau", "tau_s"), ("--camera", "camera")]);
    let camera = opt_path("camera", camera)?;
    let request = JumpRequest {
        tau_s,
        camera_fps: checked(
            "camera_fps",
            camera_fps,
            sandjumper_rig::hil_command::parse_camera_fps,
        )?,
        camera: sandjumper_rig::hil::camera::read_camera(camera.as_deref())
            .map_err(|e| lib_err(e, &names))?,
        model,
        params,
        ..JumpRequest::new(target, kind, freq_hz)
    };
    run_program(py, "jump", &request, out, mcap, progress, &names, |_| {
        Vec::new()
    })
}

/// The slow-intrusion program (the paper's `F_p(z)` measurement), as `sandjumper rig intrude`
/// does: from `start` (m, the surface) down `depth`, back `withdraw`, then down to
/// `reintrusion_depth`, at `speed` (m/s) with `hold` (s) between, force binned every `bin`
/// (m). The controller as [`rig_jump`]'s; `out`: also write the folder (`mcap`:
/// acquisition.mcap too). Returns [`HilResult`] with `tables["intrusion"]` and
/// `tables["reintrusion"]` (`depth_m`, `force_n`); a run with a fault raises
/// [`RunNotCompleted`].
#[pyfunction]
#[pyo3(signature = (link = None, start = -0.02, depth = 0.02, withdraw = 0.005, reintrusion_depth = 0.03, speed = 0.01, hold = 0.5, bin = 0.00025, model = "eq4".to_string(), phi = 0.57, params = None, out = None, mcap = false, progress = None, port = None, firmware = None, virtual_board = None, board_pace = None, drive_calibration = None))]
#[allow(clippy::too_many_arguments)]
pub fn rig_intrude(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = typed::start)] start: f64,
    #[pyo3(from_py_with = typed::depth)] depth: f64,
    #[pyo3(from_py_with = typed::withdraw)] withdraw: f64,
    #[pyo3(from_py_with = typed::reintrusion_depth)] reintrusion_depth: f64,
    #[pyo3(from_py_with = typed::speed)] speed: f64,
    #[pyo3(from_py_with = typed::hold)] hold: f64,
    #[pyo3(from_py_with = typed::bin)] bin: f64,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    params: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::mcap)] mcap: bool,
    progress: Option<Py<PyAny>>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    firmware: Option<&Bound<'_, PyAny>>,
    virtual_board: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::board_pace)] board_pace: Option<f64>,
    drive_calibration: Option<&Bound<'_, PyAny>>,
) -> PyResult<HilResult> {
    use sandjumper_core::intrusion::{MAX_HOLD_S, MAX_INTRUSION_SPEED_M_S};
    use sandjumper_rig::tool::intrude::{
        CurvePoint, IntrudeOutcome, IntrudeRequest, parse_bounded,
    };
    let target = target(
        (link, port),
        (firmware, virtual_board),
        board_pace,
        drive_calibration,
    )?;
    let bounded = |name: &str, what: &'static str, lo: f64, hi: f64, value: f64| {
        checked(name, value, parse_bounded(what, lo, hi))
    };
    let (model, params) = rig_params(&model, phi, params)?;
    let request = IntrudeRequest {
        target,
        start_m: bounded("start", "start position (m)", -0.025, 0.025, start)?,
        depth_m: bounded("depth", "depth (m)", 0.0, 0.05, depth)?,
        withdraw_m: bounded("withdraw", "withdrawal (m)", 0.0, 0.05, withdraw)?,
        reintrusion_depth_m: bounded(
            "reintrusion_depth",
            "re-intrusion depth (m)",
            0.0,
            0.05,
            reintrusion_depth,
        )?,
        speed_m_s: bounded("speed", "speed (m/s)", 0.0, MAX_INTRUSION_SPEED_M_S, speed)?,
        hold_s: bounded("hold", "hold (s)", 0.0, MAX_HOLD_S, hold)?,
        bin_m: bounded("bin", "bin (m)", 1e-6, 0.005, bin)?,
        model,
        params,
    };
    let mut names = TARGET_NAMES.to_vec();
    names.extend([
        ("--start", "start"),
        ("--depth", "depth"),
        ("--withdraw", "withdraw"),
        ("--reintrusion-depth", "reintrusion_depth"),
        ("--speed", "speed"),
        ("--hold", "hold"),
        ("--bin", "bin"),
    ]);
    fn curve(points: &[CurvePoint]) -> Vec<(&'static str, Vec<f64>)> {
        vec![
            ("depth_m", points.iter().map(|p| p.depth_m).collect()),
            ("force_n", points.iter().map(|p| p.force_n).collect()),
        ]
    }
    run_program(
        py,
        "intrusion",
        &request,
        out,
        mcap,
        progress,
        &names,
        |o: &IntrudeOutcome| {
            vec![
                ("intrusion", curve(&o.intrusion)),
                ("reintrusion", curve(&o.reintrusion)),
            ]
        },
    )
}

/// A recorded motor trajectory (an acquisition `log`, as `sandjumper rig replay LOG` does) or a
/// stroke file (`stroke`, as `rig replay --stroke FILE`) run on the rig: edited by `scale`,
/// `time_stretch` and `clip` (`(start_s, end_s)` from the log's first sample), resampled at
/// `table_rate` (Hz, 10..=10000), checked against the rig's limits before anything is sent,
/// uploaded and run. The controller as [`rig_jump`]'s. Returns [`HilResult`] with
/// `tables["table"]` (`t_s`, `p_m`: what was uploaded); a run with a fault raises
/// [`RunNotCompleted`].
#[pyfunction]
#[pyo3(signature = (log = None, stroke = None, link = None, scale = 1.0, time_stretch = 1.0, clip = None, table_rate = None, allow_gaps = false, model = "eq4".to_string(), phi = 0.57, params = None, out = None, mcap = false, progress = None, port = None, firmware = None, virtual_board = None, board_pace = None, drive_calibration = None))]
#[allow(clippy::too_many_arguments)]
pub fn rig_replay(
    py: Python<'_>,
    log: Option<&Bound<'_, PyAny>>,
    stroke: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = typed::scale)] scale: f64,
    #[pyo3(from_py_with = typed::time_stretch)] time_stretch: f64,
    #[pyo3(from_py_with = typed::clip)] clip: Option<(f64, f64)>,
    #[pyo3(from_py_with = typed::table_rate)] table_rate: Option<i64>,
    #[pyo3(from_py_with = typed::allow_gaps)] allow_gaps: bool,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    params: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::mcap)] mcap: bool,
    progress: Option<Py<PyAny>>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    firmware: Option<&Bound<'_, PyAny>>,
    virtual_board: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::board_pace)] board_pace: Option<f64>,
    drive_calibration: Option<&Bound<'_, PyAny>>,
) -> PyResult<HilResult> {
    use sandjumper_rig::tool::replay::{
        ReplayOutcome, ReplayRequest, ReplaySource, parse_clip, parse_factor,
    };
    let target = target(
        (link, port),
        (firmware, virtual_board),
        board_pace,
        drive_calibration,
    )?;
    let (log, stroke) = (opt_path("log", log)?, opt_path("stroke", stroke)?);
    match (&log, &stroke) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "the argument 'log' cannot be used with 'stroke'",
            ));
        }
        (None, None) => return Err(crate::errors::required("log (or stroke)")),
        _ => {}
    }
    let clip = clip
        .map(|(a, b)| checked("clip", format!("{a}:{b}"), parse_clip))
        .transpose()?;
    let table_rate_hz = table_rate
        .map(|r| match u32::try_from(r) {
            Ok(r) if (10..=10_000).contains(&r) => Ok(r),
            _ => Err(crate::errors::invalid_value("table_rate", r, "10..=10000")),
        })
        .transpose()?;
    let (model, params) = rig_params(&model, phi, params)?;
    let mut names = TARGET_NAMES.to_vec();
    names.extend([
        ("--stroke", "stroke"),
        ("--scale", "scale"),
        ("--time-stretch", "time_stretch"),
        ("--clip", "clip"),
        ("--table-rate", "table_rate"),
        ("--allow-gaps", "allow_gaps"),
    ]);
    let (source, source_name) = ReplaySource::read(log.as_deref(), stroke.as_deref(), allow_gaps)
        .map_err(|e| lib_err(e, &names))?;
    let request = ReplayRequest {
        target,
        source,
        source_name,
        scale: checked("scale", scale, parse_factor("scale"))?,
        time_stretch: checked("time_stretch", time_stretch, parse_factor("time stretch"))?,
        clip,
        table_rate_hz,
        model,
        params,
    };
    run_program(
        py,
        "replay",
        &request,
        out,
        mcap,
        progress,
        &names,
        |o: &ReplayOutcome| {
            let rate = o.plan.rate_hz;
            let n = o.plan.samples.len();
            vec![(
                "table",
                vec![
                    ("t_s", (0..n).map(|i| i as f64 / rate).collect()),
                    (
                        "p_m",
                        o.plan.samples.iter().map(|&p| f64::from(p)).collect(),
                    ),
                ],
            )]
        },
    )
}

/// Set the drive's force calibration on the controller, as `sandjumper rig
/// calibrate-drive` does: `zero_code` (the DAC code at 0 V) and `codes_per_newton`; `save`:
/// also write it as a calibration file (`--drive-calibration FILE.toml` loads it at every
/// start). Returns `{"link", "zero_code", "codes_per_newton"}` as the controller accepted it.
#[pyfunction]
#[pyo3(signature = (zero_code, codes_per_newton, link = None, port = None, save = None, firmware = None, virtual_board = None, board_pace = None))]
#[allow(clippy::too_many_arguments)]
pub fn rig_calibrate_drive(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::zero_code)] zero_code: i64,
    codes_per_newton: f32,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    save: Option<&Bound<'_, PyAny>>,
    firmware: Option<&Bound<'_, PyAny>>,
    virtual_board: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::board_pace)] board_pace: Option<f64>,
) -> PyResult<Py<PyAny>> {
    use sandjumper_rig::tool::calibrate::{CalibrateRequest, calibrate};
    let request = CalibrateRequest {
        target: target((link, port), (firmware, virtual_board), board_pace, None)?,
        zero_code: u16::try_from(zero_code).map_err(|_| {
            crate::errors::invalid_value("zero_code", zero_code, "a DAC code, 0..=4095")
        })?,
        codes_per_newton,
        save: opt_path("save", save)?,
    };
    let mut names = TARGET_NAMES.to_vec();
    names.extend([
        ("--zero-code", "zero_code"),
        ("--codes-per-newton", "codes_per_newton"),
        ("--save", "save"),
    ]);
    let done = py
        .detach(|| calibrate(&request, &sandjumper_output::Silent))
        .map_err(|e| lib_err(e, &names))?;
    let d = PyDict::new(py);
    d.set_item("link", &done.link)?;
    d.set_item("zero_code", done.calibration.zero_code)?;
    d.set_item("codes_per_newton", done.calibration.codes_per_newton)?;
    Ok(d.into_any().unbind())
}

/// Acknowledge the controller's reset (a watchdog or a fault reset) so that it allows Arm
/// again, as `sandjumper rig acknowledge-reset` does. Returns `{"link", "reset_cause"}`.
#[pyfunction]
#[pyo3(signature = (link = None, port = None, firmware = None, virtual_board = None, board_pace = None))]
pub fn rig_acknowledge_reset(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    firmware: Option<&Bound<'_, PyAny>>,
    virtual_board: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::board_pace)] board_pace: Option<f64>,
) -> PyResult<Py<PyAny>> {
    let target = target((link, port), (firmware, virtual_board), board_pace, None)?;
    let done = py
        .detach(|| {
            sandjumper_rig::tool::calibrate::acknowledge_reset(&target, &sandjumper_output::Silent)
        })
        .map_err(|e| lib_err(e, &TARGET_NAMES))?;
    let d = PyDict::new(py);
    d.set_item("link", &done.link)?;
    d.set_item("reset_cause", summary_to_py(py, &done.reset_cause)?)?;
    Ok(d.into_any().unbind())
}

/// Write the F407 firmware to the board on `port` with the probe-rs program (`probe_rs`), as
/// `sandjumper rig flash --port PORT` does (`firmware`: the ELF, the release build by
/// default). A simulated link has nothing to flash. Returns `{"flashed": bool, "elf",
/// "port", "why"}` (`why`: what a simulated link says instead).
#[pyfunction]
#[pyo3(signature = (port = None, link = None, firmware = None, probe_rs = None))]
pub fn rig_flash(
    py: Python<'_>,
    #[pyo3(from_py_with = crate::convert::port_opt)] port: Option<String>,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    firmware: Option<&Bound<'_, PyAny>>,
    probe_rs: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    use sandjumper_rig::tool::flash::{FlashRequest, Flashed, flash};
    let request = FlashRequest {
        target: target((link, port), (firmware, None), None, None)?,
        probe_rs: match probe_rs.filter(|p| !p.is_none()) {
            Some(p) => path_arg("probe_rs", p)?,
            None => FlashRequest::default().probe_rs,
        },
    };
    let mut names = TARGET_NAMES.to_vec();
    names.push(("--probe-rs", "probe_rs"));
    let done = py
        .detach(|| flash(&request, &sandjumper_output::Silent))
        .map_err(|e| lib_err(e, &names))?;
    let d = PyDict::new(py);
    match done {
        Flashed::Nothing(why) => {
            d.set_item("flashed", false)?;
            d.set_item("elf", py.None())?;
            d.set_item("port", py.None())?;
            d.set_item("why", why)?;
        }
        Flashed::Board { elf, port } => {
            d.set_item("flashed", true)?;
            d.set_item("elf", elf.display().to_string())?;
            d.set_item("port", port)?;
            d.set_item("why", py.None())?;
        }
    }
    Ok(d.into_any().unbind())
}
