//! clap definitions of the `sandjumper` commands, and value parsers that say what is allowed.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use sandjumper_core::trajectory::{JumpKind, MAX_FREQ_HZ, MAX_TAU_S, MIN_FREQ_HZ};

use crate::params::ModelName;
use crate::sweep::{ShardSpec, ValueRange};

/// Simulate the spring-mass jumping robot on granular media (Aguilar & Goldman, Nature
/// Physics 2016). Exit status: 0 success, 2 bad input, 1 internal failure.
#[derive(Debug, Parser)]
#[command(name = "sandjumper", version, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Simulate one jump: a summary (or --json), and with --out the time series, parameters,
    /// summary and a figure.
    Jump(JumpArgs),
    /// Simulate every combination of kinds, models, packing fractions, delays and frequencies,
    /// in parallel; writes sweep.csv, failures.csv, sweep.toml, parameters and figures.
    Sweep(SweepArgs),
    /// Join the shard directories of one sweep (`sweep --shard I/N`) into one sweep directory.
    Merge(MergeArgs),
    /// Print the resolved parameters as TOML (re-readable with --params).
    Params(ParamsArgs),
    /// Fit the granular model to measurements (intrusion curves, added mass, jump heights);
    /// writes a params file for --params.
    Fit(crate::fit::command::FitArgs),
    /// Regenerate the simulations behind the paper's figures: PNG, SVG and CSV.
    Figures(crate::figures::command::FiguresArgs),
    /// Run one jump through the control loop against the simulated rig: the core in-process
    /// (sil), the real firmware in QEMU (pil) or a board on a serial port (serial:PATH).
    Hil(crate::hil::command::HilArgs),
    /// Replay an acquisition log's encoder record in the simulator (the paper's method):
    /// reports what `jump` reports, and predicted vs measured if the log has measurements.
    Replay(crate::replay_cmd::ReplayArgs),
    /// Check (validate and summarise) or convert acquisition logs.
    Log(crate::acqlog::command::LogArgs),
    /// The rig's board over its USB serial port (--port PATH), or a simulated controller and
    /// rig (--link sil|pil): flash, status, jump, intrude, replay.
    Rig(crate::rig_tool::RigArgs),
}

/// Jump kind as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// One-cycle sine starting low: push down, return.
    Single,
    /// Pull-up half (preliminary hop), then push-off half.
    Stutter,
    /// Stutter with a pause of --tau seconds between its halves.
    Delayed,
}

impl From<KindArg> for JumpKind {
    fn from(k: KindArg) -> Self {
        match k {
            KindArg::Single => JumpKind::Single,
            KindArg::Stutter => JumpKind::Stutter,
            KindArg::Delayed => JumpKind::DelayedStutter,
        }
    }
}

/// Ground model as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ModelArg {
    /// Rigid floor, perfectly plastic impact.
    Hard,
    /// F = k1 z + alpha v^2.
    #[value(name = "eq1-linear")]
    Eq1Linear,
    /// Two-resistance F_p with re-intrusion overshoot, constant drag.
    Eq1,
    /// Cone F_p, re-intrusion, added mass (the paper's final model).
    Eq4,
}

impl From<ModelArg> for ModelName {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Hard => ModelName::Hard,
            ModelArg::Eq1Linear => ModelName::Eq1Linear,
            ModelArg::Eq1 => ModelName::Eq1,
            ModelArg::Eq4 => ModelName::Eq4,
        }
    }
}

/// Options shared by `jump` and `sweep`: parameters and integration.
#[derive(Debug, Clone, Args)]
pub struct ParamSource {
    /// TOML file overriding any parameter (tables [robot], [drive], [sand], [model], keys as
    /// printed by `sandjumper params`). Applied on top of the --phi preset.
    // The doc text is also the `--help` text: the TOML table names stay in brackets.
    #[allow(rustdoc::broken_intra_doc_links)]
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
    /// Relative tolerance of the Dormand-Prince 5(4) integrator.
    #[arg(long, value_name = "X", default_value = "1e-8", value_parser = parse_rtol)]
    pub rtol: f64,
}

