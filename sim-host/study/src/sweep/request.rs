//! `sandjumper sweep` and `merge` as calls: typed requests, [`run`] and [`merge`], and
//! outcomes that write the sweep's folder (`sweep.csv`, `failures.csv`, `sweep.toml`, the
//! parameters, the figures).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_model::resolve::{ParamsFile, resolve_params};
use sandjumper_model::trajectory::kind_name;
use sandjumper_output::plot::save_figure;
use sandjumper_output::{Progress, StagedDir};

use super::drive::run_driven;
use super::merge::{merge_shards, read_sweep_dir};
use super::{
    FAILURE_HEADER, ROW_HEADER, ShardMeta, ShardSpec, SpecMeta, SweepDrive, SweepMeta,
    SweepOutcome, SweepSpec, files, plot, write_csv,
};
use crate::StudyError;

/// A sweep: every combination of the axes, on this machine, whole or one shard.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SweepRequest {
    /// The axes (kinds, models, packing fractions, frequencies, delays), the tolerance and
    /// the drive.
    pub spec: SweepSpec,
    /// Parameter overrides on top of each packing fraction's preset.
    pub params: Option<ParamsFile>,
    /// Worker threads (None: one per core).
    pub threads: Option<usize>,
    /// Run only this shard (None: the whole sweep).
    pub shard: Option<ShardSpec>,
}

/// The command line's defaults; `kinds` and `freqs_hz` have none there (single, 10 Hz here).
impl Default for SweepSpec {
    fn default() -> Self {
        Self {
            kinds: vec![JumpKind::Single],
            models: vec![ModelName::Eq4],
            phis: vec![0.57],
            freqs_hz: vec![10.0],
            taus_s: vec![0.0],
            rtol: 1e-8,
            drive: SweepDrive::Kinematic,
        }
    }
}

impl SweepRequest {
    /// The parameters of each packing fraction (keyed by `phi.to_bits()`), the overrides on top
    /// of each preset, and their TOML text (what the sweep's hash covers).
    pub fn resolved_params(&self) -> Result<(HashMap<u64, Params>, String), StudyError> {
        resolve_sweep_params(&self.spec, self.params.as_ref())
    }

    /// Refuse bad parameters (and, in a build without the rig, a sweep through sil) before
    /// anything runs.
    pub fn validate(&self) -> Result<(), StudyError> {
        #[cfg(not(feature = "rig"))]
        if self.spec.drive != super::SweepDrive::Kinematic {
            return Err(StudyError::Input(crate::error::without_rig(
                "sweep --link sil",
            )));
        }
        self.resolved_params().map(drop)
    }
}

/// The parameters of each packing fraction of `spec` (keyed by `phi.to_bits()`), with the
/// overrides `file` on top of each preset, and their TOML text.
pub fn resolve_sweep_params(
    spec: &SweepSpec,
    file: Option<&ParamsFile>,
) -> Result<(HashMap<u64, Params>, String), StudyError> {
    let mut params_by_phi: HashMap<u64, Params> = HashMap::new();
    let mut params_text = String::new();
    for &phi in &spec.phis {
        let p = resolve_params(phi, file)?;
        params_text += &format!("# phi = {phi}\n{}", p.to_toml());
        params_by_phi.insert(phi.to_bits(), p);
    }
    Ok((params_by_phi, params_text))
}

/// A swept (shard of a) sweep: its `sweep.toml`, rows and failures, and the parameters.
#[derive(Debug, Clone)]
pub struct SweepRunOutcome {
    /// `sweep.toml`.
    pub meta: SweepMeta,
    /// Rows and failures, in combination order.
    pub outcome: SweepOutcome,
    /// The parameters of each packing fraction (keyed by `phi.to_bits()`).
    pub params_by_phi: HashMap<u64, Params>,
    /// The packing fractions, in the request's order.
    pub phis: Vec<f64>,
    /// Worker threads used.
    pub threads: usize,
    /// Wall time of the jumps, s.
    pub elapsed_s: f64,
}

/// A sweep's folder as written: where, and the figures drawn (file names).
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenSweep {
    /// The folder.
    pub dir: PathBuf,
    /// The figures' file names (none for a shard or a sweep without rows).
    pub plots: Vec<String>,
}

