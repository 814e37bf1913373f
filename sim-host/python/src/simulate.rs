//! The simulator from Python: `params`, `jump`, `sweep`, `hil`, `replay`.

use clap::ValueEnum;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySequence, PyString};
use sandjumper_acqlog::{AcqLog, Column};
use sandjumper_cli::cli::args::Command;
use sandjumper_cli::command::args::{
    KindArg, ModelArg, check_freq, check_phi, check_tau, parse_gain_lowering, parse_rtol,
};
use sandjumper_cli::command::resolve::resolve_params;
use sandjumper_model::SeriesRow;
use sandjumper_output::Silent;
use sandjumper_study::series::SERIES_HEADER;
use sandjumper_study::sweep::drive::run_driven;
use sandjumper_study::sweep::{ROW_HEADER, SweepDrive, SweepRequest, SweepSpec, ValueRange};

use crate::argv::Argv;
use crate::convert::{f64_array, i64_array, json_to_py, params_source, py_err, str_array};
use crate::typed;

/// One simulated jump: `summary` (the dict `sandjumper jump --json` prints) and `series`
/// (the columns of `trajectory.csv`, same names, as numpy arrays).
#[pyclass(module = "sandjumper", frozen, get_all)]
pub struct JumpResult {
    /// Request and metrics, same keys and values as `jump --json` (SI units: m, s, N, kg).
    pub summary: Py<PyAny>,
    /// `t_s`, `x_m_m`, `x_r_m`, `x_f_m`, `p_m`, `f_s_n`, `f_gm_n`, `m_a_kg` (float64) and
    /// `mode` (str), one entry per output step.
    pub series: Py<PyAny>,
}

#[pymethods]
impl JumpResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        summary_repr(
            py,
            "JumpResult",
            &self.summary,
            &["kind", "freq_hz", "jump_height_m"],
        )
    }
}

/// A sweep: `columns` (the columns of `sweep.csv` as numpy arrays, for
/// `pandas.DataFrame(result.columns)`) and `failures` (one dict per failed jump, the rows of
/// `failures.csv`).
#[pyclass(module = "sandjumper", frozen, get_all)]
pub struct SweepResult {
    /// `kind`, `model`, `drive` (str) and `phi`, `freq_hz`, `tau_s`, `jump_height_m`,
    /// `final_jump_height_m`, `max_depth_m`, `peak_added_mass_kg`, `peak_motor_force_n`
    /// (float64), one entry per successful jump, in combination order.
    pub columns: Py<PyAny>,
    /// The jumps that could not be simulated, with `error`.
    pub failures: Py<PyAny>,
}

#[pymethods]
impl SweepResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        let rows = self
            .columns
            .bind(py)
            .get_item("phi")
            .and_then(|c| c.len())
            .unwrap_or(0);
        let failed = self.failures.bind(py).len().unwrap_or(0);
        format!("SweepResult({rows} jumps, {failed} failed)")
    }
}

/// One jump through the control loop: `summary` (the dict `sandjumper hil --json` prints),
/// `log` (the acquisition log's columns, what `hil --out` writes as acquisition.csv) and
/// `log_metadata` (its `# key: value` lines).
#[pyclass(module = "sandjumper", frozen, get_all)]
pub struct HilResult {
    /// Request, metrics, ticks, frames lost, faults, wall time.
    pub summary: Py<PyAny>,
    /// `tick`, `encoder_counts`, `flags` (int64; `flags` is -1 where the log has no value),
    /// `t_s`, `position_m`, `p_cmd_m`, `force_cmd_n`, `current_a`, `camera_frame`,
    /// `rod_height_m` (float64, NaN where the log has no value); only the columns the log has.
    pub log: Py<PyAny>,
    /// The log's metadata, values as text.
    pub log_metadata: Py<PyAny>,
}

#[pymethods]
impl HilResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        summary_repr(
            py,
            "HilResult",
            &self.summary,
            &["link", "kind", "jump_height_m", "ticks"],
        )
    }
}