/// `sandjumper jump`.
#[derive(Debug, Clone, Args)]
pub struct JumpArgs {
    /// Jump kind.
    #[arg(long, value_enum)]
    pub kind: KindArg,
    /// Forcing frequency f of the one-cycle sine, Hz.
    #[arg(long, value_name = "HZ", value_parser = parse_freq, allow_negative_numbers = true)]
    pub freq: f64,
    /// Delay of the delayed stutter between its halves, s (required with --kind delayed).
    #[arg(long, value_name = "S", value_parser = parse_tau, required_if_eq("kind", "delayed"), allow_negative_numbers = true)]
    pub tau: Option<f64>,
    /// Ground model.
    #[arg(long, value_enum, default_value = "eq4")]
    pub model: ModelArg,
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi, allow_negative_numbers = true)]
    pub phi: f64,
    /// Parameters and integration.
    #[command(flatten)]
    pub source: ParamSource,
    /// Write trajectory.csv, params.toml, summary.json, jump.png and jump.svg into DIR
    /// (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the human summary.
    #[arg(long)]
    pub json: bool,
}

/// `sandjumper sweep`.
#[derive(Debug, Clone, Args)]
pub struct SweepArgs {
    /// Jump kinds, comma-separated (e.g. single,stutter).
    #[arg(long, value_enum, value_delimiter = ',', required = true)]
    pub kind: Vec<KindArg>,
    /// Forcing frequencies: A:B:STEP (inclusive) or a single value, Hz.
    #[arg(long, value_name = "A:B:STEP", value_parser = parse_freq_range, allow_hyphen_values = true)]
    pub freq: ValueRange,
    /// Packing fractions: A:B:STEP or a single value.
    #[arg(long, value_name = "A:B:STEP", default_value = "0.57", value_parser = parse_phi_range, allow_hyphen_values = true)]
    pub phi: ValueRange,
    /// Delays of the delayed stutter: A:B:STEP or a single value, s (other kinds use 0).
    #[arg(long, value_name = "A:B:STEP", default_value = "0", value_parser = parse_tau_range, allow_hyphen_values = true)]
    pub tau: ValueRange,
    /// Ground models, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "eq4")]
    pub model: Vec<ModelArg>,
    /// Parameters and integration.
    #[command(flatten)]
    pub source: ParamSource,
    /// Output directory (created, or replaced if it holds an earlier sandjumper output).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Run only shard I of N (1-based: 1/4 .. 4/4), a contiguous slice of the combinations;
    /// join the shard directories with `sandjumper merge`.
    #[arg(long, value_name = "I/N", value_parser = parse_shard)]
    pub shard: Option<ShardSpec>,
}

/// `sandjumper merge`.
#[derive(Debug, Clone, Args)]
pub struct MergeArgs {
    /// Shard directories written by `sandjumper sweep --shard I/N` (all N of them, any order).
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Output directory for the merged sweep.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// `sandjumper params`.
#[derive(Debug, Clone, Args)]
pub struct ParamsArgs {
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi, allow_negative_numbers = true)]
    pub phi: f64,
    /// TOML file overriding any parameter.
    #[arg(long, value_name = "FILE.toml")]
    pub params: Option<PathBuf>,
}

/// clap value parser: a finite number.
pub fn parse_number(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("`{s}` is not a finite number")),
    }
}

/// Check a forcing frequency: positive, within the trajectory's supported band.
pub fn check_freq(f: f64) -> Result<f64, String> {
    if f <= 0.0 {
        return Err(format!(
            "frequency {f} Hz is not positive (allowed: {MIN_FREQ_HZ}..={MAX_FREQ_HZ} Hz)"
        ));
    }
    if !(MIN_FREQ_HZ..=MAX_FREQ_HZ).contains(&f) {
        return Err(format!(
            "frequency {f} Hz out of range (allowed: {MIN_FREQ_HZ}..={MAX_FREQ_HZ} Hz)"
        ));
    }
    Ok(f)
}

