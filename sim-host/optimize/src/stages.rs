//! `optimize` as one call ([`run`]): its stages in order, each a function passing typed
//! values to the next: setup, the paper sweep, the search (checkpointed), the candidates
//! re-ranked through the controller, the refinement through sil, the answer and the paper's
//! best verified through every link, the ranking, and the folder.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use sandjumper_model::SimOptions;
use sandjumper_model::jump::simulate_stroke;
use sandjumper_model::params::Params;
use sandjumper_model::record::{JumpSummary, SeriesRow};
use sandjumper_output::{Progress, StagedDir, WriterLock, unfinished_beside, written_by};
use sandjumper_rig::hil::open::LinkArg;

use crate::checkpoint::{self, Checkpoint};
use crate::error::OptimizeError;
use crate::evaluate::{Evaluation, Problem};
use crate::family::{Encoding, MoveChain};
use crate::outcome::{
    BedRow, CandidateRow, KindBest, OptimizeOutcome, OverBeds, RestartAgreement, ResultStroke,
    chain_text,
};
use crate::paper_sweep::{
    PaperGrid, PaperSpace, PaperStroke, PaperSweep, SweptPoint, first_best, sweep,
};
use crate::refine::{RefineSettings, RefineSpace, Refined, refine};
use crate::request::{OptimizeRequest, Setup, checkpoint_lock_path, checkpoint_path};
use crate::search::{SearchOutcome, SearchSettings, Start, search, uniform_point};
use crate::validity::Validity;
use crate::verify::{LinkRun, StrokeOnBoard, VirtualBoard, run_through, through_sil_on_beds};

/// Run the search `request` asks for, reporting to `progress`, and write its folder
/// (`request.out`). The F407 link, if asked, runs on the virtual F407 board
/// ([`VirtualBoard`]; skipped, with the reason, when it is not there); give another board
/// with [`run_with_board`]. A search killed mid-way leaves its checkpoint beside the folder
/// ([`checkpoint_path`]): the same request again resumes it to the same answer.
pub fn run(
    request: &OptimizeRequest,
    progress: &dyn Progress,
) -> Result<OptimizeOutcome, OptimizeError> {
    run_with_board(request, progress, &VirtualBoard)
}

/// [`run`], with the F407 link's runs made by `board`.
pub fn run_with_board(
    request: &OptimizeRequest,
    progress: &dyn Progress,
    board: &dyn StrokeOnBoard,
) -> Result<OptimizeOutcome, OptimizeError> {
    let cx = Context::new(request, progress)?;
    let lock = lock_the_checkpoint(&request.out)?;
    discard_finished_checkpoint(&request.out, &cx);
    let staged = prepare_output(&request.out, &cx)?;
    let started = Instant::now();
    cx.say(format!(
        "optimize: {} on {} at phi {}, {} moves, {} evaluations on {} thread(s)",
        cx.setup.problem.objective.name(),
        cx.setup.problem.model.as_str(),
        request.params.sand.packing_fraction,
        cx.setup.encoding.moves,
        cx.setup.settings.evaluations,
        cx.threads
    ));
    let paper = cx.paper_sweep()?;
    let starts = starts(
        &paper.seeds(request.params.robot.stroke_amplitude_m),
        &request.start_from,
        &cx.setup.encoding,
        &cx.setup.settings,
    );
    let ckpt_path = checkpoint_path(&request.out);
    let mut checkpoint = cx.open_checkpoint(&ckpt_path, &starts)?;
    let searched = cx.search(&starts, &mut checkpoint)?;
    let mut ranking = cx.rank(cx.candidates(&paper, &searched));
    (ranking.ranked, ranking.values) = cx.runs_through(&ranking)?;
    cx.go_on("after the runs through the controller")?;
    cx.refine(&mut ranking, &mut checkpoint)?;
    cx.go_on("after the refinement")?;
    let verified = cx.verify(&ranking, board)?;
    cx.go_on("in the verification")?;
    let mut outcome = cx.outcome(paper, searched, ranking, verified, started)?;
    outcome.write_into(&staged)?;
    checkpoint
        .finish(&written_by(staged.path()).unwrap_or_default())
        .map_err(OptimizeError::Checkpoint)?;
    outcome.dir = match staged.commit() {
        Ok(dir) => dir,
        Err(e) => {
            // The folder did not take its place: the search resumes from its checkpoint.
            let _ = checkpoint.unfinish();
            return Err(e.into());
        }
    };
    // The answer is safe in the folder: the checkpoint has done its job, and its lock.
    drop(checkpoint);
    let _ = std::fs::remove_file(&ckpt_path);
    let _ = std::fs::remove_file(lock.path());
    drop(lock);
    Ok(outcome)
}

/// One search writes a checkpoint at a time: the lock beside it (`DIR.checkpoint.lock`), held
/// until the search ends and released by the OS however it ends. A second search on the same
/// folder is refused, naming the process that holds it.
fn lock_the_checkpoint(out: &Path) -> Result<WriterLock, OptimizeError> {
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| {
            OptimizeError::Checkpoint(format!("cannot create {}: {e}", parent.display()))
        })?;
    }
    WriterLock::take_recorded(&checkpoint_lock_path(out))
        .map_err(|e| OptimizeError::Checkpoint(e.to_string()))
}