/// `Name(key=value, …)` from a summary dict.
fn summary_repr(py: Python<'_>, name: &str, summary: &Py<PyAny>, keys: &[&str]) -> String {
    let s = summary.bind(py);
    let fields: Vec<String> = keys
        .iter()
        .map(|k| {
            let v = s
                .get_item(k)
                .map_or_else(|_| "?".to_string(), |v| v.to_string());
            format!("{k}={v}")
        })
        .collect();
    format!("{name}({})", fields.join(", "))
}

/// The series of a jump as a dict of numpy arrays named like `trajectory.csv`'s header.
fn series_dict<'py>(py: Python<'py>, rows: &[SeriesRow]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let cols: [fn(&SeriesRow) -> f64; 8] = [
        |r| r.t_s,
        |r| r.x_m,
        |r| r.x_r,
        |r| r.x_f,
        |r| r.p,
        |r| r.f_s,
        |r| r.f_gm,
        |r| r.m_a,
    ];
    for (name, get) in SERIES_HEADER.iter().zip(cols) {
        d.set_item(name, f64_array(py, rows.iter().map(get).collect()))?;
    }
    d.set_item(
        SERIES_HEADER[8],
        str_array(
            py,
            rows.iter().map(|r| r.mode.as_str().to_string()).collect(),
        )?,
    )?;
    Ok(d)
}

/// Reads an optional value of a log row as f64.
type OptionalValue = fn(&sandjumper_acqlog::LogRow) -> Option<f64>;

/// An acquisition log's columns (see [`HilResult::log`]).
pub fn log_columns<'py>(py: Python<'py>, log: &AcqLog) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let has = |c: Column| log.columns.contains(c);
    let opt = |v: Option<f64>| v.unwrap_or(f64::NAN);
    if has(Column::Tick) {
        let ticks = log
            .rows
            .iter()
            .map(|r| r.tick.map_or(-1, |t| t as i64))
            .collect();
        d.set_item("tick", i64_array(py, ticks))?;
    }
    d.set_item(
        "t_s",
        f64_array(py, log.rows.iter().map(|r| r.t_s).collect()),
    )?;
    d.set_item(
        "encoder_counts",
        i64_array(py, log.rows.iter().map(|r| r.encoder_counts).collect()),
    )?;
    d.set_item("position_m", f64_array(py, log.positions_m()))?;
    let floats: [(Column, &str, OptionalValue); 5] = [
        (Column::PCmdM, "p_cmd_m", |r| r.p_cmd_m),
        (Column::ForceCmdN, "force_cmd_n", |r| r.force_cmd_n),
        (Column::CurrentA, "current_a", |r| r.current_a),
        (Column::CameraFrame, "camera_frame", |r| {
            r.camera_frame.map(|f| f as f64)
        }),
        (Column::RodHeightM, "rod_height_m", |r| r.rod_height_m),
    ];
    for (column, name, get) in floats {
        if has(column) {
            d.set_item(
                name,
                f64_array(py, log.rows.iter().map(|r| opt(get(r))).collect()),
            )?;
        }
    }
    if has(Column::Flags) {
        let flags = log
            .rows
            .iter()
            .map(|r| r.flags.map_or(-1, i64::from))
            .collect();
        d.set_item("flags", i64_array(py, flags))?;
    }
    Ok(d)
}

/// The log's metadata lines as a dict of text.
pub fn log_metadata<'py>(py: Python<'py>, log: &AcqLog) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for line in log.meta.to_lines().lines() {
        if let Some((k, v)) = line.strip_prefix("# ").and_then(|l| l.split_once(": ")) {
            d.set_item(k, v)?;
        }
    }
    Ok(d)
}

