//! `sandjumper figures`: regenerate the simulations behind the paper's figures (Aguilar &
//! Goldman 2016) as PNG + SVG with the CSV behind each, into one output directory.
//!
//! | file stem | what |
//! |---|---|
//! | `height_vs_phi` | best jump height vs phi: single, stutter, delayed stutter (tau = 0.75 s), eq1 and eq4, hard ground for reference |
//! | `height_vs_freq` | jump height vs forcing frequency at several phi and on hard ground |
//! | `delayed_vs_tau` | delayed-stutter height vs delay at phi = 0.57 (each delay at its best frequency) |
//! | `delayed_vs_tau_sil` | the same for eq4 through the software-in-the-loop rig with gain lowering 0.05 (the paper's rig), beside the kinematic curve; tau_opt of each in `summary.txt` |
//! | `penetration_force` | quasi-static `F_p(z)`, two-resistance and cone laws, and a slow re-intrusion |
//! | `added_mass_stutter` | added mass vs depth during a stutter jump at phi = 0.57, in foot masses |
//! | `mechanism` | one stutter jump, eq1 vs eq4: positions, spring force, ground force, added mass |
//! | `ringing` | natural frequency after a small kick: hard ground, and on sand during intrusion (series spring) and once the foot rests, at every preset phi, beside `sqrt(k_s k1/(k_s+k1)/M)/2pi` |
//! | `eq1_fitted` | the paper's procedure: eq1's alpha fitted to eq4's single jumps per phi (`eq1_alpha_fit.csv`, eq1 and eq1-linear), then eq1 vs eq4 on single, stutter (push-off) and delayed-stutter jumps at phi 0.57 and 0.62; `eq1_gap_sensitivity.csv`: how b, mu, C, kappa and l_re (+-20 %) move the stutter gap |
//!
//! Beside them: the full sweeps (`*_sweep.csv`, the columns of `sweep.csv`), `failures.csv`
//! (jumps that could not be simulated, never dropped silently), `params.toml` (the phi = 0.57
//! preset; every phi uses its own preset), and `summary.txt`, the numbers REPRODUCTION.md
//! quotes. The directory appears complete or not at all ([`StagedDir`]).

pub mod eq1_fit;
pub mod grid;
pub mod heights;
pub mod laws;
pub mod ringing;
pub mod series;
pub mod sweeps;

use core::fmt;
use std::path::{Path, PathBuf};

use sandjumper_core::trajectory::JumpKind;

use crate::sweep::{FAILURE_HEADER, ROW_HEADER, SweepFailure, SweepRow, write_csv};
use sandjumper_model::params::{ModelName, Params};
use sandjumper_output::plot::{Figure, save_figure};
use sandjumper_output::{OutputError, StagedDir};
use sweeps::{BEST_HEADER, BestRow, Grids, LOW_PHI, best_rows, find_best};

/// How to run the figures.
#[derive(Clone)]
pub struct FiguresOptions<'a> {
    /// Coarse grids ([`Grids::quick`]) instead of the full set.
    pub quick: bool,
    /// Worker threads (0: one per core).
    pub threads: usize,
    /// Called after every simulated jump, from any worker thread (e.g. a progress bar).
    pub on_jump: &'a (dyn Fn() + Sync),
    /// Relative tolerance of the integrator.
    pub rtol: f64,
}

impl std::fmt::Debug for FiguresOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FiguresOptions")
            .field("quick", &self.quick)
            .field("threads", &self.threads)
            .field("rtol", &self.rtol)
            .finish_non_exhaustive()
    }
}

/// Why the figures could not be written.
#[derive(Debug)]
pub enum FiguresError {
    /// The output directory cannot be used (bad input).
    Output(OutputError),
    /// Something failed after the input was accepted (a simulation setup, a file, a figure).
    Internal(String),
}

