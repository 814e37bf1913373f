//! The search: CMA-ES (the `cmaes` crate) over the family's encoding, from several starts
//! (the best paper stroke of each kind, then random points), candidates evaluated in parallel
//! (rayon), every evaluation recorded in the [`Checkpoint`].
//!
//! Determinism: each start's CMA-ES has its own seed (`seed + start`), draws the same
//! candidates when told the same values, and is told values that depend on the candidate
//! alone (the kinematic jump is deterministic), whatever the number of threads. The starts
//! run one after another. So a fixed seed gives the same answer, and a resumed search the
//! same answer as one never interrupted.

use std::sync::Mutex;

use cmaes::{CMAESOptions, DVector};
use serde::Serialize;

use crate::checkpoint::{Checkpoint, point_key};
use crate::evaluate::{Evaluation, Problem};
use crate::family::{MoveChain, reflect};

/// How the search runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SearchSettings {
    /// Base seed.
    pub seed: u64,
    /// Evaluations in all, shared evenly by the starts.
    pub evaluations: usize,
    /// Candidates per generation.
    pub population: usize,
    /// Random starts after the paper strokes' starts.
    pub random_starts: usize,
    /// Initial step size from a paper stroke, in the encoding's unit coordinates.
    pub sigma_paper: f64,
    /// Initial step size from a random start.
    pub sigma_random: f64,
    /// Best distinct feasible candidates kept per start for the controller's re-ranking.
    pub elites_per_start: usize,
}

impl SearchSettings {
    /// Evaluations a search from `starts` starts makes in all: the budget shared evenly (at
    /// least one generation per start).
    pub fn budget(&self, starts: usize) -> usize {
        (self.evaluations / starts.max(1)).max(self.population) * starts
    }
}

/// Where a search started.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Start {
    /// What the start is (`best delayed stutter`, `random 2`).
    pub label: String,
    /// Coordinates in the encoding's space.
    #[serde(skip)]
    pub x: Vec<f64>,
    /// Initial step size.
    pub sigma: f64,
}

/// One generation, for the convergence record.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HistoryRow {
    /// Start index.
    pub start: usize,
    /// Restart of that start (0: its first run).
    pub restart: usize,
    /// Generation within the start.
    pub generation: usize,
    /// Evaluations so far, all starts.
    pub evaluations: usize,
    /// Best objective value of this generation (NaN when none was feasible).
    pub generation_best: f64,
    /// Best objective value so far, all starts.
    pub best_so_far: f64,
    /// The step size after the generation.
    pub sigma: f64,
}

/// One CMA-ES run of a start: its first (restart 0) or a restart with a larger population.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RestartRow {
    /// Start index.
    pub start: usize,
    /// Restart (0: the start's first run).
    pub restart: usize,
    /// Candidates per generation.
    pub population: usize,
    /// Evaluations it made.
    pub evaluations: usize,
    /// Its best objective value (NaN when none was feasible).
    pub best_value: f64,
    /// Why CMA-ES stopped.
    pub stopped_because: String,
}

