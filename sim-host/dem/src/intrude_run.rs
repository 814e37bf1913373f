//! `dem intrude` as one call: the intruder driven into a bed (or a stopped run resumed), with
//! side-wall frames, speed snapshots and checkpoints on the way, and the finished run's
//! folder written by [`crate::outputs::write`].

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::bed::{BedReport, BedSpec};
use crate::checkpoint;
use crate::error::DemError;
use crate::intrude::{self, IntrudeSpec, Run, SampleOut};
use crate::intruder::Trajectory;
use crate::outputs::Summary;
use crate::params::DemParams;
use crate::render::SideCamera;
use crate::request::{ModelRequest, with_threads};
use sandjumper_output::{Progress, StagedDir, WriterLock};

/// A part of a jump's trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Episode {
    /// The foot's last intrusion before the jump's flight.
    PushOff,
}

/// clap value parser of a share in 0..=1 ([`IntrudeRequest::min_speed_ratio`], also
/// `dem lammps`'s).
pub fn parse_share(s: &str) -> Result<f64, String> {
    let v = sandjumper_output::parse::parse_number(s)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("`{s}` not allowed (allowed: 0 to 1)"))
    }
}

/// An intrusion to run (or a stopped one to continue).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct IntrudeRequest {
    /// The bed (a `dem bed` output directory or its bed.ckpt).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "BED", required_unless_present = "resume")
    )]
    pub bed: Option<PathBuf>,
    /// Trajectory CSV (`t_s` with `x_f_m`, as `jump --out` writes, or `depth_m`); it must
    /// start at or above the bed's surface.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "CSV", conflicts_with = "speed_m_s")
    )]
    pub trajectory: Option<PathBuf>,
    /// Scale the trajectory from a foot this wide, m, to `--foot-width` at the same Froude
    /// number (depths by the width ratio, times by its square root), so a smaller foot keeps
    /// the jump's depth over radius and `v^2 / (g R)`: `0.076` for a jump of the robot.
    #[cfg_attr(feature = "clap", arg(long = "scale-from-foot", value_name = "M", requires = "trajectory", value_parser = sandjumper_output::parse::parse_positive))]
    pub scale_from_foot_m: Option<f64>,
    /// Take one episode of a jump's trajectory.csv, shifted to start at the surface:
    /// `push-off`, the foot's last intrusion before the jump's flight.
    #[cfg_attr(feature = "clap", arg(long, value_enum, value_name = "EPISODE", requires = "trajectory", conflicts_with_all = ["from_s", "to_s"]))]
    pub episode: Option<Episode>,
    /// Use the trajectory from this time, s.
    #[cfg_attr(feature = "clap", arg(long = "from", value_name = "S", value_parser = sandjumper_output::parse::parse_number))]
    pub from_s: Option<f64>,
    /// Until this time, s.
    #[cfg_attr(feature = "clap", arg(long = "to", value_name = "S", value_parser = sandjumper_output::parse::parse_number))]
    pub to_s: Option<f64>,
    /// Constant intrusion speed instead, m/s.
    #[cfg_attr(feature = "clap", arg(long = "speed", value_name = "M_PER_S", value_parser = sandjumper_output::parse::parse_positive))]
    pub speed_m_s: Option<f64>,
    /// Final depth at constant speed, m.
    #[cfg_attr(feature = "clap", arg(long = "depth", value_name = "M", default_value = "0.03", value_parser = sandjumper_output::parse::parse_positive))]
    pub depth_m: f64,
    /// Foot width, m (the robot's 7.6 cm foot; smaller for a scaled foot).
    #[cfg_attr(feature = "clap", arg(long = "foot-width", value_name = "M", default_value = "0.076", value_parser = sandjumper_output::parse::parse_positive))]
    pub foot_width_m: f64,
    /// Grains and contacts of the intrusion (the bed's grains are kept).
    #[cfg_attr(feature = "clap", command(flatten))]
    pub model: ModelRequest,
    /// Samples per second (fields, frames, snapshots): the side camera's 500 fps.
    #[cfg_attr(feature = "clap", arg(long, value_name = "FPS", default_value = "500", value_parser = sandjumper_output::parse::parse_positive))]
    pub fps: f64,
    /// Force rows per second.
    #[cfg_attr(feature = "clap", arg(long = "force-rate", value_name = "HZ", default_value = "10000", value_parser = sandjumper_output::parse::parse_positive))]
    pub force_rate_hz: f64,
    /// The added mass `P / v_foot` is taken only while the foot moves down at least this
    /// share of its fastest speed, 0..1 (the paper excluded the samples where v -> 0).
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", default_value = "0.3", value_parser = parse_share))]
    pub min_speed_ratio: f64,
    /// Coarse-graining grid spacing, m (default 2 grain diameters).
    #[cfg_attr(feature = "clap", arg(long = "grid", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub grid_m: Option<f64>,
    /// Coarse-graining width, m (default 1 grain diameter).
    #[cfg_attr(feature = "clap", arg(long = "cg-width", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub cg_width_m: Option<f64>,
    /// Side-wall frames' scale, m/px (default a tenth of a grain).
    #[cfg_attr(feature = "clap", arg(long, value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub m_per_px: Option<f64>,
    /// Render side-wall frames (`--no-frames`: false). Default true.
    #[cfg_attr(feature = "clap", arg(long = "no-frames", action = clap::ArgAction::SetFalse, help = "Do not render side-wall frames"))]
    pub frames: bool,
    /// Bed packing fraction for momentum (rho phi), as `piv --phi`.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PHI", default_value = "0.6", value_parser = sandjumper_output::parse::parse_phi))]
    pub phi: f64,
    /// Checkpoint every N steps (0: never).
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value = "20000"))]
    pub checkpoint_every: u64,
    /// Stop after this many steps (leaves the run resumable; for tests and batch queues).
    #[cfg_attr(feature = "clap", arg(long, value_name = "N"))]
    pub stop_after: Option<u64>,
    /// Continue the stopped run of `--out`.
    #[cfg_attr(feature = "clap", arg(long))]
    pub resume: bool,
    /// Seed of the frames' grey levels.
    #[cfg_attr(feature = "clap", arg(long, default_value = "1"))]
    pub seed: u64,
    /// Threads (0: all cores).
    #[cfg_attr(feature = "clap", arg(long, default_value = "0"))]
    pub threads: usize,
    /// Pin each thread to a core of its own, among those this process may run on (as
    /// OpenMP's `OMP_PROC_BIND`): steadier, and about 2 % faster on two threads. Leave it
    /// off on a node shared with jobs that are not confined to cores of their own.
    #[cfg_attr(feature = "clap", arg(long))]
    pub pin_threads: bool,
    /// Output directory.
    #[cfg_attr(feature = "clap", arg(long, value_name = "DIR"))]
    pub out: PathBuf,
}