/// A search killed after its folder took its place and before it removed its checkpoint left
/// a checkpoint no search needs: removed, saying so, when the folder's marker names the
/// writer the checkpoint's `finished` line does. Killed before the folder took its place, the
/// folder there (if any) is another search's and the checkpoint is resumed. Called with the
/// checkpoint's lock held.
fn discard_finished_checkpoint(out: &Path, cx: &Context<'_>) {
    let path = checkpoint_path(out);
    let Some(writer) = checkpoint::finished_by(&path) else {
        return;
    };
    if written_by(out).as_deref() == Some(writer.as_str()) && std::fs::remove_file(&path).is_ok() {
        cx.say(format!(
            "  removed {}: the checkpoint of the finished search that wrote {} (killed before \
             it removed it)",
            path.display(),
            out.display()
        ));
    }
}

/// A resumed search's killed run left its half-written output folder (`.DIR.partial-*` beside
/// DIR, whose marker names a process that is gone, [`unfinished_beside`]): removed, saying
/// so, since the checkpoint holds what it had. A partial output of a live process, of another
/// machine or of unknown origin is left as it is. Then the folder is staged (refused early
/// when it cannot be written).
fn prepare_output(out: &Path, cx: &Context<'_>) -> Result<StagedDir, OptimizeError> {
    if checkpoint_path(out).exists() {
        for stale in unfinished_beside(out) {
            if std::fs::remove_dir_all(&stale).is_ok() {
                cx.say(format!(
                    "  removed {}: the partial output of the killed search this one resumes",
                    stale.display()
                ));
            }
        }
    }
    Ok(StagedDir::create(out)?)
}

/// The starts: the paper's best strokes ([`PaperStage::seeds`]), the given strokes, then
/// seeded random points.
fn starts(
    sweep_best: &[SweptPoint],
    given: &[MoveChain],
    encoding: &Encoding,
    s: &SearchSettings,
) -> Vec<Start> {
    let mut v: Vec<Start> = sweep_best
        .iter()
        .map(|p| Start {
            label: format!("from the best {}", p.stroke.describe()),
            x: encoding.encode(&p.stroke.chain(encoding.moves)),
            sigma: s.sigma_paper,
        })
        .collect();
    v.extend(given.iter().enumerate().map(|(i, c)| Start {
        label: format!("from given stroke {}", i + 1),
        x: encoding.encode(c),
        sigma: s.sigma_paper,
    }));
    // Random starts depend on the seed alone (one SplitMix64 stream, a start at a time).
    let dim = encoding.dim();
    let stream = uniform_point(s.seed, dim * s.random_starts);
    for (i, x) in stream.chunks(dim.max(1)).enumerate() {
        v.push(Start {
            label: format!("random start {}", i + 1),
            x: x.to_vec(),
            sigma: s.sigma_random,
        });
    }
    v
}

/// Reports a stage's position (steps done so far) to a [`Progress`] as steps advanced.
struct Position<'a> {
    progress: &'a dyn Progress,
    at: AtomicU64,
}

impl<'a> Position<'a> {
    /// Start the stage `what` of `len` steps.
    fn start(progress: &'a dyn Progress, what: &str, len: usize) -> Self {
        progress.start(what, Some(len as u64));
        Self {
            progress,
            at: AtomicU64::new(0),
        }
    }

    /// `n` steps are done; false when the caller asked the run to stop (Ctrl-C).
    fn at(&self, n: usize) -> bool {
        let n = n as u64;
        let before = self.at.fetch_max(n, Ordering::Relaxed);
        if n > before {
            self.progress.advance(n - before);
        }
        !self.progress.cancelled()
    }
}

impl Drop for Position<'_> {
    fn drop(&mut self) {
        self.progress.finish();
    }
}

/// The paper sweep's result.
struct PaperStage {
    sweep: PaperSweep,
    /// Its best feasible point.
    best: SweptPoint,
    /// Points within the limits.
    feasible: usize,
    /// Seconds it took.
    seconds: f64,
}

impl PaperStage {
    /// The paper strokes the search starts from: the best of each kind, then, when the stroke
    /// limit is wider than the robot's own amplitude `a` (the paper's), the best of each kind
    /// at that amplitude (the grid's nearest) where it is another stroke: what the narrower
    /// limits give.
    fn seeds(&self, a: f64) -> Vec<SweptPoint> {
        let mut v = self.sweep.best_by_kind.clone();
        for best in &self.sweep.best_by_kind {
            let at_a = first_best(
                self.at_amplitude(a)
                    .filter(|p| p.stroke.kind == best.stroke.kind),
            );
            if let Some(p) = at_a.filter(|p| p.stroke != best.stroke) {
                v.push(p.clone());
            }
        }
        v
    }

