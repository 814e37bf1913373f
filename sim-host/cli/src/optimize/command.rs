//! `sandjumper optimize`: search for the stroke that makes the robot jump highest (or best by
//! another objective) within the rig's limits, compare it with the best of the paper's
//! strokes, re-run both through the real controller, and write stroke.csv for `jump`, `hil`
//! and `rig replay --stroke`. The search is [`sandjumper_optimize::run`] (its F407 runs on the
//! library's virtual board); this module maps the arguments to its request and prints its
//! outcome.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use crate::command::CliError;
use crate::command::args::{ModelArg, ParamSource, parse_phi};
use crate::command::progress::Bars;
use crate::command::resolve::{ParamsFile, resolve_params};
use sandjumper_optimize::evaluate::Objective;
use sandjumper_optimize::outcome::answer_chain_in;
use sandjumper_optimize::{OptimizeRequest, parse_phi_range, parse_verify, ranged};
use sandjumper_rig::hil::open::LinkArg;

/// The objective on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ObjectiveArg {
    /// The highest rod apex of the run.
    Height,
    /// The highest apex after the push-off begins (the final hop).
    FinalHeight,
    /// The highest rise of the robot's centre of mass (motor, rod and foot).
    ComRise,
    /// Jump height per peak motor power (m/W).
    HeightPerPeakPower,
    /// Jump height per positive motor work (m/J).
    HeightPerEnergy,
}

impl From<ObjectiveArg> for Objective {
    fn from(o: ObjectiveArg) -> Self {
        match o {
            ObjectiveArg::Height => Objective::Height,
            ObjectiveArg::FinalHeight => Objective::FinalHeight,
            ObjectiveArg::ComRise => Objective::ComRise,
            ObjectiveArg::HeightPerPeakPower => Objective::HeightPerPeakPower,
            ObjectiveArg::HeightPerEnergy => Objective::HeightPerEnergy,
        }
    }
}

/// The links of `--verify`.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyLinks(pub Vec<LinkArg>);

fn parse_links(s: &str) -> Result<VerifyLinks, String> {
    parse_verify(s).map(VerifyLinks)
}