/// Check a delay: non-negative, at most the trajectory's longest delay.
pub fn check_tau(t: f64) -> Result<f64, String> {
    if t < 0.0 {
        return Err(format!(
            "delay tau {t} s is negative (allowed: 0..={MAX_TAU_S} s)"
        ));
    }
    if t > MAX_TAU_S {
        return Err(format!(
            "delay tau {t} s out of range (allowed: 0..={MAX_TAU_S} s)"
        ));
    }
    Ok(t)
}

/// Check a packing fraction: a fraction in (0, 1). Whether a preset exists is checked when
/// the parameters are resolved (a params file may supply the sand values).
pub fn check_phi(phi: f64) -> Result<f64, String> {
    if phi > 0.0 && phi < 1.0 {
        Ok(phi)
    } else {
        Err(format!(
            "packing fraction {phi} is not a fraction (allowed: 0 < phi < 1; presets 0.57..=0.62)"
        ))
    }
}

/// clap value parser: a forcing frequency in Hz ([`check_freq`]).
pub fn parse_freq(s: &str) -> Result<f64, String> {
    check_freq(parse_number(s)?)
}

/// clap value parser: a delay in s ([`check_tau`]).
pub fn parse_tau(s: &str) -> Result<f64, String> {
    check_tau(parse_number(s)?)
}

/// clap value parser: a packing fraction ([`check_phi`]).
pub fn parse_phi(s: &str) -> Result<f64, String> {
    check_phi(parse_number(s)?)
}

/// clap value parser: an integrator relative tolerance, 1e-14 <= rtol < 1.
pub fn parse_rtol(s: &str) -> Result<f64, String> {
    let r = parse_number(s)?;
    if (1e-14..1.0).contains(&r) {
        Ok(r)
    } else {
        Err(format!(
            "rtol {r} out of range (allowed: 1e-14 <= rtol < 1)"
        ))
    }
}

/// Parse a range and check each of its values with `check`.
pub fn parse_range_checked(
    s: &str,
    check: fn(f64) -> Result<f64, String>,
) -> Result<ValueRange, String> {
    let r = ValueRange::parse(s).map_err(|e| e.to_string())?;
    for &v in &r.values {
        check(v).map_err(|e| format!("range `{s}`: {e}"))?;
    }
    Ok(r)
}

/// clap value parser: a frequency range `A:B:STEP`, every value checked.
pub fn parse_freq_range(s: &str) -> Result<ValueRange, String> {
    parse_range_checked(s, check_freq)
}

/// clap value parser: a delay range `A:B:STEP`, every value checked.
pub fn parse_tau_range(s: &str) -> Result<ValueRange, String> {
    parse_range_checked(s, check_tau)
}

/// clap value parser: a packing-fraction range `A:B:STEP`, every value checked.
pub fn parse_phi_range(s: &str) -> Result<ValueRange, String> {
    parse_range_checked(s, check_phi)
}

/// clap value parser: a shard `I/N` (1-based).
pub fn parse_shard(s: &str) -> Result<ShardSpec, String> {
    ShardSpec::parse(s).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn clap_definitions_are_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn kinds_and_models_map_to_the_library_names() {
        assert_eq!(JumpKind::from(KindArg::Delayed), JumpKind::DelayedStutter);
        for m in ModelArg::value_variants() {
            let name = m.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(ModelName::from(*m).as_str(), name);
        }
    }

    #[test]
    fn sweep_takes_lists_and_ranges() {
        let cli = Cli::try_parse_from([
            "sandjumper",
            "sweep",
            "--kind",
            "single,stutter",
            "--freq",
            "5:7:1",
            "--model",
            "eq1,eq4",
            "--out",
            "x",
        ])
        .unwrap();
        let Command::Sweep(a) = cli.command else {
            panic!("not a sweep")
        };
        assert_eq!(a.kind, vec![KindArg::Single, KindArg::Stutter]);
        assert_eq!(a.freq.values, vec![5.0, 6.0, 7.0]);
        assert_eq!(a.model, vec![ModelArg::Eq1, ModelArg::Eq4]);
        assert_eq!(a.tau.values, vec![0.0]);
    }
}
