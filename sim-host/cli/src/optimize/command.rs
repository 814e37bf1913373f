//! `sandjumper optimize`: search for the stroke that makes the robot jump highest (or best by
//! another objective) within the rig's limits, compare it with the best of the paper's
//! strokes, re-run both through the real controller, and write stroke.csv for `jump`, `hil`
//! and `rig replay --stroke`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, ValueEnum};
use serde::Serialize;

use crate::command::args::{ModelArg, ParamSource, parse_phi};
use crate::command::resolve::{ParamsFile, resolve_params};
use sandjumper_model::SimOptions;
use sandjumper_model::jump::simulate_stroke;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_optimize::checkpoint::Checkpoint;
use sandjumper_optimize::evaluate::{Evaluation, Objective, Problem, SearchLimits};
use sandjumper_optimize::family::{Encoding, MoveChain};
use sandjumper_optimize::figure::{Shown, search_figure};
use sandjumper_optimize::paper_sweep::{PaperGrid, SweptPoint, sweep};
use sandjumper_optimize::refine::{RefineSettings, refine};
use sandjumper_optimize::search::{SearchSettings, Start, search};
use sandjumper_optimize::verify::{LinkRun, run_through};
use sandjumper_output::CliError;
use sandjumper_output::StagedDir;
use sandjumper_output::folder::write_csv;
use sandjumper_output::plot::save_figure;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable};

/// The objective on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ObjectiveArg {
    /// The highest rod apex of the run.
    Height,
    /// The highest apex after the push-off begins (the final hop).
    FinalHeight,
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
            ObjectiveArg::HeightPerPeakPower => Objective::HeightPerPeakPower,
            ObjectiveArg::HeightPerEnergy => Objective::HeightPerEnergy,
        }
    }
}

fn ranged(
    what: &'static str,
    lo: f64,
    hi: f64,
    unit: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > lo && v <= hi => Ok(v),
        _ => Err(format!(
            "{what} `{s}` out of range (allowed: {lo} < X <= {hi} {unit})"
        )),
    }
}

/// The links of `--verify`.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifyLinks(pub Vec<LinkArg>);