/// The resolved parameters for packing fraction `phi` with `overrides` on top, as the dict
/// `sandjumper params --phi PHI` prints as TOML (tables `robot`, `drive`, `sand`, `model`;
/// SI units). The dict round-trips: `params(phi, overrides=params(phi)) == params(phi)`, and
/// any function's `params=` takes it.
#[pyfunction]
#[pyo3(signature = (phi = 0.57, overrides = None))]
pub fn params(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    overrides: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let mut argv = Argv::new(&["params"]);
    argv.value("phi", "--phi", phi);
    let Command::Params(a) = argv.parse()? else {
        unreachable!("`sandjumper params` parses as Command::Params")
    };
    let file = params_source("overrides", overrides)?;
    let p = resolve_params(a.phi, file.as_ref()).map_err(|e| argv.error(e))?;
    let value: serde_json::Value = toml::from_str(&p.to_toml())
        .map_err(|e| PyValueError::new_err(format!("parameters: {e}")))?;
    Ok(json_to_py(py, &value.to_string())?.unbind())
}

/// Simulate one jump (docs/model.md's plant, imposed stroke) as `sandjumper jump` does.
///
/// `kind`: `"single"`, `"stutter"` or `"delayed"`; `freq_hz`: forcing frequency, Hz;
/// `model`: `"hard"`, `"eq1-linear"`, `"eq1"` or `"eq4"`; `phi`: packing fraction (presets
/// 0.57..=0.62); `tau_s`: the delayed stutter's delay, s; `params`: overrides (a dict as
/// `params()` returns, or a TOML file path); `rtol`: the integrator's relative tolerance.
#[pyfunction]
#[pyo3(signature = (kind, freq_hz, model = "eq4".to_string(), phi = 0.57, tau_s = None, params = None, rtol = 1e-8))]
#[allow(clippy::too_many_arguments)]
pub fn jump(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::kind)] kind: String,
    #[pyo3(from_py_with = typed::freq_hz)] freq_hz: f64,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    #[pyo3(from_py_with = typed::tau_s)] tau_s: Option<f64>,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::rtol)] rtol: f64,
) -> PyResult<JumpResult> {
    let mut argv = Argv::new(&["jump"]);
    argv.value("kind", "--kind", kind);
    argv.value("freq_hz", "--freq", freq_hz);
    argv.value("model", "--model", model);
    argv.value("phi", "--phi", phi);
    argv.opt("tau_s", "--tau", tau_s);
    argv.value("rtol", "--rtol", rtol);
    let Command::Jump(a) = argv.parse()? else {
        unreachable!("`sandjumper jump` parses as Command::Jump")
    };
    let file = params_source("params", params)?;
    let request = a.request(file.as_ref().map(|f| f.to_library()), true);
    let out = py
        .detach(|| sandjumper_study::jump::run(&request, &Silent))
        .map_err(|e| argv.error(e.into()))?;
    Ok(JumpResult {
        summary: json_to_py(py, &out.json().map_err(|e| argv.error(e.into()))?)?.unbind(),
        series: series_dict(py, &out.simulated.series)?.into_any().unbind(),
    })
}

/// Values of a sweep axis: a number, a sequence of numbers, or a range `"A:B:STEP"` (as the
/// CLI writes it, inclusive), each checked by `check`.
fn axis(
    name: &str,
    obj: &Bound<'_, PyAny>,
    check: fn(f64) -> Result<f64, String>,
) -> PyResult<Vec<f64>> {
    let values: Vec<f64> = if obj.is_instance_of::<PyString>() {
        let spec: String = obj.extract()?;
        ValueRange::parse(&spec)
            .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?
            .values
    } else if let Ok(v) = obj.extract::<f64>() {
        vec![v]
    } else if obj.cast::<PySequence>().is_ok() {
        obj.try_iter()?
            .map(|item| {
                item?.extract::<f64>().map_err(|_| {
                    PyTypeError::new_err(format!("{name}: every value must be a number"))
                })
            })
            .collect::<PyResult<_>>()?
    } else {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a number, a sequence of numbers or a range \"A:B:STEP\", got {}",
            obj.get_type().name()?
        )));
    };
    if values.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{name}: no values (allowed: one or more)"
        )));
    }
    values
        .into_iter()
        .map(|v| check(v).map_err(|e| PyValueError::new_err(format!("{name}: {e}"))))
        .collect()
}

