//! `sandjumper figures --out DIR [--quick] [--threads N]`.

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use crate::command::progress::Bars;
use sandjumper_study::figures::{self, FiguresRequest};

/// `sandjumper figures`: the jump model's figures, or `figures dem` (Supplementary I).
#[derive(Debug, Clone, Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct FiguresArgs {
    /// Another set of figures.
    #[command(subcommand)]
    pub set: Option<FigureSet>,
    /// Output directory (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR", required = true)]
    pub out: Option<PathBuf>,
    /// Coarse grids (0.5 Hz, phi by 0.01, tau by 0.125 s) instead of the full set (0.1 Hz, phi by
    /// 0.0025, tau by 10 ms).
    #[arg(long)]
    pub quick: bool,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
}

/// The other sets of figures.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum FigureSet {
    /// Supplementary I and Extended Data Fig. 2: the DEM's added mass, grain momentum and
    /// jammed cone for the three jumps' push-offs at full scale, PIV on its frames, and the
    /// sensitivity rows (about 10 minutes on 2 cores).
    Dem(crate::dem::paper_figures::DemFiguresArgs),
}

/// Run `figures`: simulate, write, print what was written and the headline numbers.
pub fn run(a: &FiguresArgs) -> Result<(), CliError> {
    if let Some(FigureSet::Dem(d)) = &a.set {
        return crate::dem::paper_figures::run(d);
    }
    let Some(out) = &a.out else {
        return Err(CliError::input("figures: --out DIR is required"));
    };
    if cfg!(not(feature = "rig")) {
        // Its delay curve runs through the sil rig.
        return crate::command::unavailable::refuse("figures", "rig", "rig");
    }
    let request = FiguresRequest {
        out: out.clone(),
        quick: a.quick,
        threads: a.threads.map(|t| t as usize),
        ..FiguresRequest::default()
    };
    let report = figures::run(&request, &Bars::default())?;
    print!("{report}");
    if report.failures > 0 {
        eprintln!(
            "warning: {} jumps failed; see failures.csv",
            report.failures
        );
    }
    Ok(())
}