/// The reason of a jump a stopped sweep did not run, and the start of the stopped sweep's error.
pub const INTERRUPTED: &str = "interrupted";

/// Run the sweep `request` asks for; one `progress` step per jump ("jumps"). When
/// `progress` says the caller stopped it (Ctrl-C), the jumps not yet started are not run and
/// the sweep ends as an error saying how many were done.
pub fn run(request: &SweepRequest, progress: &dyn Progress) -> Result<SweepRunOutcome, StudyError> {
    let (params_by_phi, params_text) = request.resolved_params()?;
    let spec = request.spec.clone();
    let shard = request.shard.unwrap_or(ShardSpec::WHOLE);
    let combos = spec.combinations();
    let total = combos.len();
    let slice = shard.slice(total);
    let threads = request
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let started = Instant::now();
    progress.start("jumps", Some(slice.len() as u64));
    let outcome = run_driven(
        &combos[slice.clone()],
        threads,
        // The jumps a stop skips are not counted as done.
        &|| {
            if !progress.cancelled() {
                progress.advance(1);
            }
        },
        spec.drive,
        spec.rtol,
        |c| {
            // Stopped by the caller (Ctrl-C): the jumps not started are not run.
            if progress.cancelled() {
                return Err(INTERRUPTED.to_string());
            }
            Ok(&params_by_phi[&c.phi.to_bits()])
        },
    )
    .map_err(StudyError::Internal)?;
    progress.finish();
    if progress.cancelled() {
        let skipped = outcome
            .failures
            .iter()
            .filter(|f| f.error == INTERRUPTED)
            .count();
        return Err(StudyError::Internal(format!(
            "{INTERRUPTED}: {} of {} jumps done",
            slice.len() - skipped,
            slice.len()
        )));
    }
    let file = request.params.as_ref();
    let meta = SweepMeta {
        format: SweepMeta::FORMAT.into(),
        spec_hash: spec.hash(&params_text),
        total_combinations: total,
        shard: ShardMeta {
            index: shard.index,
            count: shard.count,
            first: slice.start,
            end: slice.end,
            rows: outcome.rows.len(),
            failures: outcome.failures.len(),
        },
        spec: SpecMeta {
            kinds: spec
                .kinds
                .iter()
                .map(|&k| kind_name(k).to_string())
                .collect(),
            models: spec.models.iter().map(|m| m.as_str().to_string()).collect(),
            phi: spec.phis.clone(),
            freq_hz: spec.freqs_hz.clone(),
            tau_s: spec.taus_s.clone(),
            rtol: spec.rtol,
            params_file: file.map(|f| f.path.display().to_string()),
            params_overrides: file.map(|f| f.text.clone()),
            drive: spec.drive.name(),
        },
    };
    Ok(SweepRunOutcome {
        meta,
        outcome,
        params_by_phi,
        phis: spec.phis,
        threads,
        elapsed_s: started.elapsed().as_secs_f64(),
    })
}

/// File name of the resolved parameters for one packing fraction of a multi-phi sweep.
pub fn params_file_name(phi: f64, several: bool) -> String {
    if several {
        format!("params-phi-{phi}.toml")
    } else {
        "params.toml".into()
    }
}

impl SweepRunOutcome {
    /// Whether this is the whole sweep (not one shard of it).
    pub fn is_whole(&self) -> bool {
        self.meta.shard.count == 1
    }

    /// Write the folder `dir` (created, or replacing an earlier sandjumper output).
    pub fn write(&self, dir: &Path) -> Result<WrittenSweep, StudyError> {
        let staged = StagedDir::create(dir)?;
        let plots = self.write_into(&staged)?;
        Ok(WrittenSweep {
            dir: staged.commit()?,
            plots,
        })
    }

    /// Write the folder's files into a folder being staged; the figures' file names (a
    /// shard's figures would show a fraction of the sweep: [`merge`] draws them).
    pub fn write_into(&self, staged: &StagedDir) -> Result<Vec<String>, StudyError> {
        write_sweep_files(staged.path(), &self.meta, &self.outcome)?;
        let several = self.phis.len() > 1;
        for &phi in &self.phis {
            staged.write_text(
                &params_file_name(phi, several),
                &self.params_by_phi[&phi.to_bits()].to_toml(),
            )?;
        }
        if self.is_whole() {
            write_sweep_plots(staged.path(), &self.outcome)
        } else {
            Ok(Vec::new())
        }
    }

