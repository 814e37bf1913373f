//! `sandjumper dem bed | intrude | collide`: prepare a bed, run an intrusion into it, check
//! the contact law on one collision.

use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use serde::Serialize;

use super::bed::{BedMethod, BedReport, BedSpec, prepare};
use super::checkpoint;
use super::collide::{Collision, CollisionResult};
use super::grains::SizeDistribution;
use super::intrude::{self, IntrudeSpec, Run, SampleOut};
use super::intruder::Trajectory;
use super::params::{Choice, DemParams, Model};
use super::world::Integrator;
use crate::command::args::{parse_number, parse_positive as positive};
use sandjumper_output::CliError;
use sandjumper_output::{StagedDir, write_csv};

/// `sandjumper dem`.
#[derive(Debug, Clone, Args)]
pub struct DemArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: DemCommand,
}

/// The DEM's subcommands.
#[derive(Debug, Clone, Subcommand)]
pub enum DemCommand {
    /// Prepare a bed (settled under gravity, or packed to an area fraction) as a checkpoint.
    Bed(Box<BedArgs>),
    /// Drive the intruder into a bed along a trajectory; force, flow, frames.
    Intrude(Box<IntrudeArgs>),
    /// One head-on collision with the paper's contact law: restitution and contact time.
    Collide(CollideArgs),
    /// The intrusion in 3-D, run by LAMMPS (here, or on Slurm with --slurm): a poured bed,
    /// the disc foot on its trajectory, dumps at the camera's rate read back into the
    /// column's momentum, the added mass against eq. 6, the force against F_p(z), the cone.
    Lammps(Box<super::lammps_command::LammpsArgs>),
    /// Read a finished `dem lammps` run's dumps back again (another speed rule, or a run
    /// made elsewhere).
    LammpsRead(Box<super::lammps_command::LammpsReadArgs>),
}

/// The DEM's model as named on the command line ([`Model`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ModelChoice {
    /// Supplementary I exactly.
    Paper,
    /// Gravity, walls, friction, velocity Verlet.
    Full,
}

impl From<ModelChoice> for Model {
    fn from(m: ModelChoice) -> Self {
        match m {
            ModelChoice::Paper => Model::Paper,
            ModelChoice::Full => Model::Full,
        }
    }
}

/// The DEM's integrator as named on the command line ([`Integrator`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum IntegratorChoice {
    /// Forward Euler (the paper's).
    ForwardEuler,
    /// Velocity Verlet (leapfrog form).
    VelocityVerlet,
}

impl From<IntegratorChoice> for Integrator {
    fn from(i: IntegratorChoice) -> Self {
        match i {
            IntegratorChoice::ForwardEuler => Integrator::ForwardEuler,
            IntegratorChoice::VelocityVerlet => Integrator::VelocityVerlet,
        }
    }
}

/// A share in 0..=1.
pub(crate) fn parse_share(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("`{s}` not allowed (allowed: 0 to 1)"))
    }
}

/// `--episode`: a part of a jump's trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EpisodeChoice {
    /// The foot's last intrusion before the jump's flight.
    PushOff,
}

