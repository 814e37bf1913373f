//! The DEM from Python: `dem_collide`, `dem_bed`, `dem_intrude` (the 2-D DEM,
//! `sandjumper_dem`) and `lammps` (the 3-D intrusion through LAMMPS, `sandjumper_lammps`).
//!
//! Options carry the command line's flag names (`foot_width=` for `--foot-width`), each
//! checked by the library's own check.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use sandjumper_dem::bed_run::BedRequest;
use sandjumper_dem::collide::CollideRequest;
use sandjumper_dem::intrude_run::{IntrudeOutcome, IntrudeRequest, parse_share};
use sandjumper_dem::request::ModelRequest;
use sandjumper_lammps::run::LammpsRequest;
use sandjumper_output::Silent;
use sandjumper_output::parse::{parse_number, parse_phi, parse_positive};

use crate::analyses::{FolderResult, load_folder};
use crate::call::long_call;
use crate::convert::{json_to_py, path_arg};
use crate::errors::lib_err;
use crate::options::{self, Setter, apply, choice, count, flag, number, path};
use crate::typed;

/// The DEM's flags whose names differ from the Python arguments', for the libraries' messages.
const DEM_NAMES: [(&str, &str); 15] = [
    ("--trajectory", "trajectory"),
    ("--scale-from-foot", "scale_from_foot"),
    ("--episode", "episode"),
    ("--from", "from_s"),
    ("--to", "to_s"),
    ("--kn", "kn"),
    ("--d1", "d1_m"),
    ("--d2", "d2_m"),
    ("--damping", "damping"),
    ("--speed", "speed"),
    ("--depth", "depth"),
    ("--foot-width", "foot_width"),
    ("--bed", "bed"),
    ("--out", "out"),
    ("--resume", "resume"),
];

/// The contact model's and the grains' options (`dem bed` and `dem intrude`).
const MODEL_OPTIONS: [(&str, Setter<ModelRequest>); 18] = [
    ("model", |r, v| {
        r.model = choice("model", v)?;
        Ok(())
    }),
    ("sizes", |r, v| {
        r.sizes = choice("sizes", v)?;
        Ok(())
    }),
    ("ratio", |r, v| {
        r.ratio = number("ratio", v, parse_positive)?;
        Ok(())
    }),
    ("spread", |r, v| {
        r.spread = number("spread", v, parse_number)?;
        Ok(())
    }),
    ("diameter", |r, v| {
        r.diameter_m = number("diameter", v, parse_number)?;
        Ok(())
    }),
    ("density", |r, v| {
        r.density_kg_m3 = number("density", v, parse_number)?;
        Ok(())
    }),
    ("design_speed", |r, v| {
        r.design_speed_m_s = number("design_speed", v, parse_number)?;
        Ok(())
    }),
    ("overlap", |r, v| {
        r.overlap = number("overlap", v, parse_number)?;
        Ok(())
    }),
    ("kn", |r, v| {
        r.kn_n_per_m = Some(number("kn", v, parse_number)?);
        Ok(())
    }),
    ("restitution", |r, v| {
        r.restitution = number("restitution", v, parse_number)?;
        Ok(())
    }),
    ("damping", |r, v| {
        r.damping_n_s_per_m = Some(number("damping", v, parse_number)?);
        Ok(())
    }),
    ("mu", |r, v| {
        r.mu = number("mu", v, parse_number)?;
        Ok(())
    }),
    ("drag", |r, v| {
        r.drag_per_s = Some(number("drag", v, parse_number)?);
        Ok(())
    }),
    ("integrator", |r, v| {
        r.integrator = Some(choice("integrator", v)?);
        Ok(())
    }),
    ("steps_per_contact", |r, v| {
        r.steps_per_contact = number("steps_per_contact", v, parse_number)?;
        Ok(())
    }),
    ("dt", |r, v| {
        r.dt_s = Some(number("dt", v, parse_number)?);
        Ok(())
    }),
    ("force_step", |r, v| {
        r.force_step = flag("force_step", v)?;
        Ok(())
    }),
    ("walls", |r, v| {
        r.walls = flag("walls", v)?;
        Ok(())
    }),
];

