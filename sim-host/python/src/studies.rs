//! Whole studies from Python: `fit`, `optimize`, `campaign_run`, `campaign_resume`,
//! `campaign_status`, `figures` and `figures_dem`, each a call of
//! its library with the command line's defaults and checks.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sandjumper_campaign::session::{
    self as campaign, Hooks, ResumeRequest, RunRequest, StatusRequest,
};
use sandjumper_model::resolve::resolve_params;
use sandjumper_optimize::OptimizeRequest;
use sandjumper_optimize::evaluate::Objective;
use sandjumper_output::parse::{check_freq, check_phi, check_tau, parse_number};
use sandjumper_study::fit::{FitKind, FitRequest};

use crate::analyses::{FolderResult, load_folder};
use crate::call::long_call;
use crate::convert::{json_to_py, out_arg, params_source, path_arg, summary_to_py};
use crate::errors::{checked_number, choice, lib_err};
use crate::options::{self, Setter, apply, count, flag, number, path};
use crate::simulate::models;
use crate::typed;

/// Fit the model's parameters to measurements, as `sandjumper fit WHAT FILE` does: `what`
/// is `"intrusion"` (k1, k2, delta or kappa, l_re from `depth_m,force_n`), `"added-mass"`
/// (mu and C from `depth_m,added_mass_kg`), `"drag"` (alpha per phi from measured jump
/// heights) or `"inertial"` (b per phi). `phi`, `params`: the base parameters; `out`: also
/// write the fitted values as a params TOML file there. Options: `reintrusion=True` or
/// `first=True`, `z_start=…` (intrusion); `exclude_deepest=…` (added mass); `model=…`,
/// `height="jump"` or `"final"`, `rtol=…` (drag, inertial). Returns the dict `fit --json`
/// prints (`fits`: value, standard error, unit; `residual_rms`, …).
#[pyfunction]
#[pyo3(signature = (what, file, phi = 0.57, params = None, out = None, **options))]
pub fn fit(
    py: Python<'_>,
    what: String,
    file: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::phi)] phi: f64,
    params: Option<&Bound<'_, PyAny>>,
    out: Option<&Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    use sandjumper_study::fit::data::HeightColumn;
    use sandjumper_study::fit::intrusion::CurveKind;
    use sandjumper_study::fit::jumps::DragParam;
    let what = choice(
        "what",
        &what,
        &[
            ("intrusion", 0),
            ("added-mass", 1),
            ("drag", 2),
            ("inertial", 3),
        ],
    )?;
    let mut request = FitRequest {
        file: path_arg("file", file)?,
        kind: match what {
            0 => FitKind::Intrusion {
                curve: CurveKind::Auto,
                z_start_m: None,
            },
            1 => FitRequest::default().kind,
            _ => FitKind::Jumps {
                param: if what == 2 {
                    DragParam::Alpha
                } else {
                    DragParam::B
                },
                model: None,
                height: HeightColumn::Jump,
                rtol: 1e-9,
            },
        },
        phi: checked_number("phi", phi, check_phi)?,
        params: params_source("params", params)?,
    };
    const OPTIONS: [(&str, Setter<FitKind>); 7] = [
        ("reintrusion", |k, v| match k {
            FitKind::Intrusion { curve, .. } => {
                if flag("reintrusion", v)? {
                    if *curve == CurveKind::First {
                        return Err(PyValueError::new_err(
                            "reintrusion cannot be used with first",
                        ));
                    }
                    *curve = CurveKind::Re;
                }
                Ok(())
            }
            _ => Err(PyValueError::new_err(
                "reintrusion: only for what=\"intrusion\"",
            )),
        }),
        ("first", |k, v| match k {
            FitKind::Intrusion { curve, .. } => {
                if flag("first", v)? {
                    if *curve == CurveKind::Re {
                        return Err(PyValueError::new_err(
                            "first cannot be used with reintrusion",
                        ));
                    }
                    *curve = CurveKind::First;
                }
                Ok(())
            }
            _ => Err(PyValueError::new_err("first: only for what=\"intrusion\"")),
        }),
        ("z_start", |k, v| match k {
            FitKind::Intrusion { z_start_m, .. } => {
                *z_start_m = Some(number("z_start", v, parse_number)?);
                Ok(())
            }
            _ => Err(PyValueError::new_err(
                "z_start: only for what=\"intrusion\"",
            )),
        }),
        ("exclude_deepest", |k, v| match k {
            FitKind::AddedMass { exclude_deepest } => {
                *exclude_deepest = number("exclude_deepest", v, parse_number)?;
                Ok(())
            }
            _ => Err(PyValueError::new_err(
                "exclude_deepest: only for what=\"added-mass\"",
            )),
        }),
        ("model", |k, v| match k {
            FitKind::Jumps { model, .. } => {
                let name: String = v.extract()?;
                *model = Some(choice("model", &name, &models())?);
                Ok(())
            }
            _ => Err(PyValueError::new_err(
                "model: only for what=\"drag\" or \"inertial\"",
            )),
        }),
        ("height", |k, v| match k {
            FitKind::Jumps { height, .. } => {
                let name: String = v.extract()?;
                *height = choice(
                    "height",
                    &name,
                    &[("jump", HeightColumn::Jump), ("final", HeightColumn::Final)],
                )?;
                Ok(())
            }
            _ => Err(PyValueError::new_err(
                "height: only for what=\"drag\" or \"inertial\"",
            )),
        }),
        ("rtol", |k, v| match k {
            FitKind::Jumps { rtol, .. } => {
                *rtol = number("rtol", v, parse_number)?;
                Ok(())
            }
            _ => Err(PyValueError::new_err(
                "rtol: only for what=\"drag\" or \"inertial\"",
            )),
        }),
    ];
    apply(&mut request.kind, options, &OPTIONS, &mut options::none)?;
    let names = [
        ("--z-start", "z_start"),
        ("--rtol", "rtol"),
        ("--phi", "phi"),
    ];
    let out = out_arg(out)?;
    let report = py
        .detach(|| sandjumper_study::fit::run(&request, &sandjumper_output::Silent))
        .map_err(|e| lib_err(e, &names))?;
    if let Some(out) = &out {
        sandjumper_study::fit::write_params_files(&report, out)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
    }
    Ok(json_to_py(py, &report.to_json())?.unbind())
}