/// Grain and contact choices shared by `bed` and `intrude`.
#[derive(Debug, Clone, Args)]
pub struct ModelArgs {
    /// Model: `paper` (Supplementary I) or `full` (gravity, walls, friction, Verlet).
    #[arg(long, value_enum, default_value = "paper")]
    pub model: ModelChoice,
    /// Grain sizes: mono, bi (50:50, ratio 1.4) or poly.
    #[arg(long, value_enum, default_value = "bi")]
    pub sizes: SizesArg,
    /// Large over small diameter (bi).
    #[arg(long, value_name = "R", default_value = "1.4", value_parser = positive)]
    pub ratio: f64,
    /// Spread of diameters about the mean (poly), share.
    #[arg(long, value_name = "S", default_value = "0.2", value_parser = parse_number)]
    pub spread: f64,
    /// Small grain diameter, m.
    #[arg(long, value_name = "M", default_value = "1e-3", value_parser = parse_number)]
    pub diameter: f64,
    /// Grain density, kg/m^3.
    #[arg(long, value_name = "KG_M3", default_value = "1000", value_parser = parse_number)]
    pub density: f64,
    /// Intrusion speed the stiffness is chosen for, m/s.
    #[arg(long, value_name = "M_PER_S", default_value = "0.5", value_parser = parse_number)]
    pub design_speed: f64,
    /// Largest overlap at that speed, share of a diameter.
    #[arg(long, value_name = "F", default_value = "0.01", value_parser = parse_number)]
    pub overlap: f64,
    /// Normal stiffness instead, N/m.
    #[arg(long, value_name = "N_PER_M", value_parser = parse_number)]
    pub kn: Option<f64>,
    /// Coefficient of restitution (paper: of two small grains, with one dashpot for all
    /// pairs; full: of every pair).
    #[arg(long, value_name = "E", default_value = "0.5", value_parser = parse_number)]
    pub restitution: f64,
    /// Dashpot instead, N s/m (the same for every pair).
    #[arg(long, value_name = "N_S_PER_M", value_parser = parse_number)]
    pub damping: Option<f64>,
    /// Friction coefficient (full model).
    #[arg(long, value_name = "MU", default_value = "0.5", value_parser = parse_number)]
    pub mu: f64,
    /// Per-grain drag rate, 1/s (paper default 20, full 0).
    #[arg(long, value_name = "PER_S", value_parser = parse_number)]
    pub drag: Option<f64>,
    /// Integrator (paper: forward Euler, full: velocity Verlet).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorChoice>,
    /// Steps per shortest contact time.
    #[arg(long, value_name = "N", default_value = "50", value_parser = parse_number)]
    pub steps_per_contact: f64,
    /// Time step instead, s.
    #[arg(long, value_name = "S", value_parser = parse_number)]
    pub dt: Option<f64>,
    /// Allow a step above t_c / 10.
    #[arg(long)]
    pub force_step: bool,
    /// Walls in the paper model (the full model always has them).
    #[arg(long)]
    pub walls: bool,
}

/// `--sizes`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SizesArg {
    /// One size.
    Mono,
    /// Two sizes, 50:50.
    Bi,
    /// Uniform spread.
    Poly,
}

impl ModelArgs {
    /// Resolve to parameters.
    pub fn resolve(&self) -> Result<DemParams, CliError> {
        let mut c = Choice::new(self.model.into());
        c.sizes = match self.sizes {
            SizesArg::Mono => SizeDistribution::Mono,
            SizesArg::Bi => SizeDistribution::Bi {
                ratio: self.ratio,
                small_share: 0.5,
            },
            SizesArg::Poly => SizeDistribution::Poly {
                spread: self.spread,
            },
        };
        c.diameter_m = self.diameter;
        c.density_kg_m3 = self.density;
        c.speed_m_s = self.design_speed;
        c.overlap = self.overlap;
        c.kn_n_per_m = self.kn;
        c.restitution = self.restitution;
        c.damping_n_s_per_m = self.damping;
        c.mu = self.mu;
        c.drag_per_s = self.drag;
        c.integrator = self.integrator.map(Into::into);
        c.steps_per_contact = self.steps_per_contact;
        c.dt_s = self.dt;
        c.walls = self.walls;
        c.resolve(self.force_step).map_err(CliError::input)
    }
}