    /// The feasible points of the sweep at its amplitude nearest `a` (m), in grid order.
    fn at_amplitude(&self, a: f64) -> impl Iterator<Item = &SweptPoint> {
        let points = &self.sweep.points;
        let nearest = points
            .iter()
            .map(|p| p.stroke.amplitude_m)
            .min_by(|x, y| (x - a).abs().total_cmp(&(y - a).abs()))
            .unwrap_or(a);
        points
            .iter()
            .filter(move |p| p.evaluation.feasible() && p.stroke.amplitude_m == nearest)
    }
}

/// The search's result.
struct SearchStage {
    starts: Vec<Start>,
    outcome: SearchOutcome,
    /// Seconds it took.
    seconds: f64,
}

/// A stroke considered for the answer.
#[derive(Clone, Debug)]
struct Candidate {
    label: String,
    chain: MoveChain,
    kinematic: Evaluation,
    /// The paper stroke it is, if it is one.
    paper: Option<PaperStroke>,
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

/// The candidates and their runs through the ranking link.
struct Ranking {
    pool: Vec<Candidate>,
    /// One run per candidate (None: no link), on the nominal bed.
    ranked: Vec<Option<LinkRun>>,
    /// Each candidate's objective value through the ranking link: the worst over the beds
    /// (None: not run, or it faulted or broke a limit on a bed).
    values: Vec<Option<f64>>,
    /// The link they are ranked through: sil if asked, else the first link asked.
    link: Option<LinkArg>,
    /// Runs through sil of the answer's refinement.
    refine_runs: usize,
    /// Runs through sil of the paper's best's refinement.
    paper_refine_runs: usize,
}

/// The answer and the paper's best, through every link.
struct Verified {
    answer_i: usize,
    paper_i: usize,
    answer: ResultStroke,
    paper_answer: ResultStroke,
    kinematic_optimum: Option<ResultStroke>,
    /// `sil` (the ranking link) or `kinematic`.
    basis: String,
}

/// What every stage needs: the request, its setup, the threads, the sink.
struct Context<'a> {
    request: &'a OptimizeRequest,
    setup: Setup,
    threads: usize,
    pool: rayon::ThreadPool,
    progress: &'a dyn Progress,
}

