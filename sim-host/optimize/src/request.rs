//! What `optimize` is asked: [`OptimizeRequest`] (its `Default` is the command line's
//! defaults), its checks ([`OptimizeRequest::validate`], the command line's messages) and the
//! search it sets up ([`Setup`]).

use std::path::{Path, PathBuf};

use serde::Serialize;

use sandjumper_model::SimOptions;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::resolve::{ParamsFile, resolve_params};
use sandjumper_output::parse::number_within;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil::rig_model::RigModelConfig;
use sandjumper_rig::stroke_table::RigLimits;

use crate::error::OptimizeError;
use crate::evaluate::{Objective, Problem, SearchLimits};
use crate::family::{Encoding, MoveChain};
use crate::search::SearchSettings;

/// A stroke search: what to maximise, on which ground, within which limits, how hard to
/// search, which links verify the answer and where to write it.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizeRequest {
    /// What to maximise.
    pub objective: Objective,
    /// Ground model.
    pub model: ModelName,
    /// Robot, drive and sand (the `--phi` preset with any `--params` file applied); with
    /// `beds`, the nominal bed (the figure's jumps, the F407 and pil runs are on it).
    pub params: Params,
    /// Other beds the stroke must jump on, for a packing fraction known only to a range
    /// (`--phi-range`): with any, the search maximises the worst case over `params` and these,
    /// through the kinematic model and through the controller, and reports the mean. The
    /// beds differ from `params` in their sand only.
    pub beds: Vec<Params>,
    /// Relative tolerance of the Dormand-Prince 5(4) integrator (1e-14 <= rtol < 1).
    pub rtol: f64,
    /// Largest |p| a stroke may reach, m (0 < X <= 0.025, the rig's stroke).
    pub max_stroke_m: f64,
    /// Longest stroke, s (start to the end of its last move; at most what the replay buffer
    /// holds at `table_rate_hz`).
    pub max_duration_s: f64,
    /// Samples per second of the stroke table, Hz (10..=10000; divides the 10 kHz control
    /// rate).
    pub table_rate_hz: u32,
    /// Least jump height of a stroke for the ratio objectives, m (0 < X <= 1).
    pub min_height_m: f64,
    /// Most the spring may be compressed below its free length, m (`None`: the free length
    /// itself, `robot.spring_rest_length_m`: a spring cannot be shorter than nothing; a
    /// coil-bind length from the spring's data sheet is tighter).
    pub max_spring_compression_m: Option<f64>,
    /// Highest the rod may rise above its rest, m (0 < X <= 10): the rig's frame above the bed.
    /// No document of the rig gives it; 1 m is a stated default, not a measurement.
    pub max_rise_m: f64,
    /// Moves per stroke (2..=8; the paper's strokes have 2).
    pub moves: usize,
    /// Longest hold between moves, s (0 < X <= 5).
    pub max_hold_s: f64,
    /// Evaluations of the search in all, shared by its starts (100..=10,000,000).
    pub evaluations: usize,
    /// Candidates per CMA-ES generation (4..=1000).
    pub population: usize,
    /// Random starts after the three paper strokes' starts (0..=100).
    pub random_starts: usize,
    /// Seed of the search (the same seed, the same answer).
    pub seed: u64,
    /// Strokes the search also starts from, after the paper's best of each kind (e.g. a search's
    /// answer under narrower limits, `--start-from DIR`). Each is also a candidate for the
    /// answer when it keeps this search's limits, so wider limits never answer lower than the
    /// narrower search that gave it. At most `moves` moves each.
    pub start_from: Vec<MoveChain>,
    /// Step of the paper strokes' frequency sweep (1..25 Hz), Hz (0 < X <= 5).
    pub sweep_freq_step_hz: f64,
    /// Step of the delayed stutter's delay in the sweep, s (0 < X <= 1).
    pub sweep_tau_step_s: f64,
    /// Links the best strokes are re-run through, force-driven: `Sil` (candidates are
    /// re-ranked through it, or through the first link without it), `Pil`, `F407`; empty:
    /// none, the answer is the kinematic model's.
    pub verify: Vec<LinkArg>,
    /// Candidates of each start re-ranked through the controller (1..=1000).
    pub elites: usize,
    /// Runs through sil refining the best re-ranked stroke, and as many refining the paper's
    /// best over its own amplitude, frequency and delay (0..=100,000; 0: none).
    pub refine: usize,
    /// Paper strokes of each kind re-ranked through the controller (1..=1000).
    pub paper_candidates: usize,
    /// Firmware ELF for the `Pil` link (built with `--features board-qemu`).
    pub firmware: PathBuf,
    /// Worker threads (1..=1024; `None`: one per core).
    pub threads: Option<usize>,
    /// Output folder. The search's checkpoint lives beside it ([`checkpoint_path`]) until
    /// the run finishes: the same request again resumes it.
    pub out: PathBuf,
}

