//! `sandjumper fit intrusion|added-mass|drag|inertial FILE.csv [--out FILE.toml] [--json]`.

use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};

use crate::command::CliError;
use crate::command::args::ModelArg;
use sandjumper_model::resolve::ParamsFile;
use sandjumper_output::Silent;
use sandjumper_study::StudyError;
use sandjumper_study::fit::added_mass::DEFAULT_EXCLUDE_DEEPEST;
use sandjumper_study::fit::data::HeightColumn;
use sandjumper_study::fit::intrusion::CurveKind;
use sandjumper_study::fit::jumps::DragParam;
use sandjumper_study::fit::{
    self, FitKind, FitReport, FitRequest, check_rtol, parse_phi, write_params_files,
};

/// `sandjumper fit`.
#[derive(Debug, Clone, Args)]
pub struct FitArgs {
    /// What to fit.
    #[command(subcommand)]
    pub what: FitCommand,
}

/// The fits.
#[derive(Debug, Clone, Subcommand)]
pub enum FitCommand {
    /// k1, k2, delta from a slow-intrusion curve `depth_m,force_n`; or kappa, l_re of the
    /// re-intrusion overshoot from a re-intrusion curve (auto-detected when the curve starts
    /// deeper than 2 mm).
    Intrusion(IntrusionArgs),
    /// mu and C of the added mass m_a(s) from `depth_m,added_mass_kg` (e.g. from PIV),
    /// leaving out the singular low-speed end.
    AddedMass(AddedMassArgs),
    /// Constant drag alpha per phi from measured single-jump heights (sweep.csv columns).
    Drag(JumpFitArgs),
    /// Added-mass drag factor b per phi from measured heights of all jump kinds.
    Inertial(JumpFitArgs),
}

/// Output options shared by every fit.
#[derive(Debug, Clone, Args)]
pub struct FitOutput {
    /// Write the fitted values as a params file (TOML) that jump, sweep, hil and replay
    /// accept with --params. Fits over several phi write one file per phi,
    /// STEM.phi-0.570.toml, beside it.
    #[arg(long, value_name = "FILE.toml")]
    pub out: Option<PathBuf>,
    /// Print {"fits": [{"phi", "param", "value", "stderr"}], "residual_rms"} on stdout
    /// instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// TOML file overriding any base parameter (applied on top of the preset).
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
}

/// `fit intrusion`.
#[derive(Debug, Clone, Args)]
pub struct IntrusionArgs {
    /// CSV with columns depth_m,force_n (depth strictly increasing).
    #[arg(value_name = "FORCE_DEPTH.csv")]
    pub file: PathBuf,
    /// Treat the curve as a re-intrusion (fit kappa, l_re on top of the base F_p).
    #[arg(long, conflicts_with = "first")]
    pub reintrusion: bool,
    /// Treat the curve as a first intrusion (fit k1, k2, delta).
    #[arg(long)]
    pub first: bool,
    /// Depth where the re-intrusion starts, m (default: the curve's first depth).
    #[arg(long, value_name = "M")]
    pub z_start: Option<f64>,
    /// Packing fraction whose preset gives the base F_p of a re-intrusion fit.
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi)]
    pub phi: f64,
    /// Output.
    #[command(flatten)]
    pub output: FitOutput,
}

/// `fit added-mass`.
#[derive(Debug, Clone, Args)]
pub struct AddedMassArgs {
    /// CSV with columns depth_m,added_mass_kg (episode depth s, strictly increasing).
    #[arg(value_name = "MA_DEPTH.csv")]
    pub file: PathBuf,
    /// Fraction of the depth range left out at the deep end, where the foot slows to rest and
    /// m_a = P / v diverges (0 keeps every point).
    #[arg(long, value_name = "F", default_value_t = DEFAULT_EXCLUDE_DEEPEST)]
    pub exclude_deepest: f64,
    /// Packing fraction (enters m_a directly; its preset gives rho, R, theta).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi)]
    pub phi: f64,
    /// Output.
    #[command(flatten)]
    pub output: FitOutput,
}

/// Which measured height a jump fit uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum HeightArg {
    /// jump_height_m (highest point of the run, the paper's camera measure).
    Jump,
    /// final_jump_height_m (highest point after the push-off half begins).
    Final,
}

/// `fit drag` / `fit inertial`.
#[derive(Debug, Clone, Args)]
pub struct JumpFitArgs {
    /// CSV with the columns of sweep.csv: kind,phi,freq_hz,tau_s,jump_height_m (extra columns
    /// ignored).
    #[arg(value_name = "JUMPS.csv")]
    pub file: PathBuf,
    /// Ground model of the inner simulations (drag: eq1 or eq1-linear; inertial: eq4).
    #[arg(long, value_enum)]
    pub model: Option<ModelArg>,
    /// Measured height column to fit.
    #[arg(long, value_enum, default_value = "jump")]
    pub height: HeightArg,
    /// Relative tolerance of the inner simulations.
    #[arg(long, value_name = "X", default_value_t = 1e-9)]
    pub rtol: f64,
    /// Output.
    #[command(flatten)]
    pub output: FitOutput,
}

impl FitCommand {
    /// The library's request (`--params` read and checked in the order the command line
    /// always had: a jump fit's `--rtol` first).
    pub fn request(&self) -> Result<(FitRequest, &FitOutput), CliError> {
        let (file, phi, kind, output) = match self {
            FitCommand::Intrusion(i) => {
                let curve = match (i.reintrusion, i.first) {
                    (true, _) => CurveKind::Re,
                    (_, true) => CurveKind::First,
                    _ => CurveKind::Auto,
                };
                let z_start_m = i.z_start;
                let kind = FitKind::Intrusion { curve, z_start_m };
                (&i.file, i.phi, kind, &i.output)
            }
            FitCommand::AddedMass(m) => {
                let exclude_deepest = m.exclude_deepest;
                (
                    &m.file,
                    m.phi,
                    FitKind::AddedMass { exclude_deepest },
                    &m.output,
                )
            }
            FitCommand::Drag(j) => (&j.file, 0.57, j.kind(DragParam::Alpha)?, &j.output),
            FitCommand::Inertial(j) => (&j.file, 0.57, j.kind(DragParam::B)?, &j.output),
        };
        let params = ParamsFile::read_opt(output.params.as_deref()).map_err(StudyError::from)?;
        let request = FitRequest {
            file: file.clone(),
            kind,
            phi,
            params,
        };
        Ok((request, output))
    }
}

impl JumpFitArgs {
    fn kind(&self, param: DragParam) -> Result<FitKind, CliError> {
        check_rtol(self.rtol)?;
        Ok(FitKind::Jumps {
            param,
            model: self.model.map(Into::into),
            height: match self.height {
                HeightArg::Jump => HeightColumn::Jump,
                HeightArg::Final => HeightColumn::Final,
            },
            rtol: self.rtol,
        })
    }
}

/// Run `fit ...`.
pub fn run(a: &FitArgs) -> Result<(), CliError> {
    let (request, output) = a.what.request()?;
    let report = fit::run(&request, &Silent)?;
    emit(&report, output)
}

fn emit(report: &FitReport, output: &FitOutput) -> Result<(), CliError> {
    let written = match &output.out {
        Some(out) => write_params_files(report, out)?,
        None => Vec::new(),
    };
    if output.json {
        println!("{}", report.to_json());
    } else {
        print!("{}", report.summary());
        for path in &written {
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}
