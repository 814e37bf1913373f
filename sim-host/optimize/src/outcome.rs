//! What a search found ([`OptimizeOutcome`]): what `summary.json` holds (its serde form),
//! the human summary (its `Display`) and the folder it writes ([`OptimizeOutcome::write`]).

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use sandjumper_model::params::Params;
use sandjumper_model::record::SeriesRow;
use sandjumper_output::StagedDir;
use sandjumper_output::folder::write_csv;
use sandjumper_output::plot::save_figure;
use sandjumper_rig::stroke_table::StrokeTable;

use crate::error::OptimizeError;
use crate::evaluate::{Evaluation, SearchLimits};
use crate::family::{Encoding, MoveChain};
use crate::figure::{Shown, search_figure};
use crate::paper_sweep::SweptPoint;
use crate::search::{HistoryRow, RestartRow, SearchSettings};
use crate::validity::Validity;
use crate::verify::LinkRun;

/// A stroke of the result: its description, its kinematic evaluation and its runs through
/// the links.
#[derive(Clone, Debug, Serialize)]
pub struct ResultStroke {
    /// In words.
    pub label: String,
    /// The chain (start and moves): what `--start-from` reads back.
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

/// The best paper stroke of one kind in the kinematic sweep.
#[derive(Clone, Debug, Serialize)]
pub struct KindBest {
    /// In words.
    pub stroke: String,
    /// Objective value, kinematic.
    pub kinematic_value: f64,
    /// Jump height, kinematic, m.
    pub kinematic_height_m: f64,
}

/// One row of candidates.csv: a candidate re-ranked through the controller.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateRow {
    /// Rank through the controller (1: the answer).
    pub rank: usize,
    /// In words.
    pub label: String,
    /// The objective's value through the ranking link (NaN: not run, or it faulted).
    pub controller_value: f64,
    /// Jump height through the ranking link, m.
    pub controller_height_m: f64,
    /// Faults the controller latched, by name, space-separated.
    pub controller_faults: String,
    /// The objective's value, kinematic.
    pub kinematic_value: f64,
    /// Jump height, kinematic, m.
    pub kinematic_height_m: f64,
    /// Highest apex after the push-off begins, kinematic, m.
    pub kinematic_final_height_m: f64,
    /// Highest rise of the robot's centre of mass, kinematic, m.
    pub kinematic_com_rise_m: f64,
    /// Largest motor force of the kinematic run, N.
    pub model_peak_force_n: f64,
    /// The rig check's force estimate on the table, N.
    pub table_peak_force_n: f64,
    /// Largest |F_m p'|, W.
    pub peak_power_w: f64,
    /// Positive work of the motor, J.
    pub work_j: f64,
    /// Duration of the stroke, s.
    pub duration_s: f64,
    /// The chain in words ([`chain_text`]).
    pub stroke: String,
}

/// One row of paper_sweep.csv.
#[derive(Serialize)]
struct SweepRow<'a> {
    kind: &'static str,
    amplitude_m: f64,
    freq_hz: f64,
    tau_s: f64,
    feasible: bool,
    value: f64,
    jump_height_m: f64,
    final_jump_height_m: f64,
    com_rise_m: f64,
    model_peak_force_n: f64,
    table_peak_force_n: f64,
    violation: &'a str,
}

/// What a search found. Serialised (serde), it is `summary.json` and what `optimize --json`
/// prints; the fields marked `skip` are the rest of the folder.
#[derive(Clone, Debug, Serialize)]
pub struct OptimizeOutcome {
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
    /// Runs through sil refining the paper's best (the same budget, over the paper's
    /// amplitude, frequency and delay), before the two are compared.
    pub paper_refine_runs: usize,
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
    /// The answer's stroke table (stroke.csv), m at the table rate.
    #[serde(skip)]
    pub stroke: StrokeTable,
    /// The best paper stroke's table (paper_stroke.csv).
    #[serde(skip)]
    pub paper_stroke: StrokeTable,
    /// The parameters searched with (params.toml).
    #[serde(skip)]
    pub params: Params,
    /// The candidates, best through the controller first (candidates.csv).
    #[serde(skip)]
    pub candidates: Vec<CandidateRow>,
    /// Every point of the paper sweep, in grid order (paper_sweep.csv).
    #[serde(skip)]
    pub paper_sweep: Vec<SweptPoint>,
    /// One row per generation of the search (history.csv).
    #[serde(skip)]
    pub history: Vec<HistoryRow>,
    /// Every CMA-ES run of the kinematic search, in order: each start's first and its IPOP
    /// restarts (population doubled each time CMA-ES stopped by its own criteria with budget
    /// left).
    pub restarts: Vec<RestartRow>,
    /// How far the runs agree: of the runs whose best was feasible, how many came within 1 %
    /// of the search's best, and the spread (best minus worst) of their best values, in the
    /// objective's unit. The search's uncertainty.
    pub restart_agreement: RestartAgreement,
    /// The answer against the paper's measured regime: its landings, pushes and overshoots
    /// beside the paper's best's, re-scored under the model's alternative rules
    /// (validity.csv), and the rules its result relies on, in words.
    pub validity: Validity,
    /// The answer and the paper's best on each bed (beds.csv; one row, the nominal bed,
    /// without `--phi-range`).
    pub beds: Vec<BedRow>,
    /// Their worst case and mean over the beds.
    pub over_beds: OverBeds,
    /// The answer's kinematic jump, for the figure.
    #[serde(skip)]
    pub answer_series: Vec<SeriesRow>,
    /// The best paper stroke's kinematic jump, for the figure.
    #[serde(skip)]
    pub paper_series: Vec<SeriesRow>,
    /// The folder the run wrote (empty until written).
    #[serde(skip)]
    pub dir: PathBuf,
}