/// `sandjumper dem bed`.
#[derive(Debug, Clone, Args)]
pub struct BedArgs {
    /// Grains and contacts.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Box width, m.
    #[arg(long, value_name = "M", default_value = "0.23", value_parser = parse_number)]
    pub width: f64,
    /// Bed height, m.
    #[arg(long, value_name = "M", default_value = "0.08", value_parser = parse_number)]
    pub height: f64,
    /// Pack to this area fraction with no gravity instead of settling under gravity.
    #[arg(long, value_name = "PHI", value_parser = parse_number)]
    pub pack: Option<f64>,
    /// Seed.
    #[arg(long, default_value = "1")]
    pub seed: u64,
    /// Longest preparation, simulated s.
    #[arg(long, value_name = "S", default_value = "2", value_parser = parse_number)]
    pub max_time: f64,
    /// At rest once the kinetic energy per grain is below this share of m g d.
    #[arg(long, value_name = "F", default_value = "1e-8", value_parser = parse_number)]
    pub rest: f64,
    /// Threads (0: all cores).
    #[arg(long, default_value = "0")]
    pub threads: usize,
    /// Pin each thread to a core of its own, among those this process may run on (as
    /// OpenMP's `OMP_PROC_BIND`): steadier, and about 2 % faster on two threads. Leave it
    /// off on a node shared with jobs that are not confined to cores of their own.
    #[arg(long)]
    pub pin_threads: bool,
    /// Output directory: bed.ckpt, grains.csv, load.csv, bed.toml, bed.png/.svg.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// `sandjumper dem intrude`.
#[derive(Debug, Clone, Args)]
pub struct IntrudeArgs {
    /// The bed (a `dem bed` output directory or its bed.ckpt).
    #[arg(long, value_name = "BED", required_unless_present = "resume")]
    pub bed: Option<PathBuf>,
    /// Trajectory CSV (`t_s` with `x_f_m`, as `jump --out` writes, or `depth_m`); it must
    /// start at or above the bed's surface.
    #[arg(long, value_name = "CSV", conflicts_with = "speed")]
    pub trajectory: Option<PathBuf>,
    /// Take one episode of a jump's trajectory.csv, shifted to start at the surface:
    /// `push-off`, the foot's last intrusion before the jump's flight.
    #[arg(long, value_enum, value_name = "EPISODE", requires = "trajectory", conflicts_with_all = ["from", "to"])]
    pub episode: Option<EpisodeChoice>,
    /// Use the trajectory from this time, s.
    #[arg(long, value_name = "S", value_parser = parse_number)]
    pub from: Option<f64>,
    /// Until this time, s.
    #[arg(long, value_name = "S", value_parser = parse_number)]
    pub to: Option<f64>,
    /// Constant intrusion speed instead, m/s.
    #[arg(long, value_name = "M_PER_S", value_parser = positive)]
    pub speed: Option<f64>,
    /// Final depth at constant speed, m.
    #[arg(long, value_name = "M", default_value = "0.03", value_parser = positive)]
    pub depth: f64,
    /// Foot width, m (the robot's 7.6 cm foot; smaller for a scaled foot).
    #[arg(long, value_name = "M", default_value = "0.076", value_parser = positive)]
    pub foot_width: f64,
    /// Grains and contacts of the intrusion (the bed's grains are kept).
    #[command(flatten)]
    pub model: ModelArgs,
    /// Samples per second (fields, frames, snapshots): the side camera's 500 fps.
    #[arg(long, value_name = "FPS", default_value = "500", value_parser = positive)]
    pub fps: f64,
    /// Force rows per second.
    #[arg(long, value_name = "HZ", default_value = "10000", value_parser = positive)]
    pub force_rate: f64,
    /// The added mass `P / v_foot` is taken only while the foot moves down at least this
    /// share of its fastest speed, 0..1 (the paper excluded the samples where v -> 0).
    #[arg(long, value_name = "F", default_value = "0.3", value_parser = parse_share)]
    pub min_speed_ratio: f64,
    /// Coarse-graining grid spacing, m (default 2 grain diameters).
    #[arg(long, value_name = "M", value_parser = positive)]
    pub grid: Option<f64>,
    /// Coarse-graining width, m (default 1 grain diameter).
    #[arg(long, value_name = "M", value_parser = positive)]
    pub cg_width: Option<f64>,
    /// Side-wall frames' scale, m/px (default a tenth of a grain).
    #[arg(long, value_name = "M", value_parser = positive)]
    pub m_per_px: Option<f64>,
    /// Do not render side-wall frames.
    #[arg(long)]
    pub no_frames: bool,
    /// Bed packing fraction for momentum (rho phi), as `piv --phi`.
    #[arg(long, value_name = "PHI", default_value = "0.6", value_parser = crate::command::args::parse_phi)]
    pub phi: f64,
    /// Checkpoint every N steps (0: never).
    #[arg(long, value_name = "N", default_value = "20000")]
    pub checkpoint_every: u64,
    /// Stop after this many steps (leaves the run resumable; for tests and batch queues).
    #[arg(long, value_name = "N")]
    pub stop_after: Option<u64>,
    /// Continue the stopped run of `--out`.
    #[arg(long)]
    pub resume: bool,
    /// Seed of the frames' grey levels.
    #[arg(long, default_value = "1")]
    pub seed: u64,
    /// Threads (0: all cores).
    #[arg(long, default_value = "0")]
    pub threads: usize,
    /// Pin each thread to a core of its own, among those this process may run on (as
    /// OpenMP's `OMP_PROC_BIND`): steadier, and about 2 % faster on two threads. Leave it
    /// off on a node shared with jobs that are not confined to cores of their own.
    #[arg(long)]
    pub pin_threads: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `sandjumper dem collide`.
#[derive(Debug, Clone, Args)]
pub struct CollideArgs {
    /// Diameter of disk 1 (the one that hits the wall), m.
    #[arg(long, value_name = "M", value_parser = parse_number)]
    pub d1: f64,
    /// Diameter of disk 2, m.
    #[arg(long, value_name = "M", value_parser = parse_number, required_unless_present = "wall")]
    pub d2: Option<f64>,
    /// Disk 1 against a flat wall.
    #[arg(long)]
    pub wall: bool,
    /// Normal stiffness, N/m.
    #[arg(long, value_name = "N_PER_M", value_parser = parse_number)]
    pub kn: f64,
    /// Normal damping, N s/m.
    #[arg(long, value_name = "N_S_PER_M", value_parser = parse_number)]
    pub damping: f64,
    /// Impact speed, m/s.
    #[arg(long, value_name = "M_PER_S", value_parser = parse_number)]
    pub speed: f64,
    /// Grain density, kg/m^3.
    #[arg(long, value_name = "KG_M3", default_value = "1000", value_parser = parse_number)]
    pub density: f64,
    /// Time step, s (default t_c / 50).
    #[arg(long, value_name = "S", value_parser = parse_number)]
    pub dt: Option<f64>,
    /// Allow a step above t_c / 10.
    #[arg(long)]
    pub force_step: bool,
    /// Integrator.
    #[arg(long, value_enum, default_value = "velocity-verlet")]
    pub integrator: IntegratorChoice,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Run `sandjumper dem`.
pub fn run(a: &DemArgs) -> Result<(), CliError> {
    match &a.command {
        DemCommand::Collide(c) => run_collide(c),
        DemCommand::Bed(b) => with_threads(b.threads, b.pin_threads, || run_bed(b)),
        DemCommand::Intrude(i) => with_threads(i.threads, i.pin_threads, || run_intrude(i)),
        DemCommand::Lammps(l) => super::lammps_command::run(l),
        DemCommand::LammpsRead(r) => super::lammps_command::run_read(r),
    }
}

/// Run `f` on a pool of `n` threads (0: one a core), each pinned to a core of its own when
/// `pin`.
fn with_threads(
    n: usize,
    pin: bool,
    f: impl FnOnce() -> Result<(), CliError> + Send,
) -> Result<(), CliError> {
    let cores = if pin {
        core_affinity::get_core_ids().unwrap_or_default()
    } else {
        Vec::new()
    };
    let n = if n == 0 {
        rayon::current_num_threads()
    } else {
        n
    };
    if pin && cores.len() < n {
        return Err(CliError::input(format!(
            "--pin-threads: {n} threads need {n} cores, and this process may run on {} \
             (use --threads {} or fewer, or drop --pin-threads)",
            cores.len(),
            cores.len().max(1)
        )));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .start_handler(move |k| {
            if let Some(&core) = cores.get(k) {
                core_affinity::set_for_current(core);
            }
        })
        .build()
        .map_err(|e| CliError::internal(format!("cannot start {n} threads: {e}")))?;
    pool.install(f)
}

/// The JSON object `dem collide --json` prints, for `dem collide` arguments (bad input, and
/// any other `dem` subcommand, is an error).
pub fn collide_json(a: &DemArgs) -> Result<String, CliError> {
    let DemCommand::Collide(c) = &a.command else {
        return Err(CliError::input("not a `dem collide` command"));
    };
    serde_json::to_string_pretty(&collide(c)?).map_err(|e| CliError::internal(e.to_string()))
}

fn collide(a: &CollideArgs) -> Result<CollisionResult, CliError> {
    let c = Collision {
        d1_m: a.d1,
        d2_m: a.d2.unwrap_or(a.d1),
        wall: a.wall,
        kn_n_per_m: a.kn,
        damping_n_s_per_m: a.damping,
        speed_m_s: a.speed,
        density_kg_m3: a.density,
        dt_s: a.dt,
        integrator: a.integrator.into(),
    };
    c.run(a.force_step).map_err(CliError::input)
}

fn run_collide(a: &CollideArgs) -> Result<(), CliError> {
    let r = collide(a)?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&r).map_err(|e| CliError::internal(e.to_string()))?
        );
    } else {
        println!(
            "restitution {:.6} (analytic {:.6}, error {:+.2e}), contact time {:.6e} s (analytic {:.6e} s, error {:+.2e}), effective mass {:.4e} kg, step {:.3e} s ({:.1} per contact), largest overlap {:.3e} m",
            r.restitution,
            r.restitution_analytic,
            r.restitution_error,
            r.contact_time_s,
            r.contact_time_analytic_s,
            r.contact_time_error,
            r.effective_mass_kg,
            r.dt_s,
            r.steps_per_contact,
            r.max_overlap_m
        );
    }
    Ok(())
}

/// What `bed.toml` holds.
#[derive(Serialize)]
struct BedRecord<'a> {
    params: &'a DemParams,
    spec: &'a BedSpec,
    report: &'a BedReport,
    bytes_per_grain: f64,
}