/// `sandjumper optimize`.
#[derive(Debug, Clone, Args)]
pub struct OptimizeArgs {
    /// What to maximise.
    #[arg(long, value_enum, default_value = "height")]
    pub objective: ObjectiveArg,
    /// Ground model.
    #[arg(long, value_enum, default_value = "eq4")]
    pub model: ModelArg,
    /// Packing fraction phi of the sand (presets 0.57..=0.62).
    #[arg(long, value_name = "PHI", default_value = "0.57", value_parser = parse_phi)]
    pub phi: f64,
    /// A bed known only to a range of packing fractions, A:B (e.g. 0.57:0.62): the search
    /// maximises the worst case over --phi-points beds across it (ends included), through the
    /// kinematic model and the controller, and reports the mean; the nominal bed (the
    /// figure's, pil's and the F407's) is the one nearest the middle. Not with --phi.
    #[arg(long, value_name = "A:B", conflicts_with = "phi")]
    pub phi_range: Option<String>,
    /// Beds sampled across --phi-range, ends included.
    #[arg(long, value_name = "N", default_value = "5", requires = "phi_range",
          value_parser = clap::value_parser!(u32).range(2..=21))]
    pub phi_points: u32,
    /// Parameters and integration.
    #[command(flatten)]
    pub source: ParamSource,
    /// Largest |p| a stroke may reach, m (at most the rig's 0.025).
    #[arg(long, value_name = "M", default_value = "0.025",
          value_parser = ranged("--max-stroke", 0.0, 0.025, "m"))]
    pub max_stroke: f64,
    /// Longest stroke, s (start to the end of its last move; at most what the replay
    /// buffer holds at --table-rate).
    #[arg(long, value_name = "S", default_value = "2",
          value_parser = ranged("--max-duration", 0.0, 409.5, "s"))]
    pub max_duration: f64,
    /// Samples per second of the stroke table (stroke.csv, the rig's replay table; divides
    /// the 10 kHz control rate).
    #[arg(long, value_name = "HZ", default_value = "1000",
          value_parser = clap::value_parser!(u32).range(10..=10_000))]
    pub table_rate: u32,
    /// Least jump height of a stroke for the ratio objectives, m (they also need the foot to
    /// leave the ground: a rod raised by a retracting motor is not a jump).
    #[arg(long, value_name = "M", default_value = "0.02",
          value_parser = ranged("--min-height", 0.0, 1.0, "m"))]
    pub min_height: f64,
    /// Most the spring may be compressed below its free length, m (default: the free length,
    /// robot.spring_rest_length_m; a coil-bind length from the spring's data sheet is tighter).
    #[arg(long, value_name = "M", value_parser = ranged("--max-spring-compression", 0.0, 1.0, "m"))]
    pub max_spring_compression: Option<f64>,
    /// Highest the rod may rise above its rest, m: the rig's frame above the bed (no document
    /// of the rig gives it; 1 m is a stated default).
    #[arg(long, value_name = "M", default_value = "1",
          value_parser = ranged("--max-rise", 0.0, 10.0, "m"))]
    pub max_rise: f64,
    /// Moves per stroke (the family: rest-to-rest cosine moves with holds; the paper's
    /// strokes have 2).
    #[arg(long, value_name = "N", default_value = "4",
          value_parser = clap::value_parser!(u32).range(2..=8))]
    pub moves: u32,
    /// Longest hold between moves, s.
    #[arg(long, value_name = "S", default_value = "0.5",
          value_parser = ranged("--max-hold", 0.0, 5.0, "s"))]
    pub max_hold: f64,
    /// Evaluations of the search in all (shared by its starts).
    #[arg(long, value_name = "N", default_value = "192000",
          value_parser = clap::value_parser!(u64).range(100..=10_000_000))]
    pub evaluations: u64,
    /// Candidates per CMA-ES generation.
    #[arg(long, value_name = "N", default_value = "24",
          value_parser = clap::value_parser!(u32).range(4..=1000))]
    pub population: u32,
    /// Random starts after the three paper strokes' starts.
    #[arg(long, value_name = "N", default_value = "9",
          value_parser = clap::value_parser!(u32).range(0..=100))]
    pub random_starts: u32,
    /// Seed of the search (the same seed, the same answer).
    #[arg(long, value_name = "N", default_value = "1")]
    pub seed: u64,
    /// Also start from the answer of an earlier search (its folder; repeatable), e.g. one
    /// under narrower limits: it is a candidate too, so the answer here is at least as good
    /// when it keeps these limits.
    #[arg(long, value_name = "DIR")]
    pub start_from: Vec<PathBuf>,
    /// Step of the paper strokes' frequency sweep, Hz (1..25 Hz).
    #[arg(long, value_name = "HZ", default_value = "0.1",
          value_parser = ranged("--sweep-freq-step", 0.0, 5.0, "Hz"))]
    pub sweep_freq_step: f64,
    /// Step of the delayed stutter's delay in the sweep, s (0..--max-hold).
    #[arg(long, value_name = "S", default_value = "0.01",
          value_parser = ranged("--sweep-tau-step", 0.0, 1.0, "s"))]
    pub sweep_tau_step: f64,
    /// Re-run the best strokes (and the paper's best) force-driven through these links:
    /// `sil` (candidates are re-ranked through it), `pil` (the emulated firmware under QEMU),
    /// `f407` (the F407 release binary on the virtual board, as `rig replay --stroke --link
    /// f407` runs it), a comma-separated list, or `none`. A link that is not available here is
    /// skipped with the reason.
    #[arg(long, value_name = "LINKS", default_value = "sil,pil,f407", value_parser = parse_links)]
    pub verify: VerifyLinks,
    /// Candidates of each start re-ranked through the controller (its best distinct ones).
    #[arg(long, value_name = "N", default_value = "16",
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub elites: u32,
    /// Runs through sil refining the best re-ranked stroke (CMA-ES on the controller's
    /// value), and as many refining the paper's best over its amplitude, frequency and delay,
    /// before the two are compared (0: none).
    #[arg(long, value_name = "N", default_value = "600",
          value_parser = clap::value_parser!(u32).range(0..=100_000))]
    pub refine: u32,
    /// Paper strokes of each kind re-ranked through the controller (the sweep's best).
    #[arg(long, value_name = "N", default_value = "8",
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub paper_candidates: u32,
    /// Firmware ELF for --verify pil (built with --features board-qemu).
    #[arg(long, value_name = "ELF", default_value = sandjumper_rig::firmware_image::EMULATED_ELF)]
    pub firmware: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Output directory: stroke.csv, paper_stroke.csv, candidates.csv, paper_sweep.csv,
    /// history.csv, validity.csv (the answer under the model's alternative rules), beds.csv
    /// (the answer and the paper's best on each bed), summary.json, params.toml, optimize.png
    /// and optimize.svg. The search's
    /// checkpoint lives beside it (DIR.checkpoint) until it finishes: run the same command
    /// again to resume.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print the summary as JSON (best_height_m, best_paper_stroke_height_m, height_ratio
    /// and the rest of summary.json).
    #[arg(long)]
    pub json: bool,
}

/// The request `a` asks for (its parameters resolved from `--phi` and `--params`).
fn request(a: &OptimizeArgs) -> Result<OptimizeRequest, CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    let (params, beds) = match &a.phi_range {
        None => (resolve_params(a.phi, file.as_ref())?, Vec::new()),
        Some(range) => parse_phi_range(range, a.phi_points as usize)
            .map_err(CliError::input)?
            .beds(file.as_ref().map(ParamsFile::to_library).as_ref())?,
    };
    Ok(OptimizeRequest {
        objective: a.objective.into(),
        model: a.model.into(),
        params,
        beds,
        rtol: a.source.rtol,
        max_stroke_m: a.max_stroke,
        max_duration_s: a.max_duration,
        table_rate_hz: a.table_rate,
        min_height_m: a.min_height,
        max_spring_compression_m: a.max_spring_compression,
        max_rise_m: a.max_rise,
        moves: a.moves as usize,
        max_hold_s: a.max_hold,
        evaluations: a.evaluations as usize,
        population: a.population as usize,
        random_starts: a.random_starts as usize,
        seed: a.seed,
        start_from: a
            .start_from
            .iter()
            .map(|d| answer_chain_in(d))
            .collect::<Result<_, _>>()?,
        sweep_freq_step_hz: a.sweep_freq_step,
        sweep_tau_step_s: a.sweep_tau_step,
        verify: a.verify.0.clone(),
        elites: a.elites as usize,
        refine: a.refine as usize,
        paper_candidates: a.paper_candidates as usize,
        firmware: a.firmware.clone(),
        threads: a.threads.map(|t| t as usize),
        out: a.out.clone(),
    })
}

/// Run `optimize`: the search, then its summary on stdout (JSON with `--json`).
pub fn run(a: &OptimizeArgs) -> Result<(), CliError> {
    let request = request(a)?;
    let bars = Bars::new().with_notes(!a.json);
    let outcome = sandjumper_optimize::run(&request, &bars)?;
    if a.json {
        println!("{}", outcome.json()?);
    } else {
        print!("{outcome}");
    }
    Ok(())
}
