//! The analyses from Python: `track`, `piv`, the DEM (`dem_collide`, `dem_bed`,
//! `dem_intrude`) and acquisition logs (`read_log`, `log_to_mcap`).
//!
//! The folder-writing commands run exactly as on the command line into `out` (a temporary
//! folder, removed afterwards, when `out` is None) and their results come back loaded: the
//! JSON summary as a dict, every CSV table as numpy columns, every `.npy` array as a numpy
//! array.

use std::path::{Path, PathBuf};

use pyo3::exceptions::{PyRuntimeError, PyTypeError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyList, PyString, PyTuple};
use sandjumper_acqlog::check::{self, CheckRequest};
use sandjumper_cli::acqlog::command::LogAction;
use sandjumper_cli::cli::args::Command;
use sandjumper_cli::command::CliError;
use sandjumper_cli::command::progress::Bars;
use sandjumper_cli::dem::command::DemCommand;
use sandjumper_output::Silent;

use crate::argv::Argv;
use crate::convert::{f64_array, json_to_py, path_arg, py_err, str_array};
use crate::simulate::{log_columns, log_metadata};
use crate::typed;

/// What an analysis wrote, loaded: `summary` (its JSON summary), `tables` (each CSV file of
/// the output folder by its stem, as a dict of numpy columns: float64 where every cell is a
/// number or empty (NaN), str otherwise), `arrays` (each `.npy` file by its stem) and `path`
/// (the output folder, or None when it was temporary).
#[pyclass(module = "sandjumper", frozen, get_all)]
pub struct FolderResult {
    /// The command's JSON summary (what `--json` prints or `summary.json` holds).
    pub summary: Py<PyAny>,
    /// CSV tables by file stem.
    pub tables: Py<PyAny>,
    /// `.npy` arrays by file stem (PIV fields are stacks of 2-D arrays: pair, row, column).
    pub arrays: Py<PyAny>,
    /// The output folder, or None.
    pub path: Option<String>,
}

#[pymethods]
impl FolderResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        let keys = |d: &Py<PyAny>| {
            d.bind(py)
                .cast::<PyDict>()
                .map(|d| {
                    d.keys()
                        .iter()
                        .map(|k| k.to_string())
                        .collect::<Vec<_>>()
                        .join(", ")
                })
                .unwrap_or_default()
        };
        let path = self
            .path
            .as_ref()
            .map_or_else(|| "None".to_string(), |p| format!("{p:?}"));
        format!(
            "FolderResult(tables=[{}], arrays=[{}], path={path})",
            keys(&self.tables),
            keys(&self.arrays),
        )
    }
}

/// `**options` as CLI flags: `name=value` is `--name value` (`_` as `-`); `True` is the bare
/// flag, `False` and `None` leave it out; a list or tuple is written comma-separated.
fn add_options(argv: &mut Argv, options: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    let Some(options) = options else {
        return Ok(());
    };
    for (key, value) in options.iter() {
        let key: String = key.extract()?;
        let py_name = key.as_str();
        let flag = format!("--{}", key.replace('_', "-"));
        if value.is_none() {
            continue;
        }
        if value.is_instance_of::<PyBool>() {
            argv.switch(py_name, &flag, value.extract()?);
        } else if let Ok(v) = value.extract::<i64>() {
            argv.value(py_name, &flag, v);
        } else if let Ok(v) = value.extract::<f64>() {
            argv.value(py_name, &flag, v);
        } else if value.is_instance_of::<PyString>() {
            argv.value(py_name, &flag, value.extract::<String>()?);
        } else if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
            let parts: Vec<String> = value
                .try_iter()?
                .map(|item| {
                    let item = item?;
                    if let Ok(v) = item.extract::<i64>() {
                        Ok(v.to_string())
                    } else if let Ok(v) = item.extract::<f64>() {
                        Ok(v.to_string())
                    } else {
                        Err(PyTypeError::new_err(format!(
                            "{key}: every item must be a number"
                        )))
                    }
                })
                .collect::<PyResult<_>>()?;
            argv.value(py_name, &flag, parts.join(","));
        } else if let Ok(path) = path_arg(&key, &value) {
            argv.value(py_name, &flag, path.display());
        } else {
            return Err(PyTypeError::new_err(format!(
                "{key}: expected a number, str, bool, path or list of numbers, got {}",
                value.get_type().name()?
            )));
        }
    }
    Ok(())
}

