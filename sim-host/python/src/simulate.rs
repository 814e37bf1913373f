//! The simulator from Python: `params`, `jump`, `sweep`, `hil`, `replay`, `fit`.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PySequence, PyString};
use sandjumper_acqlog::{AcqLog, Column};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::SeriesRow;
use sandjumper_model::params::ModelName;
use sandjumper_model::resolve::resolve_params;
use sandjumper_output::parse::{check_freq, check_phi, check_tau, parse_gain_lowering, parse_rtol};
use sandjumper_study::series::SERIES_HEADER;
use sandjumper_study::sweep::SweepRequest;
use sandjumper_study::sweep::{ROW_HEADER, SweepDrive, SweepSpec, ValueRange};

use crate::call::long_call;
use crate::convert::{f64_array, i64_array, json_to_py, out_arg, params_source, str_array};
use crate::errors::{checked, checked_number, choice, lib_err, required};
use crate::typed;

/// The jump kinds by their command-line names.
pub const KINDS: [(&str, JumpKind); 3] = [
    ("single", JumpKind::Single),
    ("stutter", JumpKind::Stutter),
    ("delayed", JumpKind::DelayedStutter),
];

/// The ground models by their command-line names.
pub fn models() -> Vec<(&'static str, ModelName)> {
    ModelName::ALL.iter().map(|m| (m.as_str(), *m)).collect()
}

/// The flags of the simulator's commands and the Python arguments that carry them.
const JUMP_NAMES: [(&str, &str); 7] = [
    ("--freq", "freq_hz"),
    ("--tau", "tau_s"),
    ("--phi", "phi"),
    ("--kind", "kind"),
    ("--model", "model"),
    ("--rtol", "rtol"),
    ("--params", "params"),
];

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
    /// What the program measured besides its log, each a dict of float64 arrays named like
    /// its CSV's header: `rig_intrude`'s `intrusion` and `reintrusion` (`depth_m`, `force_n`),
    /// `rig_replay`'s `table` (`t_s`, `p_m`: what was uploaded); empty for a jump.
    pub tables: Py<PyAny>,
}

impl HilResult {
    /// A run's summary (its `--json` text) and its acquisition log.
    pub fn new(py: Python<'_>, json: &str, log: &AcqLog) -> PyResult<Self> {
        Self::with_tables(py, json, log, Vec::new())
    }

    /// [`HilResult::new`] with the `tables` the program measured (name, columns).
    pub fn with_tables(
        py: Python<'_>,
        json: &str,
        log: &AcqLog,
        tables: Vec<crate::rig::Table>,
    ) -> PyResult<Self> {
        let dict = PyDict::new(py);
        for (name, columns) in tables {
            let table = PyDict::new(py);
            for (column, values) in columns {
                table.set_item(column, crate::convert::f64_array(py, values))?;
            }
            dict.set_item(name, table)?;
        }
        Ok(Self {
            summary: json_to_py(py, json)?.unbind(),
            log: log_columns(py, log)?.into_any().unbind(),
            log_metadata: log_metadata(py, log)?.into_any().unbind(),
            tables: dict.into_any().unbind(),
        })
    }
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
    let phi = checked_number("phi", phi, check_phi)?;
    let file = params_source("overrides", overrides)?;
    let p = resolve_params(phi, file.as_ref()).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let value: serde_json::Value = toml::from_str(&p.to_toml())
        .map_err(|e| PyValueError::new_err(format!("parameters: {e}")))?;
    Ok(json_to_py(py, &value.to_string())?.unbind())
}

