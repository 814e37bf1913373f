//! `sandjumper sweep`: every combination, in parallel, into one output directory.

use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

use crate::command::args::{KindArg, ModelArg, ParamSource, check_freq, check_phi, check_tau};
use crate::command::resolve::{ParamsFile, resolve_params};
use clap::Args;
use sandjumper_model::params::Params;
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::plot::save_figure;
use sandjumper_study::sweep::SweepDrive;
use sandjumper_study::sweep::ValueRange;
use sandjumper_study::sweep::drive::run_driven;
use sandjumper_study::sweep::plot as sweep_plot;
use sandjumper_study::sweep::{
    FAILURE_HEADER, ROW_HEADER, ShardMeta, ShardSpec, SpecMeta, SweepMeta, SweepOutcome, SweepSpec,
    files, write_csv,
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

/// File name of the resolved parameters for one packing fraction of a multi-phi sweep.
pub fn params_file_name(phi: f64, several: bool) -> String {
    if several {
        format!("params-phi-{phi}.toml")
    } else {
        "params.toml".into()
    }
}

/// Write `sweep.csv`, `failures.csv` and `sweep.toml` into `dir`.
pub(super) fn write_sweep_files(
    dir: &Path,
    meta: &SweepMeta,
    out: &SweepOutcome,
) -> Result<(), CliError> {
    write_csv(&dir.join(files::ROWS), &out.rows, &ROW_HEADER).map_err(CliError::internal)?;
    write_csv(&dir.join(files::FAILURES), &out.failures, &FAILURE_HEADER)
        .map_err(CliError::internal)?;
    let toml = toml::to_string(meta)
        .map_err(|e| CliError::internal(format!("cannot encode {}: {e}", files::META)))?;
    std::fs::write(dir.join(files::META), toml)
        .map_err(|e| CliError::internal(format!("cannot write {}: {e}", files::META)))
}

/// Draw the sweep figures (height vs frequency; vs delay when it varies) into `dir`;
/// returns the file names written.
pub(super) fn write_sweep_plots(dir: &Path, out: &SweepOutcome) -> Result<Vec<String>, CliError> {
    let mut written = Vec::new();
    if out.rows.is_empty() {
        return Ok(written);
    }
    let fig = sweep_plot::height_vs_freq(&out.rows, "Jump height vs forcing frequency");
    save_figure(
        &fig,
        &dir.join("height_vs_freq.png"),
        Some(&dir.join("height_vs_freq.svg")),
    )?;
    written.extend([
        "height_vs_freq.png".to_string(),
        "height_vs_freq.svg".to_string(),
    ]);
    if let Some(fig) = sweep_plot::height_vs_tau(&out.rows, "Delayed stutter: jump height vs delay")
    {
        save_figure(
            &fig,
            &dir.join("height_vs_tau.png"),
            Some(&dir.join("height_vs_tau.svg")),
        )?;
        written.extend([
            "height_vs_tau.png".to_string(),
            "height_vs_tau.svg".to_string(),
        ]);
    }
    Ok(written)
}

/// The parameters of each packing fraction of `spec` (keyed by `phi.to_bits()`), with the
/// overrides `file` on top of each preset, and their TOML text (what the sweep's hash covers).
pub fn resolve_sweep_params(
    spec: &SweepSpec,
    file: Option<&ParamsFile>,
) -> Result<(HashMap<u64, Params>, String), CliError> {
    let mut params_by_phi: HashMap<u64, Params> = HashMap::new();
    let mut params_text = String::new();
    for &phi in &spec.phis {
        let p = resolve_params(phi, file)?;
        params_text += &format!("# phi = {phi}\n{}", p.to_toml());
        params_by_phi.insert(phi.to_bits(), p);
    }
    Ok((params_by_phi, params_text))
}

/// Run `sweep`.
pub fn run(a: &SweepArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    let spec = SweepSpec {
        kinds: a.kind.iter().map(|&k| k.into()).collect(),
        models: a.model.iter().map(|&m| m.into()).collect(),
        phis: a.phi.values.clone(),
        freqs_hz: a.freq.values.clone(),
        taus_s: a.tau.values.clone(),
        rtol: a.source.rtol,
        drive: match a.link {
            None => SweepDrive::Kinematic,
            Some(SweepLinkArg::Sil) => SweepDrive::Sil {
                gain_lowering: a.gain_lowering,
            },
        },
    };
    let (params_by_phi, params_text) = resolve_sweep_params(&spec, file.as_ref())?;
    if a.slurm.slurm.is_some() {
        if a.shard.is_some() {
            return Err(CliError::input(
                "--slurm N makes the shards itself (task I runs --shard I/N): drop --shard",
            ));
        }
        let argv = crate::slurm::arguments()?;
        return super::slurm::submit(&argv, &a.out, &a.slurm);
    }
    let shard = a.shard.unwrap_or(ShardSpec::WHOLE);
    let combos = spec.combinations();
    let total = combos.len();
    let slice = shard.slice(total);
    let staged = StagedDir::create(&a.out)?;
    let threads = a
        .threads
        .map(|t| t as usize)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let started = Instant::now();
    let bar = crate::command::progress_bar(slice.len() as u64, "jumps");
    let outcome = run_driven(
        &combos[slice.clone()],
        threads,
        &|| bar.inc(1),
        spec.drive,
        spec.rtol,
        |c| Ok(&params_by_phi[&c.phi.to_bits()]),
    )
    .map_err(CliError::internal)?;
    bar.finish_and_clear();
    let elapsed = started.elapsed();
    let meta = SweepMeta {
        format: SweepMeta::FORMAT.into(),
        spec_hash: spec.hash(&params_text),
        total_combinations: total,
        shard: ShardMeta {
            index: shard.index,
            count: shard.count,
            first: slice.start,
            end: slice.end,
            rows: outcome.rows.len(),
            failures: outcome.failures.len(),
        },
        spec: SpecMeta {
            kinds: spec
                .kinds
                .iter()
                .map(|&k| kind_name(k).to_string())
                .collect(),
            models: spec.models.iter().map(|m| m.as_str().to_string()).collect(),
            phi: spec.phis.clone(),
            freq_hz: spec.freqs_hz.clone(),
            tau_s: spec.taus_s.clone(),
            rtol: spec.rtol,
            params_file: file.as_ref().map(|f| f.path.display().to_string()),
            params_overrides: file.as_ref().map(|f| f.text.clone()),
            drive: spec.drive.name(),
        },
    };
    write_sweep_files(staged.path(), &meta, &outcome)?;
    let several = spec.phis.len() > 1;
    for &phi in &spec.phis {
        staged.write_text(
            &params_file_name(phi, several),
            &params_by_phi[&phi.to_bits()].to_toml(),
        )?;
    }
    // A shard's figures would show a fraction of the sweep: `merge` draws them.
    let plots = if shard.is_whole() {
        write_sweep_plots(staged.path(), &outcome)?
    } else {
        Vec::new()
    };
    let dir = staged.commit()?;
    let n = slice.len();
    let what = if shard.is_whole() {
        format!("{n} jumps")
    } else {
        format!("shard {shard}: {n} of {total} jumps")
    };
    eprintln!(
        "swept {what} in {:.2} s on {threads} thread(s); wrote {}/ (sweep.csv, failures.csv, sweep.toml, params{}{})",
        elapsed.as_secs_f64(),
        dir.display(),
        if several { "-phi-*.toml" } else { ".toml" },
        plots.iter().map(|p| format!(", {p}")).collect::<String>()
    );
    report_failures_and_force(&outcome, &params_by_phi);
    Ok(())
}

/// Tell the user how many jumps failed and how many ask more force than the motor has.
pub(super) fn report_failures_and_force(
    outcome: &SweepOutcome,
    params_by_phi: &HashMap<u64, Params>,
) {
    if !outcome.failures.is_empty() {
        eprintln!(
            "warning: {} jump(s) failed and have no row in sweep.csv; see failures.csv (first: {} {} f = {} Hz: {})",
            outcome.failures.len(),
            outcome.failures[0].kind,
            outcome.failures[0].model,
            outcome.failures[0].freq_hz,
            outcome.failures[0].error
        );
    }
    let over = outcome
        .rows
        .iter()
        .filter(|r| {
            params_by_phi
                .get(&r.phi.to_bits())
                .is_some_and(|p| r.peak_motor_force_n > p.drive.peak_force_n)
        })
        .count();
    if over > 0 {
        eprintln!(
            "note: {over} jump(s) ask more than the motor's peak force (drive.peak_force_n); see the peak_motor_force_n column"
        );
    }
}