/// A point uniform in the unit cube of `dim` coordinates, from `seed` alone (SplitMix64).
pub fn uniform_point(seed: u64, dim: usize) -> Vec<f64> {
    let mut state = seed ^ 0x5EED_5EED_5EED_5EED;
    (0..dim)
        .map(|_| {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// Added to a start's seed for each restart, so no two runs share a sampler.
const RESTART_SEED_STEP: u64 = 0x9E37_79B9_7F4A_7C15;

/// The best candidate of one start.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StartBest {
    /// The start.
    pub start: Start,
    /// Its best chain.
    pub chain: MoveChain,
    /// Its evaluation.
    pub evaluation: Evaluation,
    /// Why the start's CMA-ES stopped.
    pub stopped_because: String,
}

/// Progress after a generation.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Evaluations so far.
    pub evaluations: usize,
    /// Of this many.
    pub budget: usize,
    /// Best value so far.
    pub best: f64,
}

/// A good candidate kept for re-ranking through the controller.
#[derive(Clone, Debug, PartialEq)]
pub struct Elite {
    /// Index of its start.
    pub start: usize,
    /// The candidate.
    pub chain: MoveChain,
    /// Its fitness (minus the objective's value).
    pub fitness: f64,
}

/// What a search found.
#[derive(Clone, Debug)]
pub struct SearchOutcome {
    /// Each start's best, best first.
    pub by_start: Vec<StartBest>,
    /// Each start's best feasible candidates (at most `elites_per_start`, best first, start
    /// by start; a candidate is distinct when its point is), for the controller's re-ranking.
    pub elites: Vec<Elite>,
    /// One row per generation.
    pub history: Vec<HistoryRow>,
    /// One row per CMA-ES run: each start's first and its restarts.
    pub restarts: Vec<RestartRow>,
    /// Evaluations done (simulated or read from the checkpoint).
    pub evaluations: usize,
    /// Of which read from the checkpoint.
    pub replayed: usize,
    /// Candidates outside the limits (their fitness was the penalty).
    pub infeasible: usize,
}

/// Two candidates closer than this in every unit coordinate (after reflection into
/// `[0, 1]`) count as one for the re-ranking: the controller's runs should see different
/// strokes, not one converged stroke sixteen times.
pub const ELITE_SEPARATION: f64 = 0.02;

/// The best `n` of `pool` (fitness, key, point), each at least [`ELITE_SEPARATION`] from every
/// better one kept, best first; ties broken by key so the threads' order does not matter.
fn diverse_best(mut pool: Vec<(f64, u64, Vec<f64>)>, n: usize) -> Vec<(f64, u64, Vec<f64>)> {
    pool.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut kept: Vec<(f64, u64, Vec<f64>)> = Vec::with_capacity(n);
    for c in pool {
        if kept.len() == n {
            break;
        }
        let far = kept.iter().all(|k| {
            k.2.iter()
                .zip(&c.2)
                .any(|(a, b)| (reflect(*a) - reflect(*b)).abs() >= ELITE_SEPARATION)
        });
        if far {
            kept.push(c);
        }
    }
    kept
}

/// The start of the error of a search its caller stopped (Ctrl-C).
pub const INTERRUPTED: &str = "interrupted";

/// Run the search over the space `decode` maps to chains (the family's
/// [`Encoding`](crate::family::Encoding), or a smaller one such as the paper's strokes), from
/// `starts`
/// (`progress` is told after each generation and returns false to stop the search).
pub fn search(
    problem: &Problem,
    decode: &(dyn Fn(&[f64]) -> MoveChain + Sync),
    starts: &[Start],
    settings: &SearchSettings,
    checkpoint: Option<&mut Checkpoint>,
    progress: &(dyn Fn(Progress) -> bool + Sync),
) -> Result<SearchOutcome, String> {
    if starts.is_empty() {
        return Err("no start for the search".into());
    }
    let budget = settings.budget(starts.len());
    let per_start = budget / starts.len();
    let mut history = Vec::new();
    let mut by_start = Vec::new();
    let (mut evaluations, mut replayed, mut infeasible) = (0usize, 0usize, 0usize);
    let mut best_so_far = f64::NEG_INFINITY;
    let checkpoint = Mutex::new(checkpoint);
    let mut elites = Vec::new();
    let mut restarts = Vec::new();
    for (i, start) in starts.iter().enumerate() {
        let fitness = |x: &[f64]| problem.evaluate(&decode(x)).fitness();
        // IPOP (Auger & Hansen 2005): once CMA-ES stops by its own criteria (converged) or
        // stalls (no gain over its window) with budget left, it starts again from a random
        // point of the space with twice the population, until the start's budget is spent; a
        // run that stops at the budget ends the start. The first run starts from the start's
        // point.
        let (mut left, mut population) = (per_start, settings.population);
        let mut best: Option<(f64, Vec<f64>)> = None;
        let mut reasons = Vec::new();
        for restart in 0.. {
            if left < population {
                break;
            }
            let mut used = 0usize;
            let seed = settings
                .seed
                .wrapping_add(i as u64)
                .wrapping_add((restart as u64).wrapping_mul(RESTART_SEED_STEP));
            let (x0, sigma) = if restart == 0 {
                (start.x.clone(), start.sigma)
            } else {
                (uniform_point(seed, start.x.len()), settings.sigma_random)
            };
            let run = cma_run(
                &CmaSpec {
                    x0: &x0,
                    sigma,
                    seed,
                    population,
                    // Whole generations: CMA-ES ends on the generation that reaches its budget.
                    budget: left - left % population,
                    elites: settings.elites_per_start,
                    salt: 0,
                    stall_generations: Some(stall_window(start.x.len(), population)),
                },
                &fitness,
                &checkpoint,
                &mut |g: &Generation| {
                    used += g.evaluations;
                    evaluations += g.evaluations;
                    replayed += g.replayed;
                    infeasible += g.infeasible;
                    if g.best_value > best_so_far {
                        best_so_far = g.best_value;
                    }
                    history.push(HistoryRow {
                        start: i,
                        restart,
                        generation: g.generation,
                        evaluations,
                        generation_best: g.best_value,
                        best_so_far,
                        sigma: g.sigma,
                    });
                    progress(Progress {
                        evaluations,
                        budget,
                        best: best_so_far,
                    })
                },
            )?;
            elites.extend(run.pool.into_iter().map(|(fitness, _, x)| Elite {
                start: i,
                chain: decode(&x),
                fitness,
            }));
            let run_best = run.best.ok_or_else(|| {
                format!(
                    "start {} restart {restart}: CMA-ES stopped with no candidate",
                    start.label
                )
            })?;
            restarts.push(RestartRow {
                start: i,
                restart,
                population,
                evaluations: used,
                best_value: if run_best.0 < crate::evaluate::INFEASIBLE_FITNESS {
                    -run_best.0
                } else {
                    f64::NAN
                },
                stopped_because: run.stopped_because.clone(),
            });
            reasons.push(run.stopped_because);
            if best.as_ref().is_none_or(|b| run_best.0 < b.0) {
                best = Some(run_best);
            }
            left = left.saturating_sub(used);
            if run.spent || used == 0 {
                break;
            }
            population = population.saturating_mul(2);
        }
        let (_, point) =
            best.ok_or_else(|| format!("start {}: no CMA-ES run fitted its budget", start.label))?;
        let chain = decode(&point);
        let evaluation = problem.evaluate(&chain);
        by_start.push(StartBest {
            start: start.clone(),
            chain,
            evaluation,
            stopped_because: reasons.join("; then "),
        });
    }
    by_start.sort_by(|a, b| a.evaluation.fitness().total_cmp(&b.evaluation.fitness()));
    Ok(SearchOutcome {
        by_start,
        elites,
        history,
        restarts,
        evaluations,
        replayed,
        infeasible,
    })
}

/// One CMA-ES run's settings.
pub(crate) struct CmaSpec<'a> {
    /// Initial mean, in the encoding's coordinates.
    pub x0: &'a [f64],
    /// Initial step size.
    pub sigma: f64,
    /// Seed of its sampler.
    pub seed: u64,
    /// Candidates per generation.
    pub population: usize,
    /// Evaluations at most.
    pub budget: usize,
    /// Best distinct feasible candidates to keep.
    pub elites: usize,
    /// Mixed into the checkpoint's keys, so runs of different objectives do not share values.
    pub salt: u64,
    /// Stop once the run's best has not improved by more than [`STALL_TOLERANCE`] for this
    /// many generations (None: CMA-ES's own criteria only).
    pub stall_generations: Option<usize>,
}