impl Default for IntrudeRequest {
    fn default() -> Self {
        Self {
            bed: None,
            trajectory: None,
            scale_from_foot_m: None,
            episode: None,
            from_s: None,
            to_s: None,
            speed_m_s: None,
            depth_m: 0.03,
            foot_width_m: 0.076,
            model: ModelRequest::default(),
            fps: 500.0,
            force_rate_hz: 10000.0,
            min_speed_ratio: 0.3,
            grid_m: None,
            cg_width_m: None,
            m_per_px: None,
            frames: true,
            phi: 0.6,
            checkpoint_every: 20000,
            stop_after: None,
            resume: false,
            seed: 1,
            threads: 0,
            pin_threads: false,
            out: PathBuf::new(),
        }
    }
}

/// How an intrusion ended.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum IntrudeOutcome {
    /// It ran to its end: its summary (what `--json` prints; `summary.json` holds it with
    /// the spec, grid and camera).
    Finished(Box<Summary>),
    /// It stopped at [`IntrudeRequest::stop_after`], resumable.
    Stopped {
        /// Steps done.
        steps: u64,
        /// Steps of the whole run.
        total_steps: u64,
        /// The checkpoint a resume starts from, step.
        resumes_from: u64,
        /// The run's output folder (not written yet).
        out: PathBuf,
    },
}

impl fmt::Display for IntrudeOutcome {
    /// The line `dem intrude` prints.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Finished(s) => f.write_str(&s.line()),
            Self::Stopped {
                steps,
                total_steps,
                resumes_from,
                out,
            } => write!(
                f,
                "dem intrude: stopped after {steps} of {total_steps} steps; `dem intrude --resume --out {}` continues from the checkpoint at step {resumes_from}",
                out.display()
            ),
        }
    }
}

