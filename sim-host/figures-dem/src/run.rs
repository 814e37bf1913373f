//! The request, the stages in order, and the outcome.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::compare::{PivComparison, ROW_HEADER, Row, compare_piv};
use crate::error::FiguresDemError;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_dem::bed_run::BedRequest;
use sandjumper_dem::intrude_run::{Episode, IntrudeOutcome, IntrudeRequest};
use sandjumper_dem::outputs::Summary;
use sandjumper_dem::params::Model;
use sandjumper_dem::request::ModelRequest;
use sandjumper_flow::analysis::FlowRow;
use sandjumper_flow::cone::ShearBandCone;
use sandjumper_flow::run::PivRequest;
use sandjumper_output::{Progress, StagedDir, write_csv};
use sandjumper_study::StudyError;
use sandjumper_study::jump::{JumpOutcome, JumpRequest};

/// `dem bed`'s longest preparation, simulated s (its default).
const BED_MAX_TIME_S: f64 = 2.0;

/// `figures dem`'s request.
#[derive(Clone, Debug, PartialEq)]
pub struct FiguresDemRequest {
    /// Output directory (created, or replaced if it holds an earlier sandjumper output).
    pub out: PathBuf,
    /// Packing fraction of the jumps whose push-offs drive the DEM (eq. 4 model), and the
    /// bulk phi of eq. 6, 1. Default 0.57.
    pub phi: f64,
    /// Forcing frequency of the three jumps, Hz. Default 10.
    pub freq_hz: f64,
    /// Delay of the delayed stutter, s. Default 0.1.
    pub tau_s: f64,
    /// Foot width, m (the bed is 4 widths wide and 1.6 deep). Default 0.076.
    pub foot_width_m: f64,
    /// Run the full model's row (its bed settles under gravity). Default true.
    pub full_model: bool,
    /// Threads (0: all cores). Default 0.
    pub threads: usize,
    /// Longest preparation of each bed, simulated s (`dem bed --max-time`). Default 2, as
    /// `dem bed`'s. The packed beds come to rest in a few hundredths of a second; the full
    /// model's, settling under gravity, may take it all: a shorter one is a test's knob.
    pub bed_max_time_s: f64,
}

impl Default for FiguresDemRequest {
    fn default() -> Self {
        Self {
            out: PathBuf::new(),
            phi: 0.57,
            freq_hz: 10.0,
            tau_s: 0.1,
            foot_width_m: 0.076,
            full_model: true,
            threads: 0,
            bed_max_time_s: BED_MAX_TIME_S,
        }
    }
}

impl FiguresDemRequest {
    /// Refuse a foot, frequency or delay out of range (what and what is allowed).
    pub fn validate(&self) -> Result<(), FiguresDemError> {
        if !(0.005..=0.2).contains(&self.foot_width_m) {
            return Err(FiguresDemError::input(format!(
                "--foot-width {} m (allowed: 0.005..=0.2)",
                self.foot_width_m
            )));
        }
        if !(self.bed_max_time_s.is_finite() && self.bed_max_time_s > 0.0) {
            return Err(FiguresDemError::input(format!(
                "bed preparation {} s (allowed: above 0)",
                self.bed_max_time_s
            )));
        }
        if !(0.5..=40.0).contains(&self.freq_hz) || !(0.0..=1.0).contains(&self.tau_s) {
            return Err(FiguresDemError::input(format!(
                "--freq {} Hz, --tau {} s (allowed: 0.5..=40 Hz, as `jump` takes, and 0..=1 s)",
                self.freq_hz, self.tau_s
            )));
        }
        Ok(())
    }
}

/// How a jump is simulated: [`sandjumper_study::jump::run`] of the request, whose outcome
/// is then written into the folder (the second argument). [`run`] uses that; a test may put a
/// failing one in its place ([`run_with_jump`]).
pub type JumpRunner<'a> = &'a dyn Fn(&JumpRequest, &Path) -> Result<JumpOutcome, StudyError>;