impl fmt::Display for FiguresError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Output(e) => write!(f, "{e}"),
            Self::Internal(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for FiguresError {}

impl From<OutputError> for FiguresError {
    fn from(e: OutputError) -> Self {
        Self::Output(e)
    }
}

/// What was written.
#[derive(Clone, Debug, PartialEq)]
pub struct FiguresReport {
    /// The output directory.
    pub dir: PathBuf,
    /// Files written, by name.
    pub files: Vec<String>,
    /// Jumps simulated in the sweeps.
    pub jumps: usize,
    /// Jumps that failed (listed in `failures.csv`).
    pub failures: usize,
    /// The numbers of `summary.txt`, as (name, value) pairs.
    pub findings: Vec<(String, String)>,
    /// Wall time of the whole call, s.
    pub elapsed_s: f64,
}

impl std::fmt::Display for FiguresReport {
    /// What `sandjumper figures` prints: the files written, the jumps, the time, then each
    /// finding on its own line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "wrote {} files to {} ({} jumps, {} failed, {:.1} s)",
            self.files.len(),
            self.dir.display(),
            self.jumps,
            self.failures,
            self.elapsed_s
        )?;
        for (k, v) in &self.findings {
            writeln!(f, "  {k} = {v}")?;
        }
        Ok(())
    }
}

/// Writes files into the staging directory and remembers their names.
struct Writer {
    dir: StagedDir,
    files: Vec<String>,
}

impl Writer {
    fn csv<T: serde::Serialize>(
        &mut self,
        name: &str,
        rows: &[T],
        header: &[&str],
    ) -> Result<(), FiguresError> {
        write_csv(&self.dir.file(name), rows, header).map_err(FiguresError::Internal)?;
        self.files.push(name.into());
        Ok(())
    }

    fn figure(&mut self, stem: &str, fig: &impl Figure) -> Result<(), FiguresError> {
        let (png, svg) = (format!("{stem}.png"), format!("{stem}.svg"));
        save_figure(fig, &self.dir.file(&png), Some(&self.dir.file(&svg)))
            .map_err(|e| FiguresError::Internal(e.to_string()))?;
        self.files.extend([png, svg]);
        Ok(())
    }

    fn text(&mut self, name: &str, text: &str) -> Result<(), FiguresError> {
        self.dir
            .write_text(name, text)
            .map_err(|e| FiguresError::Internal(e.to_string()))?;
        self.files.push(name.into());
        Ok(())
    }
}

/// The jump model's figures (`sandjumper figures`), written into `out`.
#[derive(Clone, Debug, PartialEq)]
pub struct FiguresRequest {
    /// Output directory (created, or replacing an earlier sandjumper output).
    pub out: PathBuf,
    /// Coarse grids ([`Grids::quick`]) instead of the full set.
    pub quick: bool,
    /// Worker threads (None: one per core).
    pub threads: Option<usize>,
    /// Relative tolerance of the integrator.
    pub rtol: f64,
}

impl Default for FiguresRequest {
    fn default() -> Self {
        Self {
            out: PathBuf::new(),
            quick: false,
            threads: None,
            rtol: sandjumper_model::options::SimOptions::default().rtol,
        }
    }
}

/// Simulate and write every figure `request` asks for; one `progress` step per jump (its
/// count is known only as they run).
pub fn run(
    request: &FiguresRequest,
    progress: &dyn sandjumper_output::Progress,
) -> Result<FiguresReport, FiguresError> {
    progress.start("jumps simulated", None);
    let opts = FiguresOptions {
        quick: request.quick,
        threads: request.threads.unwrap_or(0),
        on_jump: &|| progress.advance(1),
        rtol: request.rtol,
    };
    let report = write_figures(&request.out, &opts);
    progress.finish();
    report
}

impl sandjumper_output::Blamed for FiguresError {
    fn blame(&self) -> sandjumper_output::Blame {
        match self {
            Self::Output(_) => sandjumper_output::Blame::Input,
            Self::Internal(_) => sandjumper_output::Blame::Internal,
        }
    }
}

