//! The analyses from Python: `track`, `piv` and acquisition logs (`read_log`,
//! `log_to_mcap`), each a call of its library (`sandjumper_imaging`, `sandjumper_flow`,
//! `sandjumper_acqlog`).
//!
//! `track` and `piv` return their results from the outcome in memory (the JSON summary as a
//! dict, `track.csv`'s and PIV's tables as numpy columns, PIV's fields as the arrays its folder
//! holds as `.npy` files), the same with `out` as without; `out` also writes the folder.

use std::path::{Path, PathBuf};

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sandjumper_acqlog::check::{self, CheckRequest};
use sandjumper_flow::run::PivRequest;
use sandjumper_imaging::run::TrackRequest;
use sandjumper_output::Silent;
use sandjumper_output::parse::{parse_number, parse_phi, parse_positive};

use crate::call::long_call;
use crate::convert::{f64_array, json_to_py, out_arg, path_arg, str_array};
use crate::errors::{checked, lib_err};
use crate::options::{self, Setter, apply, choice, count, flag, list_text, number, path};
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
pub fn load_folder(
    py: Python<'_>,
    dir: &Path,
    summary_json: Option<&str>,
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
        path: Some(dir.display().to_string()),
    })
}

/// The flags of `track` and `piv` and the Python arguments that carry them, for the
/// libraries' messages.
const FRAME_NAMES: [(&str, &str); 5] = [
    ("--m-per-px", "m_per_px"),
    ("--origin", "origin"),
    ("--fps", "fps"),
    ("--log", "log"),
    ("--windows", "windows"),
];

/// `track`'s options by name.
const TRACK_OPTIONS: [(&str, Setter<TrackRequest>); 7] = [
    ("fps", |r, v| {
        r.fps = Some(number("fps", v, sandjumper_imaging::run::parse_fps)?);
        Ok(())
    }),
    ("log", |r, v| {
        r.log = Some(path("log", v)?);
        Ok(())
    }),
    ("roi", |r, v| {
        r.roi = Some(checked(
            "roi",
            list_text("roi", v)?,
            sandjumper_imaging::run::parse_roi,
        )?);
        Ok(())
    }),
    ("ball_diameter", |r, v| {
        r.ball_diameter_m = number("ball_diameter", v, sandjumper_imaging::run::parse_length)?;
        Ok(())
    }),
    ("rest_frames", |r, v| {
        r.rest_frames = count::<usize>("rest_frames", v)?;
        if r.rest_frames == 0 {
            return Err(crate::errors::invalid_value(
                "rest_frames",
                0,
                "0 is not in 1..4294967296",
            ));
        }
        Ok(())
    }),
    ("exposure", |r, v| {
        r.exposure_s = number("exposure", v, sandjumper_imaging::run::parse_exposure)?;
        Ok(())
    }),
    ("apex_window", |r, v| {
        r.apex_window_s = number("apex_window", v, sandjumper_imaging::run::parse_seconds)?;
        Ok(())
    }),
];