/// The command line's rules for the intruder's motion from a trajectory file (which the
/// command line's parser also enforces): `--speed` cannot be used with `--trajectory`,
/// `--episode` needs `--trajectory`, and `--from`/`--to` cannot be used with `--episode`.
/// `window`: `--from` or `--to` given.
pub fn check_motion(
    trajectory: bool,
    speed: bool,
    episode: bool,
    window: bool,
) -> Result<(), String> {
    if trajectory && speed {
        return Err("--speed cannot be used with --trajectory (the file gives the motion)".into());
    }
    if episode && !trajectory {
        return Err("--episode needs --trajectory (the file whose episode is driven)".into());
    }
    if episode && window {
        return Err("--from and --to cannot be used with --episode".into());
    }
    Ok(())
}

impl IntrudeRequest {
    /// The checks that need no file: a bed unless resuming, and the intruder's motion.
    pub fn validate(&self) -> Result<(), DemError> {
        if !self.resume && self.bed.is_none() {
            return Err(DemError::input("--bed BED is required (or --resume)"));
        }
        check_motion(
            self.trajectory.is_some(),
            self.speed_m_s.is_some(),
            self.episode.is_some(),
            self.from_s.is_some() || self.to_s.is_some(),
        )
        .map_err(DemError::Input)?;
        if self.scale_from_foot_m.is_some() && self.trajectory.is_none() {
            return Err(DemError::input(
                "--scale-from-foot scales a --trajectory CSV (a constant --speed is given for \
                 this foot already)",
            ));
        }
        if let Some(w0) = self.scale_from_foot_m
            && !(w0.is_finite() && w0 > 0.0)
        {
            return Err(DemError::input(format!(
                "--scale-from-foot {w0}: a foot's width, m (allowed: > 0)"
            )));
        }
        if !self.resume && self.trajectory.is_none() && self.speed_m_s.is_none() {
            return Err(DemError::input(
                "give the intruder's motion: --trajectory CSV or --speed M_PER_S",
            ));
        }
        self.model.resolve().map(|_| ())
    }
}

/// The lock file in the work folder that the run writing it holds.
const LOCK: &str = ".lock";

/// Remove everything in `work` but its lock file.
fn clear_except_lock(work: &Path) -> Result<(), DemError> {
    let fail = |e: std::io::Error| DemError::input(format!("cannot clear {}: {e}", work.display()));
    for entry in std::fs::read_dir(work).map_err(fail)? {
        let entry = entry.map_err(fail)?;
        if entry.file_name() == LOCK {
            continue;
        }
        let path = entry.path();
        if entry.file_type().map_err(fail)?.is_dir() {
            std::fs::remove_dir_all(&path).map_err(fail)?;
        } else {
            std::fs::remove_file(&path).map_err(fail)?;
        }
    }
    Ok(())
}

/// The work folder of a run writing to `out`: checkpoints and frames until it finishes.
pub fn work_dir(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".incomplete");
    out.with_file_name(name)
}

/// Run the intrusion `request` asks for on its threads: resumed from its checkpoint or
/// started from a bed, advanced with frames, snapshots and checkpoints, then its folder
/// written (unless it stopped early).
pub fn run(request: &IntrudeRequest, progress: &dyn Progress) -> Result<IntrudeOutcome, DemError> {
    with_threads(request.threads, request.pin_threads, || {
        run_here(request, progress)
    })
}

fn run_here(a: &IntrudeRequest, progress: &dyn Progress) -> Result<IntrudeOutcome, DemError> {
    let work = work_dir(&a.out);
    let ckpt = work.join("run.ckpt");
    // One writer per output, held until this returns (the OS lets go however the process
    // ends).
    let (mut run, _lock) = if a.resume {
        resume_intrusion(a, &work, &ckpt)?
    } else {
        start_intrusion(a, &work, &ckpt, progress)?
    };
    std::fs::create_dir_all(work.join("frames"))
        .and_then(|()| std::fs::create_dir_all(work.join("snapshots")))
        .map_err(|e| DemError::input(format!("cannot create {}: {e}", work.display())))?;
    let p = run.spec.params;
    let dl = p.dimensionless(run.spec.trajectory().max_speed());
    progress.note(&format!(
        "dem intrude: {} grains, {} steps of {:.3e} s; contact time {:.3e} s: t_c v / d = {:.3e}, Froude v / sqrt(g d) = {:.2}",
        run.world.g.len(),
        run.total_steps,
        p.dt_s,
        dl.contact_time_s,
        dl.contact_time_speed_over_d,
        dl.froude
    ));
    advance_intrusion(a, &mut run, &work, &ckpt, progress)?;
    if run.steps() < run.total_steps {
        // Resuming from the last regular checkpoint (not from here) repeats the
        // uninterrupted run bit for bit; the steps since are done again.
        let every = run.spec.checkpoint_every;
        return Ok(IntrudeOutcome::Stopped {
            steps: run.steps(),
            total_steps: run.total_steps,
            resumes_from: run.steps().checked_div(every).map_or(0, |k| k * every),
            out: a.out.clone(),
        });
    }
    let summary = crate::outputs::write(&run, &work, &a.out)?;
    Ok(IntrudeOutcome::Finished(Box::new(summary)))
}