    /// The line the command line prints when the folder `dir` is written with the figures
    /// `plots`: how many jumps (of which shard), how long, on how many threads, what was written.
    pub fn report(&self, dir: &Path, plots: &[String]) -> String {
        let n = self.meta.shard.end - self.meta.shard.first;
        let what = if self.is_whole() {
            format!("{n} jumps")
        } else {
            let (index, count) = (self.meta.shard.index, self.meta.shard.count);
            let total = self.meta.total_combinations;
            format!("shard {index}/{count}: {n} of {total} jumps")
        };
        let params = if self.phis.len() > 1 {
            "-phi-*.toml"
        } else {
            ".toml"
        };
        format!(
            "swept {what} in {:.2} s on {} thread(s); wrote {}/ (sweep.csv, failures.csv, sweep.toml, params{params}{})",
            self.elapsed_s,
            self.threads,
            dir.display(),
            plots.iter().map(|p| format!(", {p}")).collect::<String>()
        )
    }

    /// What the user should know after the sweep: how many jumps failed, how many ask more
    /// force than the motor has (one line each, `warning: ...` / `note: ...`).
    pub fn warnings(&self) -> Vec<String> {
        let outcome = &self.outcome;
        let mut lines = Vec::new();
        if let Some(first) = outcome.failures.first() {
            lines.push(format!(
                "warning: {} jump(s) failed and have no row in sweep.csv; see failures.csv (first: {} {} f = {} Hz: {})",
                outcome.failures.len(),
                first.kind,
                first.model,
                first.freq_hz,
                first.error
            ));
        }
        let over = outcome
            .rows
            .iter()
            .filter(|r| {
                self.params_by_phi
                    .get(&r.phi.to_bits())
                    .is_some_and(|p| r.peak_motor_force_n > p.drive.peak_force_n)
            })
            .count();
        if over > 0 {
            lines.push(format!(
                "note: {over} jump(s) ask more than the motor's peak force (drive.peak_force_n); see the peak_motor_force_n column"
            ));
        }
        lines
    }
}

/// Write `sweep.csv`, `failures.csv` and `sweep.toml` into `dir`.
fn write_sweep_files(dir: &Path, meta: &SweepMeta, out: &SweepOutcome) -> Result<(), StudyError> {
    write_csv(&dir.join(files::ROWS), &out.rows, &ROW_HEADER).map_err(StudyError::Internal)?;
    write_csv(&dir.join(files::FAILURES), &out.failures, &FAILURE_HEADER)
        .map_err(StudyError::Internal)?;
    let toml = toml::to_string(meta)
        .map_err(|e| StudyError::internal(format!("cannot encode {}: {e}", files::META)))?;
    std::fs::write(dir.join(files::META), toml)
        .map_err(|e| StudyError::internal(format!("cannot write {}: {e}", files::META)))
}

/// Draw the sweep figures (height vs frequency; vs delay when it varies) into `dir`; the
/// file names written.
fn write_sweep_plots(dir: &Path, out: &SweepOutcome) -> Result<Vec<String>, StudyError> {
    let mut written = Vec::new();
    if out.rows.is_empty() {
        return Ok(written);
    }
    let mut save = |fig: &dyn Fn(&Path, &Path) -> Result<(), StudyError>, stem: &str| {
        let (png, svg) = (format!("{stem}.png"), format!("{stem}.svg"));
        fig(&dir.join(&png), &dir.join(&svg))?;
        written.extend([png, svg]);
        Ok::<(), StudyError>(())
    };
    let freq = plot::height_vs_freq(&out.rows, "Jump height vs forcing frequency");
    save(
        &|png, svg| Ok(save_figure(&freq, png, Some(svg))?),
        "height_vs_freq",
    )?;
    if let Some(fig) = plot::height_vs_tau(&out.rows, "Delayed stutter: jump height vs delay") {
        save(
            &|png, svg| Ok(save_figure(&fig, png, Some(svg))?),
            "height_vs_tau",
        )?;
    }
    Ok(written)
}

