//! `sandjumper sweep`: every combination, in parallel, into one output directory.

use std::collections::HashMap;

use crate::command::CliError;
use crate::command::args::{KindArg, ModelArg, ParamSource, check_freq, check_phi, check_tau};
use crate::command::progress::Bars;
use crate::command::resolve::ParamsFile;
use crate::study::cli_error;
use clap::Args;
use sandjumper_model::params::Params;
use sandjumper_output::StagedDir;
use sandjumper_study::sweep::{
    self as sweep, MergeRequest, ShardSpec, SweepDrive, SweepRequest, SweepSpec, ValueRange,
};
use std::path::PathBuf;

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
    /// Drive each jump through the software-in-the-loop rig (the core's controller, the drive
    /// model with its 300 N limit, the encoder) instead of imposing the stroke exactly.
    #[arg(long, value_enum)]
    pub link: Option<SweepLinkArg>,
    /// With --link sil: the position gain times FACTOR during a delayed stutter's delay
    /// (0 < FACTOR <= 1; 0.05 damps the spring's ringing ~10x), as the paper's rig did.
    #[arg(long, value_name = "FACTOR", requires = "link", value_parser = crate::command::args::parse_gain_lowering)]
    pub gain_lowering: Option<f64>,
    /// Run on a Slurm cluster as a job array.
    #[command(flatten)]
    pub slurm: super::slurm::SlurmArgs,
}

/// The loop a sweep's jumps run through instead of the imposed stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepLinkArg {
    /// The core's controller in this process against the simulated rig.
    Sil,
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

pub use sandjumper_study::sweep::params_file_name;

/// The parameters of each packing fraction of `spec` (keyed by `phi.to_bits()`), with the
/// overrides `file` on top of each preset, and their TOML text (what the sweep's hash covers).
pub fn resolve_sweep_params(
    spec: &SweepSpec,
    file: Option<&ParamsFile>,
) -> Result<(HashMap<u64, Params>, String), CliError> {
    let request = SweepRequest {
        spec: spec.clone(),
        params: file.map(ParamsFile::to_library),
        ..SweepRequest::default()
    };
    request.resolved_params().map_err(cli_error)
}

impl SweepArgs {
    /// The library's request for these arguments (`params`: the `--params` file, read).
    pub fn request(&self, params: Option<&ParamsFile>) -> SweepRequest {
        let spec = SweepSpec {
            kinds: self.kind.iter().map(|&k| k.into()).collect(),
            models: self.model.iter().map(|&m| m.into()).collect(),
            phis: self.phi.values.clone(),
            freqs_hz: self.freq.values.clone(),
            taus_s: self.tau.values.clone(),
            rtol: self.source.rtol,
            drive: match self.link {
                None => SweepDrive::Kinematic,
                Some(SweepLinkArg::Sil) => SweepDrive::Sil {
                    gain_lowering: self.gain_lowering,
                },
            },
        };
        SweepRequest {
            spec,
            params: params.map(ParamsFile::to_library),
            threads: self.threads.map(|t| t as usize),
            shard: self.shard,
        }
    }
}

/// Run `sweep`.
pub fn run(a: &SweepArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    let request = a.request(file.as_ref());
    request.validate()?;
    if a.slurm.slurm.is_some() {
        if a.shard.is_some() {
            return Err(CliError::input(
                "--slurm N makes the shards itself (task I runs --shard I/N): drop --shard",
            ));
        }
        let argv = sandjumper_slurm::arguments()?;
        return match super::slurm::submit(&argv, &a.out, &a.slurm)? {
            Some(dirs) => super::merge_command::merge_into(&MergeRequest {
                dirs,
                out: a.out.clone(),
            }),
            None => Ok(()),
        };
    }
    let staged = StagedDir::create(&a.out)?;
    let swept = sweep::run(&request, &Bars::default())?;
    let plots = swept.write_into(&staged)?;
    let dir = staged.commit()?;
    let shard = request.shard.unwrap_or(ShardSpec::WHOLE);
    let n = swept.meta.shard.end - swept.meta.shard.first;
    let what = if shard.is_whole() {
        format!("{n} jumps")
    } else {
        format!(
            "shard {shard}: {n} of {} jumps",
            swept.meta.total_combinations
        )
    };
    eprintln!(
        "swept {what} in {:.2} s on {} thread(s); wrote {}/ (sweep.csv, failures.csv, sweep.toml, params{}{})",
        swept.elapsed_s,
        swept.threads,
        dir.display(),
        if swept.phis.len() > 1 {
            "-phi-*.toml"
        } else {
            ".toml"
        },
        plots.iter().map(|p| format!(", {p}")).collect::<String>()
    );
    for line in swept.warnings() {
        eprintln!("{line}");
    }
    Ok(())
}
