//! The answer refined through the controller: CMA-ES once more, from the best stroke of the
//! re-ranking, every candidate run force-driven through the core's controller in this
//! process (sil: the replay table uploaded and replayed in lockstep against the
//! force-driven plant). The kinematic model finds where the good strokes are; strokes that
//! ride a knife-edge of the model (a foot that just turns static, a stroke that grazes the
//! controller's stroke limit) fail through the controller, and this stage keeps only what
//! the controller makes of a stroke.
//!
//! A candidate must still keep every limit of the kinematic evaluation (the rig's check, the
//! model's motor force); one the controller faults on is infeasible. Values go into the same
//! checkpoint, their keys salted apart from the kinematic ones.

use std::path::Path;
use std::sync::Mutex;

use serde::Serialize;

use crate::checkpoint::Checkpoint;
use crate::evaluate::{INFEASIBLE_FITNESS, Problem};
use crate::family::{Encoding, MoveChain};
use crate::search::{CmaSpec, Generation, cma_run};
use crate::verify::through_sil_on_beds;

/// Salt of the refinement's checkpoint keys.
const REFINE_SALT: u64 = 0x5111_0000_5111_0000;

/// How the refinement runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RefineSettings {
    /// Runs through the controller at most.
    pub evaluations: usize,
    /// Candidates per generation.
    pub population: usize,
    /// Initial step size, unit coordinates.
    pub sigma: f64,
    /// Seed.
    pub seed: u64,
}

/// A map from a point of a space's coordinates to the chain it stands for.
pub type Decoder<'a> = Box<dyn Fn(&[f64]) -> MoveChain + Sync + 'a>;

/// What the refinement searches over: a point of its coordinates (reflected into range by
/// `decode`) and the chain it stands for.
pub struct RefineSpace<'a> {
    /// The point the refinement starts from.
    pub x0: Vec<f64>,
    /// The chain at a point.
    pub decode: Decoder<'a>,
    /// Mixed into the checkpoint's keys, so two spaces never share a value.
    pub salt: u64,
}

impl<'a> RefineSpace<'a> {
    /// The family's space, from `from`.
    pub fn family(encoding: &'a Encoding, from: &MoveChain) -> Self {
        Self {
            x0: encoding.encode(from),
            decode: Box::new(|x| encoding.decode(x)),
            salt: 0,
        }
    }
}

/// What the refinement found.
#[derive(Clone, Debug)]
pub struct Refined {
    /// The best stroke through the controller.
    pub chain: MoveChain,
    /// Its point in the refinement's space.
    pub point: Vec<f64>,
    /// Its value through the controller.
    pub value: f64,
    /// Runs made (or read back from the checkpoint).
    pub evaluations: usize,
    /// Of which read back.
    pub replayed: usize,
    /// Candidates outside the limits or faulted.
    pub infeasible: usize,
}

/// Refine through sil over `space`, from its `x0`. `firmware` is unused by sil (kept for the
/// link's opening).
pub fn refine(
    problem: &Problem,
    space: &RefineSpace<'_>,
    settings: &RefineSettings,
    checkpoint: Option<&mut Checkpoint>,
    firmware: &Path,
    progress: &(dyn Fn(usize, usize, f64) -> bool + Sync),
) -> Result<Refined, String> {
    let fitness = |x: &[f64]| -> f64 {
        let chain = (space.decode)(x);
        let kinematic = problem.evaluate(&chain);
        if !kinematic.feasible() {
            return kinematic.fitness();
        }
        match through_sil_on_beds(problem, &chain, firmware) {
            Ok((_, Some(v))) => -v,
            // Faulted (or below the least height) on a bed: the safe state is worth nothing.
            Ok((_, None)) => INFEASIBLE_FITNESS + 0.5,
            Err(_) => INFEASIBLE_FITNESS + 1.0,
        }
    };
    let checkpoint = Mutex::new(checkpoint);
    let (mut evaluations, mut replayed, mut infeasible) = (0, 0, 0);
    let mut best = f64::NEG_INFINITY;
    let run = cma_run(
        &CmaSpec {
            x0: &space.x0,
            sigma: settings.sigma,
            seed: settings.seed,
            population: settings.population,
            budget: settings.evaluations,
            elites: 1,
            salt: REFINE_SALT ^ space.salt,
            // One run on a small budget: it refines, it does not restart.
            stall_generations: None,
        },
        &fitness,
        &checkpoint,
        &mut |g: &Generation| {
            evaluations += g.evaluations;
            replayed += g.replayed;
            infeasible += g.infeasible;
            if g.best_value > best {
                best = g.best_value;
            }
            progress(evaluations, settings.evaluations, best)
        },
    )?;
    let (fitness, point) = match run.pool.first() {
        Some((f, _, x)) => (*f, x.clone()),
        None => {
            return Err(
                "no candidate of the refinement kept the limits through the controller".into(),
            );
        }
    };
    Ok(Refined {
        chain: (space.decode)(&point),
        point,
        value: -fitness,
        evaluations,
        replayed,
        infeasible,
    })
}