impl Default for OptimizeRequest {
    /// The command line's defaults; `out` is empty (the command line requires `--out`).
    fn default() -> Self {
        Self {
            objective: Objective::Height,
            model: ModelName::Eq4,
            params: Params::preset(0.57).expect("0.57 is a preset packing fraction"),
            beds: Vec::new(),
            rtol: 1e-8,
            max_stroke_m: 0.025,
            max_duration_s: 2.0,
            table_rate_hz: 1000,
            min_height_m: 0.02,
            max_spring_compression_m: None,
            max_rise_m: 1.0,
            moves: 4,
            max_hold_s: 0.5,
            evaluations: 192_000,
            population: 24,
            random_starts: 9,
            seed: 1,
            start_from: Vec::new(),
            sweep_freq_step_hz: 0.1,
            sweep_tau_step_s: 0.01,
            verify: vec![LinkArg::Sil, LinkArg::Pil, LinkArg::F407],
            elites: 16,
            refine: 600,
            paper_candidates: 8,
            firmware: PathBuf::from(sandjumper_rig::firmware_image::EMULATED_ELF),
            threads: None,
            out: PathBuf::new(),
        }
    }
}

/// The search a request sets up: the problem every candidate is evaluated on, the family's
/// encoding and the CMA-ES settings.
#[derive(Clone, Debug)]
pub struct Setup {
    /// Robot, ground, limits, objective.
    pub problem: Problem,
    /// The family searched (its bounds).
    pub encoding: Encoding,
    /// How the search runs.
    pub settings: SearchSettings,
}

/// The checkpoint's path for the output folder `out`: `DIR.checkpoint` beside it.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".checkpoint");
    out.with_file_name(name)
}

/// The lock of the checkpoint for `out` (`DIR.checkpoint.lock` beside it): held by the one
/// search that writes the checkpoint.
pub fn checkpoint_lock_path(out: &Path) -> PathBuf {
    let mut path = checkpoint_path(out).into_os_string();
    path.push(".lock");
    PathBuf::from(path)
}

/// `v` within `lo < v <= hi` (in `unit`), or the command line's refusal of `flag`.
fn within(flag: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), OptimizeError> {
    if v.is_finite() && v > lo && v <= hi {
        Ok(())
    } else {
        Err(OptimizeError::Invalid(out_of_range(flag, v, lo, hi, unit)))
    }
}

/// `v` within `lo..=hi`, or a refusal naming `flag`.
fn counted(flag: &str, v: usize, lo: usize, hi: usize) -> Result<(), OptimizeError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(OptimizeError::Invalid(format!(
            "{flag} {v} out of range (allowed: {lo}..={hi})"
        )))
    }
}

/// A value parser for a number `what` (a flag's name, e.g. `--max-stroke`) with `lo < X <=
/// hi` in `unit`; the refusal names the flag, the value and the range.
pub fn ranged(
    what: &'static str,
    lo: f64,
    hi: f64,
    unit: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        number_within(s, |v| v > lo && v <= hi).ok_or_else(|| out_of_range(what, s, lo, hi, unit))
    }
}

/// The refusal of `shown` (a value of `flag`) outside `lo < X <= hi` in `unit`.
fn out_of_range(flag: &str, shown: impl std::fmt::Display, lo: f64, hi: f64, unit: &str) -> String {
    format!("{flag} `{shown}` out of range (allowed: {lo} < X <= {hi} {unit})")
}

/// A packing fraction known to a range: `--phi-range A:B` (A < B, both within the presets'
/// 0.57..=0.62 unless a params file gives the sand), sampled at `points` evenly spaced
/// packing fractions, ends included.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhiRange {
    /// Lowest packing fraction.
    pub lo: f64,
    /// Highest packing fraction.
    pub hi: f64,
    /// Beds sampled, ends included (2..=21).
    pub points: usize,
}

impl PhiRange {
    /// The packing fractions sampled, lowest first.
    pub fn phis(&self) -> Vec<f64> {
        let n = self.points.max(2);
        (0..n)
            .map(|i| self.lo + (self.hi - self.lo) * i as f64 / (n - 1) as f64)
            .collect()
    }

    /// The nominal bed's packing fraction: the sample nearest the middle of the range.
    pub fn nominal(&self) -> f64 {
        let phis = self.phis();
        phis[(phis.len() - 1) / 2]
    }