/// Names of a sweep axis: one name or a sequence of names, each one of `T`'s CLI values.
fn names<T: ValueEnum>(name: &str, what: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<T>> {
    let list: Vec<String> = if obj.is_instance_of::<PyString>() {
        vec![obj.extract()?]
    } else if obj.is_instance_of::<PyList>() || obj.cast::<PySequence>().is_ok() {
        obj.extract()
            .map_err(|_| PyTypeError::new_err(format!("{name}: expected {what} names (str)")))?
    } else {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a {what} name or a list of them, got {}",
            obj.get_type().name()?
        )));
    };
    if list.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{name}: no values (allowed: one or more)"
        )));
    }
    let allowed: Vec<String> = T::value_variants()
        .iter()
        .filter_map(|v| v.to_possible_value().map(|p| p.get_name().to_string()))
        .collect();
    list.iter()
        .map(|s| {
            T::from_str(s, false).map_err(|_| {
                PyValueError::new_err(format!(
                    "{name}: `{s}` is not a {what} (allowed: {})",
                    allowed.join(", ")
                ))
            })
        })
        .collect()
}

/// Simulate every combination of kinds, models, packing fractions, delays and frequencies in
/// parallel (as `sandjumper sweep` does), with the GIL released: other Python threads run
/// meanwhile.
///
/// `kinds`, `models`: a name or a list; `freqs_hz` (Hz), `phis`, `taus_s` (s): a number, a
/// list or a range `"A:B:STEP"`; `params`: overrides (dict or TOML path); `link`: `None`
/// (the stroke imposed exactly) or `"sil"` (through the controller and the drive model);
/// `gain_lowering`: with `link="sil"`, the position gain factor during a delay (0..1];
/// `threads`: worker threads (default one per core).
#[pyfunction]
#[pyo3(signature = (kinds, freqs_hz, phis = None, taus_s = None, models = None, params = None, rtol = 1e-8, link = None, gain_lowering = None, threads = None))]
#[allow(clippy::too_many_arguments)]
pub fn sweep(
    py: Python<'_>,
    kinds: &Bound<'_, PyAny>,
    freqs_hz: &Bound<'_, PyAny>,
    phis: Option<&Bound<'_, PyAny>>,
    taus_s: Option<&Bound<'_, PyAny>>,
    models: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::rtol)] rtol: f64,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = typed::gain_lowering)] gain_lowering: Option<f64>,
    #[pyo3(from_py_with = typed::threads)] threads: Option<usize>,
) -> PyResult<SweepResult> {
    let kinds: Vec<KindArg> = names("kinds", "jump kind", kinds)?;
    let models: Vec<ModelArg> = match models {
        Some(m) => names("models", "ground model", m)?,
        None => vec![ModelArg::Eq4],
    };
    let phis = match phis {
        Some(p) => axis("phis", p, check_phi)?,
        None => vec![0.57],
    };
    let taus = match taus_s {
        Some(t) => axis("taus_s", t, check_tau)?,
        None => vec![0.0],
    };
    let freqs = axis("freqs_hz", freqs_hz, check_freq)?;
    let rtol =
        parse_rtol(&rtol.to_string()).map_err(|e| PyValueError::new_err(format!("rtol: {e}")))?;
    let gain_lowering = gain_lowering
        .map(|g| parse_gain_lowering(&g.to_string()))
        .transpose()
        .map_err(|e| PyValueError::new_err(format!("gain_lowering: {e}")))?;
    let drive = match link.as_deref() {
        None if gain_lowering.is_some() => {
            return Err(PyValueError::new_err(
                "gain_lowering needs link=\"sil\" (the imposed stroke has no controller gains)",
            ));
        }
        None => SweepDrive::Kinematic,
        Some("sil") => SweepDrive::Sil { gain_lowering },
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "link: `{other}` is not a sweep link (allowed: None, \"sil\")"
            )));
        }
    };
    let threads = match threads {
        Some(0) | Some(1025..) => {
            return Err(PyValueError::new_err(
                "threads: must be 1..=1024 (or None: one per core)",
            ));
        }
        Some(n) => n,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let spec = SweepSpec {
        kinds: kinds.into_iter().map(Into::into).collect(),
        models: models.into_iter().map(Into::into).collect(),
        phis,
        freqs_hz: freqs,
        taus_s: taus,
        rtol,
        drive,
    };
    let request = SweepRequest {
        spec: spec.clone(),
        params: params_source("params", params)?.map(|f| f.to_library()),
        ..SweepRequest::default()
    };
    let (params_by_phi, _) = request.resolved_params().map_err(|e| py_err(e.into()))?;
    let combos = spec.combinations();
    let outcome = py
        .detach(|| {
            run_driven(&combos, threads, &|| {}, spec.drive, spec.rtol, |c| {
                Ok(&params_by_phi[&c.phi.to_bits()])
            })
        })
        .map_err(pyo3::exceptions::PyRuntimeError::new_err)?;

    let columns = PyDict::new(py);
    let rows = &outcome.rows;
    // Each row once as JSON: its numeric columns by name, as `sweep.csv` writes them.
    let as_json: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| serde_json::to_value(r).unwrap_or_default())
        .collect();
    for name in ROW_HEADER {
        let column = match name {
            "kind" => str_array(py, rows.iter().map(|r| r.kind.clone()).collect())?,
            "model" => str_array(py, rows.iter().map(|r| r.model.clone()).collect())?,
            "drive" => str_array(py, rows.iter().map(|r| r.drive.clone()).collect())?,
            _ => {
                let values = as_json
                    .iter()
                    .map(|r| {
                        r.get(name)
                            .and_then(serde_json::Value::as_f64)
                            .unwrap_or(f64::NAN)
                    })
                    .collect();
                f64_array(py, values)
            }
        };
        columns.set_item(name, column)?;
    }
    let failures = PyList::empty(py);
    for f in &outcome.failures {
        let text = serde_json::to_string(f)
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        failures.append(json_to_py(py, &text)?)?;
    }
    Ok(SweepResult {
        columns: columns.into_any().unbind(),
        failures: failures.into_any().unbind(),
    })
}