impl<'a> Context<'a> {
    /// Setup: the request checked, the search set up, the threads started.
    fn new(
        request: &'a OptimizeRequest,
        progress: &'a dyn Progress,
    ) -> Result<Self, OptimizeError> {
        let setup = request.setup()?;
        let threads = request
            .threads
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| OptimizeError::Internal(format!("cannot start {threads} threads: {e}")))?;
        Ok(Self {
            request,
            setup,
            threads,
            pool,
            progress,
        })
    }

    fn say(&self, line: String) {
        self.progress.note(&line);
    }

    /// An error when the caller asked the run to stop (Ctrl-C), `stage` naming where it
    /// stopped; the checkpoint resumes the search.
    fn go_on(&self, stage: &str) -> Result<(), OptimizeError> {
        if self.progress.cancelled() {
            return Err(OptimizeError::Internal(format!(
                "{}: stopped {stage} (the same request resumes it from its checkpoint)",
                crate::search::INTERRUPTED
            )));
        }
        Ok(())
    }

    /// The paper sweep's grid.
    fn grid(&self) -> PaperGrid {
        let r = self.request;
        PaperGrid::standard(
            r.max_stroke_m,
            r.sweep_freq_step_hz,
            r.max_hold_s,
            r.sweep_tau_step_s,
        )
    }

    /// Stage 1: the paper's strokes swept on the kinematic model.
    fn paper_sweep(&self) -> Result<PaperStage, OptimizeError> {
        let r = self.request;
        let grid = self.grid();
        let started = Instant::now();
        let sweep = {
            let at = Position::start(self.progress, "paper strokes", grid.len());
            let moves = self.setup.encoding.moves;
            self.pool
                .install(|| sweep(&self.setup.problem, &grid, moves, &|n| at.at(n)))
        };
        let Some(sweep) = sweep.filter(|_| !self.progress.cancelled()) else {
            return Err(OptimizeError::Internal(format!(
                "{}: stopped in the sweep of the paper's strokes",
                crate::search::INTERRUPTED
            )));
        };
        let seconds = started.elapsed().as_secs_f64();
        let feasible = sweep
            .points
            .iter()
            .filter(|p| p.evaluation.feasible())
            .count();
        let Some(best) = sweep.best().cloned() else {
            return Err(OptimizeError::NoFeasiblePaperStroke {
                points: sweep.points.len(),
                stroke_m: r.max_stroke_m,
                peak_force_n: r.params.drive.peak_force_n,
                duration_s: r.max_duration_s,
            });
        };
        self.say(format!(
            "  paper strokes: {} swept in {seconds:.1} s ({feasible} within the limits); best {} \
             ({:.2} mm)",
            sweep.points.len(),
            best.stroke.describe(),
            1e3 * best.evaluation.jump_height_m
        ));
        Ok(PaperStage {
            sweep,
            best,
            feasible,
            seconds,
        })
    }

    /// The checkpoint for `starts` at `path`: new, or resumed when it was made with the same
    /// settings.
    fn open_checkpoint(&self, path: &Path, starts: &[Start]) -> Result<Checkpoint, OptimizeError> {
        let checkpoint = Checkpoint::open(path, &checkpoint_settings(&self.setup, starts)?)
            .map_err(OptimizeError::Checkpoint)?;
        if checkpoint.resumed_evaluations > 0 {
            self.say(format!(
                "  resuming from {}: {} evaluations recorded",
                path.display(),
                checkpoint.resumed_evaluations
            ));
        }
        Ok(checkpoint)
    }

    /// Stage 2: the search, from the paper's bests and random points.
    fn search(
        &self,
        starts: &[Start],
        checkpoint: &mut Checkpoint,
    ) -> Result<SearchStage, OptimizeError> {
        let s = &self.setup;
        let started = Instant::now();
        let outcome = {
            let at = Position::start(
                self.progress,
                "evaluations",
                s.settings.budget(starts.len()),
            );
            self.pool
                .install(|| {
                    search(
                        &s.problem,
                        &|x| s.encoding.decode(x),
                        starts,
                        &s.settings,
                        Some(checkpoint),
                        &|p| at.at(p.evaluations),
                    )
                })
                .map_err(OptimizeError::Internal)?
        };
        let seconds = started.elapsed().as_secs_f64();
        self.say(format!(
            "  search: {} evaluations in {seconds:.1} s ({} resumed, {} outside the limits)",
            outcome.evaluations, outcome.replayed, outcome.infeasible,
        ));
        Ok(SearchStage {
            starts: starts.to_vec(),
            outcome,
            seconds,
        })
    }

    /// Stage 3: the candidates for the controller: the kinematic optimum (the search's best,
    /// or the paper's best when the search found nothing better: the paper's strokes are
    /// members of the family), each start's elites, and the paper's best of each kind.
    fn candidates(&self, paper: &PaperStage, searched: &SearchStage) -> Vec<Candidate> {
        let (problem, moves) = (&self.setup.problem, self.setup.encoding.moves);
        let optimum = match searched.outcome.by_start.first() {
            Some(b)
                if b.evaluation.feasible() && b.evaluation.value >= paper.best.evaluation.value =>
            {
                Candidate {
                    label: format!("optimised ({})", b.start.label),
                    chain: b.chain.clone(),
                    kinematic: b.evaluation.clone(),
                    paper: None,
                }
            }
            _ => Candidate::paper(&paper.best, moves),
        };
        let mut pool = vec![optimum];
        // The given strokes, as they are: when one keeps these limits, the answer is at least
        // as good (a wider search never answers below the narrower one that gave it).
        for (i, c) in self.request.start_from.iter().enumerate() {
            let chain = c.clone().padded_to(moves);
            let kinematic = problem.evaluate(&chain);
            if let Some(why) = &kinematic.violation {
                self.say(format!(
                    "  given stroke {} starts the search but is not a candidate: it breaks this \
                     search's limits ({why})",
                    i + 1
                ));
                continue;
            }
            if kinematic.value > pool[0].kinematic.value {
                pool.insert(
                    0,
                    Candidate {
                        label: format!("given stroke {}", i + 1),
                        chain,
                        kinematic,
                        paper: None,
                    },
                );
            } else {
                pool.push(Candidate {
                    label: format!("given stroke {}", i + 1),
                    chain,
                    kinematic,
                    paper: None,
                });
            }
        }
        for e in &searched.outcome.elites {
            let kinematic = problem.evaluate(&e.chain);
            if kinematic.feasible() {
                pool.push(Candidate {
                    label: format!("optimised ({})", searched.starts[e.start].label),
                    chain: e.chain.clone(),
                    kinematic,
                    paper: None,
                });
            }
        }
        for kind in ["single", "stutter", "delayed"] {
            let mut of_kind: Vec<&SweptPoint> = paper
                .sweep
                .points
                .iter()
                .filter(|p| p.stroke.kind == kind && p.evaluation.feasible())
                .collect();
            of_kind.sort_by(|x, y| y.evaluation.value.total_cmp(&x.evaluation.value));
            pool.extend(
                of_kind
                    .into_iter()
                    .take(self.request.paper_candidates)
                    .map(|p| Candidate::paper(p, moves)),
            );
        }
        pool
    }

    /// The ranking of `pool`, before any run: through sil whenever the request verifies through
    /// any link (sil runs the controller core pil and the F407 run, at thousands of runs a
    /// second, so the candidates rank and the answer refines there; pil and the F407 then run
    /// the answer), through none without. Ranking through pil or the F407 instead refined
    /// nothing, and an F407 that could not run left the ranking on the kinematic model without
    /// a word.
    fn rank(&self, pool: Vec<Candidate>) -> Ranking {
        let link = (!self.request.verify.is_empty()).then_some(LinkArg::Sil);
        Ranking {
            ranked: vec![None; pool.len()],
            values: vec![None; pool.len()],
            pool,
            link,
            refine_runs: 0,
            paper_refine_runs: 0,
        }
    }

    /// Stage 4: every candidate through the ranking link, on every bed (a stroke the
    /// controller cannot follow is worth nothing): the nominal bed's runs and the worst values.
    #[allow(clippy::type_complexity)]
    fn runs_through(
        &self,
        ranking: &Ranking,
    ) -> Result<(Vec<Option<LinkRun>>, Vec<Option<f64>>), OptimizeError> {
        let (pool, problem) = (&ranking.pool, &self.setup.problem);
        let Some(link) = &ranking.link else {
            return Ok((vec![None; pool.len()], vec![None; pool.len()]));
        };
        self.say(format!(
            "  re-ranking {} candidates (the search's best, the paper's best) through {link}{}",
            pool.len(),
            if problem.beds.is_empty() {
                String::new()
            } else {
                format!(" on {} beds", 1 + problem.beds.len())
            }
        ));
        let at = Position::start(self.progress, "runs through the controller", pool.len());
        let done = AtomicU64::new(0);
        let runs = self
            .pool
            .install(|| {
                use rayon::prelude::*;
                pool.par_iter()
                    .map(|c| {
                        if self.progress.cancelled() {
                            return Ok((None, None));
                        }
                        let r = through_sil_on_beds(problem, &c.chain, &self.request.firmware);
                        at.at(done.fetch_add(1, Ordering::Relaxed) as usize + 1);
                        r.map(|(run, value)| (Some(run), value))
                    })
                    .collect::<Result<Vec<_>, _>>()
            })
            .map_err(OptimizeError::Internal)?;
        Ok(runs.into_iter().unzip())
    }

    /// Stage 5: the best stroke through the controller refined there (sil only), and the
    /// paper's best through the controller refined there with the same budget, over the
    /// paper's own parameters (amplitude, frequency, delay): the two are compared on equal
    /// terms.
    fn refine(
        &self,
        ranking: &mut Ranking,
        checkpoint: &mut Checkpoint,
    ) -> Result<(), OptimizeError> {
        let (r, s) = (self.request, &self.setup);
        if ranking.link != Some(LinkArg::Sil) || r.refine == 0 {
            return Ok(());
        }
        let from = ranking.best(false);
        let label = ranking.pool[from].label.clone();
        let space = RefineSpace::family(&s.encoding, &ranking.pool[from].chain);
        let (refined, run, value) = self.refine_in(&space, &label, checkpoint)?;
        ranking.refine_runs = refined.evaluations;
        ranking.pool.push(Candidate {
            label: format!("refined through sil from {label}"),
            kinematic: s.problem.evaluate(&refined.chain),
            chain: refined.chain,
            paper: None,
        });
        ranking.ranked.push(Some(run));
        ranking.values.push(value);
        self.go_on("in the refinement")?;
        let from = ranking.best(true);
        let Some(stroke) = ranking.pool[from].paper else {
            return Ok(());
        };
        let label = ranking.pool[from].label.clone();
        let Some(paper) = PaperSpace::of(stroke.kind, &self.grid()) else {
            return Ok(());
        };
        let moves = s.encoding.moves;
        let space = RefineSpace {
            x0: paper.encode(&stroke),
            decode: Box::new(|x| paper.stroke(x).chain(moves)),
            salt: PAPER_REFINE_SALT,
        };
        let (refined, run, value) =
            match self.refine_in(&space, &format!("the paper's {label}"), checkpoint) {
                Ok(r) => r,
                Err(OptimizeError::Internal(e)) if !e.starts_with(crate::search::INTERRUPTED) => {
                    self.say(format!(
                        "warning: the paper's best was not refined through sil ({e}): it is \
                         compared as the sweep found it"
                    ));
                    return Ok(());
                }
                Err(e) => return Err(e),
            };
        ranking.paper_refine_runs = refined.evaluations;
        let stroke = paper.stroke(&refined.point);
        ranking.pool.push(Candidate {
            label: format!("{}, refined through sil", stroke.describe()),
            kinematic: s.problem.evaluate(&refined.chain),
            chain: refined.chain,
            paper: Some(stroke),
        });
        ranking.ranked.push(Some(run));
        ranking.values.push(value);
        Ok(())
    }

    /// One refinement through sil over `space` (`r.refine` runs), its best's run on the
    /// nominal bed and its worst value over the beds.
    fn refine_in(
        &self,
        space: &RefineSpace<'_>,
        label: &str,
        checkpoint: &mut Checkpoint,
    ) -> Result<(Refined, LinkRun, Option<f64>), OptimizeError> {
        let (r, s) = (self.request, &self.setup);
        self.say(format!(
            "  refining {label} through sil ({} runs)",
            r.refine
        ));
        let refined = {
            let at = Position::start(self.progress, "runs through sil", r.refine);
            self.pool
                .install(|| {
                    refine(
                        &s.problem,
                        space,
                        &RefineSettings {
                            evaluations: r.refine,
                            population: 12,
                            sigma: 0.02,
                            seed: s.settings.seed,
                        },
                        Some(checkpoint),
                        &r.firmware,
                        &|n, _, _| at.at(n),
                    )
                })
                .map_err(OptimizeError::Internal)?
        };
        let (run, value) = through_sil_on_beds(&s.problem, &refined.chain, &r.firmware)
            .map_err(OptimizeError::Internal)?;
        Ok((refined, run, value))
    }

    /// Stage 6: the answer and the paper's best (and the kinematic model's best, when the
    /// controller made another stroke the answer) through every link asked.
    fn verify(
        &self,
        ranking: &Ranking,
        board: &dyn StrokeOnBoard,
    ) -> Result<Verified, OptimizeError> {
        let (answer_i, paper_i) = (ranking.best(false), ranking.best(true));
        let result = |i: usize| {
            self.go_on("in the verification")?;
            self.result(ranking, i, board)
        };
        let answer = result(answer_i)?;
        let paper_answer = result(paper_i)?;
        let pool = &ranking.pool;
        let kinematic_optimum = if answer_i == 0 || pool[0].chain == pool[paper_i].chain {
            None
        } else {
            Some(result(0)?)
        };
        let basis = ranking.basis();
        if let Some(link) = ranking.link.as_ref().filter(|_| basis == "kinematic") {
            self.say(format!(
                "warning: no candidate kept its limits through {link} (every run faulted or \
                 stopped): the answer and its heights are the kinematic model's"
            ));
        }
        for run in [&answer, &paper_answer]
            .into_iter()
            .flat_map(|r| &r.links)
            .filter_map(|l| l.skipped.as_ref().map(|why| (&l.link, why)))
        {
            self.say(format!("warning: --verify {}: not run: {}", run.0, run.1));
        }
        let verified = Verified {
            answer_i,
            paper_i,
            answer,
            paper_answer,
            kinematic_optimum,
            basis,
        };
        self.say(format!(
            "  answer: {} ({:.2} mm on {})",
            verified.answer.label,
            1e3 * verified.height_on(&verified.answer),
            verified.basis
        ));
        Ok(verified)
    }

    /// Candidate `i` of `ranking` as a result stroke: its table's jump, its ranking run and
    /// its runs through the other links.
    fn result(
        &self,
        ranking: &Ranking,
        i: usize,
        board: &dyn StrokeOnBoard,
    ) -> Result<ResultStroke, OptimizeError> {
        let (problem, r) = (&self.setup.problem, self.request);
        let c = &ranking.pool[i];
        let table = problem.table(&c.chain);
        let table_jump = table_jump(problem, &c.chain).map_err(OptimizeError::Internal)?;
        let mut links: Vec<LinkRun> = ranking.ranked[i].iter().cloned().collect();
        for link in r
            .verify
            .iter()
            .filter(|l| Some(*l) != ranking.link.as_ref())
        {
            links.push(if *link == LinkArg::F407 {
                board.replay(r, &table)
            } else {
                run_through(link, &problem.params, problem.model, &table, &r.firmware)
                    .map_err(OptimizeError::Internal)?
            });
        }
        Ok(ResultStroke {
            label: c.label.clone(),
            chain: Some(c.chain.clone()),
            controller_value: ranking.controller_value(i),
            kinematic: c.kinematic.clone(),
            table_jump_height_m: table_jump.jump_height_m,
            links,
        })
    }

    /// The kinematic jump of `chain` with its time series, for the figure.
    fn series(&self, chain: &MoveChain) -> Result<Vec<SeriesRow>, OptimizeError> {
        let problem = &self.setup.problem;
        let opts = SimOptions {
            record_series: true,
            ..problem.opts.clone()
        };
        simulate_stroke(&problem.params, problem.model, chain.stroke(), &opts)
            .map(|o| o.series)
            .map_err(|e| OptimizeError::Internal(format!("cannot record the jump: {e}")))
    }

    /// The answer against the paper's measured regime and the model's alternative rules,
    /// the paper's regime being its swept strokes' at the robot's own amplitude (the
    /// paper's 18.75 mm; the grid's nearest amplitude): their fastest landing.
    fn validity(
        &self,
        paper: &PaperStage,
        answer: &MoveChain,
        paper_chain: &MoveChain,
    ) -> Result<Validity, OptimizeError> {
        let robot_a = self.setup.problem.params.robot.stroke_amplitude_m;
        let regime: Vec<&Evaluation> = paper.at_amplitude(robot_a).map(|p| &p.evaluation).collect();
        let fastest = regime
            .iter()
            .map(|e| e.max_touchdown_speed_m_s)
            .fold(0.0, f64::max);
        let soonest = regime
            .iter()
            .filter_map(|e| e.earliest_push_after_landing_s)
            .min_by(f64::total_cmp);
        Validity::assess(
            &self.setup.problem,
            answer,
            paper_chain,
            fastest,
            soonest,
            &table_jump,
        )
        .map_err(OptimizeError::Internal)
    }

    /// The answer and the paper's best on every bed, kinematic and (`sil`) through sil, the
    /// beds in order of their packing fraction.
    fn beds(
        &self,
        answer: &MoveChain,
        paper: &MoveChain,
        sil: bool,
    ) -> Result<Vec<BedRow>, OptimizeError> {
        let (p, firmware) = (&self.setup.problem, &self.request.firmware);
        let through = |params: &Params, chain: &MoveChain| -> Result<f64, OptimizeError> {
            if !sil {
                return Ok(f64::NAN);
            }
            let run = run_through(&LinkArg::Sil, params, p.model, &p.table(chain), firmware)
                .map_err(OptimizeError::Internal)?;
            Ok(run
                .value(p.objective, &p.limits, p.released_energy_j(chain))
                .unwrap_or(f64::NAN))
        };
        let mut rows = Vec::new();
        for params in p.all_beds() {
            rows.push(BedRow {
                phi: params.sand.packing_fraction,
                answer_kinematic_value: p.evaluate_on(params, answer).value,
                answer_sil_value: through(params, answer)?,
                paper_kinematic_value: p.evaluate_on(params, paper).value,
                paper_sil_value: through(params, paper)?,
            });
        }
        rows.sort_by(|a, b| a.phi.total_cmp(&b.phi));
        Ok(rows)
    }

    /// Stage 7: the outcome: the candidates in their order through the controller, the
    /// answer's and the paper's tables and jumps, the counts and the times.
    fn outcome(
        &self,
        paper: PaperStage,
        searched: SearchStage,
        ranking: Ranking,
        verified: Verified,
        started: Instant,
    ) -> Result<OptimizeOutcome, OptimizeError> {
        let s = &self.setup;
        let answer_chain = &ranking.pool[verified.answer_i].chain;
        let paper_chain = &ranking.pool[verified.paper_i].chain;
        let answer_series = self.series(answer_chain)?;
        let paper_series = self.series(paper_chain)?;
        let validity = self.validity(&paper, answer_chain, paper_chain)?;
        let beds = self.beds(answer_chain, paper_chain, ranking.link.is_some())?;
        let over_beds = OverBeds::of(&beds, verified.basis != "kinematic");
        let search = &searched.outcome;
        let fresh = paper.sweep.points.len() + search.evaluations - search.replayed;
        let (h, hp) = (
            verified.height_on(&verified.answer),
            verified.height_on(&verified.paper_answer),
        );
        let (v, vp) = (
            verified.value_on(&verified.answer),
            verified.value_on(&verified.paper_answer),
        );
        Ok(OptimizeOutcome {
            best_height_m: h,
            best_paper_stroke_height_m: hp,
            height_ratio: h / hp,
            height_basis: verified.basis.clone(),
            objective: s.problem.objective.name(),
            objective_unit: s.problem.objective.unit(),
            best_value: v,
            best_paper_value: vp,
            value_ratio: v / vp,
            model: s.problem.model.as_str(),
            phi: s.problem.params.sand.packing_fraction,
            stroke: s.problem.table(answer_chain),
            paper_stroke: s.problem.table(paper_chain),
            candidates: ranking.rows(),
            answer: verified.answer,
            paper_answer: verified.paper_answer,
            kinematic_optimum: verified.kinematic_optimum,
            paper_best_by_kind: paper
                .sweep
                .best_by_kind
                .iter()
                .map(|p| KindBest {
                    stroke: p.stroke.describe(),
                    kinematic_value: p.evaluation.value,
                    kinematic_height_m: p.evaluation.jump_height_m,
                })
                .collect(),
            candidates_ranked: ranking.pool.len(),
            refine_runs: ranking.refine_runs,
            paper_refine_runs: ranking.paper_refine_runs,
            paper_sweep_points: paper.sweep.points.len(),
            paper_sweep_feasible: paper.feasible,
            evaluations: search.evaluations,
            evaluations_resumed: search.replayed,
            evaluations_infeasible: search.infeasible,
            evaluations_per_s: fresh as f64 / (paper.seconds + searched.seconds),
            threads: self.threads,
            wall_time_s: started.elapsed().as_secs_f64(),
            limits: s.problem.limits,
            encoding: s.encoding,
            search: s.settings.clone(),
            params: s.problem.params.clone(),
            paper_sweep: paper.sweep.points,
            restart_agreement: RestartAgreement::of(&searched.outcome.restarts),
            validity,
            beds,
            over_beds,
            restarts: searched.outcome.restarts,
            history: searched.outcome.history,
            answer_series,
            paper_series,
            dir: PathBuf::new(),
        })
    }
}