/// The objectives of the stroke search by their command-line names.
const OBJECTIVES: [(&str, Objective); 5] = [
    ("height", Objective::Height),
    ("final-height", Objective::FinalHeight),
    ("com-rise", Objective::ComRise),
    ("height-per-peak-power", Objective::HeightPerPeakPower),
    ("height-per-energy", Objective::HeightPerEnergy),
];

/// `optimize`'s options by name (checked together by [`OptimizeRequest::validate`]).
const OPTIMIZE_OPTIONS: [(&str, Setter<OptimizeRequest>); 21] = [
    ("rtol", |r, v| {
        r.rtol = number("rtol", v, sandjumper_output::parse::parse_rtol)?;
        Ok(())
    }),
    ("max_stroke", |r, v| {
        r.max_stroke_m = number("max_stroke", v, parse_number)?;
        Ok(())
    }),
    ("max_duration", |r, v| {
        r.max_duration_s = number("max_duration", v, parse_number)?;
        Ok(())
    }),
    ("table_rate", |r, v| {
        r.table_rate_hz = count("table_rate", v)?;
        Ok(())
    }),
    ("min_height", |r, v| {
        r.min_height_m = number("min_height", v, parse_number)?;
        Ok(())
    }),
    ("max_spring_compression", |r, v| {
        r.max_spring_compression_m = Some(number("max_spring_compression", v, parse_number)?);
        Ok(())
    }),
    ("max_rise", |r, v| {
        r.max_rise_m = number("max_rise", v, parse_number)?;
        Ok(())
    }),
    ("moves", |r, v| {
        r.moves = count("moves", v)?;
        Ok(())
    }),
    ("max_hold", |r, v| {
        r.max_hold_s = number("max_hold", v, parse_number)?;
        Ok(())
    }),
    ("evaluations", |r, v| {
        r.evaluations = count("evaluations", v)?;
        Ok(())
    }),
    ("population", |r, v| {
        r.population = count("population", v)?;
        Ok(())
    }),
    ("random_starts", |r, v| {
        r.random_starts = count("random_starts", v)?;
        Ok(())
    }),
    ("seed", |r, v| {
        r.seed = count("seed", v)?;
        Ok(())
    }),
    ("sweep_freq_step", |r, v| {
        r.sweep_freq_step_hz = number("sweep_freq_step", v, parse_number)?;
        Ok(())
    }),
    ("sweep_tau_step", |r, v| {
        r.sweep_tau_step_s = number("sweep_tau_step", v, parse_number)?;
        Ok(())
    }),
    ("verify", |r, v| {
        let text = match v.extract::<String>() {
            Ok(s) => s,
            Err(_) => v.extract::<Vec<String>>()?.join(","),
        };
        r.verify = crate::errors::checked("verify", text, sandjumper_optimize::parse_verify)?;
        Ok(())
    }),
    ("elites", |r, v| {
        r.elites = count("elites", v)?;
        Ok(())
    }),
    ("refine", |r, v| {
        r.refine = count("refine", v)?;
        Ok(())
    }),
    ("paper_candidates", |r, v| {
        r.paper_candidates = count("paper_candidates", v)?;
        Ok(())
    }),
    ("firmware", |r, v| {
        r.firmware = path("firmware", v)?;
        Ok(())
    }),
    ("threads", |r, v| {
        r.threads = Some(count("threads", v)?);
        Ok(())
    }),
];

