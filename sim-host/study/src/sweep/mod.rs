//! Parameter sweeps: every combination of jump kind, model, packing fraction, delay and
//! forcing frequency, run in parallel, in a deterministic order, optionally one shard of it.
//!
//! - [`range`]: `A:B:STEP` ranges; [`shard`]: `--shard I/N` slices; [`mod@merge`]: joining shards;
//!   [`plot`]: height against frequency and delay; [`cluster`]: a sweep as a Slurm job array,
//!   merged ([`cluster::run_on_slurm`]).
//! - [`SweepSpec::combinations`] fixes the row order: kind, model, phi, tau, then frequency
//!   (innermost, so each height-vs-frequency line is contiguous). The delay only applies to
//!   the delayed stutter: other kinds run once with `tau_s = 0`.
//! - [`run_parallel`] runs a list of combinations on its own rayon pool and returns one row
//!   per success and one [`SweepFailure`] per failed jump, both in combination order.
//! - [`SweepMeta`] (`sweep.toml`) records the spec, its hash and the shard, so shards can be
//!   checked and merged, and a sweep reproduced from its folder alone.

pub mod cluster;
pub mod drive;
pub mod merge;
pub mod plot;
pub mod range;
mod request;
pub mod shard;

use std::path::Path;

use rayon::prelude::*;
use sandjumper_core::trajectory::JumpKind;
use serde::{Deserialize, Serialize};

pub use range::{
    RangeError, ValueRange, parse_freq_range, parse_phi_range, parse_range_checked, parse_tau_range,
};
pub use request::{
    MergeOutcome, MergeRequest, SweepRequest, SweepRunOutcome, WrittenSweep, merge,
    params_file_name, run,
};
use sandjumper_model::params::ModelName;
pub use shard::{ShardSpec, ShardSpecError, parse_shard};

use sandjumper_model::trajectory::kind_name;

/// One jump of a sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Combination {
    /// Which one-cycle sine.
    pub kind: JumpKind,
    /// Ground model.
    pub model: ModelName,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay of the delayed stutter, s (0 for the other kinds).
    pub tau_s: f64,
}

/// How each jump of a sweep is driven.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SweepDrive {
    /// The paper's method: the stroke `p(t)` imposed exactly (docs/model.md).
    Kinematic,
    /// Through the software-in-the-loop rig: the core's controller, the drive model with its
    /// 300 N limit, the encoder; with the position gain lowered by `gain_lowering` during the
    /// delay if given (`HilSpec::gain_lowering_factor`).
    Sil {
        /// The factor on kp (and ki) during a delayed stutter's delay.
        gain_lowering: Option<f64>,
    },
}

impl SweepDrive {
    /// The drive's name in `sweep.csv` and `sweep.toml`: `kinematic`, `sil` or
    /// `sil-gain-lowering-F`.
    pub fn name(&self) -> String {
        match self {
            Self::Kinematic => "kinematic".into(),
            Self::Sil {
                gain_lowering: None,
            } => "sil".into(),
            Self::Sil {
                gain_lowering: Some(f),
            } => format!("sil-gain-lowering-{f}"),
        }
    }

    /// The drive a name of [`SweepDrive::name`] stands for.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "kinematic" => Some(Self::Kinematic),
            "sil" => Some(Self::Sil {
                gain_lowering: None,
            }),
            _ => name
                .strip_prefix("sil-gain-lowering-")?
                .parse::<f64>()
                .ok()
                .map(|f| Self::Sil {
                    gain_lowering: Some(f),
                }),
        }
    }
}

fn kinematic() -> String {
    SweepDrive::Kinematic.name()
}

/// What to sweep. Values are used in the order given (the CLI gives them ascending).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    /// Jump kinds.
    pub kinds: Vec<JumpKind>,
    /// Ground models.
    pub models: Vec<ModelName>,
    /// Packing fractions.
    pub phis: Vec<f64>,
    /// Forcing frequencies, Hz.
    pub freqs_hz: Vec<f64>,
    /// Delays, s (used for the delayed stutter only).
    pub taus_s: Vec<f64>,
    /// Relative tolerance of the integrator.
    pub rtol: f64,
    /// How each jump is driven.
    pub drive: SweepDrive,
}