/// Simulate and write every figure into `out`.
pub fn write_figures(out: &Path, opts: &FiguresOptions<'_>) -> Result<FiguresReport, FiguresError> {
    let started = std::time::Instant::now();
    let mut w = Writer {
        dir: StagedDir::create(out)?,
        files: Vec::new(),
    };
    let grids = if opts.quick {
        Grids::quick()
    } else {
        Grids::full()
    };
    let mut failures: Vec<SweepFailure> = Vec::new();

    // 1 + 2: every kind, eq1/eq4 at every phi and hard ground, at every frequency.
    let phi_sweep = sweeps::run(&sweeps::phi_combinations(&grids), opts)?;
    let best = best_rows(&phi_sweep.rows);
    w.csv("height_vs_phi_sweep.csv", &phi_sweep.rows, &ROW_HEADER)?;
    w.csv("height_vs_phi.csv", &best, &BEST_HEADER)?;
    w.figure("height_vs_phi", &heights::height_vs_phi(&best))?;
    let freq_phis: Vec<f64> = laws::LAW_PHIS
        .into_iter()
        .filter(|p| grids.phis.iter().any(|g| (g - p).abs() < 1e-9))
        .collect();
    let freq_rows: Vec<SweepRow> = phi_sweep
        .rows
        .iter()
        .filter(|r| r.kind != "delayed")
        .filter(|r| r.model == "hard" || freq_phis.iter().any(|p| (p - r.phi).abs() < 1e-9))
        .cloned()
        .collect();
    w.csv("height_vs_freq.csv", &freq_rows, &ROW_HEADER)?;
    w.figure(
        "height_vs_freq",
        &heights::height_vs_freq(&freq_rows, &freq_phis),
    )?;
    failures.extend(phi_sweep.failures.iter().cloned());

    // 3: the delayed stutter against its delay.
    let tau_sweep = sweeps::run(&sweeps::tau_combinations(&grids), opts)?;
    let tau_best = best_rows(&tau_sweep.rows);
    w.csv("delayed_vs_tau_sweep.csv", &tau_sweep.rows, &ROW_HEADER)?;
    w.csv("delayed_vs_tau.csv", &tau_best, &BEST_HEADER)?;
    w.figure("delayed_vs_tau", &heights::height_vs_tau(&tau_best, &best))?;
    failures.extend(tau_sweep.failures.iter().cloned());

    // 3b: the same delay curve the way the rig made it: eq4 through the SIL rig with the
    // position gain lowered during the delay, beside the kinematic curve.
    let sil_drive = crate::sweep::SweepDrive::Sil {
        gain_lowering: Some(sweeps::SIL_GAIN_LOWERING),
    };
    let sil_sweep = sweeps::run_driven(&sweeps::tau_combinations_eq4(&grids), opts, sil_drive)?;
    let sil_best = best_rows(&sil_sweep.rows);
    let kin_best: Vec<BestRow> = tau_best
        .iter()
        .filter(|b| b.model == ModelName::Eq4.as_str())
        .cloned()
        .collect();
    w.csv("delayed_vs_tau_sil_sweep.csv", &sil_sweep.rows, &ROW_HEADER)?;
    w.csv("delayed_vs_tau_sil.csv", &sil_best, &BEST_HEADER)?;
    w.figure(
        "delayed_vs_tau_sil",
        &heights::delay_curve_sil(&kin_best, &sil_best, &sil_drive.name()),
    )?;
    failures.extend(sil_sweep.failures.iter().cloned());

    // 4: quasi-static force laws.
    let law_rows = laws::curves().map_err(FiguresError::Internal)?;
    w.csv("penetration_force.csv", &law_rows, &laws::HEADER)?;
    w.figure("penetration_force", &laws::figure(&law_rows))?;

    // 4b: the natural frequencies after a small kick (hard ground ~8 Hz, ~5 Hz intruding).
    let kicks =
        crate::ringing::kick_presets(&ringing::RINGING_MODELS, &ringing::RINGING_PHIS, opts.rtol)
            .map_err(FiguresError::Internal)?;
    let ringing_rows: Vec<_> = kicks.iter().map(|k| k.ringing.clone()).collect();
    let weight = {
        let p = Params::preset(LOW_PHI).map_err(|e| FiguresError::Internal(e.to_string()))?;
        p.motor_rod_mass_kg() * p.robot.gravity_m_s2
    };
    let kick_series = ringing::series_rows(&kicks, weight);
    w.csv("ringing.csv", &ringing_rows, &crate::ringing::HEADER)?;
    w.csv("ringing_series.csv", &kick_series, &ringing::SERIES_HEADER)?;
    w.figure("ringing", &ringing::figure(&ringing_rows, &kick_series))?;

    // 5 + 6: one stutter jump at phi = 0.57, at the frequency where the eq4 stutter's
    // push-off (final) height is highest: the push-off is where the laws differ.
    let freq = find_best(&best, JumpKind::Stutter, ModelName::Eq4, Some(LOW_PHI))
        .map(|b| b.best_final_freq_hz)
        .ok_or_else(|| {
            FiguresError::Internal("no successful eq4 stutter jump at phi = 0.57".into())
        })?;
    let (params4, run4) =
        series::stutter(ModelName::Eq4, freq, opts.rtol).map_err(FiguresError::Internal)?;
    let (params1, run1) =
        series::stutter(ModelName::Eq1, freq, opts.rtol).map_err(FiguresError::Internal)?;
    let rows4 = series::csv_rows(ModelName::Eq4, &params4, &run4.series);
    let rows1 = series::csv_rows(ModelName::Eq1, &params1, &run1.series);
    w.csv("added_mass_stutter.csv", &rows4, &series::HEADER)?;
    w.figure(
        "added_mass_stutter",
        &series::added_mass_figure(&rows4, freq),
    )?;
    let both: Vec<_> = rows1.iter().chain(&rows4).cloned().collect();
    w.csv("mechanism.csv", &both, &series::HEADER)?;
    w.figure("mechanism", &series::mechanism_figure(&rows1, &rows4, freq))?;

    // 7: the paper's fitting procedure: eq1's alpha fitted to (eq4's) single jumps, then eq1
    // and eq4 compared on the other jumps.
    let fit_freqs: Vec<f64> = grids
        .freqs_hz
        .iter()
        .copied()
        .filter(|&f| f >= eq1_fit::FIT_MIN_FREQ_HZ)
        .collect();
    let mut alphas = eq1_fit::fit_alphas(ModelName::Eq1, &fit_freqs, opts.rtol)
        .map_err(FiguresError::Internal)?;
    alphas.extend(
        eq1_fit::fit_alphas(ModelName::Eq1Linear, &fit_freqs, opts.rtol)
            .map_err(FiguresError::Internal)?,
    );
    w.csv("eq1_alpha_fit.csv", &alphas, &eq1_fit::ALPHA_HEADER)?;
    let compared =
        eq1_fit::compare(&alphas, &fit_freqs, opts.rtol).map_err(FiguresError::Internal)?;
    w.csv("eq1_fitted.csv", &compared, &eq1_fit::COMPARE_HEADER)?;
    w.figure("eq1_fitted", &eq1_fit::figure(&compared))?;
    let sensitivity =
        eq1_fit::sensitivity(&fit_freqs, opts.rtol).map_err(FiguresError::Internal)?;
    w.csv(
        "eq1_gap_sensitivity.csv",
        &sensitivity,
        &eq1_fit::SENSITIVITY_HEADER,
    )?;

    // Records: failures, parameters, the numbers.
    w.csv("failures.csv", &failures, &FAILURE_HEADER)?;
    let params = Params::preset(LOW_PHI).map_err(|e| FiguresError::Internal(e.to_string()))?;
    w.text(
        "params.toml",
        &format!(
            "# Parameters of the phi = {LOW_PHI} runs; every phi uses its own preset (docs/model.md tables),\n\
             # hard ground the robot of this file. Integrator rtol = {}; grids: {}.\n{}",
            opts.rtol,
            if opts.quick { "quick" } else { "full" },
            params.to_toml()
        ),
    )?;
    let mut findings = findings(&params, &best, &tau_best, &phi_sweep.rows, &run1, &run4);
    for a in &alphas {
        findings.push((
            format!("{}.fitted_alpha.phi{}", a.model, a.phi),
            format!(
                "{:.1} kg/m (start {} kg/m; single-jump residual RMS {:.2} mm over {} jumps)",
                a.alpha_fitted_kg_m, a.alpha_start_kg_m, a.residual_rms_mm, a.jumps
            ),
        ));
    }
    for r in &ringing_rows {
        let key = if r.model == ModelName::Hard.as_str() {
            "ringing.hard".to_string()
        } else {
            format!("ringing.{}.phi{}", r.model, r.phi)
        };
        findings.push((
            key,
            format!(
                "intrusion {:.2} Hz (series spring: k1 {:.2} Hz, dF_p/dz {:.2} Hz), foot at rest {:.2} Hz (sqrt(k_s/M)/2pi {:.2} Hz)",
                r.intrusion_freq_hz,
                r.series_k1_estimate_hz,
                r.series_local_estimate_hz,
                r.static_freq_hz,
                r.hard_estimate_hz
            ),
        ));
    }
    for (name, rows) in [("kinematic", &kin_best), ("sil_gain_lowering", &sil_best)] {
        if let Some((tau, h, f)) = heights::tau_opt(rows) {
            findings.push((
                format!("eq4.delayed_tau_opt.phi0.57.{name}"),
                format!("{tau} s ({} at {f} Hz)", mm(h)),
            ));
        }
    }
    findings.push((
        "eq4.delayed_sil_failures.phi0.57".into(),
        format!(
            "{} of {} jumps (faults or drive limits; in failures.csv)",
            sil_sweep.failures.len(),
            sil_sweep.failures.len() + sil_sweep.rows.len()
        ),
    ));
    for r in sensitivity.iter().filter(|r| r.param != "none") {
        findings.push((
            format!("eq1_gap_sensitivity.{}x{}.phi{}", r.param, r.factor, r.phi),
            format!(
                "stutter gap {:.3} ({:+.1} points), alpha {:.1} kg/m",
                r.stutter_gap, r.gap_change_points, r.alpha_fitted_kg_m
            ),
        ));
    }
    for (kind, phi, ratio) in eq1_fit::gaps(&compared) {
        findings.push((
            format!("eq1_fitted_over_eq4.{kind}.phi{phi}"),
            format!("{ratio:.3}"),
        ));
    }
    let summary: String = findings
        .iter()
        .map(|(k, v)| format!("{k} = {v}\n"))
        .collect();
    w.text("summary.txt", &summary)?;

    let jumps = phi_sweep.rows.len() + tau_sweep.rows.len() + failures.len() + 2 + compared.len();
    let Writer { dir, files } = w;
    let dir = dir.commit()?;
    Ok(FiguresReport {
        dir,
        files,
        jumps,
        failures: failures.len(),
        findings,
        elapsed_s: started.elapsed().as_secs_f64(),
    })
}