impl Ranking {
    /// Candidate `i`'s objective value through the ranking link, the worst over the beds
    /// (None: not run, faulted).
    fn controller_value(&self, i: usize) -> Option<f64> {
        self.values[i]
    }

    /// The best candidate by its value through the controller, among the paper's strokes
    /// only with `paper_only`; by the kinematic value when no run gave one (no link, or
    /// every run faulted).
    fn best(&self, paper_only: bool) -> usize {
        let eligible = |i: &usize| !paper_only || self.pool[*i].paper.is_some();
        let by_controller = (0..self.pool.len())
            .filter(eligible)
            .filter_map(|i| self.controller_value(i).map(|v| (i, v)))
            .fold(None::<(usize, f64)>, |best, (i, v)| match best {
                Some((_, bv)) if bv >= v => best,
                _ => Some((i, v)),
            });
        match by_controller {
            Some((i, _)) => i,
            None => (0..self.pool.len())
                .filter(eligible)
                .fold(None::<usize>, |best, i| match best {
                    Some(b) if self.pool[b].kinematic.value >= self.pool[i].kinematic.value => {
                        Some(b)
                    }
                    _ => Some(i),
                })
                .unwrap_or(0),
        }
    }

    /// What the heights and values are measured on: the ranking link when any run through
    /// it gave a value, else `kinematic`.
    fn basis(&self) -> String {
        match &self.link {
            Some(l) if (0..self.pool.len()).any(|i| self.controller_value(i).is_some()) => {
                l.to_string()
            }
            _ => "kinematic".to_string(),
        }
    }

