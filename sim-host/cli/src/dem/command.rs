//! `sandjumper dem bed | intrude | collide`: prepare a bed, run an intrusion into it, check
//! the contact law on one collision.

use clap::{Args, Subcommand};

use super::bed_run::BedRequest;
use super::collide::CollideRequest;
use super::intrude_run::{IntrudeOutcome, IntrudeRequest};
use crate::command::CliError;
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
    Bed(Box<BedRequest>),
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

/// `sandjumper dem intrude`.
#[derive(Debug, Clone, Args)]
pub struct IntrudeArgs {
    /// The intrusion.
    #[command(flatten)]
    pub request: IntrudeRequest,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `sandjumper dem collide`.
#[derive(Debug, Clone, Args)]
pub struct CollideArgs {
    /// The collision.
    #[command(flatten)]
    pub request: CollideRequest,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// Run `sandjumper dem`.
pub fn run(a: &DemArgs) -> Result<(), CliError> {
    match &a.command {
        DemCommand::Collide(c) => {
            let r = super::collide::run(&c.request, &sandjumper_output::Silent)?;
            if c.json {
                println!("{}", r.json()?);
            } else {
                println!("{r}");
            }
        }
        DemCommand::Bed(b) => println!("{}", super::bed_run::run(b, &Bars::new())?),
        DemCommand::Intrude(i) => match super::intrude_run::run(&i.request, &Bars::new())? {
            IntrudeOutcome::Finished(s) if i.json => println!("{}", s.json()?),
            outcome => println!("{outcome}"),
        },
        DemCommand::Lammps(l) => super::lammps_command::run(l)?,
        DemCommand::LammpsRead(r) => super::lammps_command::run_read(r)?,
    }
    Ok(())
}