/// The output folder: `out` as given, or a new temporary one.
fn output_folder(out: Option<&Bound<'_, PyAny>>) -> PyResult<(PathBuf, Option<tempfile::TempDir>)> {
    match out.filter(|o| !o.is_none()) {
        Some(o) => Ok((path_arg("out", o)?, None)),
        None => {
            let tmp = tempfile::tempdir().map_err(|e| {
                PyRuntimeError::new_err(format!("cannot make a temporary folder: {e}"))
            })?;
            Ok((tmp.path().join("out"), Some(tmp)))
        }
    }
}

/// A CSV file as a dict of numpy columns.
fn csv_columns<'py>(py: Python<'py>, path: &Path) -> PyResult<Bound<'py, PyDict>> {
    let fail = |e: &dyn std::fmt::Display| {
        PyRuntimeError::new_err(format!("cannot read `{}`: {e}", path.display()))
    };
    let mut reader = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(false)
        .from_path(path)
        .map_err(|e| fail(&e))?;
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| fail(&e))?
        .iter()
        .map(str::to_string)
        .collect();
    let mut cells: Vec<Vec<String>> = vec![Vec::new(); header.len()];
    for record in reader.records() {
        let record = record.map_err(|e| fail(&e))?;
        for (column, cell) in cells.iter_mut().zip(record.iter()) {
            column.push(cell.to_string());
        }
    }
    let d = PyDict::new(py);
    for (name, column) in header.iter().zip(cells) {
        let numbers: Option<Vec<f64>> = column
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(f64::NAN)
                } else {
                    c.parse::<f64>().ok()
                }
            })
            .collect();
        match numbers {
            Some(v) => d.set_item(name, f64_array(py, v))?,
            None => d.set_item(name, str_array(py, column)?)?,
        }
    }
    Ok(d)
}

/// Loads an output folder: its CSV tables and `.npy` arrays (top level), `summary` given or
/// from `summary.json`.
fn load_folder(
    py: Python<'_>,
    dir: &Path,
    summary_json: Option<&str>,
    keep: bool,
) -> PyResult<FolderResult> {
    let tables = PyDict::new(py);
    let arrays = PyDict::new(py);
    let numpy = py.import("numpy")?;
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot list `{}`: {e}", dir.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for path in entries {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        match path.extension().and_then(|e| e.to_str()) {
            Some("csv") => tables.set_item(&stem, csv_columns(py, &path)?)?,
            Some("npy") => arrays.set_item(
                &stem,
                numpy.call_method1("load", (path.display().to_string(),))?,
            )?,
            _ => {}
        }
    }
    let summary = match summary_json {
        Some(text) => json_to_py(py, text)?,
        None => match std::fs::read_to_string(dir.join("summary.json")) {
            Ok(text) => json_to_py(py, &text)?,
            Err(_) => py.None().into_bound(py),
        },
    };
    Ok(FolderResult {
        summary: summary.unbind(),
        tables: tables.into_any().unbind(),
        arrays: arrays.into_any().unbind(),
        path: keep.then(|| dir.display().to_string()),
    })
}

/// Runs `sandjumper <command> FRAMES --out DIR [options]` (`track` or `piv`; `more` adds
/// the command's own arguments) without printing, and loads the folder it wrote.
fn frames_analysis(
    py: Python<'_>,
    command: &str,
    frames: &Bound<'_, PyAny>,
    out: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
    more: impl FnOnce(&mut Argv),
) -> PyResult<FolderResult> {
    let frames = path_arg("frames", frames)?;
    let (dir, tmp) = output_folder(out)?;
    let mut argv = Argv::new(&[command]);
    argv.positional("frames", "FRAMES", frames.display());
    more(&mut argv);
    argv.value("out", "--out", dir.display());
    add_options(&mut argv, options)?;
    let command = argv.parse()?;
    let json = py
        .detach(|| -> Result<String, CliError> {
            // As the command line: `wrote DIR`, then the run's notes, on stderr.
            let progress = Bars::holding();
            let (written, json) = match command {
                Command::Track(a) => {
                    let (outcome, written) =
                        sandjumper_imaging::run::run_into(&a.request(), &dir, &progress)?;
                    (written, outcome.summary_json()?)
                }
                Command::Piv(a) => {
                    let (outcome, written) =
                        sandjumper_flow::run::run_into(&a.request()?, &dir, &progress)?;
                    (written, outcome.summary_json()?)
                }
                _ => unreachable!("frames_analysis runs track or piv"),
            };
            progress.release(Some(&written));
            Ok(json)
        })
        .map_err(|e| argv.error(e))?;
    load_folder(py, &dir, Some(&json), tmp.is_none())
}

