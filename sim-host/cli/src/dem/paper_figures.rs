//! `sandjumper figures dem`: Supplementary I and Extended Data Fig. 2 from the project's own
//! runs. The push-off episodes of the three jumps (single, stutter, delayed stutter) driven
//! into a free, gravity-free bidisperse bed at area fraction 0.70 with the paper's model
//! (forward Euler, per-grain drag), full scale (76 mm foot, 1.0/1.4 mm grains, the bed four
//! foot widths wide and 1.6 deep); PIV run on the stutter's rendered side-wall frames; the
//! near-jammed 0.80 bed and the full model (gravity, friction, walls) as sensitivity rows.
//! Every run keeps its own folder under `runs/`; the comparison is written beside them.

use std::path::PathBuf;

use clap::Args;

use crate::command::args::{KindArg, ModelArg, ParamSource, parse_number};
use crate::command::progress::Bars;
use crate::flow::command::{PairingArg, PivArgs, SubPixelArg};
use crate::study::jump_command::JumpArgs;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_figures_dem::{FiguresDemError, FiguresDemRequest, JumpStage, PivStage, Stages};
use sandjumper_output::CliError;

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

/// Run `figures dem`.
pub fn run(a: &DemFiguresArgs) -> Result<(), CliError> {
    let request = FiguresDemRequest {
        out: a.out.clone(),
        phi: a.phi,
        freq_hz: a.freq,
        tau_s: a.tau,
        foot_width_m: a.foot_width,
        full_model: !a.no_full_model,
        threads: a.threads,
    };
    let outcome = sandjumper_figures_dem::run(&request, &CliStages, &Bars::default())
        .map_err(super::shared::cli_error)?;
    println!("{outcome}");
    Ok(())
}

/// The stages `figures dem` still takes from the command line: `jump` and `piv`, called as
/// typed Rust functions (until they are library calls of their own crates).
struct CliStages;

/// A command-line error as a stage's error, blamed as its exit status says.
fn stage_error(e: CliError) -> FiguresDemError {
    if e.exit == sandjumper_output::EXIT_BAD_INPUT {
        FiguresDemError::Input(e.message)
    } else {
        FiguresDemError::Internal(e.message)
    }
}

impl Stages for CliStages {
    fn jump(&self, stage: &JumpStage) -> Result<f64, FiguresDemError> {
        let args = JumpArgs {
            kind: Some(match stage.kind {
                JumpKind::Single => KindArg::Single,
                JumpKind::Stutter => KindArg::Stutter,
                _ => KindArg::Delayed,
            }),
            freq: Some(stage.freq_hz),
            stroke: None,
            tau: stage.tau_s,
            model: ModelArg::Eq4,
            phi: stage.phi,
            source: ParamSource {
                params: None,
                rtol: 1e-8,
            },
            out: Some(stage.out.clone()),
            json: false,
        };
        crate::study::jump_command::run(&args).map_err(stage_error)?;
        // Until `jump` is a library call with a typed outcome: its summary's deepest point.
        let path = stage.out.join("summary.json");
        let text = std::fs::read_to_string(&path)
            .map_err(|e| FiguresDemError::internal(format!("{}: {e}", path.display())))?;
        let j: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| FiguresDemError::internal(format!("{}: {e}", path.display())))?;
        Ok(j["max_depth_m"].as_f64().unwrap_or(0.0))
    }

    fn piv(&self, stage: &PivStage) -> Result<(), FiguresDemError> {
        let args = PivArgs {
            frames: stage.frames.display().to_string(),
            pairs: PairingArg::Consecutive,
            every: 1,
            windows: "64,32,16".into(),
            overlap: 0.5,
            no_deform: false,
            subpixel: SubPixelArg::Gaussian,
            median_threshold: 2.0,
            min_peak_ratio: 1.2,
            local_contrast: 4.0,
            clahe_tile: 0,
            clahe_clip: 0.01,
            subtract_background: false,
            cap_sigma: 0.0,
            mask: None,
            foot: Some(stage.foot.clone()),
            m_per_px: Some(stage.m_per_px),
            fps: Some(stage.fps),
            log: None,
            origin: Some(stage.origin_px),
            phi: stage.phi,
            grain_density: 1000.0,
            min_speed_ratio: 0.3,
            out: Some(stage.out.clone()),
            json: false,
        };
        crate::flow::command::run(&args).map_err(stage_error)
    }
}