/// A run stalls when its best improves by no more than this (relative to the best, and at
/// least 1 um on heights in metres) over its stall window: on a rugged landscape (a foot that
/// turns static or not, a hop that lands or not) CMA-ES's own history criterion never
/// fires, since each generation's best keeps jumping, and a run would spend the whole budget
/// in one basin.
pub const STALL_TOLERANCE: f64 = 1e-3;

/// The stall window of a run of `dim` coordinates and population `lambda`: Hansen's
/// `10 + 30 n / lambda` generations (his TolHistFun window), at least 10.
pub fn stall_window(dim: usize, lambda: usize) -> usize {
    10 + (30 * dim).div_ceil(lambda.max(1))
}

/// What one generation did.
pub(crate) struct Generation {
    /// Its number, from 1.
    pub generation: usize,
    /// Candidates evaluated.
    pub evaluations: usize,
    /// Of which read from the checkpoint.
    pub replayed: usize,
    /// Of which outside the limits.
    pub infeasible: usize,
    /// The generation's best objective value (NaN when none was feasible).
    pub best_value: f64,
    /// The step size after it.
    pub sigma: f64,
}

/// What one CMA-ES run found.
pub(crate) struct CmaRun {
    /// Its best (fitness, point), if it evaluated any candidate.
    pub best: Option<(f64, Vec<f64>)>,
    /// Why it stopped, in words (CMA-ES's reasons, or `Stagnated`).
    pub stopped_because: String,
    /// Whether it stopped at its evaluation budget.
    pub spent: bool,
    /// Its best distinct feasible candidates (fitness, key, point), best first.
    pub pool: Vec<(f64, u64, Vec<f64>)>,
}