/// An option of the contact model, for a request that holds one.
fn model_option(
    model: &mut ModelRequest,
    key: &str,
    value: &Bound<'_, PyAny>,
) -> Option<PyResult<()>> {
    MODEL_OPTIONS
        .iter()
        .find(|(n, _)| *n == key)
        .map(|(_, set)| set(model, value))
}

/// One head-on binary collision with the `paper` contact law, as `sandjumper dem collide
/// --json` does: `d1_m`, `d2_m` (m; required unless `wall`), `wall` (disk on a wall), `kn`
/// (N/m), `damping` (N s/m), `speed` (m/s), `options`: `dt=…`, `density=…`,
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
    const OPTIONS: [(&str, Setter<CollideRequest>); 4] = [
        ("density", |r, v| {
            r.density_kg_m3 = number("density", v, parse_number)?;
            Ok(())
        }),
        ("dt", |r, v| {
            r.dt_s = Some(number("dt", v, parse_number)?);
            Ok(())
        }),
        ("force_step", |r, v| {
            r.force_step = flag("force_step", v)?;
            Ok(())
        }),
        ("integrator", |r, v| {
            r.integrator = choice("integrator", v)?;
            Ok(())
        }),
    ];
    if d2_m.is_none() && !wall {
        return Err(crate::errors::required("d2_m"));
    }
    let mut request = CollideRequest {
        d1_m,
        d2_m,
        wall,
        kn_n_per_m: kn,
        damping_n_s_per_m: damping,
        speed_m_s: speed,
        ..CollideRequest::default()
    };
    apply(&mut request, options, &OPTIONS, &mut options::none)?;
    let json = sandjumper_dem::collide::run(&request, &Silent)
        .and_then(|r| r.json())
        .map_err(|e| lib_err(e, &DEM_NAMES))?;
    Ok(json_to_py(py, &json)?.unbind())
}

/// Prepare a DEM bed, as `sandjumper dem bed --out OUT` does (fill and settle under gravity,
/// or pack to `pack=PHI`): `options` are the command's options by name (`width=…`,
/// `height=…`, `sizes="bi"`, `seed=…`, `threads=…`, `max_time=…`, the contact model's
/// `kn=…`, `mu=…`, …). `progress`: `progress(stage, done, total)`. Returns the folder loaded
/// (`tables["grains"]`, `tables["load"]`, …); `summary` is None (the bed's record is
/// `bed.toml`).
#[pyfunction]
#[pyo3(signature = (out, progress = None, **options))]
pub fn dem_bed(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    progress: Option<Py<PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    const OPTIONS: [(&str, Setter<BedRequest>); 8] = [
        ("width", |r, v| {
            r.width_m = number("width", v, parse_number)?;
            Ok(())
        }),
        ("height", |r, v| {
            r.height_m = number("height", v, parse_number)?;
            Ok(())
        }),
        ("pack", |r, v| {
            r.pack = Some(number("pack", v, parse_number)?);
            Ok(())
        }),
        ("seed", |r, v| {
            r.seed = count("seed", v)?;
            Ok(())
        }),
        ("max_time", |r, v| {
            r.max_time_s = number("max_time", v, parse_number)?;
            Ok(())
        }),
        ("rest", |r, v| {
            r.rest = number("rest", v, parse_number)?;
            Ok(())
        }),
        ("threads", |r, v| {
            r.threads = count("threads", v)?;
            Ok(())
        }),
        ("pin_threads", |r, v| {
            r.pin_threads = flag("pin_threads", v)?;
            Ok(())
        }),
    ];
    let mut request = BedRequest {
        out: path_arg("out", out)?,
        ..BedRequest::default()
    };
    apply(&mut request, options, &OPTIONS, &mut |r, k, v| {
        model_option(&mut r.model, k, v)
    })?;
    let dir = request.out.clone();
    long_call(py, progress, |progress| {
        sandjumper_dem::bed_run::run(&request, progress)
    })?
    .map_err(|e| lib_err(e, &DEM_NAMES))?;
    load_folder(py, &dir, None)
}