/// What `figures dem` found (`summary.json`).
#[derive(Clone, Debug, Serialize)]
pub struct FiguresDemOutcome {
    /// One row per DEM run.
    pub runs: Vec<Row>,
    /// Each push-off's peak momentum over the stutter's (the paper's relative scaling), 1.
    pub momentum_peak_over_stutter: BTreeMap<String, f64>,
    /// Median of PIV's added mass over the DEM's, 1.
    pub piv_over_dem_added_mass_median: f64,
    /// PIV pairs compared.
    pub piv_pairs_compared: usize,
    /// Wall time, s.
    pub wall_s: f64,
    /// The folder written.
    #[serde(skip)]
    pub out: PathBuf,
}

impl fmt::Display for FiguresDemOutcome {
    /// The summary `figures dem` prints.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "figures dem: wrote {} ({:.0} s)",
            self.out.display(),
            self.wall_s
        )?;
        for r in &self.runs {
            writeln!(f, "{}", r.line())?;
        }
        write!(
            f,
            "  PIV on the stutter's frames / DEM added mass: median {:.3} over {} pairs",
            self.piv_over_dem_added_mass_median, self.piv_pairs_compared
        )
    }
}

/// The resolved parameters, written as `figures_dem.toml`.
#[derive(Serialize)]
struct Resolved<'a> {
    phi: f64,
    freq_hz: f64,
    tau_s: f64,
    foot_width_m: f64,
    bed_width_m: f64,
    bed_height_m: f64,
    area_fraction: f64,
    near_jammed_area_fraction: f64,
    full_model: bool,
    commands: &'a [String],
}

/// The stages run so far: their command lines, wall times and intrusion summaries.
struct Log<'a> {
    progress: &'a dyn Progress,
    started: Instant,
    total: usize,
    stage: usize,
    commands: Vec<String>,
    wall: BTreeMap<PathBuf, f64>,
}

impl Log<'_> {
    /// Announce stage `what`, run `f`, record its command line and its time into `out`.
    fn stage<T>(
        &mut self,
        what: &str,
        command: String,
        out: &Path,
        f: impl FnOnce() -> Result<T, FiguresDemError>,
    ) -> Result<T, FiguresDemError> {
        self.stage += 1;
        self.progress.note(&format!(
            "figures dem [{}/{}] {what} ({:.0} s so far)",
            self.stage,
            self.total,
            self.started.elapsed().as_secs_f64()
        ));
        let t0 = Instant::now();
        let value = f()?;
        self.wall
            .insert(out.to_path_buf(), t0.elapsed().as_secs_f64());
        self.commands.push(command);
        Ok(value)
    }
}

/// Run `figures dem`: the jumps ([`sandjumper_study::jump`]), the DEM runs
/// ([`sandjumper_dem`]) and PIV ([`sandjumper_flow::run`]) in this process, each into its folder
/// under `runs/`, and the comparison written into `request.out`.
pub fn run(
    request: &FiguresDemRequest,
    progress: &dyn Progress,
) -> Result<FiguresDemOutcome, FiguresDemError> {
    run_with_jump(
        request,
        &|jump, _| sandjumper_study::jump::run(jump, progress),
        progress,
    )
}