/// Simulate one jump (docs/model.md's plant, imposed stroke) as `sandjumper jump` does, in
/// memory; `out` (a folder) also writes what `jump --out` writes.
///
/// `kind`: `"single"`, `"stutter"` or `"delayed"`; `freq_hz`: forcing frequency, Hz;
/// `model`: `"hard"`, `"eq1-linear"`, `"eq1"` or `"eq4"`; `phi`: packing fraction (presets
/// 0.57..=0.62); `tau_s`: the delayed stutter's delay, s; `params`: overrides (a dict as
/// `params()` returns, or a TOML file path); `rtol`: the integrator's relative tolerance;
/// `stroke`: a stroke file (`t_s,p_m`, e.g. `optimize`'s stroke.csv) run instead of a sine.
#[pyfunction]
#[pyo3(signature = (kind = None, freq_hz = None, model = "eq4".to_string(), phi = 0.57, tau_s = None, params = None, rtol = 1e-8, stroke = None, out = None))]
#[allow(clippy::too_many_arguments)]
pub fn jump(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::kind_opt)] kind: Option<String>,
    #[pyo3(from_py_with = typed::freq_hz_opt)] freq_hz: Option<f64>,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    #[pyo3(from_py_with = typed::tau_s)] tau_s: Option<f64>,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::rtol)] rtol: f64,
    stroke: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
) -> PyResult<JumpResult> {
    let stroke = crate::convert::opt_path("stroke", stroke)?;
    let (kind, freq_hz, tau_s) = sine("kind", "freq_hz", kind, freq_hz, tau_s, stroke.is_some())?;
    let request = sandjumper_study::jump::JumpRequest {
        kind,
        freq_hz,
        tau_s,
        stroke,
        model: choice("model", &model, &models())?,
        phi: checked_number("phi", phi, check_phi)?,
        params: params_source("params", params)?,
        rtol: checked("rtol", rtol, parse_rtol)?,
        record_series: true,
    };
    let out = out_arg(out)?;
    let (outcome, _) = py
        .detach(|| {
            sandjumper_study::jump::run_into(&request, out.as_deref(), &sandjumper_output::Silent)
        })
        .map_err(|e| lib_err(e, &JUMP_NAMES))?;
    let json = outcome.json().map_err(|e| lib_err(e, &[]))?;
    Ok(JumpResult {
        summary: json_to_py(py, &json)?.unbind(),
        series: series_dict(py, &outcome.simulated.series)?
            .into_any()
            .unbind(),
    })
}