/// The answer and the paper's best on one bed (beds.csv): the nominal bed alone, or each bed
/// of `--phi-range`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BedRow {
    /// The bed's packing fraction.
    pub phi: f64,
    /// The answer's objective value, kinematic model (NaN when it breaks a limit there).
    pub answer_kinematic_value: f64,
    /// The answer's value through sil (NaN: not run, faulted, or past a limit).
    pub answer_sil_value: f64,
    /// The paper's best's value, kinematic model.
    pub paper_kinematic_value: f64,
    /// The paper's best's value through sil.
    pub paper_sil_value: f64,
}

/// The worst case and the mean over the beds of the answer and of the paper's best.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct OverBeds {
    /// Beds.
    pub beds: usize,
    /// The answer's worst value on the basis (sil when it ran, else kinematic).
    pub answer_worst: f64,
    /// The answer's mean value on the basis.
    pub answer_mean: f64,
    /// The paper's best's worst value on the basis.
    pub paper_worst: f64,
    /// The paper's best's mean value on the basis.
    pub paper_mean: f64,
}

impl OverBeds {
    /// The worst and mean of `rows`, through sil when `sil` (else kinematic); NaN values
    /// (a faulted run, a broken limit) make the worst case NaN.
    pub fn of(rows: &[BedRow], sil: bool) -> Self {
        let pick = |r: &BedRow, answer: bool| match (sil, answer) {
            (true, true) => r.answer_sil_value,
            (true, false) => r.paper_sil_value,
            (false, true) => r.answer_kinematic_value,
            (false, false) => r.paper_kinematic_value,
        };
        let worst = |answer: bool| {
            rows.iter()
                .map(|r| pick(r, answer))
                .fold(f64::INFINITY, |w, v| {
                    if v.is_nan() || w.is_nan() {
                        f64::NAN
                    } else {
                        w.min(v)
                    }
                })
        };
        let mean =
            |answer: bool| rows.iter().map(|r| pick(r, answer)).sum::<f64>() / rows.len() as f64;
        Self {
            beds: rows.len(),
            answer_worst: worst(true),
            answer_mean: mean(true),
            paper_worst: worst(false),
            paper_mean: mean(false),
        }
    }
}

/// How far a search's CMA-ES runs agree ([`OptimizeOutcome::restart_agreement`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RestartAgreement {
    /// Runs whose best candidate kept the limits.
    pub feasible_runs: usize,
    /// Of those, the runs within 1 % of the best value.
    pub within_1_percent: usize,
    /// Best minus worst of the feasible runs' best values (0 for one run).
    pub spread: f64,
}

impl RestartAgreement {
    /// The agreement of `runs`.
    pub fn of(runs: &[RestartRow]) -> Self {
        let values: Vec<f64> = runs
            .iter()
            .map(|r| r.best_value)
            .filter(|v| v.is_finite())
            .collect();
        let best = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let worst = values.iter().copied().fold(f64::INFINITY, f64::min);
        Self {
            feasible_runs: values.len(),
            within_1_percent: values
                .iter()
                .filter(|&&v| v >= best - 0.01 * best.abs())
                .count(),
            spread: if values.is_empty() { 0.0 } else { best - worst },
        }
    }
}

/// The files of an outcome's folder ([`OptimizeOutcome::write`]).
pub const FILES: [&str; 11] = [
    "stroke.csv",
    "beds.csv",
    "validity.csv",
    "paper_stroke.csv",
    "candidates.csv",
    "paper_sweep.csv",
    "history.csv",
    "summary.json",
    "params.toml",
    "optimize.png",
    "optimize.svg",
];