/// [`run`] with the jumps simulated by `jump` (a test's failing stage; [`run`] passes
/// [`sandjumper_study::jump::run`]).
#[doc(hidden)]
pub fn run_with_jump(
    request: &FiguresDemRequest,
    jump: JumpRunner<'_>,
    progress: &dyn Progress,
) -> Result<FiguresDemOutcome, FiguresDemError> {
    request.validate()?;
    let started = Instant::now();
    let staged = StagedDir::create(&request.out)?;
    let runs = staged.file("runs");
    std::fs::create_dir_all(&runs)
        .map_err(|e| FiguresDemError::internal(format!("cannot create {}: {e}", runs.display())))?;
    let mut log = Log {
        progress,
        started,
        total: if request.full_model { 12 } else { 10 },
        stage: 0,
        commands: Vec::new(),
        wall: BTreeMap::new(),
    };
    let w = request.foot_width_m;
    // The jumps first: their depth sizes the bed.
    let mut deepest: f64 = 0.0;
    for (kind, name) in [
        (JumpKind::Single, "single"),
        (JumpKind::Stutter, "stutter"),
        (JumpKind::DelayedStutter, "delayed"),
    ] {
        let depth = jump_stage(&mut log, jump, request, kind, name, &runs)?;
        deepest = deepest.max(depth);
    }
    // Four foot widths by 1.6, as the supplement's bed; deeper if the push-off and the cone
    // under it (R tan 60) would reach the bottom (a small foot's bed).
    let cone = 0.5 * w * 60f64.to_radians().tan();
    let (bed_w, bed_h) = (
        4.0 * w + 0.01,
        (1.6 * w + 0.003).max(deepest + cone + 0.005),
    );
    let plan = Plan {
        request,
        runs: &runs,
        bed_w: format!("{bed_w:.4}").parse().unwrap_or(bed_w),
        bed_h: format!("{bed_h:.4}").parse().unwrap_or(bed_h),
    };
    let mut summaries: BTreeMap<String, Summary> = BTreeMap::new();
    plan.bed(
        &mut log,
        "the bed at 0.70",
        "bed-0.70",
        Model::Paper,
        Some(0.70),
    )?;
    for kind in ["single", "stutter", "delayed"] {
        let what = format!("the {kind} push-off into it");
        let s = plan.intrude(&mut log, &what, kind, "bed-0.70", kind, Model::Paper)?;
        summaries.insert(kind.into(), s);
    }
    let piv_flow = plan.piv(&mut log, &runs.join("stutter"), &runs.join("piv-stutter"))?;
    plan.bed(
        &mut log,
        "the near-jammed bed at 0.80",
        "bed-0.80",
        Model::Paper,
        Some(0.80),
    )?;
    let s = plan.intrude(
        &mut log,
        "the stutter into it",
        "stutter-0.80",
        "bed-0.80",
        "stutter",
        Model::Paper,
    )?;
    summaries.insert("stutter-0.80".into(), s);
    if request.full_model {
        plan.bed(
            &mut log,
            "the full model's bed, settled under gravity",
            "bed-full",
            Model::Full,
            None,
        )?;
        let s = plan.intrude(
            &mut log,
            "the stutter into it (gravity, friction, walls)",
            "stutter-full",
            "bed-full",
            "stutter",
            Model::Full,
        )?;
        summaries.insert("stutter-full".into(), s);
    }
    // Every path the runs recorded names the staging folder, renamed to --out at the end:
    // recorded as the final paths, so the commands can be run again.
    let staging = staged.path().display().to_string();
    let final_out = request.out.display().to_string();
    for c in &mut log.commands {
        *c = c.replace(&staging, &final_out);
    }
    rewrite_paths(&runs, &staging, &final_out)?;
    // The comparison.
    let mut names = vec![
        ("single", "single jump's push-off, paper model, 0.70"),
        ("stutter", "stutter's push-off, paper model, 0.70"),
        ("delayed", "delayed stutter's push-off, paper model, 0.70"),
        (
            "stutter-0.80",
            "stutter's push-off, paper model, 0.80 (near jamming)",
        ),
    ];
    if request.full_model {
        names.push((
            "stutter-full",
            "stutter's push-off, full model (gravity, friction 0.5, walls), settled bed",
        ));
    }
    let rows: Vec<(Row, Option<ShearBandCone>)> = names
        .iter()
        .filter_map(|(name, what)| {
            let s = summaries.get(*name)?;
            let wall = log.wall.get(&runs.join(name)).copied().unwrap_or(f64::NAN);
            Some((Row::of(s, name, what, wall), s.shear_band_cone.clone()))
        })
        .collect();
    let piv = compare_piv(&runs.join("stutter"), &piv_flow)?;
    let resolved = Resolved {
        phi: request.phi,
        freq_hz: request.freq_hz,
        tau_s: request.tau_s,
        foot_width_m: w,
        bed_width_m: bed_w,
        bed_height_m: bed_h,
        area_fraction: 0.70,
        near_jammed_area_fraction: 0.80,
        full_model: request.full_model,
        commands: &log.commands,
    };
    write_comparison(&staged, &runs, request, &rows, &piv, &resolved)?;
    let runs_rows: Vec<Row> = rows.into_iter().map(|(r, _)| r).collect();
    let mut outcome = FiguresDemOutcome {
        momentum_peak_over_stutter: {
            let stutter = runs_rows
                .iter()
                .find(|r| r.name == "stutter")
                .map_or(f64::NAN, |r| r.grain_momentum_under_foot_kg_m_s);
            runs_rows
                .iter()
                .take(3)
                .map(|r| (r.name.clone(), r.grain_momentum_under_foot_kg_m_s / stutter))
                .collect()
        },
        runs: runs_rows,
        piv_over_dem_added_mass_median: piv.ratio_median,
        piv_pairs_compared: piv.points.len(),
        wall_s: started.elapsed().as_secs_f64(),
        out: PathBuf::new(),
    };
    staged.write_text(
        "summary.json",
        &serde_json::to_string_pretty(&outcome).map_err(FiguresDemError::internal)?,
    )?;
    outcome.out = staged.commit()?;
    outcome.wall_s = started.elapsed().as_secs_f64();
    Ok(outcome)
}