/// Search for the stroke that makes the robot jump highest (or best by `objective`) within
/// the rig's limits, as `sandjumper optimize --out OUT` does: CMA-ES over the stroke family,
/// the best of the paper's strokes beside it, both re-run through the controller on the links
/// of `verify`. `out`: the output folder (stroke.csv for `jump(stroke=…)`, `hil` and `rig
/// replay`); a search stopped by Ctrl-C leaves its checkpoint beside it and the same call
/// resumes it. `objective`: `"height"`, `"final-height"`, `"com-rise"`, `"height-per-peak-power"` or
/// `"height-per-energy"`; options: the command's by name (`max_stroke=0.025`,
/// `evaluations=…`, `moves=4`, `verify="sil"`, `threads=…`, `seed=…`, …). `phi_range`
/// (`"0.57:0.62"`, instead of `phi`): a bed known to a range, the worst case over
/// `phi_points` beds maximised. `start_from`: earlier searches' folders whose answers the
/// search also starts from. Returns `summary` (as `optimize --json`) and the folder's
/// tables (`stroke`, …).
#[pyfunction]
#[pyo3(signature = (out, objective = "height".to_string(), model = "eq4".to_string(), phi = None, params = None, progress = None, phi_range = None, phi_points = None, start_from = Vec::new(), **options))]
#[allow(clippy::too_many_arguments)]
pub fn optimize(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    objective: String,
    #[pyo3(from_py_with = typed::model)] model: String,
    #[pyo3(from_py_with = typed::phi_opt)] phi: Option<f64>,
    params: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    phi_range: Option<String>,
    phi_points: Option<usize>,
    start_from: Vec<std::path::PathBuf>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    let file = params_source("params", params)?;
    let (params, beds) = match (phi_range, phi) {
        (Some(_), Some(_)) => {
            return Err(PyValueError::new_err(
                "phi and phi_range given together (allowed: one of them)",
            ));
        }
        (None, phi) => {
            if phi_points.is_some() {
                return Err(PyValueError::new_err(
                    "phi_points given without phi_range (allowed: with phi_range only)",
                ));
            }
            let phi = checked_number("phi", phi.unwrap_or(0.57), check_phi)?;
            (
                resolve_params(phi, file.as_ref())
                    .map_err(|e| PyValueError::new_err(e.to_string()))?,
                Vec::new(),
            )
        }
        (Some(range), None) => {
            sandjumper_optimize::parse_phi_range(&range, phi_points.unwrap_or(5))
                .map_err(|e| {
                    PyValueError::new_err(
                        e.replace("--phi-range", "phi_range")
                            .replace("--phi-points", "phi_points"),
                    )
                })?
                .beds(file.as_ref())
                .map_err(|e| PyValueError::new_err(e.to_string()))?
        }
    };
    let start_from = start_from
        .iter()
        .map(|d| sandjumper_optimize::outcome::answer_chain_in(d))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PyValueError::new_err(e.to_string().replace("--start-from", "start_from")))?;
    let mut request = OptimizeRequest {
        objective: choice("objective", &objective, &OBJECTIVES)?,
        model: choice("model", &model, &models())?,
        params,
        beds,
        start_from,
        out: path_arg("out", out)?,
        ..OptimizeRequest::default()
    };
    apply(&mut request, options, &OPTIMIZE_OPTIONS, &mut options::none)?;
    let names: Vec<(String, &str)> = OPTIMIZE_OPTIONS
        .iter()
        .map(|(n, _)| (format!("--{}", n.replace('_', "-")), *n))
        .collect();
    let names: Vec<(&str, &str)> = names.iter().map(|(f, n)| (f.as_str(), *n)).collect();
    request.validate().map_err(|e| lib_err(e, &names))?;
    let dir = request.out.clone();
    let json = long_call(py, progress, |progress| {
        sandjumper_optimize::run(&request, progress)?.json()
    })?
    .map_err(|e| lib_err(e, &names))?;
    load_folder(py, &dir, Some(&json))
}