    /// The nominal bed and the other beds ([`OptimizeRequest::params`] and
    /// [`OptimizeRequest::beds`]): each sample's preset with `file` applied.
    pub fn beds(&self, file: Option<&ParamsFile>) -> Result<(Params, Vec<Params>), OptimizeError> {
        let resolve = |phi: f64| {
            resolve_params(phi, file)
                .map_err(|e| OptimizeError::Invalid(format!("--phi-range, the bed at {phi}: {e}")))
        };
        let nominal = self.nominal();
        let others = self
            .phis()
            .into_iter()
            .filter(|&p| p != nominal)
            .map(resolve)
            .collect::<Result<_, _>>()?;
        Ok((resolve(nominal)?, others))
    }
}

/// `A:B` (two packing fractions, A < B) as the ends of a [`PhiRange`] of `points` beds. Not the
/// sweep's `A:B:STEP` grammar: a range here is one uncertain bed, not a grid of runs.
pub fn parse_phi_range(s: &str, points: usize) -> Result<PhiRange, String> {
    let allowed = "allowed: A:B with 0 < A < B < 1, e.g. 0.57:0.62";
    let mut parts = s.split(':');
    let (Some(a), Some(b), None) = (parts.next(), parts.next(), parts.next()) else {
        return Err(format!(
            "--phi-range `{s}` is not two packing fractions A:B ({allowed})"
        ));
    };
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0 && *v < 1.0)
    };
    match (num(a), num(b)) {
        (Some(lo), Some(hi)) if lo < hi => {
            if !(2..=21).contains(&points) {
                return Err(format!(
                    "--phi-points {points} out of range (allowed: 2..=21)"
                ));
            }
            Ok(PhiRange { lo, hi, points })
        }
        _ => Err(format!(
            "--phi-range `{s}`: not two packing fractions with A < B ({allowed})"
        )),
    }
}

/// The refusal of a link `--verify` does not take.
fn not_verifiable(link: impl std::fmt::Display) -> String {
    format!(
        "link `{link}` not allowed in --verify (allowed: sil, pil, f407, a comma-separated list \
         of them, or none)"
    )
}

/// The links of [`OptimizeRequest::verify`] from their names: `sil`, `pil`, `f407`, a
/// comma-separated list of them, or `none` (no link).
pub fn parse_verify(s: &str) -> Result<Vec<LinkArg>, String> {
    if s.trim() == "none" {
        return Ok(Vec::new());
    }
    s.split(',')
        .map(|l| match l.trim() {
            "sil" => Ok(LinkArg::Sil),
            "pil" => Ok(LinkArg::Pil),
            "f407" => Ok(LinkArg::F407),
            other => Err(not_verifiable(other)),
        })
        .collect()
}

impl OptimizeRequest {
    /// Check every field: the ranges the command line's parsers hold, then the limits that
    /// depend on each other (the messages the command line gives after parsing).
    pub fn validate(&self) -> Result<(), OptimizeError> {
        self.setup().map(|_| ())
    }

    /// The ranges of the command line's value parsers (a Rust caller has none).
    fn check_ranges(&self) -> Result<(), OptimizeError> {
        if self.out.as_os_str().is_empty() {
            return Err(OptimizeError::Invalid(
                "no output folder given (--out DIR)".into(),
            ));
        }
        if !(1e-14..1.0).contains(&self.rtol) {
            return Err(OptimizeError::Invalid(format!(
                "rtol {} out of range (allowed: 1e-14 <= rtol < 1)",
                self.rtol
            )));
        }
        within("--max-stroke", self.max_stroke_m, 0.0, 0.025, "m")?;
        within("--max-duration", self.max_duration_s, 0.0, 409.5, "s")?;
        within("--min-height", self.min_height_m, 0.0, 1.0, "m")?;
        within("--max-rise", self.max_rise_m, 0.0, 10.0, "m")?;
        if let Some(c) = self.max_spring_compression_m {
            within(
                "--max-spring-compression",
                c,
                0.0,
                self.params.robot.spring_rest_length_m,
                "m (at most the spring's free length)",
            )?;
        }
        within("--max-hold", self.max_hold_s, 0.0, 5.0, "s")?;
        within("--sweep-freq-step", self.sweep_freq_step_hz, 0.0, 5.0, "Hz")?;
        within("--sweep-tau-step", self.sweep_tau_step_s, 0.0, 1.0, "s")?;
        counted("--table-rate", self.table_rate_hz as usize, 10, 10_000)?;
        counted("--moves", self.moves, 2, 8)?;
        counted("--evaluations", self.evaluations, 100, 10_000_000)?;
        counted("--population", self.population, 4, 1000)?;
        counted("--random-starts", self.random_starts, 0, 100)?;
        counted("--elites", self.elites, 1, 1000)?;
        counted("--refine", self.refine, 0, 100_000)?;
        counted("--paper-candidates", self.paper_candidates, 1, 1000)?;
        if let Some(t) = self.threads {
            counted("--threads", t, 1, 1024)?;
        }
        for (i, c) in self.start_from.iter().enumerate() {
            let bad = c.moves.len() > self.moves
                || !c.start_m.is_finite()
                || c.moves.iter().any(|m| {
                    !(m.to_m.is_finite()
                        && m.duration_s.is_finite()
                        && m.duration_s > 0.0
                        && m.hold_s.is_finite()
                        && m.hold_s >= 0.0)
                });
            if bad {
                return Err(OptimizeError::Invalid(format!(
                    "start stroke {} ({} moves): not a chain this search can start from \
                     (allowed: at most --moves {} moves, finite positions, durations > 0, holds \
                     >= 0)",
                    i + 1,
                    c.moves.len(),
                    self.moves
                )));
            }
        }
        if let Some(l) = self.verify.iter().find(|l| matches!(l, LinkArg::Serial(_))) {
            return Err(OptimizeError::Invalid(not_verifiable(l)));
        }
        Ok(())
    }