impl SweepSpec {
    /// How many combinations [`combinations`](Self::combinations) expands to, `None` past
    /// `usize` (a spec read from a damaged file): checked before anything is expanded.
    pub fn count(&self) -> Option<usize> {
        let delayed = self
            .kinds
            .iter()
            .filter(|&&k| k == JumpKind::DelayedStutter)
            .count();
        let per_freq =
            (self.kinds.len() - delayed).checked_add(delayed.checked_mul(self.taus_s.len())?)?;
        per_freq
            .checked_mul(self.models.len())?
            .checked_mul(self.phis.len())?
            .checked_mul(self.freqs_hz.len())
    }

    /// Every combination, in the deterministic sweep order (see the module docs).
    pub fn combinations(&self) -> Vec<Combination> {
        let mut out = Vec::new();
        for &kind in &self.kinds {
            for &model in &self.models {
                for &phi in &self.phis {
                    let taus: &[f64] = if kind == JumpKind::DelayedStutter {
                        &self.taus_s
                    } else {
                        &[0.0]
                    };
                    for &tau_s in taus {
                        for &freq_hz in &self.freqs_hz {
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
            }
        }
        out
    }

    /// A stable 64-bit hash (FNV-1a) of the spec and of `params_text` (the resolved
    /// parameters of every phi): shards of one sweep share it, shards of another do not.
    pub fn hash(&self, params_text: &str) -> String {
        let kinds: Vec<_> = self.kinds.iter().map(|&k| kind_name(k)).collect();
        let models: Vec<_> = self.models.iter().map(|m| m.as_str()).collect();
        let canonical = format!(
            "kinds={kinds:?};models={models:?};phi={:?};freq_hz={:?};tau_s={:?};rtol={:?};params={params_text}",
            self.phis, self.freqs_hz, self.taus_s, self.rtol
        );
        // Kinematic sweeps hash as before the drive existed.
        let canonical = match self.drive {
            SweepDrive::Kinematic => canonical,
            d => format!("{canonical};drive={}", d.name()),
        };
        format!("{:016x}", fnv1a64(canonical.as_bytes()))
    }
}

/// FNV-1a, 64 bit: tiny, stable across platforms and versions (unlike `DefaultHasher`).
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The measured quantities of one jump (SI).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JumpMetrics {
    /// Max rod height above rest, m.
    pub jump_height_m: f64,
    /// The same after the push-off half begins, m.
    pub final_jump_height_m: f64,
    /// Deepest foot depth, m.
    pub max_depth_m: f64,
    /// Largest added mass, kg.
    pub peak_added_mass_kg: f64,
    /// Largest motor force the trajectory implies, N.
    pub peak_motor_force_n: f64,
}

/// One row of `sweep.csv` (column order as declared).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRow {
    /// `single`, `stutter` or `delayed`.
    pub kind: String,
    /// Ground model name.
    pub model: String,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay, s.
    pub tau_s: f64,
    /// m.
    pub jump_height_m: f64,
    /// m.
    pub final_jump_height_m: f64,
    /// m.
    pub max_depth_m: f64,
    /// kg.
    pub peak_added_mass_kg: f64,
    /// N.
    pub peak_motor_force_n: f64,
    /// How the jump was driven ([`SweepDrive::name`]).
    #[serde(default = "kinematic")]
    pub drive: String,
}

/// One row of `failures.csv`: a jump of the sweep that could not be simulated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepFailure {
    /// `single`, `stutter` or `delayed`.
    pub kind: String,
    /// Ground model name.
    pub model: String,
    /// Packing fraction.
    pub phi: f64,
    /// Forcing frequency, Hz.
    pub freq_hz: f64,
    /// Delay, s.
    pub tau_s: f64,
    /// Why it failed.
    pub error: String,
}

impl SweepRow {
    /// The row for `c` with measured `m`.
    pub fn new(c: &Combination, m: &JumpMetrics) -> Self {
        Self {
            kind: kind_name(c.kind).into(),
            model: c.model.as_str().into(),
            phi: c.phi,
            freq_hz: c.freq_hz,
            tau_s: c.tau_s,
            jump_height_m: m.jump_height_m,
            final_jump_height_m: m.final_jump_height_m,
            max_depth_m: m.max_depth_m,
            peak_added_mass_kg: m.peak_added_mass_kg,
            peak_motor_force_n: m.peak_motor_force_n,
            drive: kinematic(),
        }
    }
}

impl SweepFailure {
    /// The failure record for `c`.
    pub fn new(c: &Combination, error: String) -> Self {
        Self {
            kind: kind_name(c.kind).into(),
            model: c.model.as_str().into(),
            phi: c.phi,
            freq_hz: c.freq_hz,
            tau_s: c.tau_s,
            error,
        }
    }
}

/// Rows and failures of a (part of a) sweep, each in combination order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SweepOutcome {
    /// Successful jumps.
    pub rows: Vec<SweepRow>,
    /// Jumps that failed, with the reason.
    pub failures: Vec<SweepFailure>,
}