fn parse_links(s: &str) -> Result<VerifyLinks, String> {
    if s.trim() == "none" {
        return Ok(VerifyLinks(Vec::new()));
    }
    s.split(',')
        .map(|l| match l.trim() {
            "sil" => Ok(LinkArg::Sil),
            "pil" => Ok(LinkArg::Pil),
            "f407" => Ok(LinkArg::F407),
            other => Err(format!(
                "link `{other}` not allowed in --verify (allowed: sil, pil, f407, a \
                 comma-separated list of them, or none)"
            )),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(VerifyLinks)
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
    /// value; 0: none).
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
    /// history.csv, summary.json, params.toml, optimize.png and optimize.svg. The search's
    /// checkpoint lives beside it (DIR.checkpoint) until it finishes: run the same command
    /// again to resume.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Print the summary as JSON (best_height_m, best_paper_stroke_height_m, height_ratio
    /// and the rest of summary.json).
    #[arg(long)]
    pub json: bool,
}

/// A stroke of the result: its description, its kinematic evaluation and its runs through
/// the links.
#[derive(Debug, Serialize)]
pub struct ResultStroke {
    /// In words.
    pub label: String,
    /// The chain (start and moves), for the optimised strokes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chain: Option<MoveChain>,
    /// The objective's value through the ranking link (None: not run, or it faulted).
    pub controller_value: Option<f64>,
    /// Kinematic model.
    pub kinematic: Evaluation,
    /// The stroke table as `jump --stroke` runs it (Catmull-Rom at the table rate), m.
    pub table_jump_height_m: f64,
    /// Through the controller.
    pub links: Vec<LinkRun>,
}

/// `summary.json` and `--json`.
#[derive(Debug, Serialize)]
pub struct OptimizeReport {
    /// Jump height of the answer, m, on `height_basis`.
    pub best_height_m: f64,
    /// Jump height of the best paper stroke, m, on the same basis.
    pub best_paper_stroke_height_m: f64,
    /// Their ratio.
    pub height_ratio: f64,
    /// What the heights and values are measured on: the ranking link (`sil`: force-driven
    /// through the real controller), or `kinematic` when no link ran.
    pub height_basis: String,
    /// The objective.
    pub objective: &'static str,
    /// Its unit.
    pub objective_unit: &'static str,
    /// The answer's objective value, on `height_basis`.
    pub best_value: f64,
    /// The best paper stroke's objective value, on `height_basis`.
    pub best_paper_value: f64,
    /// Their ratio.
    pub value_ratio: f64,
    /// Ground model.
    pub model: &'static str,
    /// Packing fraction.
    pub phi: f64,
    /// The answer: the best candidate through the controller (written as stroke.csv).
    pub answer: ResultStroke,
    /// The best paper stroke through the controller (paper_stroke.csv).
    pub paper_answer: ResultStroke,
    /// The best stroke of the kinematic model, when it is not the answer (the controller
    /// did worse with it).
    pub kinematic_optimum: Option<ResultStroke>,
    /// The best single, stutter and delayed stutter of the kinematic sweep.
    pub paper_best_by_kind: Vec<KindBest>,
    /// Candidates re-ranked through the controller.
    pub candidates_ranked: usize,
    /// Runs through sil of the refinement.
    pub refine_runs: usize,
    /// Points of the paper sweep.
    pub paper_sweep_points: usize,
    /// Feasible points of the sweep.
    pub paper_sweep_feasible: usize,
    /// Evaluations of the search.
    pub evaluations: usize,
    /// Of which read back from a checkpoint (a resumed search).
    pub evaluations_resumed: usize,
    /// Candidates outside the limits.
    pub evaluations_infeasible: usize,
    /// Kinematic evaluations per second (sweep and search, fresh ones only).
    pub evaluations_per_s: f64,
    /// Threads used.
    pub threads: usize,
    /// Wall time, s.
    pub wall_time_s: f64,
    /// The limits.
    pub limits: SearchLimits,
    /// The family's encoding (bounds).
    pub encoding: Encoding,
    /// The search's settings.
    pub search: SearchSettings,
}

/// The problem, encoding and search settings `a` asks for, checked.
fn setup(
    a: &OptimizeArgs,
    params: &Params,
) -> Result<(Problem, Encoding, SearchSettings), CliError> {
    let rig = RigLimits {
        stroke_m: a.max_stroke,
        ..RigLimits::of(params)
    };
    let tick_hz = RigModelConfig::default().tick_hz;
    if !tick_hz.is_multiple_of(a.table_rate) {
        return Err(CliError::input(format!(
            "--table-rate {} Hz does not divide the {tick_hz} Hz control rate (allowed: e.g. \
             500, 1000, 2000, 5000)",
            a.table_rate
        )));
    }
    let buffer_s = rig.max_duration_s(a.table_rate);
    if a.max_duration > buffer_s {
        return Err(CliError::input(format!(
            "--max-duration {} s is longer than the replay buffer holds at {} samples/s \
             ({buffer_s:.3} s; allowed: up to that, or lower --table-rate)",
            a.max_duration, a.table_rate
        )));
    }
    let (lo, hi) = rig.accel_range_m_s2();
    let max_accel = hi.min(-lo);
    if max_accel <= 0.0 {
        return Err(CliError::input(format!(
            "the drive's peak force {} N cannot hold the motor ({} kg) against gravity",
            params.drive.peak_force_n, params.robot.motor_mass_kg
        )));
    }
    let moves = a.moves as usize;
    // The longest move: the slowest half period of the sweep (1 Hz), whatever --moves and
    // --max-duration (the duration limit is checked on every candidate).
    let max_move = 0.5;
    let encoding = Encoding {
        moves,
        stroke_m: a.max_stroke,
        max_accel_m_s2: max_accel,
        min_move_s: 4.0 / f64::from(a.table_rate),
        max_move_s: max_move,
        max_hold_s: a.max_hold,
    };
    let problem = Problem {
        params: params.clone(),
        model: a.model.into(),
        limits: SearchLimits {
            rig,
            table_rate_hz: a.table_rate,
            max_duration_s: a.max_duration,
            min_height_m: a.min_height,
        },
        objective: a.objective.into(),
        opts: SimOptions {
            rtol: a.source.rtol,
            ..SimOptions::default()
        },
    };
    let settings = SearchSettings {
        seed: a.seed,
        evaluations: a.evaluations as usize,
        population: a.population as usize,
        random_starts: a.random_starts as usize,
        sigma_paper: 0.1,
        sigma_random: 0.3,
        elites_per_start: a.elites as usize,
    };
    Ok((problem, encoding, settings))
}

/// The starts: the paper's best of each kind, then seeded random points.
fn starts(sweep_best: &[SweptPoint], encoding: &Encoding, s: &SearchSettings) -> Vec<Start> {
    let mut v: Vec<Start> = sweep_best
        .iter()
        .map(|p| Start {
            label: format!("from the best {}", p.stroke.describe()),
            x: encoding.encode(&p.stroke.chain(encoding.moves)),
            sigma: s.sigma_paper,
        })
        .collect();
    // SplitMix64 from the seed: random starts depend on the seed alone.
    let mut state = s.seed ^ 0x5EED_5EED_5EED_5EED;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..s.random_starts {
        v.push(Start {
            label: format!("random start {}", i + 1),
            x: (0..encoding.dim()).map(|_| next()).collect(),
            sigma: s.sigma_random,
        });
    }
    v
}

/// The checkpoint's path for `out`: `DIR.checkpoint` beside it.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".checkpoint");
    out.with_file_name(name)
}

/// A resumed search's killed runs left their half-written output folders
/// (`.DIR.partial-*` beside DIR): remove them.
fn remove_stale_partials(out: &Path) {
    let (Some(parent), Some(name)) = (out.parent(), out.file_name()) else {
        return;
    };
    let parent = if parent.as_os_str().is_empty() {
        Path::new(".")
    } else {
        parent
    };
    let prefix = format!(".{}.partial-", name.to_string_lossy());
    if let Ok(entries) = std::fs::read_dir(parent) {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(&prefix) && e.path().is_dir() {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
}

/// The settings a checkpoint must agree on, as JSON.
fn checkpoint_settings(
    problem: &Problem,
    encoding: &Encoding,
    settings: &SearchSettings,
    starts: &[Start],
) -> Result<String, CliError> {
    let start_bits: Vec<Vec<String>> = starts
        .iter()
        .map(|s| {
            s.x.iter()
                .map(|v| format!("{:016x}", v.to_bits()))
                .collect()
        })
        .collect();
    serde_json::to_string(&serde_json::json!({
        "objective": problem.objective.name(),
        "model": problem.model.as_str(),
        "params": problem.params.to_toml(),
        "rtol": problem.opts.rtol,
        "limits": problem.limits,
        "encoding": encoding,
        "search": settings,
        "starts": start_bits,
    }))
    .map_err(|e| CliError::internal(format!("cannot encode the checkpoint's settings: {e}")))
}

/// One row of candidates.csv.
#[derive(Serialize)]
struct CandidateRow<'a> {
    rank: usize,
    label: &'a str,
    controller_value: f64,
    controller_height_m: f64,
    controller_faults: String,
    kinematic_value: f64,
    kinematic_height_m: f64,
    kinematic_final_height_m: f64,
    model_peak_force_n: f64,
    table_peak_force_n: f64,
    peak_power_w: f64,
    work_j: f64,
    duration_s: f64,
    stroke: String,
}

/// One row of paper_sweep.csv.
#[derive(Serialize)]
struct SweepRow {
    kind: &'static str,
    amplitude_m: f64,
    freq_hz: f64,
    tau_s: f64,
    feasible: bool,
    value: f64,
    jump_height_m: f64,
    final_jump_height_m: f64,
    model_peak_force_n: f64,
    table_peak_force_n: f64,
    violation: String,
}

fn chain_text(c: &MoveChain) -> String {
    let mut s = format!("start {:.3} mm", 1e3 * c.start_m);
    let mut p = c.start_m;
    for (i, m) in c.moves.iter().enumerate() {
        if m.to_m == p {
            if i + 1 < c.moves.len() && m.hold_s > 0.0 {
                s += &format!("; hold {:.1} ms", 1e3 * m.hold_s);
            }
            continue;
        }
        s += &format!(
            "; to {:.3} mm in {:.1} ms",
            1e3 * m.to_m,
            1e3 * m.duration_s
        );
        if i + 1 < c.moves.len() && m.hold_s > 0.0 {
            s += &format!(", hold {:.1} ms", 1e3 * m.hold_s);
        }
        p = m.to_m;
    }
    s
}

/// Run `optimize`.
pub fn run(a: &OptimizeArgs) -> Result<(), CliError> {
    let file = ParamsFile::read_opt(a.source.params.as_deref())?;
    let params = resolve_params(a.phi, file.as_ref())?;
    let (problem, encoding, settings) = setup(a, &params)?;
    let threads = a
        .threads
        .map(|t| t as usize)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let rayon_pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| CliError::internal(format!("cannot start {threads} threads: {e}")))?;
    if checkpoint_path(&a.out).exists() {
        remove_stale_partials(&a.out);
    }
    let staged = StagedDir::create(&a.out)?;
    let started = Instant::now();
    let quiet = a.json;
    let say = |s: String| {
        if !quiet {
            eprintln!("{s}");
        }
    };
    let model: ModelName = problem.model;
    say(format!(
        "optimize: {} on {} at phi {}, {} moves, {} evaluations on {threads} thread(s)",
        problem.objective.name(),
        model.as_str(),
        params.sand.packing_fraction,
        encoding.moves,
        settings.evaluations
    ));

    // 1. The paper's strokes.
    let grid = PaperGrid::standard(
        a.max_stroke,
        a.sweep_freq_step,
        a.max_hold,
        a.sweep_tau_step,
    );
    let bar = crate::command::progress_bar(grid.len() as u64, "paper strokes");
    let sweep_started = Instant::now();
    let paper = rayon_pool.install(|| {
        sweep(&problem, &grid, encoding.moves, &|n| {
            bar.set_position(n as u64)
        })
    });
    bar.finish_and_clear();
    let sweep_s = sweep_started.elapsed().as_secs_f64();
    let feasible = paper
        .points
        .iter()
        .filter(|p| p.evaluation.feasible())
        .count();
    let Some(paper_best) = paper.best().cloned() else {
        return Err(CliError::input(format!(
            "none of the {} paper strokes swept keeps the limits (stroke {} m, peak force {} N, \
             duration {} s): loosen them",
            paper.points.len(),
            a.max_stroke,
            params.drive.peak_force_n,
            a.max_duration
        )));
    };
    say(format!(
        "  paper strokes: {} swept in {sweep_s:.1} s ({feasible} within the limits); best {} \
         ({:.2} mm)",
        paper.points.len(),
        paper_best.stroke.describe(),
        1e3 * paper_best.evaluation.jump_height_m
    ));

    // 2. The search, from the paper's bests and random points.
    let starts = starts(&paper.best_by_kind, &encoding, &settings);
    let ckpt_path = checkpoint_path(&a.out);
    let mut checkpoint = Checkpoint::open(
        &ckpt_path,
        &checkpoint_settings(&problem, &encoding, &settings, &starts)?,
    )
    .map_err(CliError::input)?;
    if checkpoint.resumed_evaluations > 0 {
        say(format!(
            "  resuming from {}: {} evaluations recorded",
            ckpt_path.display(),
            checkpoint.resumed_evaluations
        ));
    }
    let bar = crate::command::progress_bar(settings.evaluations as u64, "evaluations");
    let search_started = Instant::now();
    let outcome = rayon_pool
        .install(|| {
            search(
                &problem,
                &encoding,
                &starts,
                &settings,
                Some(&mut checkpoint),
                &|p| {
                    bar.set_length(p.budget as u64);
                    bar.set_position(p.evaluations as u64);
                    if p.best.is_finite() {
                        bar.set_message(format!("{:.4}", p.best));
                    }
                },
            )
        })
        .map_err(CliError::internal)?;
    bar.finish_and_clear();
    let search_s = search_started.elapsed().as_secs_f64();
    say(format!(
        "  search: {} evaluations in {search_s:.1} s ({} resumed, {} outside the limits)",
        outcome.evaluations, outcome.replayed, outcome.infeasible,
    ));

    // The kinematic optimum: the search's best, or the paper's best when the search found
    // nothing better (the paper's strokes are members of the family).
    let kinematic_optimum = match outcome.by_start.first() {
        Some(b) if b.evaluation.feasible() && b.evaluation.value >= paper_best.evaluation.value => {
            Candidate {
                label: format!("optimised ({})", b.start.label),
                chain: b.chain.clone(),
                kinematic: b.evaluation.clone(),
                paper: None,
            }
        }
        _ => Candidate::paper(&paper_best, encoding.moves),
    };

    // 3. The candidates re-ranked through the controller (a stroke it cannot follow is worth
    // nothing), then the answer and the paper's best through every link.
    let rank_link = a
        .verify
        .0
        .iter()
        .find(|l| **l == LinkArg::Sil)
        .or(a.verify.0.first())
        .cloned();
    let mut pool: Vec<Candidate> = vec![kinematic_optimum.clone()];
    for e in &outcome.elites {
        let kinematic = problem.evaluate(&e.chain);
        if kinematic.feasible() {
            pool.push(Candidate {
                label: format!("optimised ({})", starts[e.start].label),
                chain: e.chain.clone(),
                kinematic,
                paper: None,
            });
        }
    }
    for kind in ["single", "stutter", "delayed"] {
        let mut of_kind: Vec<&SweptPoint> = paper
            .points
            .iter()
            .filter(|p| p.stroke.kind == kind && p.evaluation.feasible())
            .collect();
        of_kind.sort_by(|x, y| y.evaluation.value.total_cmp(&x.evaluation.value));
        pool.extend(
            of_kind
                .into_iter()
                .take(a.paper_candidates as usize)
                .map(|p| Candidate::paper(p, encoding.moves)),
        );
    }
    let mut refine_runs = 0;
    let ranked: Vec<Option<LinkRun>> = match &rank_link {
        None => vec![None; pool.len()],
        Some(link) => {
            say(format!(
                "  re-ranking {} candidates (the search's best, the paper's best) through {link}",
                pool.len()
            ));
            let bar =
                crate::command::progress_bar(pool.len() as u64, "runs through the controller");
            let runs = rayon_pool
                .install(|| {
                    use rayon::prelude::*;
                    pool.par_iter()
                        .map(|c| {
                            let r = run_through(
                                link,
                                &problem.params,
                                model,
                                &problem.table(&c.chain),
                                &a.firmware,
                            );
                            bar.inc(1);
                            r.map(Some)
                        })
                        .collect::<Result<Vec<_>, _>>()
                })
                .map_err(CliError::internal)?;
            bar.finish_and_clear();
            runs
        }
    };
    let mut ranked = ranked;
    // The best stroke through the controller, refined there.
    if rank_link == Some(LinkArg::Sil) && a.refine > 0 {
        let from = best_index(&pool, &ranked, &problem, false);
        say(format!(
            "  refining {} through sil ({} runs)",
            pool[from].label, a.refine
        ));
        let bar = crate::command::progress_bar(u64::from(a.refine), "runs through sil");
        let refined = rayon_pool
            .install(|| {
                refine(
                    &problem,
                    &encoding,
                    &pool[from].chain,
                    &RefineSettings {
                        evaluations: a.refine as usize,
                        population: 12,
                        sigma: 0.02,
                        seed: settings.seed,
                    },
                    Some(&mut checkpoint),
                    &a.firmware,
                    &|n, _, _| bar.set_position(n as u64),
                )
            })
            .map_err(CliError::internal)?;
        bar.finish_and_clear();
        let run = run_through(
            &LinkArg::Sil,
            &problem.params,
            model,
            &problem.table(&refined.chain),
            &a.firmware,
        )
        .map_err(CliError::internal)?;
        refine_runs = refined.evaluations;
        pool.push(Candidate {
            label: format!("refined through sil from {}", pool[from].label),
            kinematic: problem.evaluate(&refined.chain),
            chain: refined.chain,
            paper: None,
        });
        ranked.push(Some(run));
    }
    let controller_value = |i: usize| {
        ranked[i].as_ref().and_then(|r| {
            r.value(
                problem.objective,
                a.min_height,
                problem.released_energy_j(&pool[i].chain),
            )
        })
    };
    let best_of = |paper_only: bool| best_index(&pool, &ranked, &problem, paper_only);
    let basis = if rank_link.is_some() && (0..pool.len()).any(|i| controller_value(i).is_some()) {
        rank_link
            .as_ref()
            .map_or("kinematic".to_string(), ToString::to_string)
    } else {
        "kinematic".to_string()
    };
    let (answer_i, paper_i) = (best_of(false), best_of(true));
    let result = |i: usize| -> Result<ResultStroke, CliError> {
        let c = &pool[i];
        let table = problem.table(&c.chain);
        let table_stroke = table.kinematic_stroke().map_err(CliError::internal)?;
        let table_jump = simulate_stroke(&problem.params, model, table_stroke, &problem.opts)
            .map_err(|e| CliError::internal(format!("the stroke table's jump failed: {e}")))?;
        let mut links: Vec<LinkRun> = ranked[i].iter().cloned().collect();
        for link in a.verify.0.iter().filter(|l| Some(*l) != rank_link.as_ref()) {
            links.push(if *link == LinkArg::F407 {
                run_on_the_virtual_board(a, &table)
            } else {
                run_through(link, &problem.params, model, &table, &a.firmware)
                    .map_err(CliError::internal)?
            });
        }
        Ok(ResultStroke {
            label: c.label.clone(),
            chain: c.paper.is_none().then(|| c.chain.clone()),
            controller_value: controller_value(i),
            kinematic: c.kinematic.clone(),
            table_jump_height_m: table_jump.summary.jump_height_m,
            links,
        })
    };
    let answer = result(answer_i)?;
    let paper_answer = result(paper_i)?;
    // The kinematic model's best, when the controller made another stroke the answer and it
    // is not the paper's best shown already.
    let kinematic_result = if answer_i == 0 || pool[0].chain == pool[paper_i].chain {
        None
    } else {
        Some(result(0)?)
    };
    let answer_chain = pool[answer_i].chain.clone();
    let paper_chain = pool[paper_i].chain.clone();
    let height_on = |r: &ResultStroke| -> f64 {
        if basis == "kinematic" {
            r.kinematic.jump_height_m
        } else {
            r.links
                .first()
                .and_then(|l| l.jump_height_m)
                .unwrap_or(f64::NAN)
        }
    };
    let value_on = |r: &ResultStroke| -> f64 {
        if basis == "kinematic" {
            r.kinematic.value
        } else {
            r.controller_value.unwrap_or(f64::NAN)
        }
    };
    say(format!(
        "  answer: {} ({:.2} mm on {basis})",
        answer.label,
        1e3 * height_on(&answer)
    ));

    // 4. Files.
    let best_table = problem.table(&answer_chain);
    let paper_table = problem.table(&paper_chain);
    staged.write_text("stroke.csv", &best_table.to_csv())?;
    staged.write_text("paper_stroke.csv", &paper_table.to_csv())?;
    staged.write_text("params.toml", &params.to_toml())?;
    let mut order: Vec<usize> = (0..pool.len()).collect();
    order.sort_by(|&x, &y| {
        let key = |i: usize| controller_value(i).unwrap_or(f64::NEG_INFINITY);
        key(y)
            .total_cmp(&key(x))
            .then(pool[y].kinematic.value.total_cmp(&pool[x].kinematic.value))
    });
    let candidates: Vec<CandidateRow> = order
        .iter()
        .enumerate()
        .map(|(rank, &i)| {
            let c = &pool[i];
            let run = ranked[i].as_ref();
            CandidateRow {
                rank: rank + 1,
                label: &c.label,
                kinematic_value: c.kinematic.value,
                kinematic_height_m: c.kinematic.jump_height_m,
                kinematic_final_height_m: c.kinematic.final_jump_height_m,
                controller_value: controller_value(i).unwrap_or(f64::NAN),
                controller_height_m: run.and_then(|r| r.jump_height_m).unwrap_or(f64::NAN),
                controller_faults: run.map(|r| r.faults.join(" ")).unwrap_or_default(),
                model_peak_force_n: c.kinematic.model_peak_force_n,
                table_peak_force_n: c.kinematic.table_peak_force_n,
                peak_power_w: c.kinematic.peak_power_w,
                work_j: c.kinematic.work_j,
                duration_s: c.kinematic.duration_s,
                stroke: chain_text(&c.chain),
            }
        })
        .collect();
    write_csv(&staged.file("candidates.csv"), &candidates, &[]).map_err(CliError::internal)?;
    let sweep_rows: Vec<SweepRow> = paper
        .points
        .iter()
        .map(|p| SweepRow {
            kind: p.stroke.kind,
            amplitude_m: p.stroke.amplitude_m,
            freq_hz: p.stroke.freq_hz,
            tau_s: p.stroke.tau_s,
            feasible: p.evaluation.feasible(),
            value: p.evaluation.value,
            jump_height_m: p.evaluation.jump_height_m,
            final_jump_height_m: p.evaluation.final_jump_height_m,
            model_peak_force_n: p.evaluation.model_peak_force_n,
            table_peak_force_n: p.evaluation.table_peak_force_n,
            violation: p.evaluation.violation.clone().unwrap_or_default(),
        })
        .collect();
    write_csv(&staged.file("paper_sweep.csv"), &sweep_rows, &[]).map_err(CliError::internal)?;
    write_csv(
        &staged.file("history.csv"),
        &outcome.history,
        &[
            "start",
            "generation",
            "evaluations",
            "generation_best",
            "best_so_far",
            "sigma",
        ],
    )
    .map_err(CliError::internal)?;

    let series_opts = SimOptions {
        record_series: true,
        ..problem.opts.clone()
    };
    let series = |c: &MoveChain| {
        simulate_stroke(&problem.params, model, c.stroke(), &series_opts)
            .map(|o| o.series)
            .map_err(|e| CliError::internal(format!("cannot record the jump: {e}")))
    };
    let best_series = series(&answer_chain)?;
    let paper_series = series(&paper_chain)?;
    let fig = search_figure(
        format!(
            "best {} on {}, φ = {} ({basis}): {:.2} mm vs the paper's {:.2} mm",
            problem.objective.name(),
            model.as_str(),
            params.sand.packing_fraction,
            1e3 * height_on(&answer),
            1e3 * height_on(&paper_answer)
        ),
        &[
            Shown {
                label: "answer".into(),
                stroke: best_table.points(),
                series: &best_series,
            },
            Shown {
                label: format!("paper: {}", paper_answer.label),
                stroke: paper_table.points(),
                series: &paper_series,
            },
        ],
        &outcome.history,
        problem.objective.name(),
        problem.objective.unit(),
    );
    save_figure(
        &fig,
        &staged.file("optimize.png"),
        Some(&staged.file("optimize.svg")),
    )?;

    let fresh = paper.points.len() + outcome.evaluations - outcome.replayed;
    let wall = started.elapsed().as_secs_f64();
    let (h, hp) = (height_on(&answer), height_on(&paper_answer));
    let (v, vp) = (value_on(&answer), value_on(&paper_answer));
    let report = OptimizeReport {
        best_height_m: h,
        best_paper_stroke_height_m: hp,
        height_ratio: h / hp,
        height_basis: basis.clone(),
        objective: problem.objective.name(),
        objective_unit: problem.objective.unit(),
        best_value: v,
        best_paper_value: vp,
        value_ratio: v / vp,
        model: model.as_str(),
        phi: params.sand.packing_fraction,
        answer,
        paper_answer,
        kinematic_optimum: kinematic_result,
        paper_best_by_kind: paper
            .best_by_kind
            .iter()
            .map(|p| KindBest {
                stroke: p.stroke.describe(),
                kinematic_value: p.evaluation.value,
                kinematic_height_m: p.evaluation.jump_height_m,
            })
            .collect(),
        candidates_ranked: pool.len(),
        refine_runs,
        paper_sweep_points: paper.points.len(),
        paper_sweep_feasible: feasible,
        evaluations: outcome.evaluations,
        evaluations_resumed: outcome.replayed,
        evaluations_infeasible: outcome.infeasible,
        evaluations_per_s: fresh as f64 / (sweep_s + search_s),
        threads,
        wall_time_s: wall,
        limits: problem.limits,
        encoding,
        search: settings,
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| CliError::internal(format!("cannot encode the summary as JSON: {e}")))?;
    staged.write_text("summary.json", &format!("{json}\n"))?;
    let dir = staged.commit()?;
    // The answer is safe in DIR: the checkpoint has done its job.
    drop(checkpoint);
    let _ = std::fs::remove_file(&ckpt_path);
    if a.json {
        println!("{json}");
    } else {
        print!("{}", human(&report, &dir));
    }
    Ok(())
}

/// `table` through the F407 release binary on the virtual board: `rig replay --stroke
/// --link f407` run as its own process (the board runs free on its own tick, not in
/// lockstep), its summary read back. Skipped, with the reason, when the board or the binary
/// is not there.
fn run_on_the_virtual_board(a: &OptimizeArgs, table: &StrokeTable) -> LinkRun {
    let skipped = |why: String| LinkRun::skipped(&LinkArg::F407, why);
    let scratch = match tempfile::tempdir() {
        Ok(d) => d,
        Err(e) => return skipped(format!("no scratch directory: {e}")),
    };
    let stroke = scratch.path().join("stroke.csv");
    if let Err(e) = std::fs::write(&stroke, table.to_csv()) {
        return skipped(format!("cannot write {}: {e}", stroke.display()));
    }
    let out = scratch.path().join("f407");
    let exe = match std::env::current_exe() {
        Ok(p) => p,
        Err(e) => return skipped(format!("cannot find this program: {e}")),
    };
    let mut cmd = std::process::Command::new(exe);
    cmd.args(["rig", "replay", "--link", "f407", "--json", "--stroke"])
        .arg(&stroke)
        .arg("--out")
        .arg(&out)
        .args(["--model", ModelName::from(a.model).as_str()])
        .args(["--phi", &a.phi.to_string()]);
    if let Some(p) = &a.source.params {
        cmd.arg("--params").arg(p);
    }
    let output = match cmd.output() {
        Ok(o) => o,
        Err(e) => return skipped(format!("cannot run rig replay: {e}")),
    };
    let summary: Option<serde_json::Value> = std::fs::read_to_string(out.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    let Some(s) = summary else {
        let err = String::from_utf8_lossy(&output.stderr);
        return skipped(
            err.lines()
                .find(|l| l.starts_with("error"))
                .unwrap_or("rig replay --link f407 wrote no summary")
                .trim_start_matches("error: ")
                .to_string(),
        );
    };
    LinkRun {
        link: "f407".into(),
        skipped: None,
        jump_height_m: s["simulated_jump_height_m"].as_f64(),
        final_jump_height_m: None,
        faults: s["faults"]
            .as_array()
            .map(|f| {
                f.iter()
                    .filter_map(|x| x["name"].as_str().map(str::to_string))
                    .collect()
            })
            .unwrap_or_default(),
        tracking_error_max_m: s["tracking_error_max_m"].as_f64(),
        saturated_periods: None,
        lifted_off: s["simulated_jump_height_m"]
            .as_f64()
            .is_some_and(|h| h > 0.0),
        peak_power_w: None,
        work_j: None,
    }
}

/// The best of `pool` by its value through the controller (`ranked`, one run per candidate),
/// among the paper's strokes only with `paper_only`; by the kinematic value when no run gave
/// one (no link, or every run faulted).
fn best_index(
    pool: &[Candidate],
    ranked: &[Option<LinkRun>],
    problem: &Problem,
    paper_only: bool,
) -> usize {
    let eligible = |i: &usize| !paper_only || pool[*i].paper.is_some();
    let by_controller = (0..pool.len())
        .filter(eligible)
        .filter_map(|i| {
            ranked[i]
                .as_ref()
                .and_then(|r| {
                    r.value(
                        problem.objective,
                        problem.limits.min_height_m,
                        problem.released_energy_j(&pool[i].chain),
                    )
                })
                .map(|v| (i, v))
        })
        .fold(None::<(usize, f64)>, |best, (i, v)| match best {
            Some((_, bv)) if bv >= v => best,
            _ => Some((i, v)),
        });
    match by_controller {
        Some((i, _)) => i,
        None => (0..pool.len())
            .filter(eligible)
            .fold(None::<usize>, |best, i| match best {
                Some(b) if pool[b].kinematic.value >= pool[i].kinematic.value => Some(b),
                _ => Some(i),
            })
            .unwrap_or(0),
    }
}

/// A stroke considered for the answer.
#[derive(Clone, Debug)]
struct Candidate {
    label: String,
    chain: MoveChain,
    kinematic: Evaluation,
    /// The paper stroke it is, if it is one.
    paper: Option<sandjumper_optimize::paper_sweep::PaperStroke>,
}

impl Candidate {
    fn paper(p: &SweptPoint, moves: usize) -> Self {
        Self {
            label: p.stroke.describe(),
            chain: p.stroke.chain(moves),
            kinematic: p.evaluation.clone(),
            paper: Some(p.stroke),
        }
    }
}

/// The best paper stroke of one kind in the kinematic sweep.
#[derive(Debug, Serialize)]
pub struct KindBest {
    /// In words.
    pub stroke: String,
    /// Objective value, kinematic.
    pub kinematic_value: f64,
    /// Jump height, kinematic, m.
    pub kinematic_height_m: f64,
}

fn human(r: &OptimizeReport, dir: &Path) -> String {
    let mm = |v: f64| format!("{:.2} mm", 1e3 * v);
    let value = |v: f64| {
        if r.objective_unit == "m" {
            mm(v)
        } else {
            format!("{v:.4e} {}", r.objective_unit)
        }
    };
    let mut t = format!(
        "best {} on {} at phi {} ({}): {}, the paper's best {}: ratio {:.3}\n",
        r.objective,
        r.model,
        r.phi,
        r.height_basis,
        value(r.best_value),
        value(r.best_paper_value),
        r.value_ratio
    );
    let kinematic = r.kinematic_optimum.iter();
    let heads = ["answer", "the paper's best", "the kinematic model's best"];
    for (s, head) in [&r.answer, &r.paper_answer]
        .into_iter()
        .chain(kinematic)
        .zip(heads)
    {
        t += &format!("  {head}: {}\n", s.label);
        if let Some(c) = &s.chain {
            t += &format!("    stroke: {}\n", chain_text(c));
        }
        t += &format!(
            "    kinematic {} (its table {}), peak force {:.0} N (table estimate {:.0} N)\n",
            mm(s.kinematic.jump_height_m),
            mm(s.table_jump_height_m),
            s.kinematic.model_peak_force_n,
            s.kinematic.table_peak_force_n
        );
        for l in &s.links {
            match (&l.skipped, l.jump_height_m) {
                (Some(why), _) => t += &format!("    {}: not run ({why})\n", l.link),
                (None, Some(h)) => {
                    t += &format!(
                        "    {}: {} through the controller, {} fault(s){}\n",
                        l.link,
                        mm(h),
                        l.faults.len(),
                        if l.faults.is_empty() {
                            String::new()
                        } else {
                            format!(" ({})", l.faults.join(", "))
                        }
                    )
                }
                _ => {}
            }
        }
    }
    t += &format!(
        "  {} kinematic evaluations ({:.0}/s on {} thread(s)), {} candidates through the \
         controller, {:.1} s; wrote {}/\n",
        r.evaluations + r.paper_sweep_points,
        r.evaluations_per_s,
        r.threads,
        r.candidates_ranked,
        r.wall_time_s,
        dir.display()
    );
    t
}