/// Run one jump through the control loop against the simulated rig, as `sandjumper hil`
/// does: `link="sil"` (the core in this process), `"pil"` (the real firmware in QEMU;
/// `firmware` is its ELF) or `"serial:PATH"` (a board). The GIL is released meanwhile.
///
/// `gain_lowering`: position gain factor during a delay (0..1]; `rtol`: the plant's tolerance
/// inside each control period (default 1e-6); `camera_fps`: frames/s (0: none);
/// `encoder_noise`: counts (standard deviation, seeded).
#[pyfunction]
#[pyo3(signature = (kind, freq_hz, link = "sil".to_string(), tau_s = None, gain_lowering = None, model = "eq4".to_string(), phi = 0.57, params = None, rtol = None, camera_fps = 200, encoder_noise = 0.0, firmware = None))]
#[allow(clippy::too_many_arguments)]
pub fn hil(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::kind)] kind: String,
    #[pyo3(from_py_with = typed::freq_hz)] freq_hz: f64,
    #[pyo3(from_py_with = typed::link)] link: String,
    #[pyo3(from_py_with = typed::tau_s)] tau_s: Option<f64>,
    #[pyo3(from_py_with = typed::gain_lowering)] gain_lowering: Option<f64>,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::rtol_opt)] rtol: Option<f64>,
    #[pyo3(from_py_with = typed::camera_fps)] camera_fps: i64,
    #[pyo3(from_py_with = typed::encoder_noise)] encoder_noise: f64,
    firmware: Option<&Bound<'_, PyAny>>,
) -> PyResult<HilResult> {
    let mut argv = Argv::new(&["hil"]);
    argv.value("link", "--link", link);
    argv.value("kind", "--kind", kind);
    argv.value("freq_hz", "--freq", freq_hz);
    argv.opt("tau_s", "--tau", tau_s);
    argv.opt("gain_lowering", "--gain-lowering", gain_lowering);
    argv.value("model", "--model", model);
    argv.value("phi", "--phi", phi);
    argv.opt("rtol", "--rtol", rtol);
    argv.value("camera_fps", "--camera-fps", camera_fps);
    argv.value("encoder_noise", "--encoder-noise", encoder_noise);
    if let Some(f) = firmware {
        let path = crate::convert::path_arg("firmware", f)?;
        argv.value("firmware", "--firmware", path.display());
    }
    let Command::Hil(a) = argv.parse()? else {
        unreachable!("`sandjumper hil` parses as Command::Hil")
    };
    let file = params_source("params", params)?;
    let params = resolve_params(a.phi, file.as_ref()).map_err(|e| argv.error(e))?;
    let request = a.request(params).map_err(|e| argv.error(e))?;
    let run = py
        .detach(|| {
            request.validate()?;
            let jump = sandjumper_rig::hil_command::run_checked(
                &request,
                &sandjumper_output::Silent,
                None,
            )?;
            Ok((jump.json()?, jump.acquisition_log()))
        })
        .map_err(|e: sandjumper_rig::RigError| argv.error(e.into()))?;
    let (json, log) = run;
    Ok(HilResult {
        summary: json_to_py(py, &json)?.unbind(),
        log: log_columns(py, &log)?.into_any().unbind(),
        log_metadata: log_metadata(py, &log)?.into_any().unbind(),
    })
}