/// Track the rod's ball through camera frames and measure the jump height the paper's way,
/// as `sandjumper track FRAMES --m-per-px X` does. `frames`: a folder or glob of images;
/// `m_per_px`: the camera's scale, m/px; `out`: also write `track --out`'s folder (without
/// it nothing is written: `tables["track"]` comes from memory, `frame` int64, positions and
/// heights float64 with NaN where a frame is flagged, `status` and `reason` str);
/// `options`: the command's other options by name (`fps=200` or `log="acquisition.csv"`,
/// `ball_diameter=0.0095`, `roi=[x, y, w, h]`, `rest_frames=10`, `apex_window=0.02`,
/// `exposure=0`). Returns `summary` (as `track --json`) and `tables["track"]` (per frame).
#[pyfunction]
#[pyo3(signature = (frames, m_per_px, out = None, progress = None, **options))]
pub fn track(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::m_per_px)] m_per_px: f64,
    out: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    let mut request = TrackRequest {
        frames: path_arg("frames", frames)?.display().to_string(),
        m_per_px: checked(
            "m_per_px",
            m_per_px,
            sandjumper_imaging::run::parse_m_per_px,
        )?,
        ..TrackRequest::default()
    };
    apply(&mut request, options, &TRACK_OPTIONS, &mut options::none)?;
    if request.fps.is_some() == request.log.is_some() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            if request.fps.is_some() {
                "fps cannot be used with log (the log's camera ticks time the frames)"
            } else {
                "the following required arguments were not provided: fps or log"
            },
        ));
    }
    // The same typed table either way (`track.csv`'s columns from the outcome); the folder
    // is written only with `out`.
    let dir = out_arg(out)?;
    let (outcome, written) = long_call(py, progress, |progress| match &dir {
        Some(dir) => sandjumper_imaging::run::run_into(&request, dir, progress)
            .map(|(outcome, dir)| (outcome, Some(dir))),
        None => sandjumper_imaging::run::run(&request, progress).map(|o| (o, None)),
    })?
    .map_err(|e| lib_err(e, &FRAME_NAMES))?;
    let json = outcome.summary_json().map_err(|e| lib_err(e, &[]))?;
    let rows = &outcome.result.frames;
    let table = PyDict::new(py);
    table.set_item(
        "frame",
        crate::convert::i64_array(py, rows.iter().map(|f| f.frame as i64).collect()),
    )?;
    let floats: [(&str, FrameValue); 4] = [
        ("t_s", |f| f.t_s),
        ("x_px", |f| f.x_px),
        ("y_px", |f| f.y_px),
        ("rod_height_m", |f| f.rod_height_m),
    ];
    for (name, get) in floats {
        table.set_item(name, f64_array(py, rows.iter().map(get).collect()))?;
    }
    table.set_item(
        "status",
        str_array(
            py,
            rows.iter().map(|f| f.status.as_str().to_string()).collect(),
        )?,
    )?;
    table.set_item(
        "reason",
        str_array(py, rows.iter().map(|f| f.reason.clone()).collect())?,
    )?;
    let tables = PyDict::new(py);
    tables.set_item("track", table)?;
    Ok(FolderResult {
        summary: json_to_py(py, &json)?.unbind(),
        tables: tables.into_any().unbind(),
        arrays: PyDict::new(py).into_any().unbind(),
        path: written.map(|d| d.display().to_string()),
    })
}

/// Reads one number of a tracked frame.
type FrameValue = fn(&sandjumper_imaging::track::TrackedFrame) -> f64;