/// Run a campaign file (a plan of jumps and beds), as `sandjumper campaign run FILE --out
/// OUT` does: `link` is the controller with the simulated bed (`"sil"` or `"pil"`, the
/// firmware `firmware` in QEMU), `port` instead the rig's board on a serial port with its bed
/// apparatus; `stop_after` stops after that many points (resumable); `progress`:
/// `progress(stage, done, total)` as the points finish. Returns the session's outcome as a
/// dict (what `campaign run --json` prints).
#[pyfunction]
#[pyo3(signature = (file, out, link = None, firmware = None, stop_after = None, progress = None, port = None))]
#[allow(clippy::too_many_arguments)]
pub fn campaign_run(
    py: Python<'_>,
    file: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::link_opt)] link: Option<String>,
    firmware: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::stop_after)] stop_after: Option<usize>,
    progress: Option<Py<PyAny>>,
    port: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    let port = crate::convert::opt_path("port", port)?;
    if link.is_some() && port.is_some() {
        return Err(PyValueError::new_err(
            "the argument 'link' cannot be used with 'port'",
        ));
    }
    let mut request = RunRequest {
        file: path_arg("file", file)?,
        link,
        port,
        out: path_arg("out", out)?,
        stop_after,
        ..RunRequest::default()
    };
    if let Some(f) = firmware.filter(|f| !f.is_none()) {
        request.firmware = path_arg("firmware", f)?;
    }
    let names = [
        ("--link", "link"),
        ("--port", "port"),
        ("--out", "out"),
        ("--stop-after", "stop_after"),
    ];
    let outcome = long_call(py, progress, |progress| {
        campaign::run(&request, Hooks::default(), progress)
    })?
    .map_err(|e| lib_err(e, &names))?;
    Ok(summary_to_py(py, &outcome)?.unbind())
}

/// Resume a campaign in its output folder `dir`, as `sandjumper campaign resume DIR` does;
/// returns the session's outcome as a dict.
#[pyfunction]
#[pyo3(signature = (dir, firmware = None, stop_after = None, progress = None))]
pub fn campaign_resume(
    py: Python<'_>,
    dir: &Bound<'_, PyAny>,
    firmware: Option<&Bound<'_, PyAny>>,
    #[pyo3(from_py_with = typed::stop_after)] stop_after: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    let mut request = ResumeRequest {
        dir: path_arg("dir", dir)?,
        stop_after,
        ..ResumeRequest::default()
    };
    if let Some(f) = firmware.filter(|f| !f.is_none()) {
        request.firmware = path_arg("firmware", f)?;
    }
    let outcome = long_call(py, progress, |progress| {
        campaign::resume(&request, Hooks::default(), progress)
    })?
    .map_err(|e| lib_err(e, &[("--stop-after", "stop_after")]))?;
    Ok(summary_to_py(py, &outcome)?.unbind())
}

/// Where a campaign in `dir` stands, as `sandjumper campaign status DIR --json` prints it.
#[pyfunction]
pub fn campaign_status(py: Python<'_>, dir: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
    let request = StatusRequest {
        dir: path_arg("dir", dir)?,
    };
    let report = campaign::status(&request).map_err(|e| lib_err(e, &[]))?;
    let json = report.json().map_err(|e| lib_err(e, &[]))?;
    Ok(json_to_py(py, &json)?.unbind())
}

