//! `sandjumper dem bed | intrude | collide`: prepare a bed, run an intrusion into it, check
//! the contact law on one collision.

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::collide::CollideRequest;
use super::intrude_run::{Episode, IntrudeOutcome, parse_share};
use super::params::Model;
use super::request::{ModelRequest, Sizes};
use super::world::Integrator;
use crate::command::CliError;
use crate::command::args::{parse_number, parse_positive as positive};
use crate::command::progress::Bars;

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

/// Grain and contact choices shared by `bed` and `intrude`.
#[derive(Debug, Clone, Args)]
pub struct ModelArgs {
    /// Model: `paper` (Supplementary I) or `full` (gravity, walls, friction, Verlet).
    #[arg(long, value_enum, default_value = "paper")]
    pub model: Model,
    /// Grain sizes: mono, bi (50:50, ratio 1.4) or poly.
    #[arg(long, value_enum, default_value = "bi")]
    pub sizes: Sizes,
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
    pub integrator: Option<Integrator>,
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

impl ModelArgs {
    /// The library's request for these choices.
    pub fn request(&self) -> ModelRequest {
        ModelRequest {
            model: self.model,
            sizes: self.sizes,
            ratio: self.ratio,
            spread: self.spread,
            diameter_m: self.diameter,
            density_kg_m3: self.density,
            design_speed_m_s: self.design_speed,
            overlap: self.overlap,
            kn_n_per_m: self.kn,
            restitution: self.restitution,
            damping_n_s_per_m: self.damping,
            mu: self.mu,
            drag_per_s: self.drag,
            integrator: self.integrator,
            steps_per_contact: self.steps_per_contact,
            dt_s: self.dt,
            force_step: self.force_step,
            walls: self.walls,
        }
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
    pub episode: Option<Episode>,
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
    pub integrator: Integrator,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Run `sandjumper dem`.
pub fn run(a: &DemArgs) -> Result<(), CliError> {
    match &a.command {
        DemCommand::Collide(c) => {
            let r = super::collide::run(&c.request(), &sandjumper_output::Silent)?;
            if c.json {
                println!("{}", r.json()?);
            } else {
                println!("{r}");
            }
        }
        DemCommand::Bed(b) => println!("{}", super::bed_run::run(&b.request(), &Bars::new())?),
        DemCommand::Intrude(i) => match super::intrude_run::run(&i.request(), &Bars::new())? {
            IntrudeOutcome::Finished(s) if i.json => println!("{}", s.json()?),
            outcome => println!("{outcome}"),
        },
        DemCommand::Lammps(l) => super::lammps_command::run(l)?,
        DemCommand::LammpsRead(r) => super::lammps_command::run_read(r)?,
    }
    Ok(())
}

impl CollideArgs {
    /// The library's request for these arguments.
    pub fn request(&self) -> CollideRequest {
        CollideRequest {
            d1_m: self.d1,
            d2_m: self.d2,
            wall: self.wall,
            kn_n_per_m: self.kn,
            damping_n_s_per_m: self.damping,
            speed_m_s: self.speed,
            density_kg_m3: self.density,
            dt_s: self.dt,
            force_step: self.force_step,
            integrator: self.integrator,
        }
    }
}

impl BedArgs {
    /// The library's request for these arguments.
    pub fn request(&self) -> super::bed_run::BedRequest {
        super::bed_run::BedRequest {
            model: self.model.request(),
            width_m: self.width,
            height_m: self.height,
            pack: self.pack,
            seed: self.seed,
            max_time_s: self.max_time,
            rest: self.rest,
            threads: self.threads,
            pin_threads: self.pin_threads,
            out: self.out.clone(),
        }
    }
}

impl IntrudeArgs {
    /// The library's request for these arguments.
    pub fn request(&self) -> super::intrude_run::IntrudeRequest {
        super::intrude_run::IntrudeRequest {
            bed: self.bed.clone(),
            trajectory: self.trajectory.clone(),
            episode: self.episode,
            from_s: self.from,
            to_s: self.to,
            speed_m_s: self.speed,
            depth_m: self.depth,
            foot_width_m: self.foot_width,
            model: self.model.request(),
            fps: self.fps,
            force_rate_hz: self.force_rate,
            min_speed_ratio: self.min_speed_ratio,
            grid_m: self.grid,
            cg_width_m: self.cg_width,
            m_per_px: self.m_per_px,
            frames: !self.no_frames,
            phi: self.phi,
            checkpoint_every: self.checkpoint_every,
            stop_after: self.stop_after,
            resume: self.resume,
            seed: self.seed,
            threads: self.threads,
            pin_threads: self.pin_threads,
            out: self.out.clone(),
        }
    }
}