/// The work folder `work` made and locked for this run: a second run into the same --out
/// (fresh or resumed) is refused naming the first's process and machine, before it touches
/// the first's work folder.
fn lock_work(work: &Path) -> Result<WriterLock, DemError> {
    std::fs::create_dir_all(work)
        .map_err(|e| DemError::input(format!("cannot create {}: {e}", work.display())))?;
    WriterLock::take_recorded(&work.join(LOCK)).map_err(|e| DemError::input(e.to_string()))
}

/// A stopped run of `--out`, from its checkpoint, with the lock on its work folder.
fn resume_intrusion(
    a: &IntrudeRequest,
    work: &Path,
    ckpt: &Path,
) -> Result<(Run, WriterLock), DemError> {
    let missing = |e: String| {
        DemError::input(format!(
            "--resume: {e} (a stopped `dem intrude --out {}` leaves it there)",
            a.out.display()
        ))
    };
    if !ckpt.is_file() {
        return Err(missing(format!("{}: no checkpoint", ckpt.display())));
    }
    let lock = lock_work(work)?;
    let l = checkpoint::load(ckpt).map_err(|e| {
        DemError::input(format!(
            "--resume: {e} (a stopped `dem intrude --out {}` leaves it there)",
            a.out.display()
        ))
    })?;
    let run = intrude::resume(l.world, &l.record, &l.extra)
        .map_err(|e| DemError::input(format!("checkpoint {}: {e}", ckpt.display())))?;
    Ok((run, lock))
}

/// A bed checkpoint written by `dem bed`: its world and what it was made with.
struct Bed {
    checkpoint: checkpoint::Loaded,
    report: BedReport,
    params: DemParams,
    spec: BedSpec,
}

/// Read the bed `--bed` names (its folder or its checkpoint).
fn read_bed(bed_path: &Path) -> Result<Bed, DemError> {
    let bp = if bed_path.is_dir() {
        bed_path.join("bed.ckpt")
    } else {
        bed_path.to_path_buf()
    };
    let checkpoint = checkpoint::load(&bp).map_err(DemError::Input)?;
    let part = |key: &str| checkpoint.record["bed"][key].clone();
    let not_a_bed = |e: serde_json::Error| {
        DemError::input(format!("{}: not a bed checkpoint ({e})", bp.display()))
    };
    Ok(Bed {
        report: serde_json::from_value(part("report")).map_err(not_a_bed)?,
        params: serde_json::from_value(part("params")).map_err(not_a_bed)?,
        spec: serde_json::from_value(part("spec")).map_err(not_a_bed)?,
        checkpoint,
    })
}

/// The intruder's motion: a trajectory file or a constant speed down to `--depth`.
fn intruder_trajectory(
    a: &IntrudeRequest,
    params: &DemParams,
    progress: &dyn Progress,
) -> Result<Trajectory, DemError> {
    let traj = match (&a.trajectory, a.speed_m_s) {
        (Some(p), _) => {
            let t = match a.episode {
                Some(Episode::PushOff) => Trajectory::push_off_from_csv(p),
                None => Trajectory::from_csv(p, (a.from_s, a.to_s)),
            }
            .map_err(DemError::Input)?;
            let t = match a.scale_from_foot_m {
                Some(w0) => t.froude_scaled(a.foot_width_m / w0),
                None => t,
            };
            t.check_starts_at_surface().map_err(DemError::Input)?;
            t
        }
        (None, Some(v)) => Trajectory::Constant {
            speed_m_s: v,
            start_depth_m: -0.5 * params.diameter_m,
            end_depth_m: a.depth_m,
        },
        (None, None) => {
            return Err(DemError::input(
                "give the intruder's motion: --trajectory CSV or --speed M_PER_S",
            ));
        }
    };
    let vmax = traj.max_speed();
    if vmax > 1.5 * params.design_speed_m_s {
        progress.note(&format!(
            "dem intrude: warning: the intruder reaches {vmax:.3} m/s, above the {:.3} m/s the stiffness was chosen for (overlaps grow beyond --overlap; raise --design-speed)",
            params.design_speed_m_s
        ));
    }
    Ok(traj)
}