/// Draw the paper's figures from the model, as `sandjumper figures --out OUT` does (`quick`:
/// coarser sweeps). Returns the folder loaded (`summary` is None; `tables` holds each
/// figure's data).
#[pyfunction]
#[pyo3(signature = (out, quick = false, threads = None, rtol = 1e-8, progress = None))]
pub fn figures(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    quick: bool,
    #[pyo3(from_py_with = typed::threads)] threads: Option<usize>,
    #[pyo3(from_py_with = typed::rtol)] rtol: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<FolderResult> {
    if let Some(0 | 1025..) = threads {
        return Err(crate::errors::invalid_value(
            "threads",
            threads.unwrap_or(0),
            "1..=1024",
        ));
    }
    let request = sandjumper_study::figures::FiguresRequest {
        out: path_arg("out", out)?,
        quick,
        threads,
        rtol: crate::errors::checked("rtol", rtol, sandjumper_output::parse::parse_rtol)?,
    };
    long_call(py, progress, |progress| {
        let report = sandjumper_study::figures::run(&request, progress)?;
        if report.failures > 0 {
            sandjumper_output::Progress::note(
                progress,
                &format!(
                    "warning: {} jumps failed; see failures.csv",
                    report.failures
                ),
            );
        }
        Ok(report)
    })?
    .map_err(|e| match e {
        sandjumper_study::figures::FiguresError::Output(e) => lib_err(e, &[]),
        internal => pyo3::exceptions::PyRuntimeError::new_err(internal.to_string()),
    })?;
    load_folder(py, &request.out, None)
}

/// The supplement's DEM figures, as `sandjumper figures dem --out OUT` does: the jumps'
/// strokes driven into DEM beds, the DEM's added mass against eq. 6, PIV on its frames
/// against its own momentum. `foot_width` (m) scales the whole comparison down; the other
/// arguments as the command's. Returns `summary` (`summary.json`) and the tables.
#[pyfunction]
#[pyo3(signature = (out, phi = None, freq_hz = None, tau_s = None, foot_width = None, full_model = None, threads = None, bed_max_time = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn figures_dem(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::phi_opt)] phi: Option<f64>,
    #[pyo3(from_py_with = typed::freq_hz_opt)] freq_hz: Option<f64>,
    #[pyo3(from_py_with = typed::tau_s)] tau_s: Option<f64>,
    foot_width: Option<f64>,
    full_model: Option<bool>,
    #[pyo3(from_py_with = typed::threads)] threads: Option<usize>,
    bed_max_time: Option<f64>,
    progress: Option<Py<PyAny>>,
) -> PyResult<FolderResult> {
    use sandjumper_figures_dem::FiguresDemRequest;
    let defaults = FiguresDemRequest::default();
    let request = FiguresDemRequest {
        out: path_arg("out", out)?,
        phi: phi
            .map(|p| checked_number("phi", p, check_phi))
            .transpose()?
            .unwrap_or(defaults.phi),
        freq_hz: freq_hz
            .map(|f| checked_number("freq_hz", f, check_freq))
            .transpose()?
            .unwrap_or(defaults.freq_hz),
        tau_s: tau_s
            .map(|t| checked_number("tau_s", t, check_tau))
            .transpose()?
            .unwrap_or(defaults.tau_s),
        foot_width_m: foot_width.unwrap_or(defaults.foot_width_m),
        full_model: full_model.unwrap_or(defaults.full_model),
        threads: threads.unwrap_or(defaults.threads),
        bed_max_time_s: bed_max_time.unwrap_or(defaults.bed_max_time_s),
    };
    let names = [
        ("--foot-width", "foot_width"),
        ("--bed-max-time", "bed_max_time"),
        ("--phi", "phi"),
        ("--freq", "freq_hz"),
        ("--tau", "tau_s"),
    ];
    let json = long_call(py, progress, |progress| {
        let outcome = sandjumper_figures_dem::run(&request, progress)?;
        serde_json::to_string(&outcome)
            .map_err(|e| sandjumper_figures_dem::FiguresDemError::internal(e.to_string()))
    })?
    .map_err(|e| lib_err(e, &names))?;
    load_folder(py, &request.out, Some(&json))
}