/// Joining the shard directories of one sweep (`sandjumper merge`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MergeRequest {
    /// Shard directories written by a sharded sweep (all of them, any order).
    pub dirs: Vec<PathBuf>,
    /// Output directory for the merged sweep (refused when it is one of `dirs`).
    pub out: PathBuf,
}

impl MergeRequest {
    /// Refuse an output directory that is one of the shards.
    pub fn validate(&self) -> Result<(), StudyError> {
        let out_canon = std::fs::canonicalize(&self.out).ok();
        if out_canon.is_some()
            && self
                .dirs
                .iter()
                .any(|d| std::fs::canonicalize(d).ok() == out_canon)
        {
            return Err(StudyError::input(format!(
                "--out `{}` is one of the shard directories: write the merged sweep elsewhere",
                self.out.display()
            )));
        }
        Ok(())
    }
}

/// A merged sweep, in memory: its `sweep.toml`, rows and failures, and the parameter files
/// (identical in every shard: part of the spec hash), by name.
#[derive(Debug, Clone)]
pub struct MergeOutcome {
    /// `sweep.toml` of the whole sweep.
    pub meta: SweepMeta,
    /// Rows and failures, in combination order.
    pub outcome: SweepOutcome,
    /// Shards merged.
    pub shards: usize,
    /// The parameter files of the first shard (`params*.toml`): name and path.
    pub params_files: Vec<(String, PathBuf)>,
}

/// Read and join the shards `request` names (refusing shards of different sweeps, missing or
/// overlapping ones).
pub fn merge(request: &MergeRequest, _progress: &dyn Progress) -> Result<MergeOutcome, StudyError> {
    let input = |e: super::merge::MergeError| StudyError::Input(e.0);
    request.validate()?;
    let mut shards = Vec::with_capacity(request.dirs.len());
    for dir in &request.dirs {
        shards.push(read_sweep_dir(dir).map_err(input)?);
    }
    let Some(first_dir) = shards.first().map(|s| s.dir.clone()) else {
        return Err(StudyError::input("merge: no shard directories"));
    };
    let count = shards.len();
    let (meta, outcome) = merge_shards(shards).map_err(input)?;
    let entries = std::fs::read_dir(&first_dir)
        .map_err(|e| StudyError::input(format!("cannot read `{}`: {e}", first_dir.display())))?;
    let mut params_files = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("params") && name.ends_with(".toml") {
            params_files.push((name, entry.path()));
        }
    }
    Ok(MergeOutcome {
        meta,
        outcome,
        shards: count,
        params_files,
    })
}

impl MergeOutcome {
    /// The lines the command line prints once the merged folder is `written`: what was merged
    /// and written, and a warning when jumps failed.
    pub fn report(&self, written: &WrittenSweep) -> Vec<String> {
        let (rows, failures) = (self.outcome.rows.len(), self.outcome.failures.len());
        let mut lines = vec![format!(
            "merged {} shard(s): {rows} rows, {failures} failures; wrote {}/ (sweep.csv, failures.csv, sweep.toml, params{})",
            self.shards,
            written.dir.display(),
            written
                .plots
                .iter()
                .map(|p| format!(", {p}"))
                .collect::<String>()
        )];
        if failures > 0 {
            lines.push(format!(
                "warning: {failures} jump(s) of the sweep failed; see failures.csv"
            ));
        }
        lines
    }

    /// Write the merged sweep's folder `dir` (created, or replacing an earlier sandjumper
    /// output), figures included.
    pub fn write(&self, dir: &Path) -> Result<WrittenSweep, StudyError> {
        let staged = StagedDir::create(dir)?;
        write_sweep_files(staged.path(), &self.meta, &self.outcome)?;
        for (name, path) in &self.params_files {
            std::fs::copy(path, staged.file(name)).map_err(|e| {
                StudyError::internal(format!("cannot copy `{}`: {e}", path.display()))
            })?;
        }
        let plots = write_sweep_plots(staged.path(), &self.outcome)?;
        Ok(WrittenSweep {
            dir: staged.commit()?,
            plots,
        })
    }
}