/// The intrusion `a` asks for into `bed`.
fn intrude_spec(
    a: &IntrudeRequest,
    bed: &Bed,
    progress: &dyn Progress,
) -> Result<IntrudeSpec, DemError> {
    let mut params = a.model.resolve()?;
    // The bed's grains are what they are.
    params.diameter_m = bed.params.diameter_m;
    params.density_kg_m3 = bed.params.density_kg_m3;
    params.sizes = bed.params.sizes;
    let traj = intruder_trajectory(a, &params, progress)?;
    let (t_s, depth_m) = match &traj {
        Trajectory::Table { t_s, depth_m, .. } => (t_s.clone(), depth_m.clone()),
        Trajectory::Constant { .. } => (
            vec![0.0, traj.duration_s()],
            vec![traj.depth(0.0), traj.depth(traj.duration_s())],
        ),
    };
    let d = params.diameter_m;
    Ok(IntrudeSpec {
        params,
        foot_width_m: a.foot_width_m,
        t_s,
        depth_m,
        trajectory: a.trajectory.as_ref().map_or(
            format!("constant {} m/s", a.speed_m_s.unwrap_or(0.0)),
            |p| p.display().to_string(),
        ),
        fps: a.fps,
        force_rate_hz: a.force_rate_hz,
        grid_spacing_m: a.grid_m.unwrap_or(2.0 * d),
        cg_width_m: a.cg_width_m.unwrap_or(d),
        m_per_px: a.m_per_px.unwrap_or(0.1 * d),
        frames: a.frames,
        phi_bulk: a.phi,
        checkpoint_every: a.checkpoint_every,
        seed: a.seed,
        surface_m: bed.report.surface_m,
        bed_x_m: (0.0, bed.spec.width_m),
        min_speed_ratio: a.min_speed_ratio,
    })
}

/// Refuse an intrusion whose samples, frames or grid would not fit.
fn check_spec(spec: &IntrudeSpec) -> Result<(), DemError> {
    if spec.fps * spec.params.dt_s > 1.0 || spec.force_rate_hz * spec.params.dt_s > 1.0 {
        return Err(DemError::input(format!(
            "--fps {} / --force-rate {} Hz sample faster than the step {:.3e} s (allowed: at most one sample per step)",
            spec.fps, spec.force_rate_hz, spec.params.dt_s
        )));
    }
    let (grid, cam) = spec.views();
    if spec.frames && u64::from(cam.width_px) * u64::from(cam.height_px) > 40_000_000 {
        return Err(DemError::input(format!(
            "side-wall frames of {}x{} px at --m-per-px {} (allowed: up to 40 Mpx; raise --m-per-px or --no-frames)",
            cam.width_px, cam.height_px, spec.m_per_px
        )));
    }
    if grid.nx * grid.ny > 4_000_000 {
        return Err(DemError::input(format!(
            "a coarse-graining grid of {}x{} nodes (allowed: up to 4 million; raise --grid)",
            grid.nx, grid.ny
        )));
    }
    Ok(())
}

/// A fresh intrusion into `--bed`: checked, its work folder cleared, its step-0 checkpoint
/// written (a run stopped before its first regular checkpoint resumes from there).
fn start_intrusion(
    a: &IntrudeRequest,
    work: &Path,
    ckpt: &Path,
    progress: &dyn Progress,
) -> Result<(Run, WriterLock), DemError> {
    let Some(bed_path) = &a.bed else {
        return Err(DemError::input("--bed BED is required (or --resume)"));
    };
    let bed = read_bed(bed_path)?;
    let spec = intrude_spec(a, &bed, progress)?;
    check_spec(&spec)?;
    StagedDir::create(&a.out)?; // checks the target now, before hours of work
    // Every refusal first (in memory): a bad input leaves a stopped run of the same --out as
    // it was.
    let mut run = intrude::start(spec, bed.checkpoint.world).map_err(DemError::Input)?;
    // Then a previous stopped run of the same --out is replaced by this fresh start (its
    // files cleared; the lock this run now holds on the folder stays).
    let lock = lock_work(work)?;
    clear_except_lock(work)?;
    run.world.rebuild();
    checkpoint::save(ckpt, &run.world, &intrude::record(&run), &run.fields_flat())
        .map_err(DemError::Internal)?;
    Ok((run, lock))
}