/// Track the rod's ball through camera frames and measure the jump height the paper's way,
/// as `sandjumper track FRAMES --m-per-px X` does. `frames`: a folder or glob of images;
/// `m_per_px`: the camera's scale, m/px; `out`: the output folder (temporary if None);
/// `options`: the CLI's other flags by name (`fps=200`, `log="acquisition.csv"`,
/// `ball_diameter=0.0127`, `roi=…`, `rest_frames=…`, `apex_window=…`, `exposure=…`).
/// Returns `summary` (as `track --json`) and `tables["track"]` (per frame).
#[pyfunction]
#[pyo3(signature = (frames, m_per_px, out = None, **options))]
pub fn track(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::m_per_px)] m_per_px: f64,
    out: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    frames_analysis(py, "track", frames, out, options, |argv| {
        argv.value("m_per_px", "--m-per-px", m_per_px);
    })
}

/// PIV of side-wall grain videos, as `sandjumper piv FRAMES` does: multipass FFT correlation
/// with window deformation, validation, shear rate, grain momentum and added mass. `frames`:
/// a folder or glob; `out`: the output folder (temporary if None); `options`: the CLI's
/// other flags by name (`windows=[64, 32, 16]`, `overlap=0.5`, `fps=500`, `m_per_px=…`,
/// `origin=[x, y]`, `foot=…`, …). Returns `summary` (as `piv --json`), `tables["flow"]`
/// (momentum and added mass per pair) and `arrays` (`u_px`, `v_px`, `flag`, `s2n` and, when
/// calibrated, the velocities, vorticity and shear rate in SI: stacks of 2-D fields, one per
/// pair; `x_px`, `y_px`: the grid).
#[pyfunction]
#[pyo3(signature = (frames, out = None, **options))]
pub fn piv(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
    out: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    frames_analysis(py, "piv", frames, out, options, |_| {})
}

/// One head-on binary collision with the `paper` contact law, as `sandjumper dem collide
/// --json` does: `d1_m`, `d2_m` (m; `d2_m` defaults to `d1_m`), `wall` (disk on a wall),
/// `kn` (N/m), `damping` (N s/m), `speed` (m/s), `options`: `dt=…`, `density=…`,
/// `integrator=…`, `force_step=True`. Returns the dict `--json` prints (`restitution`,
/// `contact_time_s`, `effective_mass_kg`, `dt_s`, the analytic values and the errors).
#[pyfunction]
#[pyo3(signature = (d1_m, kn, damping, speed, d2_m = None, wall = false, **options))]
#[allow(clippy::too_many_arguments)]
pub fn dem_collide(
    py: Python<'_>,
    #[pyo3(from_py_with = typed::d1_m)] d1_m: f64,
    #[pyo3(from_py_with = typed::kn)] kn: f64,
    #[pyo3(from_py_with = typed::damping)] damping: f64,
    #[pyo3(from_py_with = typed::speed)] speed: f64,
    #[pyo3(from_py_with = typed::d2_m)] d2_m: Option<f64>,
    #[pyo3(from_py_with = typed::wall)] wall: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    let mut argv = Argv::new(&["dem", "collide"]);
    argv.value("d1_m", "--d1", d1_m);
    argv.opt("d2_m", "--d2", d2_m);
    argv.switch("wall", "--wall", wall);
    argv.value("kn", "--kn", kn);
    argv.value("damping", "--damping", damping);
    argv.value("speed", "--speed", speed);
    add_options(&mut argv, options)?;
    let Command::Dem(a) = argv.parse()? else {
        unreachable!("`sandjumper dem` parses as Command::Dem")
    };
    let DemCommand::Collide(c) = a.command else {
        unreachable!("`sandjumper dem collide` parses as DemCommand::Collide")
    };
    let json = sandjumper_dem::collide::run(&c.request, &Silent)
        .and_then(|r| r.json())
        .map_err(|e| argv.error(e.into()))?;
    Ok(json_to_py(py, &json)?.unbind())
}