/// The `name` jump of `kind` (`jump --kind NAME --freq F --phi PHI [--tau T] --out
/// runs/jump-NAME`, its folder holding `trajectory.csv`) simulated by `jump` and written; its
/// deepest intrusion, m.
fn jump_stage(
    log: &mut Log<'_>,
    jump: JumpRunner<'_>,
    request: &FiguresDemRequest,
    kind: JumpKind,
    name: &str,
    runs: &Path,
) -> Result<f64, FiguresDemError> {
    // `jump`'s command line: the eq. 4 model, no parameter overrides, rtol 1e-8.
    let jump_request = JumpRequest {
        kind,
        freq_hz: request.freq_hz,
        tau_s: (kind == JumpKind::DelayedStutter).then_some(request.tau_s),
        phi: request.phi,
        record_series: true,
        ..JumpRequest::default()
    };
    let out = runs.join(format!("jump-{name}"));
    let command = format!(
        "sandjumper jump --kind {name} --freq {} --phi {}{} --out {}",
        request.freq_hz,
        request.phi,
        jump_request
            .tau_s
            .map_or(String::new(), |t| format!(" --tau {t}")),
        out.display()
    );
    let progress = log.progress;
    log.stage(&format!("the {name} jump"), command.clone(), &out, || {
        let failed = |e: StudyError| FiguresDemError::of_stage(&command, &e);
        jump_request.validate().map_err(failed)?;
        let outcome = jump(&jump_request, &out).map_err(failed)?;
        outcome.write(&out).map_err(failed)?;
        progress.note(outcome.to_string().trim_end());
        for w in &outcome.simulated.warnings {
            progress.note(&format!("warning: {w}"));
        }
        Ok(outcome.simulated.summary.max_depth_m)
    })
}

