//! The sweeps behind the height figures: jump height against forcing frequency for every
//! kind, model and packing fraction, the optimum of each line, and the delay sweep.

use sandjumper_core::trajectory::JumpKind;
use serde::Serialize;

use super::{FiguresError, FiguresOptions};
use crate::sweep::drive;
use crate::sweep::{Combination, SweepDrive, SweepOutcome, SweepRow};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::trajectory::kind_name;

/// Delay of the delayed stutter in the height-vs-phi figure (the paper's), s.
pub const DELAYED_TAU_S: f64 = 0.75;
/// Packing fraction of the single-phi figures (the paper's loosest packing).
pub const LOW_PHI: f64 = 0.57;
/// Packing fraction the hard-ground runs take their robot parameters from (no sand used).
const HARD_PHI: f64 = LOW_PHI;

/// Grids of the sweeps.
#[derive(Clone, Debug, PartialEq)]
pub struct Grids {
    /// Forcing frequencies, Hz.
    pub freqs_hz: Vec<f64>,
    /// Packing fractions.
    pub phis: Vec<f64>,
    /// Delays of the delay sweep, s.
    pub taus_s: Vec<f64>,
}

fn steps(a: f64, b: f64, step: f64) -> Vec<f64> {
    let n = ((b - a) / step).round() as usize;
    (0..=n)
        .map(|i| a + step * i as f64)
        .map(|x| (x * 1e9).round() / 1e9)
        .collect()
}

impl Grids {
    /// The full set: 1..=20 Hz by 0.1 Hz, phi 0.57..=0.62 by 0.0025, tau 0..=0.75 s by 10 ms.
    pub fn full() -> Self {
        Self {
            freqs_hz: steps(1.0, 20.0, 0.1),
            phis: steps(0.57, 0.62, 0.0025),
            taus_s: steps(0.0, 0.75, 0.01),
        }
    }

    /// `--quick`: 1..=20 Hz by 0.5 Hz, phi by 0.01, tau by 0.125 s.
    pub fn quick() -> Self {
        Self {
            freqs_hz: steps(1.0, 20.0, 0.5),
            phis: steps(0.57, 0.62, 0.01),
            taus_s: steps(0.0, 0.75, 0.125),
        }
    }
}

/// The parameters of a combination: the preset of its phi (hard ground: the phi = 0.57 robot).
pub fn params_for(model: ModelName, phi: f64) -> Result<Params, String> {
    Params::preset(if model == ModelName::Hard {
        HARD_PHI
    } else {
        phi
    })
    .map_err(|e| e.to_string())
}

/// Simulate every combination in parallel (calling `opts.on_jump` after each), kinematically.
pub fn run(
    combos: &[Combination],
    opts: &FiguresOptions<'_>,
) -> Result<SweepOutcome, FiguresError> {
    run_driven(combos, opts, SweepDrive::Kinematic)
}

/// [`run`] with every jump driven by `drive`; the rows name the drive.
pub fn run_driven(
    combos: &[Combination],
    opts: &FiguresOptions<'_>,
    drive: SweepDrive,
) -> Result<SweepOutcome, FiguresError> {
    drive::run_driven(combos, opts.threads, opts.on_jump, drive, opts.rtol, |c| {
        params_for(c.model, c.phi)
    })
    .map_err(FiguresError::Internal)
}

/// The delayed stutter against its delay at phi = 0.57 on eq4 only (the SIL delay curve).
pub fn tau_combinations_eq4(grids: &Grids) -> Vec<Combination> {
    tau_combinations(grids)
        .into_iter()
        .filter(|c| c.model == ModelName::Eq4)
        .collect()
}

/// Gain-lowering factor of the SIL delay curve (`HilSpec::gain_lowering_factor`): the
/// position gain times 0.05 during the delay damps the spring's ringing ~10x.
pub const SIL_GAIN_LOWERING: f64 = 0.05;

/// Kinds of the height-vs-phi figure, with their delays.
pub const KINDS: [(JumpKind, f64); 3] = [
    (JumpKind::Single, 0.0),
    (JumpKind::Stutter, 0.0),
    (JumpKind::DelayedStutter, DELAYED_TAU_S),
];