/// Advance `run` to its end or to `--stop-after`: side-wall frames and speed snapshots at
/// every sample, checkpoints as the spec says, progress in steps.
fn advance_intrusion(
    a: &IntrudeRequest,
    run: &mut Run,
    work: &Path,
    ckpt: &Path,
    progress: &dyn Progress,
) -> Result<(), DemError> {
    progress.start("steps", Some(run.total_steps));
    let mut at = run.steps();
    progress.advance(at);
    let until = a.stop_after.unwrap_or(u64::MAX);
    let vref = run.spec.trajectory().max_speed().max(1e-3);
    let cam = run.camera;
    let frames = run.spec.frames;
    let seed = run.spec.seed;
    let mut on_sample = |s: &SampleOut| -> Result<(), String> {
        if progress.cancelled() {
            return Err(format!(
                "interrupted at sample {}: the last checkpoint resumes it (--resume)",
                s.k
            ));
        }
        if frames {
            crate::render::side_wall_frame(s.world, &cam, seed)
                .save(work.join(format!("frames/frame_{:06}.png", s.k)))
                .map_err(|e| format!("cannot write frame {}: {e}", s.k))?;
        }
        let snap_cam = snapshot_camera(&cam);
        crate::render::speed_snapshot(s.world, &snap_cam, vref)
            .save(work.join(format!("snapshots/{:06}.png", s.k)))
            .map_err(|e| format!("cannot write snapshot {}: {e}", s.k))
    };
    let mut on_checkpoint = |r: &Run| -> Result<(), String> {
        checkpoint::save(ckpt, &r.world, &intrude::record(r), &r.fields_flat())
    };
    let mut on_progress = |s: u64| {
        progress.advance(s.saturating_sub(at));
        at = at.max(s);
    };
    run.advance(until, &mut on_sample, &mut on_checkpoint, &mut on_progress)
        .map_err(DemError::Internal)?;
    progress.finish();
    Ok(())
}

/// The snapshot camera: the side camera reduced to at most 640 px wide.
pub fn snapshot_camera(cam: &SideCamera) -> SideCamera {
    let f = (f64::from(cam.width_px) / 640.0).max(1.0);
    SideCamera {
        m_per_px: cam.m_per_px * f,
        width_px: ((f64::from(cam.width_px) / f) as u32).max(1),
        height_px: ((f64::from(cam.height_px) / f) as u32).max(1),
        ..*cam
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trajectory_is_froude_scaled_to_the_foot_it_drives() {
        let dir = std::env::temp_dir().join(format!("sj-scale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let csv = dir.join("trajectory.csv");
        // Down from the surface at 0.5 m/s for 40 ms: 20 mm.
        let rows: String = (0..=40)
            .map(|k| format!("{},{}\n", 1e-3 * f64::from(k), 0.5e-3 * f64::from(k)))
            .collect();
        std::fs::write(&csv, format!("t_s,depth_m\n{rows}")).unwrap();
        let params = ModelRequest::default().resolve().unwrap();
        let request = IntrudeRequest {
            trajectory: Some(csv.clone()),
            foot_width_m: 0.019,
            scale_from_foot_m: Some(0.076),
            ..IntrudeRequest::default()
        };
        let scaled = intruder_trajectory(&request, &params, &sandjumper_output::Silent).unwrap();
        // A quarter of the size: a quarter of the depth, in half the time, at half the speed.
        assert!(
            (scaled.duration_s() - 0.02).abs() < 1e-12,
            "{}",
            scaled.duration_s()
        );
        assert!((scaled.depth(0.02) - 0.005).abs() < 1e-12);
        assert!(
            (scaled.max_speed() - 0.25).abs() < 1e-9,
            "{}",
            scaled.max_speed()
        );
        // Unscaled without the flag; refused without a trajectory.
        let plain = IntrudeRequest {
            scale_from_foot_m: None,
            ..request.clone()
        };
        let t = intruder_trajectory(&plain, &params, &sandjumper_output::Silent).unwrap();
        assert!((t.depth(0.04) - 0.02).abs() < 1e-12);
        let no_file = IntrudeRequest {
            trajectory: None,
            speed_m_s: Some(0.1),
            bed: Some(dir.clone()),
            ..request
        };
        let e = no_file.validate().unwrap_err().to_string();
        assert!(e.contains("--scale-from-foot"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