    /// candidates.csv: best through the controller first, then by the kinematic value.
    fn rows(&self) -> Vec<CandidateRow> {
        let mut order: Vec<usize> = (0..self.pool.len()).collect();
        let key = |i: usize| self.controller_value(i).unwrap_or(f64::NEG_INFINITY);
        order.sort_by(|&x, &y| {
            key(y).total_cmp(&key(x)).then(
                self.pool[y]
                    .kinematic
                    .value
                    .total_cmp(&self.pool[x].kinematic.value),
            )
        });
        order
            .iter()
            .enumerate()
            .map(|(rank, &i)| {
                let (c, run) = (&self.pool[i], self.ranked[i].as_ref());
                CandidateRow {
                    rank: rank + 1,
                    label: c.label.clone(),
                    controller_value: self.controller_value(i).unwrap_or(f64::NAN),
                    controller_height_m: run.and_then(|r| r.jump_height_m).unwrap_or(f64::NAN),
                    controller_faults: run.map(|r| r.faults.join(" ")).unwrap_or_default(),
                    kinematic_value: c.kinematic.value,
                    kinematic_height_m: c.kinematic.jump_height_m,
                    kinematic_final_height_m: c.kinematic.final_jump_height_m,
                    kinematic_com_rise_m: c.kinematic.com_rise_m,
                    model_peak_force_n: c.kinematic.model_peak_force_n,
                    table_peak_force_n: c.kinematic.table_peak_force_n,
                    peak_power_w: c.kinematic.peak_power_w,
                    work_j: c.kinematic.work_j,
                    duration_s: c.kinematic.duration_s,
                    stroke: chain_text(&c.chain),
                }
            })
            .collect()
    }
}