/// Run `jump` for every combination on a pool of `threads` threads (0: one per core), calling
/// `on_jump` after each (from any worker thread; e.g. a progress bar). The result is in
/// combination order whatever the scheduling.
pub fn run_parallel<F>(
    combos: &[Combination],
    threads: usize,
    on_jump: &(dyn Fn() + Sync),
    jump: F,
) -> Result<SweepOutcome, String>
where
    F: Fn(&Combination) -> Result<JumpMetrics, String> + Sync,
{
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| format!("cannot start {threads} worker threads: {e}"))?;
    let results: Vec<Result<JumpMetrics, String>> = pool.install(|| {
        combos
            .par_iter()
            .map(|c| {
                let r = jump(c);
                on_jump();
                r
            })
            .collect()
    });
    let mut out = SweepOutcome::default();
    for (c, r) in combos.iter().zip(results) {
        match r {
            Ok(m) => out.rows.push(SweepRow::new(c, &m)),
            Err(e) => out.failures.push(SweepFailure::new(c, e)),
        }
    }
    Ok(out)
}

/// Contents of `sweep.toml`: enough to check shards against each other and to rerun.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepMeta {
    /// File format tag, [`SweepMeta::FORMAT`].
    pub format: String,
    /// [`SweepSpec::hash`] of the whole sweep.
    pub spec_hash: String,
    /// Number of combinations of the whole sweep.
    pub total_combinations: usize,
    /// This directory's shard (`1/1` for a whole sweep).
    pub shard: ShardMeta,
    /// What was swept.
    pub spec: SpecMeta,
}

/// The shard part of [`SweepMeta`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardMeta {
    /// 1-based shard number.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
    /// First combination index (0-based) in this shard.
    pub first: usize,
    /// One past the last combination index in this shard.
    pub end: usize,
    /// Rows in `sweep.csv`.
    pub rows: usize,
    /// Rows in `failures.csv`.
    pub failures: usize,
}

/// The spec part of [`SweepMeta`], as written on the command line and expanded.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpecMeta {
    /// Jump kinds.
    pub kinds: Vec<String>,
    /// Ground models.
    pub models: Vec<String>,
    /// Packing fractions.
    pub phi: Vec<f64>,
    /// Forcing frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Delays, s.
    pub tau_s: Vec<f64>,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// The user's parameter file, if any (path as given).
    pub params_file: Option<String>,
    /// Its text (so the folder alone reproduces the sweep).
    pub params_overrides: Option<String>,
    /// How each jump was driven ([`SweepDrive::name`]).
    #[serde(default = "kinematic")]
    pub drive: String,
}

impl SweepMeta {
    /// Format tag of `sweep.toml`.
    pub const FORMAT: &'static str = "sandjumper-sweep/1";

    /// A `sweep.toml`'s text, of this format (errors without the file's name).
    pub fn parse(text: &str) -> Result<Self, String> {
        let meta: Self = toml::from_str(text).map_err(|e| e.to_string())?;
        if meta.format != Self::FORMAT {
            return Err(format!(
                "format `{}`; this sandjumper reads `{}`",
                meta.format,
                Self::FORMAT
            ));
        }
        Ok(meta)
    }
}