/// Run CMA-ES on `fitness` (minimised; feasible below
/// [`INFEASIBLE_FITNESS`](crate::evaluate::INFEASIBLE_FITNESS)), candidates in parallel on the
/// current rayon pool, values read from and appended to the checkpoint, `on_generation` told
/// after each generation (it returns false to stop the run: the generation's values are in the
/// checkpoint, and the run ends as an error starting with [`INTERRUPTED`]).
pub(crate) fn cma_run(
    spec: &CmaSpec<'_>,
    fitness: &(dyn Fn(&[f64]) -> f64 + Sync),
    checkpoint: &Mutex<Option<&mut Checkpoint>>,
    on_generation: &mut dyn FnMut(&Generation) -> bool,
) -> Result<CmaRun, String> {
    use crate::evaluate::INFEASIBLE_FITNESS;
    // Values computed this generation, to append to the checkpoint.
    let fresh: Mutex<Vec<(u64, f64)>> = Mutex::new(Vec::new());
    // Every feasible candidate of this generation: (fitness, key, point).
    let seen: Mutex<Vec<(f64, u64, Vec<f64>)>> = Mutex::new(Vec::new());
    let counts = Mutex::new((0usize, 0usize, 0usize));
    let objective = |x: &DVector<f64>| -> f64 {
        let key = point_key(x.as_slice()) ^ spec.salt;
        let recorded = checkpoint
            .lock()
            .ok()
            .and_then(|c| c.as_ref().and_then(|c| c.recorded(key)));
        let (value, from_checkpoint) = match recorded {
            Some(v) => (v, true),
            None => (fitness(x.as_slice()), false),
        };
        if let Ok(mut c) = counts.lock() {
            c.0 += 1;
            c.1 += usize::from(from_checkpoint);
            c.2 += usize::from(value >= INFEASIBLE_FITNESS);
        }
        if !from_checkpoint && let Ok(mut f) = fresh.lock() {
            f.push((key, value));
        }
        if value < INFEASIBLE_FITNESS
            && let Ok(mut s) = seen.lock()
        {
            s.push((value, key, x.as_slice().to_vec()));
        }
        value
    };
    let mut cmaes = CMAESOptions::new(spec.x0.to_vec(), spec.sigma)
        .population_size(spec.population)
        .seed(spec.seed)
        .max_function_evals(spec.budget)
        .tol_fun(1e-12)
        // Converged: the best fitness moved less than 0.1 um (heights are metres) over the
        // last 10 + 30 n / lambda generations, or the steps shrank below 1e-7 of the unit
        // coordinates. The start then restarts with a larger population (IPOP, `search`).
        .tol_fun_hist(1e-7)
        .tol_x(1e-7)
        .build(&objective)
        .map_err(|e| format!("cannot set up CMA-ES: {e:?}"))?;
    let mut pool: Vec<(f64, u64, Vec<f64>)> = Vec::new();
    let mut generation = 0;
    // The run's best at each generation, for the stall check.
    let mut bests: Vec<f64> = Vec::new();
    let stopped_because = loop {
        let done = cmaes.next_parallel();
        generation += 1;
        let new: Vec<(u64, f64)> = fresh
            .lock()
            .map(|mut f| std::mem::take(&mut *f))
            .unwrap_or_default();
        let (evaluations, replayed, infeasible) = counts
            .lock()
            .map(|mut c| std::mem::take(&mut *c))
            .unwrap_or_default();
        // Merged in a fixed order (fitness, then key): the threads' order does not matter.
        let mut generation_seen = seen
            .lock()
            .map(|mut s| std::mem::take(&mut *s))
            .unwrap_or_default();
        pool.append(&mut generation_seen);
        pool = diverse_best(pool, spec.elites);
        let best = cmaes
            .current_best_individual()
            .map_or(f64::NAN, |b| b.value);
        let go_on = on_generation(&Generation {
            generation,
            evaluations,
            replayed,
            infeasible,
            best_value: if best < INFEASIBLE_FITNESS {
                -best
            } else {
                f64::NAN
            },
            sigma: cmaes.sigma(),
        });
        if !new.is_empty()
            && let Ok(mut c) = checkpoint.lock()
            && let Some(c) = c.as_deref_mut()
        {
            c.append(&new)?;
        }
        if !go_on {
            return Err(format!(
                "{INTERRUPTED} after generation {generation}: the checkpoint resumes the search"
            ));
        }
        if let Some(t) = done {
            let spent = t
                .reasons
                .iter()
                .any(|r| matches!(r, cmaes::TerminationReason::MaxFunctionEvals));
            let reasons = t
                .reasons
                .iter()
                .map(|r| format!("{r:?}"))
                .collect::<Vec<_>>()
                .join(", ");
            break (reasons, spent);
        }
        bests.push(
            cmaes
                .overall_best_individual()
                .map_or(f64::INFINITY, |b| b.value),
        );
        if let Some(window) = spec.stall_generations
            && bests.len() > window
        {
            let (then, now) = (bests[bests.len() - 1 - window], bests[bests.len() - 1]);
            // Fitness is minus the value: an improvement lowers it.
            let tolerance = (STALL_TOLERANCE * now.abs()).max(1e-6);
            if now < INFEASIBLE_FITNESS && then - now <= tolerance {
                break ("Stagnated".to_string(), false);
            }
        }
    };
    let (stopped_because, spent) = stopped_because;
    let best = cmaes
        .overall_best_individual()
        .map(|b| (b.value, b.point.as_slice().to_vec()));
    Ok(CmaRun {
        best,
        stopped_because,
        spent,
        pool,
    })
}