fn run_bed(a: &BedArgs) -> Result<(), CliError> {
    let p = a.model.resolve()?;
    let spec = BedSpec {
        width_m: a.width,
        height_m: a.height,
        method: match a.pack {
            Some(phi) => BedMethod::Pack { phi },
            None => BedMethod::Settle,
        },
        seed: a.seed,
        max_time_s: a.max_time,
        rest_agitation: a.rest,
    };
    spec.check(&p).map_err(CliError::input)?;
    let staged = StagedDir::create(&a.out)?;
    let n = spec.grain_count(&p);
    let dl = p.dimensionless(p.design_speed_m_s);
    eprintln!(
        "dem bed: {n} grains, step {:.3e} s, contact time {:.3e} s, t_c v / d = {:.3e}, Froude v / sqrt(g d) = {:.2} at {} m/s",
        p.dt_s, dl.contact_time_s, dl.contact_time_speed_over_d, dl.froude, p.design_speed_m_s
    );
    let bar = crate::command::progress_bar(1000, "bed preparation (share)");
    let (world, rep) =
        prepare(&p, &spec, |f| bar.set_position((f * 1000.0) as u64)).map_err(CliError::input)?;
    bar.finish_and_clear();
    checkpoint::save(
        &staged.file("bed.ckpt"),
        &world,
        &serde_json::json!({ "bed": { "params": p, "spec": spec, "report": rep } }),
        &[],
    )
    .map_err(CliError::internal)?;
    write_grains(&staged.file("grains.csv"), &world)?;
    // The load across heights against the weight above (a bed at rest carries its weight).
    let heights: Vec<f64> = (1..20).map(|k| rep.surface_m * k as f64 / 20.0).collect();
    let load = world.vertical_load_across(&heights);
    let g = world.cfg.gravity_m_s2;
    #[derive(Serialize)]
    struct LoadRow {
        height_m: f64,
        load_n: f64,
        weight_above_n: f64,
    }
    let rows: Vec<LoadRow> = heights
        .iter()
        .zip(&load)
        .map(|(&h, &l)| LoadRow {
            height_m: h,
            load_n: l,
            weight_above_n: (0..world.g.len())
                .filter(|&i| world.g.y[i] >= h)
                .map(|i| world.g.mass(i) * g)
                .sum(),
        })
        .collect();
    write_csv(
        &staged.file("load.csv"),
        &rows,
        &["height_m", "load_n", "weight_above_n"],
    )
    .map_err(CliError::internal)?;
    let rec = BedRecord {
        params: &p,
        spec: &spec,
        report: &rep,
        bytes_per_grain: world.bytes_per_grain(),
    };
    staged.write_text(
        "bed.toml",
        &toml::to_string(&rec).map_err(|e| CliError::internal(e.to_string()))?,
    )?;
    let cam = overview_camera(a.width, rep.surface_m);
    // A bed at rest: the colour scale only has to exist.
    let vmax = 0.1;
    super::figure::save_snapshot(
        &world,
        &cam,
        vmax,
        &format!(
            "DEM bed: {} grains, area fraction {:.3}, hexatic order {:.2}",
            rep.grains,
            rep.area_fraction,
            super::structure::hexatic_order(&world)
        ),
        &staged.file("bed.png"),
        &staged.file("bed.svg"),
    )?;
    let out = staged.commit()?;
    println!(
        "dem bed: {} grains ({:.3e} kg), surface {:.4} m, area fraction {:.3}, {} after {:.3} s ({} steps), written to {}",
        rep.grains,
        rep.mass_kg,
        rep.surface_m,
        rep.area_fraction,
        if rep.settled {
            "at rest"
        } else {
            "NOT at rest"
        },
        rep.time_s,
        rep.steps,
        out.display()
    );
    Ok(())
}

