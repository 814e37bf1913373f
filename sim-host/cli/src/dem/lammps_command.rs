//! `sandjumper dem lammps` (the 3-D DEM of the intrusion, run by LAMMPS here or on a Slurm
//! cluster) and `sandjumper dem lammps-read` (a finished run's dumps read back again).

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use sandjumper_lammps::run::{LammpsOutcome, LammpsReadRequest, LammpsRequest, Submitted};
use sandjumper_lammps::spec::Preset;

use super::intrude_run::{Episode, parse_share};
use crate::command::args::parse_positive as positive;
use crate::command::progress::Bars;

/// `dem lammps`.
#[derive(Debug, Clone, Args)]
pub struct LammpsArgs {
    /// The scale to start from; the options below change single values.
    #[arg(long, value_enum, default_value = "paper")]
    pub preset: Preset,
    /// Trajectory CSV (`t_s` with `x_f_m`, as `jump --out` writes, or `depth_m`); it must
    /// start at or above the bed's surface.
    #[arg(long, value_name = "CSV", conflicts_with = "speed")]
    pub trajectory: Option<PathBuf>,
    /// Take one episode of a jump's trajectory.csv, shifted to start at the surface:
    /// `push-off`, the foot's last intrusion before the jump's flight.
    #[arg(long, value_enum, value_name = "EPISODE", requires = "trajectory")]
    pub episode: Option<Episode>,
    /// Constant intrusion speed instead, m/s (from the surface).
    #[arg(long, value_name = "M_PER_S", value_parser = positive)]
    pub speed: Option<f64>,
    /// Final depth at constant speed, m.
    #[arg(long, value_name = "M", default_value = "0.02", value_parser = positive)]
    pub depth: f64,
    /// Foot diameter, m.
    #[arg(long, value_name = "M", value_parser = positive)]
    pub foot_diameter: Option<f64>,
    /// Mean grain diameter, m (uniform within +-10 %).
    #[arg(long, value_name = "M", value_parser = positive)]
    pub grain_diameter: Option<f64>,
    /// Bed width (square, periodic sides), m.
    #[arg(long, value_name = "M", value_parser = positive)]
    pub bed_width: Option<f64>,
    /// Bed depth, m.
    #[arg(long, value_name = "M", value_parser = positive)]
    pub bed_depth: Option<f64>,
    /// Target packing fraction of the poured bed (0.583 to 0.625, what pouring frictional
    /// spheres gives); also the model's phi (within the presets' 0.57 to 0.62).
    #[arg(long, value_name = "PHI", value_parser = positive)]
    pub phi: Option<f64>,
    /// Young's modulus of the (softened) grains, Pa.
    #[arg(long, value_name = "PA", value_parser = positive)]
    pub youngs_modulus: Option<f64>,
    /// Sliding friction coefficient.
    #[arg(long, value_name = "MU")]
    pub friction: Option<f64>,
    /// Normal restitution coefficient.
    #[arg(long, value_name = "E")]
    pub restitution: Option<f64>,
    /// Dump rate (the PIV camera's), frames/s.
    #[arg(long, value_name = "FPS", value_parser = positive)]
    pub fps: Option<f64>,
    /// Seed of the grains' sizes and start.
    #[arg(long)]
    pub seed: Option<u64>,
    /// The added mass is taken while the foot moves down at least this share of its
    /// fastest speed.
    #[arg(long, value_name = "F", default_value = "0.3", value_parser = parse_share)]
    pub min_speed_ratio: f64,
    /// MPI ranks (`mpiexec -n N lmp`).
    #[arg(long, value_name = "N", default_value = "2",
          value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub ranks: u32,
    /// The LAMMPS executable (default: $SANDJUMPER_LMP, else lmp on PATH).
    #[arg(long, value_name = "PATH")]
    pub lmp: Option<PathBuf>,
    /// The MPI launcher (default: the mpiexec beside lmp, else on PATH).
    #[arg(long, value_name = "PATH")]
    pub mpiexec: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Submit the run to Slurm as one job of --ranks tasks, wait for it and check it.
    #[command(flatten)]
    pub slurm: crate::slurm::JobArgs,
}

/// `dem lammps-read`.
#[derive(Debug, Clone, Args)]
pub struct LammpsReadArgs {
    /// A run's folder (`dem lammps --out`), or its `lammps/` folder.
    #[arg(value_name = "RUN")]
    pub run: PathBuf,
    /// The speed rule of the added mass (see `dem lammps`).
    #[arg(long, value_name = "F", default_value = "0.3", value_parser = parse_share)]
    pub min_speed_ratio: f64,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

impl LammpsArgs {
    /// The library's request for these arguments.
    pub fn request(&self) -> LammpsRequest {
        LammpsRequest {
            preset: self.preset,
            trajectory: self.trajectory.clone(),
            episode: self.episode,
            speed_m_s: self.speed,
            depth_m: self.depth,
            foot_diameter_m: self.foot_diameter,
            grain_diameter_m: self.grain_diameter,
            bed_width_m: self.bed_width,
            bed_depth_m: self.bed_depth,
            phi: self.phi,
            youngs_modulus_pa: self.youngs_modulus,
            friction: self.friction,
            restitution: self.restitution,
            fps: self.fps,
            seed: self.seed,
            min_speed_ratio: self.min_speed_ratio,
            ranks: self.ranks,
            lmp: self.lmp.clone(),
            mpiexec: self.mpiexec.clone(),
            out: self.out.clone(),
        }
    }
}

fn report(outcome: &LammpsOutcome, json: bool) -> Result<(), CliError> {
    if json {
        println!("{}", outcome.summary_json()?);
    } else {
        println!("{outcome}");
    }
    eprintln!("wrote {}", outcome.out.display());
    Ok(())
}

/// Run `dem lammps` (here, or submitted to Slurm with `--slurm`).
pub fn run(a: &LammpsArgs) -> Result<(), CliError> {
    if !a.slurm.slurm {
        let outcome = sandjumper_lammps::run::run(&a.request(), &Bars::default())?;
        return report(&outcome, a.json);
    }
    let queue = a.slurm.queue.options();
    match sandjumper_lammps::run::submit(&a.request(), &queue, &Bars::new())? {
        Submitted::Queued { id } => {
            println!("{id}");
            eprintln!("when it is done its output is in {}", a.out.display());
        }
        Submitted::Done { summary_json } if a.json => print!("{summary_json}"),
        Submitted::Done { .. } => {}
    }
    Ok(())
}

/// Run `dem lammps-read`.
pub fn run_read(a: &LammpsReadArgs) -> Result<(), CliError> {
    let request = LammpsReadRequest {
        run: a.run.clone(),
        min_speed_ratio: a.min_speed_ratio,
        out: a.out.clone(),
    };
    let outcome = sandjumper_lammps::run::read(&request, &Bars::default())?;
    report(&outcome, a.json)
}