    /// The limits a candidate must keep and the largest acceleration the drive allows
    /// (m/s²), checked against each other.
    fn limits(&self) -> Result<(SearchLimits, f64), OptimizeError> {
        let rig = RigLimits {
            stroke_m: self.max_stroke_m,
            ..RigLimits::of(&self.params)
        };
        let tick_hz = RigModelConfig::default().tick_hz;
        if !tick_hz.is_multiple_of(self.table_rate_hz) {
            return Err(OptimizeError::Invalid(format!(
                "--table-rate {} Hz does not divide the {tick_hz} Hz control rate (allowed: e.g. \
                 500, 1000, 2000, 5000)",
                self.table_rate_hz
            )));
        }
        let buffer_s = rig.max_duration_s(self.table_rate_hz);
        if self.max_duration_s > buffer_s {
            return Err(OptimizeError::Invalid(format!(
                "--max-duration {} s is longer than the replay buffer holds at {} samples/s \
                 ({buffer_s:.3} s; allowed: up to that, or lower --table-rate)",
                self.max_duration_s, self.table_rate_hz
            )));
        }
        let (lo, hi) = rig.accel_range_m_s2();
        let max_accel = hi.min(-lo);
        if max_accel <= 0.0 {
            return Err(OptimizeError::Invalid(format!(
                "the drive's peak force {} N cannot hold the motor ({} kg) against gravity",
                self.params.drive.peak_force_n, self.params.robot.motor_mass_kg
            )));
        }
        let limits = SearchLimits {
            rig,
            table_rate_hz: self.table_rate_hz,
            max_duration_s: self.max_duration_s,
            min_height_m: self.min_height_m,
            max_spring_compression_m: self
                .max_spring_compression_m
                .unwrap_or(self.params.robot.spring_rest_length_m),
            max_rise_m: self.max_rise_m,
        };
        Ok((limits, max_accel))
    }

    /// The search this request sets up, checked as [`validate`](Self::validate) checks it.
    pub fn setup(&self) -> Result<Setup, OptimizeError> {
        self.check_ranges()?;
        self.params
            .validate()
            .map_err(|e| OptimizeError::Invalid(format!("parameters: {e}")))?;
        for bed in &self.beds {
            bed.validate().map_err(|e| {
                OptimizeError::Invalid(format!(
                    "parameters of the bed at phi {}: {e}",
                    bed.sand.packing_fraction
                ))
            })?;
            if bed.robot != self.params.robot
                || bed.drive != self.params.drive
                || bed.model != self.params.model
            {
                return Err(OptimizeError::Invalid(format!(
                    "the bed at phi {} has another robot or drive than the nominal bed (allowed: \
                     beds that differ in their sand only)",
                    bed.sand.packing_fraction
                )));
            }
        }
        let (limits, max_accel) = self.limits()?;
        let encoding = Encoding {
            moves: self.moves,
            stroke_m: self.max_stroke_m,
            max_accel_m_s2: max_accel,
            min_move_s: 4.0 / f64::from(self.table_rate_hz),
            // The longest move: the slowest half period of the sweep (1 Hz), whatever the
            // moves and the duration limit (checked on every candidate).
            max_move_s: 0.5,
            max_hold_s: self.max_hold_s,
        };
        let problem = Problem {
            params: self.params.clone(),
            beds: self.beds.clone(),
            model: self.model,
            limits,
            objective: self.objective,
            opts: SimOptions {
                rtol: self.rtol,
                ..SimOptions::default()
            },
        };
        let settings = SearchSettings {
            seed: self.seed,
            evaluations: self.evaluations,
            population: self.population,
            random_starts: self.random_starts,
            sigma_paper: 0.1,
            sigma_random: 0.3,
            elites_per_start: self.elites,
        };
        Ok(Setup {
            problem,
            encoding,
            settings,
        })
    }
}