fn overview_camera(width: f64, surface: f64) -> super::render::SideCamera {
    let m_per_px = (width.max(surface) / 1200.0).max(1e-6);
    super::render::SideCamera {
        m_per_px,
        left_m: 0.0,
        top_m: surface * 1.05,
        width_px: (width / m_per_px) as u32,
        height_px: (surface * 1.05 / m_per_px) as u32,
    }
}

fn write_grains(path: &Path, w: &super::world::World) -> Result<(), CliError> {
    #[derive(Serialize)]
    struct Row {
        id: u32,
        kind: u8,
        x_m: f64,
        y_m: f64,
        diameter_m: f64,
        vx_m_s: f64,
        vy_m_s: f64,
    }
    let g = &w.g;
    let mut rows: Vec<Row> = (0..g.len())
        .map(|i| Row {
            id: g.id[i],
            kind: g.kind[i],
            x_m: g.x[i],
            y_m: g.y[i],
            diameter_m: 2.0 * g.radius[i],
            vx_m_s: w.u.x[i],
            vy_m_s: w.u.y[i],
        })
        .collect();
    rows.sort_by_key(|r| r.id);
    write_csv(
        path,
        &rows,
        &["id", "kind", "x_m", "y_m", "diameter_m", "vx_m_s", "vy_m_s"],
    )
    .map_err(CliError::internal)
}