/// Combinations of the height-vs-phi (and height-vs-frequency) figures: every kind, eq1 and
/// eq4 at every phi, and hard ground, at every frequency.
pub fn phi_combinations(grids: &Grids) -> Vec<Combination> {
    let mut out = Vec::new();
    for (kind, tau_s) in KINDS {
        for model in [ModelName::Eq1, ModelName::Eq4] {
            for &phi in &grids.phis {
                for &freq_hz in &grids.freqs_hz {
                    out.push(Combination {
                        kind,
                        model,
                        phi,
                        freq_hz,
                        tau_s,
                    });
                }
            }
        }
        for &freq_hz in &grids.freqs_hz {
            out.push(Combination {
                kind,
                model: ModelName::Hard,
                phi: HARD_PHI,
                freq_hz,
                tau_s,
            });
        }
    }
    out
}

/// Combinations of the delay figure: delayed stutters at [`LOW_PHI`], eq1 and eq4, every
/// delay and frequency.
pub fn tau_combinations(grids: &Grids) -> Vec<Combination> {
    let mut out = Vec::new();
    for model in [ModelName::Eq1, ModelName::Eq4] {
        for &tau_s in &grids.taus_s {
            for &freq_hz in &grids.freqs_hz {
                out.push(Combination {
                    kind: JumpKind::DelayedStutter,
                    model,
                    phi: LOW_PHI,
                    freq_hz,
                    tau_s,
                });
            }
        }
    }
    out
}

/// The best forcing frequency of one (kind, model, phi, tau) line.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BestRow {
    /// `single`, `stutter` or `delayed`.
    pub kind: String,
    /// Ground model.
    pub model: String,
    /// Packing fraction (hard ground: empty).
    pub phi: Option<f64>,
    /// Delay, s.
    pub tau_s: f64,
    /// Frequency of the highest jump on the grid, Hz.
    pub best_freq_hz: f64,
    /// Its jump height, m.
    pub jump_height_m: f64,
    /// Its final (push-off) height, m.
    pub final_jump_height_m: f64,
    /// Highest final (push-off) height over the frequency grid, m (its own optimum).
    pub best_final_jump_height_m: f64,
    /// Frequency of that highest final height, Hz.
    pub best_final_freq_hz: f64,
    /// Deepest foot depth at the best frequency, m.
    pub max_depth_m: f64,
}

/// Header of the best-row CSV (written even when empty).
pub const BEST_HEADER: [&str; 10] = [
    "kind",
    "model",
    "phi",
    "tau_s",
    "best_freq_hz",
    "jump_height_m",
    "final_jump_height_m",
    "best_final_jump_height_m",
    "best_final_freq_hz",
    "max_depth_m",
];

/// The optimum over frequency of every (kind, model, phi, tau) line of `rows`, in order of
/// first appearance.
pub fn best_rows(rows: &[SweepRow]) -> Vec<BestRow> {
    let mut out: Vec<BestRow> = Vec::new();
    for r in rows {
        let phi = (r.model != ModelName::Hard.as_str()).then_some(r.phi);
        let same = |b: &BestRow| {
            b.kind == r.kind && b.model == r.model && b.phi == phi && b.tau_s == r.tau_s
        };
        match out.iter_mut().find(|b| same(b)) {
            Some(b) => {
                if r.jump_height_m > b.jump_height_m {
                    b.best_freq_hz = r.freq_hz;
                    b.jump_height_m = r.jump_height_m;
                    b.final_jump_height_m = r.final_jump_height_m;
                    b.max_depth_m = r.max_depth_m;
                }
                if r.final_jump_height_m > b.best_final_jump_height_m {
                    b.best_final_jump_height_m = r.final_jump_height_m;
                    b.best_final_freq_hz = r.freq_hz;
                }
            }
            None => out.push(BestRow {
                kind: r.kind.clone(),
                model: r.model.clone(),
                phi,
                tau_s: r.tau_s,
                best_freq_hz: r.freq_hz,
                jump_height_m: r.jump_height_m,
                final_jump_height_m: r.final_jump_height_m,
                best_final_jump_height_m: r.final_jump_height_m,
                best_final_freq_hz: r.freq_hz,
                max_depth_m: r.max_depth_m,
            }),
        }
    }
    out
}

/// The best row of `kind` under `model` at `phi` (`None` for hard ground) and delay `tau_s`.
pub fn find_best(
    best: &[BestRow],
    kind: JumpKind,
    model: ModelName,
    phi: Option<f64>,
) -> Option<&BestRow> {
    let tau = if kind == JumpKind::DelayedStutter {
        DELAYED_TAU_S
    } else {
        0.0
    };
    best.iter().find(|b| {
        b.kind == kind_name(kind)
            && b.model == model.as_str()
            && b.tau_s == tau
            && match (b.phi, phi) {
                (Some(a), Some(b)) => (a - b).abs() < 1e-9,
                (None, None) => true,
                _ => false,
            }
    })
}