/// `piv`'s options by name.
const PIV_OPTIONS: [(&str, Setter<PivRequest>); 22] = [
    ("pairs", |r, v| {
        r.pairs = choice("pairs", v)?;
        Ok(())
    }),
    ("every", |r, v| {
        r.every = count::<usize>("every", v)?;
        if r.every == 0 {
            return Err(crate::errors::invalid_value(
                "every",
                0,
                "0 is not in 1..4294967296",
            ));
        }
        Ok(())
    }),
    ("windows", |r, v| {
        let text = list_text("windows", v)?;
        r.piv.windows =
            sandjumper_flow::run::parse_windows(&text).map_err(|e| lib_err(e, &FRAME_NAMES))?;
        Ok(())
    }),
    ("overlap", |r, v| {
        r.piv.overlap = number("overlap", v, parse_number)?;
        Ok(())
    }),
    ("no_deform", |r, v| {
        r.piv.deform = !flag("no_deform", v)?;
        Ok(())
    }),
    ("subpixel", |r, v| {
        r.piv.subpixel = choice("subpixel", v)?;
        Ok(())
    }),
    ("median_threshold", |r, v| {
        r.piv.median_threshold = number("median_threshold", v, parse_positive)?;
        Ok(())
    }),
    ("min_peak_ratio", |r, v| {
        r.piv.min_peak_ratio = number("min_peak_ratio", v, parse_number)?;
        Ok(())
    }),
    ("local_contrast", |r, v| {
        r.preprocess.local_contrast_sigma_px =
            number("local_contrast", v, sandjumper_flow::run::parse_sigma)?;
        Ok(())
    }),
    ("clahe_tile", |r, v| {
        r.preprocess.clahe_tile_px = count::<usize>("clahe_tile", v)?;
        Ok(())
    }),
    ("clahe_clip", |r, v| {
        r.preprocess.clahe_clip = number("clahe_clip", v, parse_positive)?;
        Ok(())
    }),
    ("subtract_background", |r, v| {
        r.preprocess.subtract_background = flag("subtract_background", v)?;
        Ok(())
    }),
    ("cap_sigma", |r, v| {
        r.preprocess.cap_sigma = number("cap_sigma", v, parse_number)?;
        Ok(())
    }),
    ("mask", |r, v| {
        r.mask = Some(path("mask", v)?);
        Ok(())
    }),
    ("foot", |r, v| {
        r.foot = Some(path("foot", v)?);
        Ok(())
    }),
    ("m_per_px", |r, v| {
        r.m_per_px = Some(number("m_per_px", v, parse_positive)?);
        Ok(())
    }),
    ("fps", |r, v| {
        r.fps = Some(number("fps", v, parse_positive)?);
        Ok(())
    }),
    ("log", |r, v| {
        r.log = Some(path("log", v)?);
        Ok(())
    }),
    ("origin", |r, v| {
        r.origin_px = Some(checked(
            "origin",
            list_text("origin", v)?,
            sandjumper_flow::run::parse_point,
        )?);
        Ok(())
    }),
    ("phi", |r, v| {
        r.phi = number("phi", v, parse_phi)?;
        Ok(())
    }),
    ("grain_density", |r, v| {
        r.grain_density_kg_m3 = number("grain_density", v, parse_positive)?;
        Ok(())
    }),
    ("min_speed_ratio", |r, v| {
        r.min_speed_ratio = number("min_speed_ratio", v, sandjumper_flow::run::parse_ratio)?;
        Ok(())
    }),
];

