//! Between Rust and Python: errors, JSON objects, numpy columns, parameter overrides.

use numpy::PyArray1;
use pyo3::exceptions::{PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use sandjumper_model::resolve::ParamsFile;
use serde::Serialize;

/// A JSON text (one of the libraries' summaries) as Python objects, through `json.loads`: the
/// same keys and values a Python user gets from `json.loads(cli_output)`.
pub fn json_to_py<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

/// A Python object as JSON (through `json.dumps`), for parameter overrides.
fn py_to_json(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    let text: String = obj
        .py()
        .import("json")?
        .call_method1("dumps", (obj,))
        .map_err(|e| PyTypeError::new_err(format!("{name}: cannot be written as TOML: {e}")))?
        .extract()?;
    serde_json::from_str(&text)
        .map_err(|e| PyValueError::new_err(format!("{name}: not a table of parameters: {e}")))
}

/// Drops `null`s (a key left unset) so the rest converts to TOML.
fn without_nulls(v: serde_json::Value) -> Option<serde_json::Value> {
    match v {
        serde_json::Value::Null => None,
        serde_json::Value::Object(map) => Some(serde_json::Value::Object(
            map.into_iter()
                .filter_map(|(k, v)| without_nulls(v).map(|v| (k, v)))
                .collect(),
        )),
        serde_json::Value::Array(items) => Some(serde_json::Value::Array(
            items.into_iter().filter_map(without_nulls).collect(),
        )),
        other => Some(other),
    }
}

/// A dict of overrides (tables `robot`, `drive`, `sand`, `model`, keys as `params()` gives
/// them) as the TOML text of a params file.
pub fn overrides_toml(name: &str, dict: &Bound<'_, PyAny>) -> PyResult<String> {
    if !dict.is_instance_of::<PyDict>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a dict of tables (robot, drive, sand, model), got {}",
            dict.get_type().name()?
        )));
    }
    let json = without_nulls(py_to_json(name, dict)?).unwrap_or_default();
    let table: toml::Table = serde_json::from_value(json)
        .map_err(|e| PyValueError::new_err(format!("{name}: not a table of parameters: {e}")))?;
    toml::to_string(&table).map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// The `params=` argument: `None`, a dict of overrides, or the path of a TOML file (read as
/// the CLI reads `--params`).
pub fn params_source(
    name: &str,
    params: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<ParamsFile>> {
    let Some(p) = params.filter(|p| !p.is_none()) else {
        return Ok(None);
    };
    if p.is_instance_of::<PyDict>() {
        return Ok(Some(ParamsFile {
            path: format!("<{name} dict>").into(),
            text: overrides_toml(name, p)?,
        }));
    }
    let path = path_arg(name, p)?;
    ParamsFile::read(&path)
        .map(Some)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// A library's summary (what `summary.json` holds) as Python objects, the same keys and
/// values `json.loads` gives for the file.
pub fn summary_to_py<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    json_to_py(py, &text)
}

/// The numbers of column `name` of rows serialised as JSON objects (a library's CSV rows),
/// NaN where a row has no number there.
pub fn number_column(rows: &[serde_json::Value], name: &str) -> Vec<f64> {
    rows.iter()
        .map(|r| {
            r.get(name)
                .and_then(serde_json::Value::as_f64)
                .unwrap_or(f64::NAN)
        })
        .collect()
}

/// The `out=` folder claimed before a run (as the command line claims `--out`): one that
/// cannot be written is refused before the run, not after it.
pub fn claim_out(out: Option<&Bound<'_, PyAny>>) -> PyResult<Option<sandjumper_output::StagedDir>> {
    out_arg(out)?
        .map(|dir| sandjumper_output::StagedDir::create(&dir))
        .transpose()
        .map_err(|e| crate::errors::lib_err(e, &[]))
}

/// An optional `out=` folder argument.
pub fn out_arg(out: Option<&Bound<'_, PyAny>>) -> PyResult<Option<std::path::PathBuf>> {
    opt_path("out", out)
}

/// An optional path argument `name` ([`path_arg`]); left out or None: `None`.
pub fn opt_path(
    name: &str,
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<std::path::PathBuf>> {
    obj.filter(|o| !o.is_none())
        .map(|o| path_arg(name, o))
        .transpose()
}

/// A `str` or `os.PathLike` argument as a path.
pub fn path_arg(name: &str, obj: &Bound<'_, PyAny>) -> PyResult<std::path::PathBuf> {
    if obj.is_instance_of::<PyString>() {
        return Ok(obj.extract::<String>()?.into());
    }
    let fspath = obj
        .py()
        .import("os")?
        .call_method1("fspath", (obj,))
        .map_err(|_| {
            PyTypeError::new_err(format!(
                "{name}: expected a path (str or os.PathLike), got {}",
                obj.get_type()
                    .name()
                    .map_or_else(|_| "?".to_string(), |n| n.to_string())
            ))
        })?;
    fspath
        .extract::<String>()
        .map(Into::into)
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected a text path, got bytes")))
}

/// A float64 numpy array.
pub fn f64_array(py: Python<'_>, values: Vec<f64>) -> Bound<'_, PyAny> {
    PyArray1::from_vec(py, values).into_any()
}

/// An int64 numpy array.
pub fn i64_array(py: Python<'_>, values: Vec<i64>) -> Bound<'_, PyAny> {
    PyArray1::from_vec(py, values).into_any()
}

/// A numpy array of strings (`numpy.asarray` of the list: dtype `<U…`).
pub fn str_array<'py>(py: Python<'py>, values: Vec<String>) -> PyResult<Bound<'py, PyAny>> {
    py.import("numpy")?.call_method1("asarray", (values,))
}

/// A board's serial port (`port=`): a `str` or `os.PathLike`, or None.
pub fn port_opt(obj: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    if obj.is_none() {
        return Ok(None);
    }
    Ok(Some(path_arg("port", obj)?.to_string_lossy().into_owned()))
}