fn mm(x: f64) -> String {
    format!("{:.2} mm", 1e3 * x)
}

/// The numbers docs/model.md section 4 speaks about, from the sweeps.
fn findings(
    params: &Params,
    best: &[BestRow],
    tau_best: &[BestRow],
    rows: &[SweepRow],
    eq1: &sandjumper_model::jump::JumpOutcome,
    eq4: &sandjumper_model::jump::JumpOutcome,
) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    let mut put = |k: String, v: String| out.push((k, v));
    let r = &params.robot;
    let natural = (r.spring_stiffness_n_m / params.motor_rod_mass_kg()).sqrt()
        / (2.0 * core::f64::consts::PI);
    put(
        "hard_natural_frequency_hz (sqrt(k_s/M)/2pi)".into(),
        format!("{natural:.2}"),
    );
    let kinds = [
        JumpKind::Single,
        JumpKind::Stutter,
        JumpKind::DelayedStutter,
    ];
    let h = |kind, model, phi| find_best(best, kind, model, phi);
    for kind in kinds {
        let name = sandjumper_model::trajectory::kind_name(kind);
        if let Some(b) = h(kind, ModelName::Hard, None) {
            put(
                format!("hard.{name}"),
                format!("{} at {} Hz", mm(b.jump_height_m), b.best_freq_hz),
            );
        }
        for model in [ModelName::Eq1, ModelName::Eq4] {
            for phi in [0.57, 0.62] {
                if let Some(b) = h(kind, model, Some(phi)) {
                    put(
                        format!("{model}.phi{phi}.{name}"),
                        format!(
                            "{} at {} Hz (final there {}; best final {} at {} Hz)",
                            mm(b.jump_height_m),
                            b.best_freq_hz,
                            mm(b.final_jump_height_m),
                            mm(b.best_final_jump_height_m),
                            b.best_final_freq_hz
                        ),
                    );
                }
            }
        }
    }
    let ratio = |a: Option<&BestRow>, b: Option<&BestRow>| match (a, b) {
        (Some(a), Some(b)) if b.jump_height_m > 0.0 => {
            format!("{:.3}", a.jump_height_m / b.jump_height_m)
        }
        _ => "n/a".into(),
    };
    for model in [ModelName::Eq1, ModelName::Eq4] {
        let single = |phi| h(JumpKind::Single, model, phi);
        put(
            format!("{model}.single_phi0.57_over_hard"),
            ratio(
                single(Some(0.57)),
                h(JumpKind::Single, ModelName::Hard, None),
            ),
        );
        put(
            format!("{model}.single_phi0.62_over_phi0.57"),
            ratio(single(Some(0.62)), single(Some(0.57))),
        );
        put(
            format!("{model}.stutter_over_single.phi0.57"),
            ratio(h(JumpKind::Stutter, model, Some(0.57)), single(Some(0.57))),
        );
        put(
            format!("{model}.delayed_over_single.phi0.57"),
            ratio(
                h(JumpKind::DelayedStutter, model, Some(0.57)),
                single(Some(0.57)),
            ),
        );
        for phi in [0.57, 0.62] {
            let hs: Vec<f64> = kinds
                .iter()
                .filter_map(|&k| h(k, model, Some(phi)))
                .map(|b| b.jump_height_m)
                .collect();
            let (lo, hi) = hs.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            });
            put(
                format!("{model}.kind_spread.phi{phi} ((max-min)/max)"),
                format!("{:.3}", (hi - lo) / hi),
            );
        }
        // Broad band: frequencies within 90 % of the best single jump.
        let band = |model: ModelName, phi: Option<f64>| -> String {
            let line: Vec<&SweepRow> = rows
                .iter()
                .filter(|r| r.kind == "single" && r.model == model.as_str())
                .filter(|r| phi.is_none_or(|p| (r.phi - p).abs() < 1e-9))
                .collect();
            let top = line.iter().map(|r| r.jump_height_m).fold(0.0, f64::max);
            let good: Vec<f64> = line
                .iter()
                .filter(|r| r.jump_height_m >= 0.9 * top)
                .map(|r| r.freq_hz)
                .collect();
            match (good.first(), good.last()) {
                (Some(a), Some(b)) => format!("{a}..{b} Hz ({} grid points)", good.len()),
                _ => "n/a".into(),
            }
        };
        put(
            format!("{model}.single_band90.phi0.57"),
            band(model, Some(0.57)),
        );
        if model == ModelName::Eq4 {
            put("hard.single_band90".into(), band(ModelName::Hard, None));
        }
        // Delay at which the delayed stutter first beats the single jump at phi = 0.57.
        if let Some(single) = h(JumpKind::Single, model, Some(0.57)) {
            let first = tau_best
                .iter()
                .filter(|b| b.model == model.as_str())
                .find(|b| b.jump_height_m > single.jump_height_m)
                .map_or("never on the grid".to_string(), |b| {
                    format!("{} s", b.tau_s)
                });
            put(
                format!("{model}.delayed_beats_single_from_tau.phi0.57"),
                first,
            );
        }
    }
    for (name, run) in [("eq1", eq1), ("eq4", eq4)] {
        let s = &run.summary;
        put(
            format!("mechanism.{name}"),
            format!(
                "height {} final {} max depth {} peak m_a/m_f {:.2}",
                mm(s.jump_height_m),
                mm(s.final_jump_height_m),
                mm(s.max_depth_m),
                s.peak_added_mass_kg / params.robot.foot_mass_kg
            ),
        );
    }
    out
}