/// Prepare a DEM bed, as `sandjumper dem bed --out OUT` does (fill and settle under gravity,
/// or pack to `pack=PHI`): `options` are the CLI's flags by name (`width=…`, `height=…`,
/// `grains="bi"`, `seed=…`, `threads=…`, …). Returns the folder loaded (`tables["grains"]`,
/// `tables["load"]`, …); `summary` is None (the bed's record is `bed.toml`).
#[pyfunction]
#[pyo3(signature = (out, **options))]
pub fn dem_bed(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    dem_run(py, "bed", out, options, |_| Ok(()))
}

/// Runs `sandjumper dem <sub> --out OUT [options]` (`more` adds the subcommand's own
/// arguments) and loads the folder it wrote.
fn dem_run(
    py: Python<'_>,
    sub: &str,
    out: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
    more: impl FnOnce(&mut Argv) -> PyResult<()>,
) -> PyResult<FolderResult> {
    let dir = path_arg("out", out)?;
    let mut argv = Argv::new(&["dem", sub]);
    more(&mut argv)?;
    argv.value("out", "--out", dir.display());
    add_options(&mut argv, options)?;
    let Command::Dem(a) = argv.parse()? else {
        unreachable!("`sandjumper dem` parses as Command::Dem")
    };
    py.detach(|| sandjumper_cli::dem::command::run(&a))
        .map_err(|e| argv.error(e))?;
    load_folder(py, &dir, None, true)
}

/// Run a DEM intrusion into a bed, as `sandjumper dem intrude --bed BED --out OUT` does:
/// `options` are the CLI's flags by name (`speed=…` or `trajectory=…`, `depth=…`,
/// `foot_width=…`, `fps=…`, `no_frames=True`, `threads=…`, `resume=True`, …). Returns
/// `summary` (`summary.json`), `tables` (`force_depth`, `flow`, `added_mass`, …) and `arrays`
/// (the coarse-grained fields).
#[pyfunction]
#[pyo3(signature = (bed, out, **options))]
pub fn dem_intrude(
    py: Python<'_>,
    bed: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    dem_run(py, "intrude", out, options, |argv| {
        argv.value("bed", "--bed", path_arg("bed", bed)?.display());
        Ok(())
    })
}

/// Read and check an acquisition log (CSV or binary), as `sandjumper log check` does:
/// returns a dict with `columns` (numpy arrays, as `HilResult.log`), `metadata` (text) and
/// `summary` (the dict `log check --json` prints).
#[pyfunction]
#[pyo3(signature = (path, allow_gaps = false))]
pub fn read_log(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::allow_gaps)] allow_gaps: bool,
) -> PyResult<Py<PyAny>> {
    let path = path_arg("path", path)?;
    let request = CheckRequest {
        file: path,
        allow_gaps,
    };
    let checked = check::run(&request, &Silent).map_err(|e| py_err(e.into()))?;
    let summary = checked.json().map_err(|e| py_err(e.into()))?;
    let d = PyDict::new(py);
    d.set_item("columns", log_columns(py, &checked.log)?)?;
    d.set_item("metadata", log_metadata(py, &checked.log)?)?;
    d.set_item("summary", json_to_py(py, &summary)?)?;
    Ok(d.into_any().unbind())
}

/// Convert an acquisition log (CSV or binary) to MCAP for Foxglove, Lichtblick and
/// PlotJuggler, as `sandjumper log convert IN OUT --to mcap` does.
#[pyfunction]
#[pyo3(signature = (log, out, allow_gaps = false, force = false))]
pub fn log_to_mcap(
    py: Python<'_>,
    log: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::allow_gaps)] allow_gaps: bool,
    #[pyo3(from_py_with = typed::force)] force: bool,
) -> PyResult<()> {
    let input = path_arg("log", log)?;
    let output = path_arg("out", out)?;
    let mut argv = Argv::new(&["log", "convert"]);
    argv.positional("log", "IN", input.display());
    argv.positional("out", "OUT", output.display());
    argv.value("to", "--to", "mcap");
    argv.switch("allow_gaps", "--allow-gaps", allow_gaps);
    argv.switch("force", "--force", force);
    let Command::Log(a) = argv.parse()? else {
        unreachable!("`sandjumper log` parses as Command::Log")
    };
    let LogAction::Convert(c) = a.action else {
        unreachable!("`sandjumper log convert` parses as LogAction::Convert")
    };
    let outcome = py
        .detach(|| sandjumper_acqlog::convert::run(&c.request(), &Silent))
        .map_err(|e| argv.error(e.into()))?;
    // As the command line: what was written, on stderr.
    eprint!("{outcome}");
    Ok(())
}