/// The comparison's files: `dem_runs.csv`, `piv_vs_dem.csv`, the figures,
/// `momentum_vs_time.csv`, `figures_dem.toml`.
fn write_comparison(
    staged: &StagedDir,
    runs: &Path,
    request: &FiguresDemRequest,
    rows: &[(Row, Option<ShearBandCone>)],
    piv: &PivComparison,
    resolved: &Resolved<'_>,
) -> Result<(), FiguresDemError> {
    let plain: Vec<&Row> = rows.iter().map(|(r, _)| r).collect();
    write_csv(&staged.file("dem_runs.csv"), &plain, ROW_HEADER)
        .map_err(FiguresDemError::Internal)?;
    write_csv(
        &staged.file("piv_vs_dem.csv"),
        &piv.points,
        &["t_s", "depth_m", "dem_added_mass_kg", "piv_added_mass_kg"],
    )
    .map_err(FiguresDemError::Internal)?;
    let series = crate::plots::figures(
        staged,
        runs,
        request.phi,
        0.5 * request.foot_width_m,
        rows,
        piv,
    )?;
    write_csv(
        &staged.file("momentum_vs_time.csv"),
        &series,
        &[
            "jump",
            "t_s",
            "depth_m",
            "momentum_under_foot_kg_m_s",
            "added_mass_kg",
            "eq6_added_mass_kg",
            "added_mass_vs_eq6",
            "in_cone_forming_depths",
        ],
    )
    .map_err(FiguresDemError::Internal)?;
    staged.write_text(
        "figures_dem.toml",
        &toml::to_string(resolved).map_err(FiguresDemError::internal)?,
    )?;
    Ok(())
}

/// The DEM stages' shared choices: the bed's size, the runs' folder, the request.
struct Plan<'a> {
    request: &'a FiguresDemRequest,
    runs: &'a Path,
    bed_w: f64,
    bed_h: f64,
}

fn model_name(m: Model) -> &'static str {
    match m {
        Model::Paper => "paper",
        Model::Full => "full",
    }
}

impl Plan<'_> {
    /// `dem bed` into `runs/NAME`.
    fn bed(
        &self,
        log: &mut Log<'_>,
        what: &str,
        name: &str,
        model: Model,
        pack: Option<f64>,
    ) -> Result<(), FiguresDemError> {
        let request = BedRequest {
            model: ModelRequest {
                model,
                ..ModelRequest::default()
            },
            width_m: self.bed_w,
            height_m: self.bed_h,
            pack,
            max_time_s: self.request.bed_max_time_s,
            threads: self.request.threads,
            out: self.runs.join(name),
            ..BedRequest::default()
        };
        // `--max-time` only when it is not `dem bed`'s default (the record as before).
        let max_time = self.request.bed_max_time_s;
        let command = format!(
            "sandjumper dem bed --model {} --width {:.4} --height {:.4}{}{} --threads {} --out {}",
            model_name(model),
            self.bed_w,
            self.bed_h,
            pack.map_or(String::new(), |p| format!(" --pack {p:.2}")),
            if max_time == BED_MAX_TIME_S {
                String::new()
            } else {
                format!(" --max-time {max_time}")
            },
            self.request.threads,
            request.out.display()
        );
        let progress = log.progress;
        log.stage(what, command.clone(), &request.out, || {
            let outcome = sandjumper_dem::bed_run::run(&request, progress)
                .map_err(|e| FiguresDemError::of_stage(&command, &e))?;
            progress.note(&outcome.to_string());
            Ok(())
        })
    }

    /// `dem intrude` of jump `kind`'s push-off into `runs/BED`, into `runs/NAME`.
    fn intrude(
        &self,
        log: &mut Log<'_>,
        what: &str,
        name: &str,
        bed: &str,
        kind: &str,
        model: Model,
    ) -> Result<Summary, FiguresDemError> {
        let request = IntrudeRequest {
            bed: Some(self.runs.join(bed)),
            trajectory: Some(
                self.runs
                    .join(format!("jump-{kind}"))
                    .join("trajectory.csv"),
            ),
            episode: Some(Episode::PushOff),
            foot_width_m: self.request.foot_width_m,
            model: ModelRequest {
                model,
                ..ModelRequest::default()
            },
            phi: self.request.phi,
            threads: self.request.threads,
            out: self.runs.join(name),
            ..IntrudeRequest::default()
        };
        let command = format!(
            "sandjumper dem intrude --bed {} --trajectory {} --episode push-off --foot-width {} --model {} --phi {} --threads {} --out {}",
            self.runs.join(bed).display(),
            format_args!(
                "{}/trajectory.csv",
                self.runs.join(format!("jump-{kind}")).display()
            ),
            self.request.foot_width_m,
            model_name(model),
            self.request.phi,
            self.request.threads,
            request.out.display()
        );
        let progress = log.progress;
        log.stage(
            what,
            command.clone(),
            &request.out,
            || match sandjumper_dem::intrude_run::run(&request, progress) {
                Ok(IntrudeOutcome::Finished(s)) => {
                    progress.note(&s.line());
                    Ok(*s)
                }
                Ok(stopped) => Err(FiguresDemError::internal(format!("{command}: {stopped}"))),
                Err(e) => Err(FiguresDemError::of_stage(&command, &e)),
            },
        )
    }

    /// PIV on the intrusion in `run`'s side-wall frames, as its `camera.toml` says, with
    /// `sandjumper piv`'s other defaults, written into `out`; its flow table.
    fn piv(
        &self,
        log: &mut Log<'_>,
        run: &Path,
        out: &Path,
    ) -> Result<Vec<FlowRow>, FiguresDemError> {
        let path = run.join("camera.toml");
        let text = std::fs::read_to_string(&path)
            .map_err(|e| FiguresDemError::internal(format!("{}: {e}", path.display())))?;
        #[derive(serde::Deserialize)]
        struct Camera {
            m_per_px: f64,
            fps: f64,
            origin_px: (f64, f64),
        }
        let cam: Camera = toml::from_str(&text)
            .map_err(|e| FiguresDemError::internal(format!("{}: {e}", path.display())))?;
        let three = |v: f64| format!("{v:.3}").parse().unwrap_or(v);
        let request = PivRequest {
            frames: run.join("frames").display().to_string(),
            foot: Some(run.join("foot.csv")),
            m_per_px: Some(cam.m_per_px),
            fps: Some(cam.fps),
            origin_px: Some((three(cam.origin_px.0), three(cam.origin_px.1))),
            phi: self.request.phi,
            ..PivRequest::default()
        };
        let command = piv_command(&request, out);
        let progress = log.progress;
        log.stage(
            "PIV on the stutter's side-wall frames",
            command.clone(),
            out,
            || {
                let failed =
                    |e: sandjumper_flow::FlowError| FiguresDemError::of_stage(&command, &e);
                request.validate().map_err(failed)?;
                let outcome = sandjumper_flow::run::run(&request, progress).map_err(failed)?;
                outcome.write(out).map_err(failed)?;
                progress.note(outcome.to_string().trim_end());
                Ok(outcome.flow)
            },
        )
    }
}