/// Replay an acquisition log's encoder record in the simulator (the paper's method), as
/// `sandjumper replay` does: a CSV log path; `phi` defaults to the log's; `window_ms`: the
/// Savitzky-Golay window for p'' (default 1 ms); `allow_gaps`: interpolate missing samples.
#[pyfunction]
#[pyo3(signature = (log, model = "eq4".to_string(), phi = None, params = None, rtol = 1e-8, window_ms = None, allow_gaps = false))]
#[allow(clippy::too_many_arguments)]
pub fn replay(
    py: Python<'_>,
    log: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi_opt)] phi: Option<f64>,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::rtol)] rtol: f64,
    #[pyo3(from_py_with = typed::window_ms)] window_ms: Option<f64>,
    #[pyo3(from_py_with = typed::allow_gaps)] allow_gaps: bool,
) -> PyResult<JumpResult> {
    let path = crate::convert::path_arg("log", log)?;
    let mut argv = Argv::new(&["replay"]);
    argv.positional("log", "LOG", path.display());
    argv.value("model", "--model", model);
    argv.opt("phi", "--phi", phi);
    argv.value("rtol", "--rtol", rtol);
    argv.opt("window_ms", "--window-ms", window_ms);
    argv.switch("allow_gaps", "--allow-gaps", allow_gaps);
    let Command::Replay(a) = argv.parse()? else {
        unreachable!("`sandjumper replay` parses as Command::Replay")
    };
    let file = params_source("params", params)?;
    let request = a.request(file.as_ref().map(|f| f.to_library()), true);
    let log = request.read_log().map_err(|e| argv.error(e.into()))?;
    let out = py
        .detach(|| sandjumper_study::replay::run_log(&request, &log, &Silent))
        .map_err(|e| argv.error(e.into()))?;
    Ok(JumpResult {
        summary: json_to_py(py, &out.json().map_err(|e| argv.error(e.into()))?)?.unbind(),
        series: series_dict(py, &out.replayed.outcome.series)?
            .into_any()
            .unbind(),
    })
}