/// PIV of side-wall grain videos, as `sandjumper piv FRAMES` does: multipass FFT correlation
/// with window deformation, validation, shear rate, grain momentum and added mass. `frames`:
/// a folder or glob; `out`: also write `piv --out`'s folder (without it nothing is written:
/// the arrays and tables come from memory); `progress`:
/// `progress(stage, done, total)` as the pairs are analysed (Ctrl-C stops the run between
/// pairs); `options`: the command's other options by name (`windows=[64, 32, 16]`,
/// `overlap=0.5`, `fps=500`, `m_per_px=…`, `origin=[x, y]`, `foot=…`, …). Returns `summary`
/// (as `piv --json`), `tables["flow"]` (momentum and added mass per pair) and `arrays`
/// (`u_px`, `v_px`, `flag`, `s2n` and, when calibrated, the velocities, vorticity and shear
/// rate in SI: stacks of 2-D fields, one per pair; `x_px`, `y_px`: the grid).
#[pyfunction]
#[pyo3(signature = (frames, out = None, progress = None, **options))]
pub fn piv(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
    out: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    let mut request = PivRequest {
        frames: path_arg("frames", frames)?.display().to_string(),
        ..PivRequest::default()
    };
    apply(&mut request, options, &PIV_OPTIONS, &mut options::none)?;
    if request.fps.is_some() && request.log.is_some() {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "fps cannot be used with log (the log's camera ticks time the frames)",
        ));
    }
    request.validate().map_err(|e| lib_err(e, &FRAME_NAMES))?;
    // The arrays `piv --out` writes as .npy files and its two tables, from the outcome the same
    // with `out` as without; the folder is written only with `out`.
    let dir = out_arg(out)?;
    let (outcome, written) = long_call(py, progress, |progress| match &dir {
        Some(dir) => sandjumper_flow::run::run_into(&request, dir, progress)
            .map(|(outcome, dir)| (outcome, Some(dir))),
        None => sandjumper_flow::run::run(&request, progress).map(|o| (o, None)),
    })?
    .map_err(|e| lib_err(e, &FRAME_NAMES))?;
    let json = outcome.summary_json().map_err(|e| lib_err(e, &[]))?;
    let arrays = PyDict::new(py);
    for a in sandjumper_flow::arrays(&outcome.run) {
        let shape: Vec<usize> = a.shape.iter().map(|&n| n as usize).collect();
        let array = numpy::PyArrayMethods::reshape(&numpy::PyArray1::from_vec(py, a.values), shape)
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        arrays.set_item(a.name, array)?;
    }
    let flow = PyDict::new(py);
    let rows: Vec<serde_json::Value> = outcome
        .flow
        .iter()
        .map(|r| serde_json::to_value(r).unwrap_or_default())
        .collect();
    for name in sandjumper_flow::analysis::FLOW_HEADER {
        let column = crate::convert::number_column(&rows, name);
        flow.set_item(name, f64_array(py, column))?;
    }
    let (depth, mass): (Vec<f64>, Vec<f64>) = outcome.run.added_mass_points().into_iter().unzip();
    let added_mass = PyDict::new(py);
    added_mass.set_item("depth_m", f64_array(py, depth))?;
    added_mass.set_item("added_mass_kg", f64_array(py, mass))?;
    let tables = PyDict::new(py);
    tables.set_item("flow", flow)?;
    tables.set_item("added_mass", added_mass)?;
    Ok(FolderResult {
        summary: json_to_py(py, &json)?.unbind(),
        tables: tables.into_any().unbind(),
        arrays: arrays.into_any().unbind(),
        path: written.map(|d| d.display().to_string()),
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
    let checked = check::run(&request, &Silent).map_err(|e| lib_err(e, &[]))?;
    let summary = checked.json().map_err(|e| lib_err(e, &[]))?;
    let d = PyDict::new(py);
    d.set_item("columns", log_columns(py, &checked.log)?)?;
    d.set_item("metadata", log_metadata(py, &checked.log)?)?;
    d.set_item("summary", json_to_py(py, &summary)?)?;
    Ok(d.into_any().unbind())
}

/// Convert an acquisition log (CSV or binary) to MCAP for Foxglove, Lichtblick and
/// PlotJuggler, as `sandjumper log convert IN OUT --to mcap` does. Returns what was written:
/// a dict with `out` (the file), `samples`, `channels` and the other counts of the
/// conversion.
#[pyfunction]
#[pyo3(signature = (log, out, allow_gaps = false, force = false))]
pub fn log_to_mcap(
    py: Python<'_>,
    log: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::allow_gaps)] allow_gaps: bool,
    #[pyo3(from_py_with = typed::force)] force: bool,
) -> PyResult<Py<PyAny>> {
    use sandjumper_acqlog::convert::{ConvertRequest, LogForm};
    let request = ConvertRequest {
        input: path_arg("log", log)?,
        output: path_arg("out", out)?,
        to: Some(LogForm::Mcap),
        allow_gaps,
        force,
    };
    let outcome = py
        .detach(|| sandjumper_acqlog::convert::run(&request, &Silent))
        .map_err(|e| lib_err(e, &[("--force", "force"), ("--allow-gaps", "allow_gaps")]))?;
    Ok(crate::convert::summary_to_py(py, &outcome)?.unbind())
}