fn bed_checkpoint(p: &Path) -> PathBuf {
    if p.is_dir() {
        p.join("bed.ckpt")
    } else {
        p.to_path_buf()
    }
}

/// The work directory of a run writing to `out`: checkpoints and frames until it finishes.
pub fn work_dir(out: &Path) -> PathBuf {
    let mut name = out.file_name().unwrap_or_default().to_os_string();
    name.push(".incomplete");
    out.with_file_name(name)
}

/// `dem intrude`, in stages: the run resumed from its checkpoint or started from a bed
/// ([`start_intrusion`]), advanced with frames, snapshots and checkpoints
/// ([`advance_intrusion`]), then its outputs written and summarised.
fn run_intrude(a: &IntrudeArgs) -> Result<(), CliError> {
    let work = work_dir(&a.out);
    let ckpt = work.join("run.ckpt");
    let mut run = if a.resume {
        resume_intrusion(a, &ckpt)?
    } else {
        start_intrusion(a, &work, &ckpt)?
    };
    std::fs::create_dir_all(work.join("frames"))
        .and_then(|()| std::fs::create_dir_all(work.join("snapshots")))
        .map_err(|e| CliError::input(format!("cannot create {}: {e}", work.display())))?;
    let p = run.spec.params;
    let dl = p.dimensionless(run.spec.trajectory().max_speed());
    eprintln!(
        "dem intrude: {} grains, {} steps of {:.3e} s; contact time {:.3e} s: t_c v / d = {:.3e}, Froude v / sqrt(g d) = {:.2}",
        run.world.g.len(),
        run.total_steps,
        p.dt_s,
        dl.contact_time_s,
        dl.contact_time_speed_over_d,
        dl.froude
    );
    advance_intrusion(a, &mut run, &work, &ckpt)?;
    if run.steps() < run.total_steps {
        // Resuming from the last regular checkpoint (not from here) repeats the
        // uninterrupted run bit for bit; the steps since are done again.
        let every = run.spec.checkpoint_every;
        let from = run.steps().checked_div(every).map_or(0, |k| k * every);
        println!(
            "dem intrude: stopped after {} of {} steps; `dem intrude --resume --out {}` continues from the checkpoint at step {from}",
            run.steps(),
            run.total_steps,
            a.out.display()
        );
        return Ok(());
    }
    let summary = super::outputs::write(&run, &work, &a.out)?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&summary)
                .map_err(|e| CliError::internal(e.to_string()))?
        );
    } else {
        println!("{}", summary.line());
    }
    Ok(())
}