/// `dem intrude`'s options by name (besides the contact model's).
const INTRUDE_OPTIONS: [(&str, Setter<IntrudeRequest>); 22] = [
    ("trajectory", |r, v| {
        r.trajectory = Some(path("trajectory", v)?);
        Ok(())
    }),
    ("scale_from_foot", |r, v| {
        r.scale_from_foot_m = Some(number("scale_from_foot", v, parse_positive)?);
        Ok(())
    }),
    ("episode", |r, v| {
        r.episode = Some(choice("episode", v)?);
        Ok(())
    }),
    ("from_s", |r, v| {
        r.from_s = Some(number("from_s", v, parse_number)?);
        Ok(())
    }),
    ("to_s", |r, v| {
        r.to_s = Some(number("to_s", v, parse_number)?);
        Ok(())
    }),
    ("speed", |r, v| {
        r.speed_m_s = Some(number("speed", v, parse_positive)?);
        Ok(())
    }),
    ("depth", |r, v| {
        r.depth_m = number("depth", v, parse_positive)?;
        Ok(())
    }),
    ("foot_width", |r, v| {
        r.foot_width_m = number("foot_width", v, parse_positive)?;
        Ok(())
    }),
    ("fps", |r, v| {
        r.fps = number("fps", v, parse_positive)?;
        Ok(())
    }),
    ("force_rate", |r, v| {
        r.force_rate_hz = number("force_rate", v, parse_positive)?;
        Ok(())
    }),
    ("min_speed_ratio", |r, v| {
        r.min_speed_ratio = number("min_speed_ratio", v, parse_share)?;
        Ok(())
    }),
    ("grid", |r, v| {
        r.grid_m = Some(number("grid", v, parse_positive)?);
        Ok(())
    }),
    ("cg_width", |r, v| {
        r.cg_width_m = Some(number("cg_width", v, parse_positive)?);
        Ok(())
    }),
    ("m_per_px", |r, v| {
        r.m_per_px = Some(number("m_per_px", v, parse_positive)?);
        Ok(())
    }),
    ("no_frames", |r, v| {
        r.frames = !flag("no_frames", v)?;
        Ok(())
    }),
    ("phi", |r, v| {
        r.phi = number("phi", v, parse_phi)?;
        Ok(())
    }),
    ("checkpoint_every", |r, v| {
        r.checkpoint_every = count("checkpoint_every", v)?;
        Ok(())
    }),
    ("stop_after", |r, v| {
        r.stop_after = Some(count("stop_after", v)?);
        Ok(())
    }),
    ("resume", |r, v| {
        r.resume = flag("resume", v)?;
        Ok(())
    }),
    ("seed", |r, v| {
        r.seed = count("seed", v)?;
        Ok(())
    }),
    ("threads", |r, v| {
        r.threads = count("threads", v)?;
        Ok(())
    }),
    ("pin_threads", |r, v| {
        r.pin_threads = flag("pin_threads", v)?;
        Ok(())
    }),
];