/// The answer's chain of an earlier search's folder (`DIR/summary.json`, `answer.chain`): a
/// stroke for [`OptimizeRequest::start_from`](crate::OptimizeRequest::start_from).
pub fn answer_chain_in(dir: &Path) -> Result<MoveChain, OptimizeError> {
    #[derive(serde::Deserialize)]
    struct Summary {
        answer: Answer,
    }
    #[derive(serde::Deserialize)]
    struct Answer {
        chain: Option<MoveChain>,
    }
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        OptimizeError::Invalid(format!(
            "--start-from {}: cannot read {}: {e} (allowed: a folder `optimize` wrote)",
            dir.display(),
            path.display()
        ))
    })?;
    let summary: Summary = serde_json::from_str(&text).map_err(|e| {
        OptimizeError::Invalid(format!(
            "--start-from {}: {} is not an optimize summary: {e}",
            dir.display(),
            path.display()
        ))
    })?;
    summary.answer.chain.ok_or_else(|| {
        OptimizeError::Invalid(format!(
            "--start-from {}: {} gives no answer.chain (written by an older version: run that \
             search again)",
            dir.display(),
            path.display()
        ))
    })
}

/// `c` in words: its start, then each move's target and duration and the holds between.
pub fn chain_text(c: &MoveChain) -> String {
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

impl OptimizeOutcome {
    /// `summary.json` (without its final newline): what `optimize --json` prints.
    pub fn json(&self) -> Result<String, OptimizeError> {
        serde_json::to_string_pretty(self)
            .map_err(|e| OptimizeError::Internal(format!("cannot encode the summary as JSON: {e}")))
    }

    /// Write the folder into `dir` atomically (it appears complete or not at all): stroke.csv,
    /// paper_stroke.csv, candidates.csv, paper_sweep.csv, history.csv, summary.json,
    /// params.toml, optimize.png and optimize.svg. Returns the folder.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, OptimizeError> {
        let staged = StagedDir::create(dir)?;
        self.write_into(&staged)?;
        Ok(staged.commit()?)
    }

    /// Write the folder's files into `staged` (committed by the caller).
    pub fn write_into(&self, staged: &StagedDir) -> Result<(), OptimizeError> {
        staged.write_text("stroke.csv", &self.stroke.to_csv())?;
        staged.write_text("paper_stroke.csv", &self.paper_stroke.to_csv())?;
        staged.write_text("params.toml", &self.params.to_toml())?;
        write_csv(&staged.file("candidates.csv"), &self.candidates, &[])
            .map_err(OptimizeError::Internal)?;
        let sweep: Vec<SweepRow> = self
            .paper_sweep
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
                com_rise_m: p.evaluation.com_rise_m,
                model_peak_force_n: p.evaluation.model_peak_force_n,
                table_peak_force_n: p.evaluation.table_peak_force_n,
                violation: p.evaluation.violation.as_deref().unwrap_or_default(),
            })
            .collect();
        write_csv(&staged.file("paper_sweep.csv"), &sweep, &[]).map_err(OptimizeError::Internal)?;
        write_csv(
            &staged.file("history.csv"),
            &self.history,
            &[
                "start",
                "generation",
                "evaluations",
                "generation_best",
                "best_so_far",
                "sigma",
            ],
        )
        .map_err(OptimizeError::Internal)?;
        write_csv(
            &staged.file("validity.csv"),
            &self.validity.rescored,
            &[
                "tag",
                "rule",
                "alternative",
                "answer_value",
                "answer_value_alternative",
                "paper_value",
                "paper_value_alternative",
                "answer_height_alternative_m",
                "paper_height_alternative_m",
                "violation",
            ],
        )
        .map_err(OptimizeError::Internal)?;
        write_csv(&staged.file("beds.csv"), &self.beds, &[]).map_err(OptimizeError::Internal)?;
        self.figure(staged)?;
        staged.write_text("summary.json", &format!("{}\n", self.json()?))?;
        Ok(())
    }

    /// optimize.png and optimize.svg: the answer and the paper's best, and the convergence.
    fn figure(&self, staged: &StagedDir) -> Result<(), OptimizeError> {
        let fig = search_figure(
            format!(
                "best {} on {}, {} ({}): {} vs the paper's {}",
                self.objective,
                self.model,
                self.where_(),
                self.height_basis,
                self.shown(self.best_value),
                self.shown(self.best_paper_value)
            ) + &if self.validity.relies_on.is_empty() {
                String::new()
            } else {
                format!(
                    " — relies on rules outside the paper's measured regime: {}",
                    self.validity.relies_on_tags.join(", ")
                )
            },
            &[
                Shown {
                    label: "answer".into(),
                    stroke: self.stroke.points(),
                    series: &self.answer_series,
                },
                Shown {
                    label: format!("paper: {}", self.paper_answer.label),
                    stroke: self.paper_stroke.points(),
                    series: &self.paper_series,
                },
            ],
            &self.history,
            self.objective,
            self.objective_unit,
        );
        save_figure(
            &fig,
            &staged.file("optimize.png"),
            Some(&staged.file("optimize.svg")),
        )?;
        Ok(())
    }

    /// Where the values hold: `phi 0.57` (`hard ground`), or the worst case over the beds.
    fn where_(&self) -> String {
        let b = &self.over_beds;
        if self.model == "hard" {
            "hard ground".into()
        } else if b.beds > 1 {
            format!(
                "the worst of {} beds, phi {}..{}",
                b.beds,
                self.beds.first().map_or(f64::NAN, |r| r.phi),
                self.beds.last().map_or(f64::NAN, |r| r.phi)
            )
        } else {
            format!("phi {}", self.phi)
        }
    }

    /// An objective value in its unit (heights in mm).
    fn shown(&self, v: f64) -> String {
        if self.objective_unit == "m" {
            format!("{:.2} mm", 1e3 * v)
        } else {
            format!("{v:.4e} {}", self.objective_unit)
        }
    }

    /// One stroke of the human summary.
    fn stroke_lines(s: &ResultStroke, head: &str, beds: usize) -> String {
        let mm = |v: f64| format!("{:.2} mm", 1e3 * v);
        let mut t = format!("  {head}: {}\n", s.label);
        if let Some(c) = &s.chain {
            t += &format!("    stroke: {}\n", chain_text(c));
        }
        let on = if beds > 1 {
            format!(
                " on its worst bed (phi {}; the table and the links on the nominal bed)",
                s.kinematic.worst_phi
            )
        } else {
            String::new()
        };
        t += &format!(
            "    kinematic {}{on} (its table {}; centre of mass {}), peak force {:.0} N (table \
             estimate {:.0} N)\n",
            mm(s.kinematic.jump_height_m),
            mm(s.table_jump_height_m),
            mm(s.kinematic.com_rise_m),
            s.kinematic.model_peak_force_n,
            s.kinematic.table_peak_force_n
        );
        for l in &s.links {
            match (&l.skipped, l.jump_height_m) {
                (Some(why), _) => t += &format!("    {}: not run ({why})\n", l.link),
                (None, Some(h)) => {
                    let com = l
                        .com_rise_m
                        .map_or(String::new(), |c| format!(" (centre of mass {})", mm(c)));
                    t += &format!(
                        "    {}: {}{com} through the controller, {} fault(s){}\n",
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
        t
    }
}

/// The human summary `optimize` prints without `--json`.
impl fmt::Display for OptimizeOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let value = |v: f64| self.shown(v);
        writeln!(
            f,
            "best {} on {}, {} ({}): {}, the paper's best {}: ratio {:.3}",
            self.objective,
            self.model,
            self.where_(),
            self.height_basis,
            value(self.best_value),
            value(self.best_paper_value),
            self.value_ratio
        )?;
        let a = &self.restart_agreement;
        writeln!(
            f,
            "  search: {} CMA-ES runs (IPOP restarts), {} of {} feasible within 1 % of the best, \
             their bests spread over {}",
            self.restarts.len(),
            a.within_1_percent,
            a.feasible_runs,
            value(a.spread)
        )?;
        let b = &self.over_beds;
        if b.beds > 1 {
            writeln!(
                f,
                "  over {} beds (phi {}..{}): worst {} (mean {}), the paper's best worst {} \
                 (mean {}): worst-case ratio {:.3} (beds.csv)",
                b.beds,
                self.beds.first().map_or(f64::NAN, |r| r.phi),
                self.beds.last().map_or(f64::NAN, |r| r.phi),
                value(b.answer_worst),
                value(b.answer_mean),
                value(b.paper_worst),
                value(b.paper_mean),
                b.answer_worst / b.paper_worst
            )?;
        }
        if self.validity.relies_on.is_empty() {
            writeln!(
                f,
                "  validity: within the paper's measured regime on every check (validity.csv)"
            )?;
        } else {
            writeln!(
                f,
                "  validity: the answer relies on rules outside the paper's measured regime:"
            )?;
            for r in &self.validity.relies_on {
                writeln!(f, "    - {r}")?;
            }
        }
        let heads = ["answer", "the paper's best", "the kinematic model's best"];
        for (s, head) in [&self.answer, &self.paper_answer]
            .into_iter()
            .chain(self.kinematic_optimum.iter())
            .zip(heads)
        {
            f.write_str(&Self::stroke_lines(s, head, self.over_beds.beds))?;
        }
        writeln!(
            f,
            "  {} kinematic evaluations ({:.0}/s on {} thread(s)), {} candidates through the \
             controller, {:.1} s; wrote {}/",
            self.evaluations + self.paper_sweep_points,
            self.evaluations_per_s,
            self.threads,
            self.candidates_ranked,
            self.wall_time_s,
            self.dir.display()
        )
    }
}