/// File names inside a sweep directory.
pub mod files {
    /// One row per successful jump.
    pub const ROWS: &str = "sweep.csv";
    /// One row per failed jump.
    pub const FAILURES: &str = "failures.csv";
    /// [`super::SweepMeta`].
    pub const META: &str = "sweep.toml";
}

pub use sandjumper_output::write_csv;

/// Header of `sweep.csv`.
pub const ROW_HEADER: [&str; 11] = [
    "kind",
    "model",
    "phi",
    "freq_hz",
    "tau_s",
    "jump_height_m",
    "final_jump_height_m",
    "max_depth_m",
    "peak_added_mass_kg",
    "peak_motor_force_n",
    "drive",
];

/// Header of `failures.csv`.
pub const FAILURE_HEADER: [&str; 6] = ["kind", "model", "phi", "freq_hz", "tau_s", "error"];

/// Read CSV records of type `T` from `path`; errors name the file and line.
pub fn read_csv<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<Vec<T>, String> {
    let mut r = csv::Reader::from_path(path)
        .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    r.deserialize()
        .map(|rec| rec.map_err(|e| format!("`{}`: {e}", path.display())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> SweepSpec {
        SweepSpec {
            kinds: vec![JumpKind::Single, JumpKind::DelayedStutter],
            models: vec![ModelName::Eq4],
            phis: vec![0.57, 0.6],
            freqs_hz: vec![5.0, 10.0, 15.0],
            taus_s: vec![0.0, 0.5],
            rtol: 1e-8,
            drive: SweepDrive::Kinematic,
        }
    }

    #[test]
    fn drive_names_round_trip_and_only_sil_changes_the_hash() {
        for d in [
            SweepDrive::Kinematic,
            SweepDrive::Sil {
                gain_lowering: None,
            },
            SweepDrive::Sil {
                gain_lowering: Some(0.05),
            },
        ] {
            assert_eq!(SweepDrive::parse(&d.name()), Some(d));
        }
        assert_eq!(SweepDrive::parse("pil"), None);
        let sil = SweepSpec {
            drive: SweepDrive::Sil {
                gain_lowering: None,
            },
            ..spec()
        };
        assert_ne!(sil.hash(""), spec().hash(""));
    }

    #[test]
    fn delay_multiplies_only_the_delayed_stutter() {
        let c = spec().combinations();
        // single: 2 phi x 3 f; delayed: 2 phi x 2 tau x 3 f.
        assert_eq!(c.len(), 6 + 12);
        assert!(
            c.iter()
                .filter(|c| c.kind == JumpKind::Single)
                .all(|c| c.tau_s == 0.0)
        );
        // Frequency is innermost.
        assert_eq!(c[0].freq_hz, 5.0);
        assert_eq!(c[1].freq_hz, 10.0);
        assert_eq!(c[2].phi, 0.57);
        assert_eq!(c[3].phi, 0.6);
    }

    #[test]
    fn hash_changes_with_any_part_of_the_spec() {
        let base = spec().hash("p");
        assert_eq!(base, spec().hash("p"));
        assert_ne!(base, spec().hash("q"));
        let mut s = spec();
        s.rtol = 1e-9;
        assert_ne!(base, s.hash("p"));
        let mut s = spec();
        s.freqs_hz.push(20.0);
        assert_ne!(base, s.hash("p"));
    }

    #[test]
    fn parallel_run_keeps_order_and_records_failures() {
        let combos = spec().combinations();
        let out = run_parallel(&combos, 2, &|| {}, |c| {
            if c.freq_hz == 15.0 {
                Err("boom".into())
            } else {
                Ok(JumpMetrics {
                    jump_height_m: c.freq_hz,
                    final_jump_height_m: 0.0,
                    max_depth_m: 0.0,
                    peak_added_mass_kg: 0.0,
                    peak_motor_force_n: 0.0,
                })
            }
        })
        .unwrap();
        assert_eq!(out.rows.len() + out.failures.len(), combos.len());
        assert_eq!(out.failures.len(), combos.len() / 3);
        let expected: Vec<_> = combos
            .iter()
            .filter(|c| c.freq_hz != 15.0)
            .map(|c| c.freq_hz)
            .collect();
        let got: Vec<_> = out.rows.iter().map(|r| r.jump_height_m).collect();
        assert_eq!(got, expected);
    }
}