/// Run a DEM intrusion into a bed, as `sandjumper dem intrude --bed BED --out OUT` does:
/// `bed` a folder `dem_bed` wrote (None with `resume=True`); `options` are the command's
/// options by name (`speed=…` or `trajectory=…`, `depth=…`, `foot_width=…`, `fps=…`,
/// `no_frames=True`, `threads=…`, `resume=True`, the contact model's, …); `progress`:
/// `progress(stage, done, total)`. Returns `summary` (`summary.json`), `tables`
/// (`force_depth`, `flow`, `added_mass`, …) and `arrays` (the coarse-grained fields); a run
/// stopped at `stop_after` returns its resumable state in `summary` and no tables.
#[pyfunction]
#[pyo3(signature = (bed, out, progress = None, **options))]
pub fn dem_intrude(
    py: Python<'_>,
    bed: Option<&Bound<'_, PyAny>>,
    out: &Bound<'_, PyAny>,
    progress: Option<Py<PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    let mut request = IntrudeRequest {
        bed: bed
            .filter(|b| !b.is_none())
            .map(|b| path_arg("bed", b))
            .transpose()?,
        out: path_arg("out", out)?,
        ..IntrudeRequest::default()
    };
    apply(&mut request, options, &INTRUDE_OPTIONS, &mut |r, k, v| {
        model_option(&mut r.model, k, v)
    })?;
    if request.bed.is_none() && !request.resume {
        return Err(crate::errors::required("bed"));
    }
    request.validate().map_err(|e| lib_err(e, &DEM_NAMES))?;
    let dir = request.out.clone();
    let outcome = long_call(py, progress, |progress| {
        sandjumper_dem::intrude_run::run(&request, progress)
    })?
    .map_err(|e| lib_err(e, &DEM_NAMES))?;
    match outcome {
        IntrudeOutcome::Finished(_) => load_folder(py, &dir, None),
        stopped => Ok(FolderResult {
            summary: crate::convert::summary_to_py(py, &stopped)?.unbind(),
            tables: PyDict::new(py).into_any().unbind(),
            arrays: PyDict::new(py).into_any().unbind(),
            path: Some(dir.display().to_string()),
        }),
    }
}

/// `dem lammps`'s flags whose names differ from the Python arguments'.
const LAMMPS_NAMES: [(&str, &str); 18] = [
    ("--dump-every", "dump_every"),
    ("--dump-format", "dump_format"),
    ("--scale-from-foot", "scale_from_foot"),
    ("--sidewall", "sidewall"),
    ("--restart-every", "restart_every"),
    ("--launcher", "launcher"),
    ("--speed", "speed"),
    ("--depth", "depth"),
    ("--trajectory", "trajectory"),
    ("--episode", "episode"),
    ("--lmp", "lmp"),
    ("--mpiexec", "mpiexec"),
    ("--bed", "bed"),
    ("--ranks", "ranks"),
    ("--out", "out"),
    ("--min-speed-ratio", "min_speed_ratio"),
    ("--foot-diameter", "foot_diameter"),
    ("--bed-width", "bed_width"),
];