/// The camera's scale from a slow motor move, as `sandjumper camera-scale FRAMES --log LOG
/// --ball-px PX` does: the ball tracked through the frames against the encoder's positions.
/// `ball_px`: the ball's diameter in the frames, px; `roi`: `[x, y, w, h]`. Returns the
/// dict `camera-scale --json` prints (`m_per_px`, its standard error, the fit's residuals).
#[pyfunction]
#[pyo3(signature = (frames, log, ball_px, roi = None, progress = None))]
pub fn camera_scale(
    py: Python<'_>,
    frames: &Bound<'_, PyAny>,
    log: &Bound<'_, PyAny>,
    ball_px: f64,
    roi: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    use sandjumper_imaging::camera_scale::ScaleRequest;
    let request = ScaleRequest {
        frames: path_arg("frames", frames)?.display().to_string(),
        log: path_arg("log", log)?,
        ball_px: checked("ball_px", ball_px, sandjumper_imaging::run::parse_px)?,
        roi: roi
            .filter(|r| !r.is_none())
            .map(|r| {
                checked(
                    "roi",
                    list_text("roi", r)?,
                    sandjumper_imaging::run::parse_roi,
                )
            })
            .transpose()?,
    };
    let json = long_call(py, progress, |progress| {
        sandjumper_imaging::camera_scale::run(&request, progress)?.summary_json()
    })?
    .map_err(|e| {
        lib_err(
            e,
            &[("--log", "log"), ("--ball-px", "ball_px"), ("--roi", "roi")],
        )
    })?;
    Ok(json_to_py(py, &json)?.unbind())
}

/// `piv_synthetic`'s options by name.
const SYNTHETIC_OPTIONS: [(
    &str,
    Setter<sandjumper_flow::piv_synthetic::SyntheticRequest>,
); 9] = [
    ("field", |r, v| {
        r.field = choice("field", v)?;
        Ok(())
    }),
    ("magnitude", |r, v| {
        r.magnitude_px = number("magnitude", v, parse_number)?;
        Ok(())
    }),
    ("size", |r, v| {
        let text = match v.extract::<String>() {
            Ok(s) => s,
            Err(_) => {
                let (w, h): (u32, u32) = v.extract().map_err(|_| {
                    pyo3::exceptions::PyTypeError::new_err(
                        "size: expected \"WxH\" or a pair of integers (width, height)",
                    )
                })?;
                format!("{w}x{h}")
            }
        };
        r.size_px = checked("size", text, sandjumper_flow::piv_synthetic::parse_size)?;
        Ok(())
    }),
    ("frames", |r, v| {
        let n: u32 = count("frames", v)?;
        if !(2..=10_000).contains(&n) {
            return Err(crate::errors::invalid_value(
                "frames",
                n,
                &format!("{n} is not in 2..=10000"),
            ));
        }
        r.frames = n;
        Ok(())
    }),
    ("grain_px", |r, v| {
        r.grain_px = number("grain_px", v, parse_positive)?;
        Ok(())
    }),
    ("noise", |r, v| {
        r.noise = number("noise", v, parse_number)?;
        Ok(())
    }),
    ("seed", |r, v| {
        r.seed = count("seed", v)?;
        Ok(())
    }),
    ("image", |r, v| {
        r.image = Some(path("image", v)?);
        Ok(())
    }),
    ("shift", |r, v| {
        r.shift_px = Some(checked(
            "shift",
            list_text("shift", v)?,
            sandjumper_flow::piv_synthetic::parse_shift,
        )?);
        Ok(())
    }),
];

/// Grain images with a known motion for testing PIV, as `sandjumper piv-synthetic --out OUT`
/// does: `field` (`"shift"`, `"shear"`, `"rotation"` or `"cone"`), `magnitude` (px),
/// `size` (`"WxH"` or `(w, h)`), `frames`, `grain_px`, `noise`, `seed`, or a real `image`
/// moved by `shift=[dx, dy]` px. Returns the folder written (its path).
#[pyfunction]
#[pyo3(signature = (out, **options))]
pub fn piv_synthetic(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let mut request = sandjumper_flow::piv_synthetic::SyntheticRequest::default();
    apply(
        &mut request,
        options,
        &SYNTHETIC_OPTIONS,
        &mut options::none,
    )?;
    let out = path_arg("out", out)?;
    let names = [
        ("--image", "image"),
        ("--shift", "shift"),
        ("--field", "field"),
    ];
    let dir = py
        .detach(|| {
            request.validate()?;
            sandjumper_flow::piv_synthetic::run(&request, &Silent)?.write(&out)
        })
        .map_err(|e| lib_err(e, &names))?;
    Ok(dir.display().to_string())
}