/// A stopped run of `--out`, from its checkpoint.
fn resume_intrusion(a: &IntrudeArgs, ckpt: &Path) -> Result<Run, CliError> {
    let l = checkpoint::load(ckpt).map_err(|e| {
        CliError::input(format!(
            "--resume: {e} (a stopped `dem intrude --out {}` leaves it there)",
            a.out.display()
        ))
    })?;
    intrude::resume(l.world, &l.record, &l.extra)
        .map_err(|e| CliError::input(format!("checkpoint {}: {e}", ckpt.display())))
}

/// A bed checkpoint written by `dem bed`: its world and what it was made with.
struct Bed {
    checkpoint: checkpoint::Loaded,
    report: BedReport,
    params: DemParams,
    spec: BedSpec,
}

/// Read the bed `--bed` names (its folder or its checkpoint).
fn read_bed(bed_path: &Path) -> Result<Bed, CliError> {
    let bp = bed_checkpoint(bed_path);
    let checkpoint = checkpoint::load(&bp).map_err(CliError::input)?;
    let part = |key: &str| checkpoint.record["bed"][key].clone();
    let not_a_bed = |e: serde_json::Error| {
        CliError::input(format!("{}: not a bed checkpoint ({e})", bp.display()))
    };
    Ok(Bed {
        report: serde_json::from_value(part("report")).map_err(not_a_bed)?,
        params: serde_json::from_value(part("params")).map_err(not_a_bed)?,
        spec: serde_json::from_value(part("spec")).map_err(not_a_bed)?,
        checkpoint,
    })
}

/// The intruder's motion: a trajectory file or a constant speed down to `--depth`.
fn intruder_trajectory(a: &IntrudeArgs, params: &DemParams) -> Result<Trajectory, CliError> {
    let traj = match (&a.trajectory, a.speed) {
        (Some(p), _) => {
            let t = match a.episode {
                Some(EpisodeChoice::PushOff) => Trajectory::push_off_from_csv(p),
                None => Trajectory::from_csv(p, (a.from, a.to)),
            }
            .map_err(CliError::input)?;
            t.check_starts_at_surface().map_err(CliError::input)?;
            t
        }
        (None, Some(v)) => Trajectory::Constant {
            speed_m_s: v,
            start_depth_m: -0.5 * params.diameter_m,
            end_depth_m: a.depth,
        },
        (None, None) => {
            return Err(CliError::input(
                "give the intruder's motion: --trajectory CSV or --speed M_PER_S",
            ));
        }
    };
    let vmax = traj.max_speed();
    if vmax > 1.5 * params.design_speed_m_s {
        eprintln!(
            "dem intrude: warning: the intruder reaches {vmax:.3} m/s, above the {:.3} m/s the stiffness was chosen for (overlaps grow beyond --overlap; raise --design-speed)",
            params.design_speed_m_s
        );
    }
    Ok(traj)
}

/// The intrusion `a` asks for into `bed`.
fn intrude_spec(a: &IntrudeArgs, bed: &Bed) -> Result<IntrudeSpec, CliError> {
    let mut params = a.model.resolve()?;
    // The bed's grains are what they are.
    params.diameter_m = bed.params.diameter_m;
    params.density_kg_m3 = bed.params.density_kg_m3;
    params.sizes = bed.params.sizes;
    let traj = intruder_trajectory(a, &params)?;
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
        foot_width_m: a.foot_width,
        t_s,
        depth_m,
        trajectory: a
            .trajectory
            .as_ref()
            .map_or(format!("constant {} m/s", a.speed.unwrap_or(0.0)), |p| {
                p.display().to_string()
            }),
        fps: a.fps,
        force_rate_hz: a.force_rate,
        grid_spacing_m: a.grid.unwrap_or(2.0 * d),
        cg_width_m: a.cg_width.unwrap_or(d),
        m_per_px: a.m_per_px.unwrap_or(0.1 * d),
        frames: !a.no_frames,
        phi_bulk: a.phi,
        checkpoint_every: a.checkpoint_every,
        seed: a.seed,
        surface_m: bed.report.surface_m,
        bed_x_m: (0.0, bed.spec.width_m),
        min_speed_ratio: a.min_speed_ratio,
    })
}