/// `lammps`'s options by name.
const LAMMPS_OPTIONS: [(&str, Setter<LammpsRequest>); 26] = [
    ("dump_every", |r, v| {
        r.dump_every_frames = count("dump_every", v)?;
        Ok(())
    }),
    ("dump_format", |r, v| {
        r.dump_format = Some(choice("dump_format", v)?);
        Ok(())
    }),
    ("scale_from_foot", |r, v| {
        r.scale_from_foot_m = Some(number("scale_from_foot", v, parse_positive)?);
        Ok(())
    }),
    ("sidewall", |r, v| {
        r.sidewall = flag("sidewall", v)?;
        Ok(())
    }),
    ("restart_every", |r, v| {
        r.restart_every_min = number("restart_every", v, parse_positive)?;
        Ok(())
    }),
    ("launcher", |r, v| {
        r.launcher = choice("launcher", v)?;
        Ok(())
    }),
    ("preset", |r, v| {
        r.preset = choice("preset", v)?;
        Ok(())
    }),
    ("trajectory", |r, v| {
        r.trajectory = Some(path("trajectory", v)?);
        Ok(())
    }),
    ("episode", |r, v| {
        r.episode = Some(choice("episode", v)?);
        Ok(())
    }),
    ("speed", |r, v| {
        r.speed_m_s = Some(number("speed", v, parse_positive)?);
        Ok(())
    }),
    ("depth", |r, v| {
        r.depth_m = number("depth", v, parse_positive)?;
        Ok(())
    }),
    ("foot_diameter", |r, v| {
        r.foot_diameter_m = Some(number("foot_diameter", v, parse_positive)?);
        Ok(())
    }),
    ("grain_diameter", |r, v| {
        r.grain_diameter_m = Some(number("grain_diameter", v, parse_positive)?);
        Ok(())
    }),
    ("bed_width", |r, v| {
        r.bed_width_m = Some(number("bed_width", v, parse_positive)?);
        Ok(())
    }),
    ("bed_depth", |r, v| {
        r.bed_depth_m = Some(number("bed_depth", v, parse_positive)?);
        Ok(())
    }),
    ("phi", |r, v| {
        r.phi = Some(number("phi", v, parse_positive)?);
        Ok(())
    }),
    ("youngs_modulus", |r, v| {
        r.youngs_modulus_pa = Some(number("youngs_modulus", v, parse_positive)?);
        Ok(())
    }),
    ("friction", |r, v| {
        r.friction = Some(number("friction", v, parse_number)?);
        Ok(())
    }),
    ("restitution", |r, v| {
        r.restitution = Some(number("restitution", v, parse_number)?);
        Ok(())
    }),
    ("fps", |r, v| {
        r.fps = Some(number("fps", v, parse_positive)?);
        Ok(())
    }),
    ("seed", |r, v| {
        r.seed = Some(count("seed", v)?);
        Ok(())
    }),
    ("min_speed_ratio", |r, v| {
        r.min_speed_ratio = number("min_speed_ratio", v, parse_share)?;
        Ok(())
    }),
    ("ranks", |r, v| {
        let ranks: u32 = count("ranks", v)?;
        let max = sandjumper_lammps::run::MAX_RANKS;
        if !(1..=max).contains(&ranks) {
            return Err(crate::errors::invalid_value(
                "ranks",
                ranks,
                &format!("{ranks} is not in 1..={max}"),
            ));
        }
        r.ranks = ranks;
        Ok(())
    }),
    ("lmp", |r, v| {
        r.lmp = Some(path("lmp", v)?);
        Ok(())
    }),
    ("mpiexec", |r, v| {
        r.mpiexec = Some(path("mpiexec", v)?);
        Ok(())
    }),
    ("bed", |r, v| {
        r.bed = Some(path("bed", v)?);
        Ok(())
    }),
];