impl Verified {
    /// A result's jump height on the basis, m (NaN when its ranking run gave none).
    fn height_on(&self, r: &ResultStroke) -> f64 {
        if self.basis == "kinematic" {
            r.kinematic.jump_height_m
        } else {
            r.links
                .first()
                .and_then(|l| l.jump_height_m)
                .unwrap_or(f64::NAN)
        }
    }

    /// A result's objective value on the basis.
    fn value_on(&self, r: &ResultStroke) -> f64 {
        if self.basis == "kinematic" {
            r.kinematic.value
        } else {
            r.controller_value.unwrap_or(f64::NAN)
        }
    }
}

/// Salt of the paper's best's refinement (its coordinates are not the family's).
const PAPER_REFINE_SALT: u64 = 0x9A9E_0000_9A9E_0000;

/// The kinematic jump of `chain`'s stroke table on `problem` (what `jump --stroke` runs).
fn table_jump(problem: &Problem, chain: &MoveChain) -> Result<JumpSummary, String> {
    let stroke = problem.table(chain).kinematic_stroke()?;
    simulate_stroke(&problem.params, problem.model, stroke, &problem.opts)
        .map(|o| o.summary)
        .map_err(|e| format!("the stroke table's jump failed: {e}"))
}

/// The settings a checkpoint must agree on, as JSON.
fn checkpoint_settings(s: &Setup, starts: &[Start]) -> Result<String, OptimizeError> {
    let start_bits: Vec<Vec<String>> = starts
        .iter()
        .map(|s| {
            s.x.iter()
                .map(|v| format!("{:016x}", v.to_bits()))
                .collect()
        })
        .collect();
    let p = &s.problem;
    serde_json::to_string(&serde_json::json!({
        "objective": p.objective.name(),
        "model": p.model.as_str(),
        "params": p.params.to_toml(),
        "beds": p.beds.iter().map(|b| b.to_toml()).collect::<Vec<_>>(),
        "rtol": p.opts.rtol,
        "limits": p.limits,
        "encoding": s.encoding,
        "search": s.settings,
        "starts": start_bits,
    }))
    .map_err(|e| OptimizeError::Internal(format!("cannot encode the checkpoint's settings: {e}")))
}
