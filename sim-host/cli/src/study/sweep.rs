//! `sandjumper sweep` (on this machine or, with `--slurm N`, as a Slurm job array, one shard
//! per task: [`sandjumper_study::sweep::cluster::run_on_slurm`]) and `merge` (join the shard
//! directories of one sweep: [`sandjumper_study::sweep::merge()`]).

use std::path::PathBuf;

use clap::Args;

use crate::command::CliError;
use crate::command::args::{KindArg, ModelArg, ParamSource};
use crate::command::progress::Bars;
use sandjumper_model::resolve::ParamsFile;
use sandjumper_output::{Silent, StagedDir};
use sandjumper_study::StudyError;
use sandjumper_study::sweep::cluster::{
    MAX_CPUS_PER_TASK, MAX_TASKS, SlurmSweepOutcome, SlurmSweepRequest, run_on_slurm,
};
use sandjumper_study::sweep::{
    self as sweep, MergeRequest, ShardSpec, SweepDrive, SweepRequest, SweepSpec, ValueRange, merge,
    parse_freq_range, parse_phi_range, parse_shard, parse_tau_range,
};

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
    pub slurm: SlurmArgs,
}

/// The loop a sweep's jumps run through instead of the imposed stroke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SweepLinkArg {
    /// The core's controller in this process against the simulated rig.
    Sil,
}

impl SweepArgs {
    /// The library's request for these arguments (`params`: the `--params` file, read).
    pub fn request(&self, params: Option<ParamsFile>) -> SweepRequest {
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
            params,
            threads: self.threads.map(|t| t as usize),
            shard: self.shard,
        }
    }
}

/// Run `sweep` (here, or with `--slurm N` as a job array merged into `--out`).
pub fn run(a: &SweepArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref()).map_err(StudyError::from)?;
    let request = a.request(file);
    if let Some(tasks) = a.slurm.slurm {
        let slurm = SlurmSweepRequest {
            sweep: request,
            tasks,
            cpus_per_task: a.slurm.slurm_cpus,
            queue: a.slurm.queue.options(),
            program: crate::slurm::this_program()?,
            out: a.out.clone(),
        };
        match run_on_slurm(&slurm, &Bars::new())? {
            SlurmSweepOutcome::Queued { id, dir } => {
                println!("{id}");
                eprintln!(
                    "when it is done: sandjumper merge {}/shard-* --out {}",
                    dir.display(),
                    a.out.display()
                );
            }
            SlurmSweepOutcome::Merged {
                merged, written, ..
            } => merged
                .report(&written)
                .iter()
                .for_each(|l| eprintln!("{l}")),
        }
        return Ok(());
    }
    request.validate()?;
    let staged = StagedDir::create(&a.out)?;
    let swept = sweep::run(&request, &Bars::default())?;
    let plots = swept.write_into(&staged)?;
    let dir = staged.commit()?;
    eprintln!("{}", swept.report(&dir, &plots));
    for line in swept.warnings() {
        eprintln!("{line}");
    }
    Ok(())
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

/// Run `merge`.
pub fn run_merge(a: &MergeArgs) -> Result<(), CliError> {
    let request = MergeRequest {
        dirs: a.dirs.clone(),
        out: a.out.clone(),
    };
    let merged = merge(&request, &Silent)?;
    let written = merged.write(&request.out)?;
    merged
        .report(&written)
        .iter()
        .for_each(|l| eprintln!("{l}"));
    Ok(())
}

/// The Slurm options of `sweep`.
#[derive(Debug, Clone, Args)]
pub struct SlurmArgs {
    /// Submit the sweep to Slurm as a job array of N tasks (one shard each), wait for it and
    /// merge the shards into --out.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_TASKS)))]
    pub slurm: Option<u32>,
    /// CPUs of each task (its sweep's threads).
    #[arg(long, value_name = "N", default_value = "1", requires = "slurm",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_CPUS_PER_TASK)))]
    pub slurm_cpus: u32,
    /// Partition, time limit of each task, waiting (merge the shards later with the printed
    /// `sandjumper merge` command).
    #[command(flatten)]
    pub queue: crate::slurm::QueueArgs,
}