/// The 3-D intrusion through LAMMPS, as `sandjumper dem lammps --out OUT` does (LAMMPS and,
/// for more than one rank, `mpiexec` must be installed: `lmp=` and `mpiexec=` name them):
/// a poured and settled bed, the disc foot on its trajectory, dumps at the camera's rate read
/// back into the column's momentum, the added mass against eq. 6, the force against F_p(z).
/// `options`: the command's options by name (`preset="small"`, `speed=…` or
/// `trajectory=…`, `depth=…`, `bed_width=…`, `ranks=2`, `bed=` an earlier run's folder or
/// its `lammps/settled.data` to reuse its settled bed, `restart_every=` wall minutes between
/// restart files, `launcher="srun"`, …; a run killed resumes from its newest restart file
/// when called again with the same options); `progress`:
/// `progress(stage, done, total)`; Ctrl-C stops LAMMPS. Returns the folder loaded:
/// `summary` (`summary.json`), `tables` (`flow`, `force_depth`, `cone`).
#[pyfunction]
#[pyo3(signature = (out, progress = None, **options))]
pub fn lammps(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    progress: Option<Py<PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<FolderResult> {
    let mut request = LammpsRequest {
        out: path_arg("out", out)?,
        ..LammpsRequest::default()
    };
    apply(&mut request, options, &LAMMPS_OPTIONS, &mut options::none)?;
    request.validate().map_err(|e| lib_err(e, &LAMMPS_NAMES))?;
    let dir = request.out.clone();
    long_call(py, progress, |progress| {
        sandjumper_lammps::run::run(&request, progress)
    })?
    .map_err(|e| lib_err(e, &LAMMPS_NAMES))?;
    load_folder(py, &dir, None)
}

/// [`lammps`] as one Slurm job, as `sandjumper dem lammps --slurm --out OUT` does: a job of
/// `ranks` MPI tasks (`ranks=` among the options, default 2) that runs `program` (the
/// `sandjumper` binary on the cluster's shared file system; default: the one on `PATH`) with
/// the same options, in `partition`, with the time limit `time` (Slurm's format; restart files
/// every quarter of it at most) over `nodes` nodes. LAMMPS is looked for here first (a login
/// node sees the shared file system). With `wait` (the default) the call waits for the job
/// (the GIL released) and loads its folder; a job stopped at its time limit keeps
/// `OUT.unfinished/`, and the same call resumes it. Returns `{"job_id": the id or None once
/// waited for, "dir": the job's folder, "result": the folder loaded, or None without wait}`.
#[pyfunction]
#[pyo3(signature = (out, partition = None, time = "1:00:00".to_string(), nodes = None, wait = true, program = None, progress = None, **options))]
#[allow(clippy::too_many_arguments)]
pub fn lammps_slurm(
    py: Python<'_>,
    out: &Bound<'_, PyAny>,
    partition: Option<String>,
    time: String,
    nodes: Option<u32>,
    wait: bool,
    program: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    use sandjumper_lammps::run::{Submitted, submit};
    let mut request = LammpsRequest {
        out: path_arg("out", out)?,
        ..LammpsRequest::default()
    };
    apply(&mut request, options, &LAMMPS_OPTIONS, &mut options::none)?;
    if nodes == Some(0) {
        return Err(crate::errors::invalid_value(
            "nodes",
            0,
            "a count, 1 or more",
        ));
    }
    let program = crate::simulate::program_on_path(py, program)?;
    let queue = sandjumper_slurm::QueueOptions {
        partition,
        time,
        nodes,
        no_wait: !wait,
    };
    let names = [
        ("--slurm-partition", "partition"),
        ("--slurm-time", "time"),
        ("--slurm-nodes", "nodes"),
    ];
    let all: Vec<(&str, &str)> = LAMMPS_NAMES.iter().chain(names.iter()).copied().collect();
    let submitted = long_call(py, progress, |progress| {
        submit(&request, &program, &queue, progress)
    })?
    .map_err(|e| lib_err(e, &all))?;
    let d = PyDict::new(py);
    let dir = std::path::absolute(sandjumper_slurm::job_dir(&request.out))
        .unwrap_or_else(|_| sandjumper_slurm::job_dir(&request.out));
    d.set_item("dir", dir.display().to_string())?;
    match submitted {
        Submitted::Queued { id } => {
            d.set_item("job_id", id)?;
            d.set_item("result", py.None())?;
        }
        Submitted::Done { outcome } => {
            d.set_item("job_id", py.None())?;
            d.set_item("result", Py::new(py, load_folder(py, &outcome.out, None)?)?)?;
        }
    }
    Ok(d.into_any().unbind())
}

/// Read a finished LAMMPS run's dumps back into a new folder `out`, as `sandjumper dem
/// lammps-read RUN --out OUT` does (`run`: the run's folder or its `lammps/` folder; `out`
/// apart from it): the column's momentum, added mass and cone again, e.g. with another
/// `min_speed_ratio` (the added mass's speed rule). The GIL is released meanwhile. Returns
/// the folder loaded, as [`lammps`]'s.
#[pyfunction]
#[pyo3(signature = (run, out, min_speed_ratio = 0.3, progress = None))]
pub fn lammps_read(
    py: Python<'_>,
    run: &Bound<'_, PyAny>,
    out: &Bound<'_, PyAny>,
    #[pyo3(from_py_with = typed::min_speed_ratio)] min_speed_ratio: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<FolderResult> {
    use sandjumper_lammps::run::LammpsReadRequest;
    let request = LammpsReadRequest {
        run: path_arg("run", run)?,
        min_speed_ratio: crate::errors::checked("min_speed_ratio", min_speed_ratio, parse_share)?,
        out: path_arg("out", out)?,
    };
    let names = [("--out", "out"), ("--min-speed-ratio", "min_speed_ratio")];
    request.validate().map_err(|e| lib_err(e, &names))?;
    let outcome = long_call(py, progress, |progress| {
        sandjumper_lammps::run::read(&request, progress)
    })?
    .map_err(|e| lib_err(e, &names))?;
    load_folder(py, &outcome.out, None)
}
