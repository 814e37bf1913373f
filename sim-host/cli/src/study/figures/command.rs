//! `sandjumper figures --out DIR [--quick] [--threads N]`.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::{FiguresError, FiguresOptions, write_figures};
use sandjumper_model::options::SimOptions;
use sandjumper_output::CliError;

/// `sandjumper figures`.
#[derive(Debug, Clone, Args)]
pub struct FiguresArgs {
    /// Output directory (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Coarse grids (0.5 Hz, phi by 0.01, tau by 0.125 s) instead of the full set (0.1 Hz, phi by
    /// 0.0025, tau by 10 ms).
    #[arg(long)]
    pub quick: bool,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
}

/// Run `figures`: simulate, write, print what was written and the headline numbers.
pub fn run(a: &FiguresArgs) -> Result<(), CliError> {
    let started = Instant::now();
    // One bar over all the figures' jumps (their count is known only as they run).
    let bar = crate::command::progress_counter("jumps simulated");
    let opts = FiguresOptions {
        quick: a.quick,
        threads: a.threads.map_or(0, |t| t as usize),
        on_jump: {
            let bar = bar.clone();
            std::sync::Arc::new(move || bar.inc(1))
        },
        rtol: SimOptions::default().rtol,
    };
    let report = write_figures(&a.out, &opts).map_err(|e| match e {
        FiguresError::Output(e) => CliError::input(e.to_string()),
        FiguresError::Internal(m) => CliError::internal(m),
    })?;
    bar.finish_and_clear();
    println!(
        "wrote {} files to {} ({} jumps, {} failed, {:.1} s)",
        report.files.len(),
        report.dir.display(),
        report.jumps,
        report.failures,
        started.elapsed().as_secs_f64()
    );
    for (k, v) in &report.findings {
        println!("  {k} = {v}");
    }
    if report.failures > 0 {
        eprintln!(
            "warning: {} jumps failed; see failures.csv",
            report.failures
        );
    }
    Ok(())
}