/// Refuse an intrusion whose samples, frames or grid would not fit.
fn check_spec(spec: &IntrudeSpec) -> Result<(), CliError> {
    if spec.fps * spec.params.dt_s > 1.0 || spec.force_rate_hz * spec.params.dt_s > 1.0 {
        return Err(CliError::input(format!(
            "--fps {} / --force-rate {} Hz sample faster than the step {:.3e} s (allowed: at most one sample per step)",
            spec.fps, spec.force_rate_hz, spec.params.dt_s
        )));
    }
    let (grid, cam) = spec.views();
    if spec.frames && u64::from(cam.width_px) * u64::from(cam.height_px) > 40_000_000 {
        return Err(CliError::input(format!(
            "side-wall frames of {}x{} px at --m-per-px {} (allowed: up to 40 Mpx; raise --m-per-px or --no-frames)",
            cam.width_px, cam.height_px, spec.m_per_px
        )));
    }
    if grid.nx * grid.ny > 4_000_000 {
        return Err(CliError::input(format!(
            "a coarse-graining grid of {}x{} nodes (allowed: up to 4 million; raise --grid)",
            grid.nx, grid.ny
        )));
    }
    Ok(())
}

/// A fresh intrusion into `--bed`: checked, its work folder cleared, its step-0 checkpoint
/// written (a run stopped before its first regular checkpoint resumes from there).
fn start_intrusion(a: &IntrudeArgs, work: &Path, ckpt: &Path) -> Result<Run, CliError> {
    let Some(bed_path) = &a.bed else {
        return Err(CliError::input("--bed BED is required (or --resume)"));
    };
    let bed = read_bed(bed_path)?;
    let spec = intrude_spec(a, &bed)?;
    check_spec(&spec)?;
    // A previous stopped run of the same --out is replaced by a fresh start.
    if work.exists() {
        std::fs::remove_dir_all(work)
            .map_err(|e| CliError::input(format!("cannot clear {}: {e}", work.display())))?;
    }
    StagedDir::create(&a.out)?; // checks the target now, before hours of work
    let mut run = intrude::start(spec, bed.checkpoint.world).map_err(CliError::input)?;
    std::fs::create_dir_all(work)
        .map_err(|e| CliError::input(format!("cannot create {}: {e}", work.display())))?;
    run.world.rebuild();
    checkpoint::save(ckpt, &run.world, &intrude::record(&run), &run.fields_flat())
        .map_err(CliError::internal)?;
    Ok(run)
}

/// Advance `run` to its end or to `--stop-after`: side-wall frames and speed snapshots at
/// every sample, checkpoints as the spec says, a progress bar.
fn advance_intrusion(
    a: &IntrudeArgs,
    run: &mut Run,
    work: &Path,
    ckpt: &Path,
) -> Result<(), CliError> {
    let bar = crate::command::progress_bar(run.total_steps, "steps");
    bar.set_position(run.steps());
    let until = a.stop_after.map_or(u64::MAX, |s| s);
    let vref = run.spec.trajectory().max_speed().max(1e-3);
    let cam = run.camera;
    let frames = run.spec.frames;
    let seed = run.spec.seed;
    let mut on_sample = |s: &SampleOut| -> Result<(), String> {
        if frames {
            super::render::side_wall_frame(s.world, &cam, seed)
                .save(work.join(format!("frames/frame_{:06}.png", s.k)))
                .map_err(|e| format!("cannot write frame {}: {e}", s.k))?;
        }
        let snap_cam = snapshot_camera(&cam);
        super::render::speed_snapshot(s.world, &snap_cam, vref)
            .save(work.join(format!("snapshots/{:06}.png", s.k)))
            .map_err(|e| format!("cannot write snapshot {}: {e}", s.k))
    };
    let mut on_checkpoint = |r: &Run| -> Result<(), String> {
        checkpoint::save(ckpt, &r.world, &intrude::record(r), &r.fields_flat())
    };
    let mut on_progress = |s: u64| bar.set_position(s);
    run.advance(until, &mut on_sample, &mut on_checkpoint, &mut on_progress)
        .map_err(CliError::internal)?;
    bar.finish_and_clear();
    Ok(())
}

/// The snapshot camera: the side camera reduced to at most 640 px wide.
pub fn snapshot_camera(cam: &super::render::SideCamera) -> super::render::SideCamera {
    let f = (f64::from(cam.width_px) / 640.0).max(1.0);
    super::render::SideCamera {
        m_per_px: cam.m_per_px * f,
        width_px: ((f64::from(cam.width_px) / f) as u32).max(1),
        height_px: ((f64::from(cam.height_px) / f) as u32).max(1),
        ..*cam
    }
}