/// PIV's `request` into `out` as a `sandjumper piv` command line (for the record).
fn piv_command(request: &PivRequest, out: &Path) -> String {
    let (ox, oy) = request.origin_px.unwrap_or((f64::NAN, f64::NAN));
    format!(
        "sandjumper piv {} --m-per-px {} --fps {} --origin {ox:.3},{oy:.3} --foot {} --phi {} --out {}",
        request.frames,
        request.m_per_px.unwrap_or(f64::NAN),
        request.fps.unwrap_or(f64::NAN),
        request.foot.as_deref().unwrap_or(Path::new("")).display(),
        request.phi,
        out.display()
    )
}

/// Replace `from` by `to` in the JSON and TOML files of every run folder under `runs`.
fn rewrite_paths(runs: &Path, from: &str, to: &str) -> Result<(), FiguresDemError> {
    let io =
        |p: &Path, e: std::io::Error| FiguresDemError::internal(format!("{}: {e}", p.display()));
    for dir in std::fs::read_dir(runs).map_err(|e| io(runs, e))? {
        let dir = dir.map_err(|e| io(runs, e))?.path();
        if !dir.is_dir() {
            continue;
        }
        for f in std::fs::read_dir(&dir).map_err(|e| io(&dir, e))? {
            let f = f.map_err(|e| io(&dir, e))?.path();
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ext == "json" || ext == "toml" {
                let text = std::fs::read_to_string(&f).map_err(|e| io(&f, e))?;
                if text.contains(from) {
                    std::fs::write(&f, text.replace(from, to)).map_err(|e| io(&f, e))?;
                }
            }
        }
    }
    Ok(())
}