/// The one-cycle sine a jump asks for: its kind, frequency and delay, each checked as the
/// command line checks them (`kind` and `freq_hz` required unless a stroke file replaces the
/// sine; a delayed stutter needs `tau_s`).
pub fn sine(
    kind_name: &str,
    freq_name: &str,
    kind: Option<String>,
    freq_hz: Option<f64>,
    tau_s: Option<f64>,
    stroke: bool,
) -> PyResult<(JumpKind, f64, Option<f64>)> {
    if stroke {
        if kind.is_some() || freq_hz.is_some() || tau_s.is_some() {
            return Err(PyValueError::new_err(format!(
                "stroke cannot be used with {kind_name}, {freq_name} or tau_s (the stroke file replaces the sine)"
            )));
        }
        return Ok((JumpKind::Single, 0.0, None));
    }
    let kind = kind.ok_or_else(|| required(kind_name))?;
    let kind = choice(kind_name, &kind, &KINDS)?;
    let freq_hz = freq_hz.ok_or_else(|| required(freq_name))?;
    let freq_hz = checked_number(freq_name, freq_hz, check_freq)?;
    let tau_s = tau_s
        .map(|t| checked_number("tau_s", t, check_tau))
        .transpose()?;
    if kind == JumpKind::DelayedStutter && tau_s.is_none() {
        return Err(required("tau_s"));
    }
    Ok((kind, freq_hz, tau_s))
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

/// Names of a sweep axis: one name or a sequence of names, each one of `allowed`.
fn names<T: Copy>(
    name: &str,
    what: &str,
    obj: &Bound<'_, PyAny>,
    allowed: &[(&str, T)],
) -> PyResult<Vec<T>> {
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
    list.iter()
        .map(|s| {
            allowed
                .iter()
                .find(|(n, _)| n == s)
                .map(|(_, v)| *v)
                .ok_or_else(|| {
                    let names: Vec<&str> = allowed.iter().map(|(n, _)| *n).collect();
                    PyValueError::new_err(format!(
                        "{name}: `{s}` is not a {what} (allowed: {})",
                        names.join(", ")
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
/// `threads`: worker threads (default one per core); `out`: also write what `sweep --out`
/// writes into this folder; `progress`: `progress(stage, done, total)` called as the jumps
/// finish. Ctrl-C stops the sweep between jumps and raises `KeyboardInterrupt`.
#[pyfunction]
#[pyo3(signature = (kinds, freqs_hz, phis = None, taus_s = None, models = None, params = None, rtol = 1e-8, link = None, gain_lowering = None, threads = None, out = None, progress = None))]
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
    out: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<SweepResult> {
    let request = sweep_request(
        (kinds, freqs_hz, phis, taus_s, models, params),
        rtol,
        link,
        gain_lowering,
        threads,
    )?;
    let staged = crate::convert::claim_out(out)?;
    let outcome = long_call(py, progress, |progress| {
        let outcome = sandjumper_study::sweep::run(&request, progress)?;
        if let Some(staged) = staged {
            outcome.write_into(&staged)?;
            staged.commit()?;
        }
        // What the command line prints after its report (a drive near its peak force).
        for line in outcome.warnings() {
            sandjumper_output::Progress::note(progress, &line);
        }
        Ok(outcome)
    })?
    .map_err(|e: sandjumper_study::StudyError| lib_err(e, &[]))?;

    sweep_result(py, &outcome.outcome)
}

/// The axes of a sweep as Python gives them: kinds, freqs_hz, phis, taus_s, models, params.
type SweepAxes<'a, 'py> = (
    &'a Bound<'py, PyAny>,
    &'a Bound<'py, PyAny>,
    Option<&'a Bound<'py, PyAny>>,
    Option<&'a Bound<'py, PyAny>>,
    Option<&'a Bound<'py, PyAny>>,
    Option<&'a Bound<'py, PyAny>>,
);

/// [`sweep`]'s arguments as the library's checked request.
fn sweep_request(
    (kinds, freqs_hz, phis, taus_s, models, params): SweepAxes<'_, '_>,
    rtol: f64,
    link: Option<String>,
    gain_lowering: Option<f64>,
    threads: Option<usize>,
) -> PyResult<SweepRequest> {
    let kinds: Vec<JumpKind> = names("kinds", "jump kind", kinds, &KINDS)?;
    let models: Vec<ModelName> = match models {
        Some(m) => names("models", "ground model", m, &self::models())?,
        None => vec![ModelName::Eq4],
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
    if let Some(0 | 1025..) = threads {
        return Err(PyValueError::new_err(
            "threads: must be 1..=1024 (or None: one per core)",
        ));
    }
    let request = SweepRequest {
        spec: SweepSpec {
            kinds,
            models,
            phis,
            freqs_hz: freqs,
            taus_s: taus,
            rtol,
            drive,
        },
        params: params_source("params", params)?,
        threads,
        shard: None,
    };
    request.validate().map_err(|e| lib_err(e, &[]))?;
    Ok(request)
}

/// [`sweep`] on a Slurm cluster, as `sandjumper sweep --slurm TASKS --out OUT` does: a job
/// array of `tasks` tasks, each running one shard with `cpus_per_task` threads through
/// `program` (the `sandjumper` binary on the cluster's shared file system; default: the one
/// on `PATH`), in `partition` with the time limit `time` (Slurm's format, e.g. `"30"`,
/// `"1:00:00"`). With `wait` (the default) the call waits for the job (the GIL released;
/// Ctrl-C stops waiting, the job runs on) and merges the shards into `out`. Returns
/// `{"job_id", "dir": the job's folder, "result": the merged SweepResult, or None without
/// wait}`.
#[pyfunction]
#[pyo3(signature = (tasks, kinds, freqs_hz, out, phis = None, taus_s = None, models = None, params = None, rtol = 1e-8, link = None, gain_lowering = None, cpus_per_task = 1, partition = None, time = "1:00:00".to_string(), wait = true, program = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn sweep_slurm(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::tasks)] tasks: i64,
    kinds: &Bound<'_, PyAny>,
    freqs_hz: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    phis: Option<&Bound<'_, PyAny>>,
    taus_s: Option<&Bound<'_, PyAny>>,
    models: Option<&Bound<'_, PyAny>>,
    params: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::rtol)] rtol: f64,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    #[pyo3(from_py_with = typed::gain_lowering)] gain_lowering: Option<f64>,
    #[pyo3(from_py_with = typed::cpus_per_task)] cpus_per_task: i64,
    partition: Option<String>,
    time: String,
    wait: bool,
    program: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    use sandjumper_study::sweep::cluster::{SlurmSweepOutcome, SlurmSweepRequest, run_on_slurm};
    let sweep = sweep_request(
        (kinds, freqs_hz, phis, taus_s, models, params),
        rtol,
        link,
        gain_lowering,
        None,
    )?;
    let program = program_on_path(py, program)?;
    let count = |name: &str, v: i64| {
        u32::try_from(v).map_err(|_| crate::errors::invalid_value(name, v, "a count, 1 or more"))
    };
    let request = SlurmSweepRequest {
        sweep,
        tasks: count("tasks", tasks)?,
        cpus_per_task: count("cpus_per_task", cpus_per_task)?,
        queue: sandjumper_slurm::QueueOptions {
            partition,
            time,
            nodes: None,
            no_wait: !wait,
        },
        program,
        out: crate::convert::path_arg("out", out)?,
    };
    let names = [
        ("--phi", "phis"),
        ("--freq", "freqs_hz"),
        ("--tau", "taus_s"),
        ("--slurm-cpus", "cpus_per_task"),
        ("--slurm-partition", "partition"),
        ("--slurm-time", "time"),
        ("--slurm", "tasks"),
        ("--shard", "shard"),
        ("--out", "out"),
    ];
    let outcome = long_call(py, progress, |progress| run_on_slurm(&request, progress))?
        .map_err(|e| lib_err(e, &names))?;
    let d = PyDict::new(py);
    match outcome {
        SlurmSweepOutcome::Queued { id, dir } => {
            d.set_item("job_id", id)?;
            d.set_item("dir", dir.display().to_string())?;
            d.set_item("result", py.None())?;
        }
        SlurmSweepOutcome::Merged { id, merged, .. } => {
            d.set_item("job_id", id)?;
            d.set_item(
                "dir",
                std::path::absolute(sandjumper_slurm::job_dir(&request.out))
                    .unwrap_or_else(|_| sandjumper_slurm::job_dir(&request.out))
                    .display()
                    .to_string(),
            )?;
            d.set_item("result", Py::new(py, sweep_result(py, &merged.outcome)?)?)?;
        }
    }
    Ok(d.into_any().unbind())
}

/// The `sandjumper` binary a Slurm job runs: `program` when given, else the one on `PATH`.
pub fn program_on_path(
    py: Python<'_>,
    program: Option<&Bound<'_, PyAny>>,
) -> PyResult<std::path::PathBuf> {
    match program.filter(|p| !p.is_none()) {
        Some(p) => crate::convert::path_arg("program", p),
        None => {
            let found = py
                .import("shutil")?
                .call_method1("which", ("sandjumper",))?;
            if found.is_none() {
                return Err(PyValueError::new_err(
                    "program: no `sandjumper` on PATH for the tasks to run (give program= the \
                     binary's path on the cluster's shared file system)",
                ));
            }
            Ok(found.extract::<String>()?.into())
        }
    }
}

/// A sweep's rows and failures as [`SweepResult`] (`sweep.csv`'s and `failures.csv`'s
/// columns).
fn sweep_result(
    py: Python<'_>,
    outcome: &sandjumper_study::sweep::SweepOutcome,
) -> PyResult<SweepResult> {
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
            _ => f64_array(py, crate::convert::number_column(&as_json, name)),
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

/// Merge the folders of a sweep's shards (each `sweep --shard K/N`'s `out`) into `out`, as
/// `sandjumper merge DIR... --out OUT` does: every combination checked present once, the
/// shards of one sweep only. Returns the merged sweep as [`SweepResult`].
#[pyfunction]
pub fn sweep_merge(
    py: Python<'_>,
    dirs: Vec<std::path::PathBuf>,
    out: &Bound<'_, PyAny>,
) -> PyResult<SweepResult> {
    let request = sandjumper_study::sweep::MergeRequest {
        dirs,
        out: crate::convert::path_arg("out", out)?,
    };
    let merged = py
        .detach(|| {
            let merged = sandjumper_study::sweep::merge(&request, &sandjumper_output::Silent)?;
            merged.write(&request.out)?;
            Ok(merged)
        })
        .map_err(|e: sandjumper_study::StudyError| lib_err(e, &[("--out", "out")]))?;
    sweep_result(py, &merged.outcome)
}

/// Run one jump through the control loop against the simulated rig, as `sandjumper hil`
/// does: `link="sil"` (the core in this process), `"pil"` (the real firmware in QEMU;
/// `firmware` is its ELF) or `"serial:PATH"` (a board). The GIL is released meanwhile.
///
/// `gain_lowering`: position gain factor during a delay (0..1]; `rtol`: the plant's tolerance
/// inside each control period (default 1e-6); `camera_fps`: frames/s (0: none);
/// `encoder_noise`: counts (standard deviation, seeded).
#[pyfunction]
#[pyo3(signature = (kind = None, freq_hz = None, link = "sil".to_string(), tau_s = None, gain_lowering = None, model = "eq4".to_string(), phi = 0.57, params = None, rtol = None, camera_fps = 200, encoder_noise = 0.0, firmware = None, stroke = None, progress = None, camera = None, out = None, mcap = false))]
#[allow(clippy::too_many_arguments)]
pub fn hil(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::kind_opt)] kind: Option<String>,
    #[pyo3(from_py_with = typed::freq_hz_opt)] freq_hz: Option<f64>,
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
    stroke: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    camera: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::mcap)] mcap: bool,
) -> PyResult<HilResult> {
    use sandjumper_rig::hil_command::{self as lib, HilRequest, NamedStroke};
    use sandjumper_rig::tool::output::ProgramOutcome;
    let names = [
        ("--link", "link"),
        ("--gain-lowering", "gain_lowering"),
        ("--camera-fps", "camera_fps"),
        ("--encoder-noise", "encoder_noise"),
        ("--firmware", "firmware"),
        ("--stroke", "stroke"),
        ("--camera", "camera"),
    ];
    let link = checked("link", &link, sandjumper_rig::hil::open::parse_link)?;
    let stroke = crate::convert::opt_path("stroke", stroke)?;
    let (kind, freq_hz, tau_s) = sine("kind", "freq_hz", kind, freq_hz, tau_s, stroke.is_some())?;
    let gain_lowering = gain_lowering
        .map(|g| checked("gain_lowering", g, lib::parse_gain_lowering))
        .transpose()?;
    let model = choice("model", &model, &models())?;
    let phi = checked_number("phi", phi, check_phi)?;
    let rtol = rtol
        .map(|r| checked("rtol", r, lib::parse_rtol))
        .transpose()?;
    let camera_fps = checked("camera_fps", camera_fps, lib::parse_camera_fps)?;
    let encoder_noise = checked("encoder_noise", encoder_noise, lib::parse_encoder_noise)?;
    let firmware = match firmware.filter(|f| !f.is_none()) {
        Some(f) => crate::convert::path_arg("firmware", f)?,
        None => sandjumper_rig::firmware_image::EMULATED_ELF.into(),
    };
    let file = params_source("params", params)?;
    let params =
        resolve_params(phi, file.as_ref()).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let stroke = stroke
        .as_deref()
        .map(NamedStroke::read)
        .transpose()
        .map_err(|e| lib_err(e, &names))?;
    let camera = crate::convert::opt_path("camera", camera)?;
    let mut request = HilRequest {
        link,
        kind,
        freq_hz,
        tau_s,
        gain_lowering,
        model,
        rtol,
        camera_fps,
        encoder_noise_counts: encoder_noise,
        firmware,
        params,
        stroke,
        ..HilRequest::default()
    };
    request.validate().map_err(|e| lib_err(e, &names))?;
    if request.uses_camera() {
        request.camera = sandjumper_rig::hil::camera::read_camera(camera.as_deref())
            .map_err(|e| lib_err(e, &names))?;
    }
    crate::rig::mcap_needs_out(mcap, out)?;
    let staged = crate::convert::claim_out(out)?;
    let (json, log, clean, dir) = long_call(py, progress, |progress| {
        // The warning a setting that does nothing deserves, to Python's logging.
        request.check(progress)?;
        let jump = lib::run_checked(&request, progress, None)?;
        let dir = staged.map(|s| jump.write(s, mcap)).transpose()?;
        Ok((
            jump.json()?,
            jump.acquisition_log(),
            jump.completed_cleanly(),
            dir,
        ))
    })?
    .map_err(|e: sandjumper_rig::RigError| lib_err(e, &names))?;
    let result = HilResult::new(py, &json, &log)?;
    crate::rig::concluded(py, "jump", result, clean, dir)
}

/// Replay an acquisition log's encoder record in the simulator (the paper's method), as
/// `sandjumper replay` does: a CSV log path; `phi` defaults to the log's; `window_ms`: the
/// Savitzky-Golay window for p'' (default 1 ms); `allow_gaps`: interpolate missing samples.
#[pyfunction]
#[pyo3(signature = (log, model = "eq4".to_string(), phi = None, params = None, rtol = 1e-8, window_ms = None, allow_gaps = false, out = None))]
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
    out: Option<&Bound<'_, PyAny>>,
) -> PyResult<JumpResult> {
    use sandjumper_study::replay::{self as lib, ReplayRequest};
    let names = [
        ("--phi", "phi"),
        ("--model", "model"),
        ("--rtol", "rtol"),
        ("--window-ms", "window_ms"),
        ("--allow-gaps", "allow_gaps"),
        ("--params", "params"),
    ];
    let path = crate::convert::path_arg("log", log)?;
    let window_ms = window_ms
        .map(|w| checked("window_ms", w, lib::parse_window_ms))
        .transpose()?;
    let request = ReplayRequest {
        log: path,
        model: choice("model", &model, &models())?,
        phi: phi
            .map(|p| checked_number("phi", p, check_phi))
            .transpose()?,
        params: params_source("params", params)?,
        rtol: checked("rtol", rtol, parse_rtol)?,
        window_s: window_ms.map_or(ReplayRequest::default().window_s, |w| w * 1e-3),
        allow_gaps,
        record_series: true,
    };
    let out = out_arg(out)?;
    let (outcome, _) = py
        .detach(|| lib::run_into(&request, out.as_deref(), &sandjumper_output::Silent))
        .map_err(|e| lib_err(e, &names))?;
    let json = outcome.json().map_err(|e| lib_err(e, &[]))?;
    Ok(JumpResult {
        summary: json_to_py(py, &json)?.unbind(),
        series: series_dict(py, &outcome.replayed.outcome.series)?
            .into_any()
            .unbind(),
    })
}
