//! `sandjumper figures dem`: Supplementary I and Extended Data Fig. 2 from the project's own
//! runs. The push-off episodes of the three jumps (single, stutter, delayed stutter) driven
//! into a free, gravity-free bidisperse bed at area fraction 0.70 with the paper's model
//! (forward Euler, per-grain drag), full scale (76 mm foot, 1.0/1.4 mm grains, the bed four
//! foot widths wide and 1.6 deep); PIV run on the stutter's rendered side-wall frames; the
//! near-jammed 0.80 bed and the full model (gravity, friction, walls) as sensitivity rows.
//! Every run keeps its own folder under `runs/`; the comparison is written beside them.

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use crate::command::args::parse_number;
use crate::command::progress::Bars;
use sandjumper_figures_dem::FiguresDemRequest;

/// `sandjumper figures dem`.
#[derive(Debug, Clone, Args)]
pub struct DemFiguresArgs {
    /// Output directory (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Packing fraction of the jumps whose push-offs drive the DEM (eq. 4 model), and the
    /// bulk phi of eq. 6.
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = crate::command::args::parse_phi)]
    pub phi: f64,
    /// Forcing frequency of the three jumps, Hz.
    #[arg(long, value_name = "HZ", default_value = "10", value_parser = parse_number)]
    pub freq: f64,
    /// Delay of the delayed stutter, s.
    #[arg(long, value_name = "S", default_value = "0.1", value_parser = parse_number)]
    pub tau: f64,
    /// Foot width, m (the robot's 76 mm; the bed is 4 widths wide and 1.6 deep).
    #[arg(long, value_name = "M", default_value = "0.076", value_parser = parse_number)]
    pub foot_width: f64,
    /// Leave out the full model's row (its bed settles under gravity: about 7 of the 10
    /// minutes at full scale).
    #[arg(long)]
    pub no_full_model: bool,
    /// Threads (0: all cores).
    #[arg(long, default_value = "0")]
    pub threads: usize,
}

/// Run `figures dem`: the arguments as a request, the library's run, its summary printed.
pub fn run(a: &DemFiguresArgs) -> Result<(), CliError> {
    let request = FiguresDemRequest {
        out: a.out.clone(),
        phi: a.phi,
        freq_hz: a.freq,
        tau_s: a.tau,
        foot_width_m: a.foot_width,
        full_model: !a.no_full_model,
        threads: a.threads,
        ..FiguresDemRequest::default()
    };
    let outcome = sandjumper_figures_dem::run(&request, &Bars::default())?;
    println!("{outcome}");
    Ok(())
}
