//! `sandjumper dem lammps` (the 3-D DEM of the intrusion, run by LAMMPS here or on a Slurm
//! cluster) and `sandjumper dem lammps-read` (a finished run's dumps read back again).

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use sandjumper_lammps::run::{LammpsOutcome, LammpsReadRequest, LammpsRequest, Submitted};

use super::intrude_run::parse_share;
use crate::command::progress::Bars;

/// `dem lammps`.
#[derive(Debug, Clone, Args)]
pub struct LammpsArgs {
    /// The run (its `out` is `--out` below).
    #[command(flatten)]
    pub run: LammpsRequest,
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
            out: self.out.clone(),
            ..self.run.clone()
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
    let program = crate::slurm::this_program()?;
    match sandjumper_lammps::run::submit(&a.request(), &program, &queue, &Bars::new())? {
        Submitted::Queued { id } => {
            println!("{id}");
            eprintln!("when it is done its output is in {}", a.out.display());
        }
        Submitted::Done { outcome } if a.json => println!("{}", outcome.summary_json()?),
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
