//! `sandjumper dem lammps` (the 3-D DEM of the intrusion, run by LAMMPS here or on a Slurm
//! cluster) and `sandjumper dem lammps-read` (a finished run's dumps read back again).

use std::path::{Path, PathBuf};

use clap::Args;

use sandjumper_lammps::outputs::{self, Progress, Summary};
use sandjumper_lammps::spec::{LammpsSpec, Preset};
use sandjumper_output::{CliError, StagedDir};

use super::command::{EpisodeChoice, parse_share};
use super::intruder::Trajectory;
use crate::command::args::parse_positive as positive;

/// The preset scale on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PresetChoice {
    /// The paper's 76 mm foot in ~1 mm grains, a 0.30 m x 0.15 m bed (~15 million grains,
    /// Young's modulus 100 MPa): a cluster job.
    Paper,
    /// A 20 mm foot in ~2 mm grains, a 60 mm x 40 mm bed (~20,000 grains, 5 MPa): minutes on
    /// two cores.
    Small,
}

/// `dem lammps`.
#[derive(Debug, Clone, Args)]
pub struct LammpsArgs {
    /// The scale to start from; the options below change single values.
    #[arg(long, value_enum, default_value = "paper")]
    pub preset: PresetChoice,
    /// Trajectory CSV (`t_s` with `x_f_m`, as `jump --out` writes, or `depth_m`); it must
    /// start at or above the bed's surface.
    #[arg(long, value_name = "CSV", conflicts_with = "speed")]
    pub trajectory: Option<PathBuf>,
    /// Take one episode of a jump's trajectory.csv, shifted to start at the surface:
    /// `push-off`, the foot's last intrusion before the jump's flight.
    #[arg(long, value_enum, value_name = "EPISODE", requires = "trajectory")]
    pub episode: Option<EpisodeChoice>,
    /// Constant intrusion speed instead, m/s (from the surface).
    #[arg(long, value_name = "M_PER_S", value_parser = positive)]
    pub speed: Option<f64>,
    /// Final depth at constant speed, m.
    #[arg(long, value_name = "M", default_value = "0.02", value_parser = positive)]
    pub depth: f64,
    /// Foot diameter, m.
    #[arg(long, value_name = "M", value_parser = positive)]
    pub foot_diameter: Option<f64>,
    /// Mean grain diameter, m (uniform within +-10 %).
    #[arg(long, value_name = "M", value_parser = positive)]
    pub grain_diameter: Option<f64>,
    /// Bed width (square, periodic sides), m.
    #[arg(long, value_name = "M", value_parser = positive)]
    pub bed_width: Option<f64>,
    /// Bed depth, m.
    #[arg(long, value_name = "M", value_parser = positive)]
    pub bed_depth: Option<f64>,
    /// Target packing fraction of the poured bed (0.583 to 0.625, what pouring frictional
    /// spheres gives); also the model's phi (within the presets' 0.57 to 0.62).
    #[arg(long, value_name = "PHI", value_parser = positive)]
    pub phi: Option<f64>,
    /// Young's modulus of the (softened) grains, Pa.
    #[arg(long, value_name = "PA", value_parser = positive)]
    pub youngs_modulus: Option<f64>,
    /// Sliding friction coefficient.
    #[arg(long, value_name = "MU")]
    pub friction: Option<f64>,
    /// Normal restitution coefficient.
    #[arg(long, value_name = "E")]
    pub restitution: Option<f64>,
    /// Dump rate (the PIV camera's), frames/s.
    #[arg(long, value_name = "FPS", value_parser = positive)]
    pub fps: Option<f64>,
    /// Seed of the grains' sizes and start.
    #[arg(long)]
    pub seed: Option<u64>,
    /// The added mass is taken while the foot moves down at least this share of its
    /// fastest speed.
    #[arg(long, value_name = "F", default_value = "0.3", value_parser = parse_share)]
    pub min_speed_ratio: f64,
    /// MPI ranks (`mpiexec -n N lmp`).
    #[arg(long, value_name = "N", default_value = "2",
          value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub ranks: u32,
    /// The LAMMPS executable (default: $SANDJUMPER_LMP, else lmp on PATH).
    #[arg(long, value_name = "PATH")]
    pub lmp: Option<PathBuf>,
    /// The MPI launcher (default: the mpiexec beside lmp, else on PATH).
    #[arg(long, value_name = "PATH")]
    pub mpiexec: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Submit the run to Slurm as one job of --ranks tasks, wait for it and check it.
    #[command(flatten)]
    pub slurm: crate::slurm::JobArgs,
}

/// `dem lammps-read`.
#[derive(Debug, Clone, Args)]
pub struct LammpsReadArgs {
    /// A run's folder (`dem lammps --out`), or its `lammps/` folder.
    #[arg(value_name = "RUN")]
    pub run: PathBuf,
    /// The speed rule of the added mass (see `dem lammps`).
    #[arg(long, value_name = "F", default_value = "0.3", value_parser = parse_share)]
    pub min_speed_ratio: f64,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// The run `a` asks for.
pub fn spec_of(a: &LammpsArgs) -> LammpsSpec {
    let mut s = LammpsSpec::preset(match a.preset {
        PresetChoice::Paper => Preset::Paper,
        PresetChoice::Small => Preset::Small,
    });
    let set = |v: Option<f64>, into: &mut f64| {
        if let Some(v) = v {
            *into = v;
        }
    };
    set(a.foot_diameter, &mut s.foot_diameter_m);
    set(a.grain_diameter, &mut s.grain_diameter_m);
    set(a.bed_width, &mut s.bed_width_m);
    set(a.bed_depth, &mut s.bed_depth_m);
    set(a.phi, &mut s.packing_fraction);
    set(a.youngs_modulus, &mut s.youngs_modulus_pa);
    set(a.friction, &mut s.friction);
    set(a.restitution, &mut s.restitution);
    set(a.fps, &mut s.fps);
    if let Some(seed) = a.seed {
        s.seed = seed;
    }
    s
}

fn trajectory(a: &LammpsArgs) -> Result<Trajectory, CliError> {
    let t = match (&a.trajectory, a.speed) {
        (Some(p), _) => match a.episode {
            Some(EpisodeChoice::PushOff) => Trajectory::push_off_from_csv(p),
            None => Trajectory::from_csv(p, (None, None)),
        }
        .map_err(CliError::input)?,
        (None, Some(v)) => Trajectory::Constant {
            speed_m_s: v,
            start_depth_m: 0.0,
            end_depth_m: a.depth,
        },
        (None, None) => {
            return Err(CliError::input(
                "give the foot's motion: --trajectory CSV [--episode push-off] or --speed M_PER_S",
            ));
        }
    };
    t.check_starts_at_surface().map_err(CliError::input)?;
    Ok(t)
}

/// The stages on a progress bar (on a terminal), and a line per stage on stderr.
struct Bar {
    bar: Option<indicatif::ProgressBar>,
}

impl Progress for Bar {
    fn stage(&mut self, name: &str, steps: u64) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
        eprintln!(
            "dem lammps: {name} ({steps} {})",
            if name == "read" {
                "frames"
            } else {
                "steps at most"
            }
        );
        self.bar = Some(crate::command::progress_bar(
            steps,
            if name == "read" { "frames" } else { "steps" },
        ));
    }

    fn step(&mut self, step: u64) {
        if let Some(b) = &self.bar {
            b.set_position(step);
        }
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        if let Some(b) = self.bar.take() {
            b.finish_and_clear();
        }
    }
}

fn report(s: &Summary, out: &std::path::Path, json: bool) -> Result<(), CliError> {
    if json {
        let text = serde_json::to_string_pretty(s)
            .map_err(|e| CliError::internal(format!("cannot encode the summary: {e}")))?;
        println!("{text}");
        return Ok(());
    }
    println!(
        "3-D DEM ({}): {} grains, settled phi {:.3} (target {:.3}), {} frames at {:.0} fps to {:.1} mm",
        s.lammps_version,
        s.grains,
        s.settled_packing_fraction,
        s.target_packing_fraction,
        s.frames,
        s.fps,
        1e3 * s.max_depth_m
    );
    println!(
        "  added mass / eq. 6 (median)  {:.2}\n  column momentum (peak)       {:.3} g m/s\n  force / F_p(z) (median)      {:.2}\n  peak force                   {:.2} N (overlap ~{:.2} % of a grain)\n  jammed cone                  {}\n  cost                         {:.0} core-s ({:.2e} grain-steps per core-s)",
        s.added_mass_vs_eq6_median,
        1e3 * s.grain_momentum_under_foot_kg_m_s,
        s.force_vs_penetration_force_median,
        s.peak_force_n,
        100.0 * s.peak_overlap_ratio,
        match s.cone_angle_deg {
            Some(a) => format!("{a:.0} deg to the horizontal"),
            None => format!("none ({})", s.cone_note),
        },
        s.core_seconds,
        s.grain_steps_per_core_second
    );
    eprintln!("wrote {}", out.display());
    Ok(())
}

/// Run `dem lammps`.
pub fn run(a: &LammpsArgs) -> Result<(), CliError> {
    let spec = spec_of(a);
    let traj = trajectory(a)?;
    outputs::check_inputs(&spec, &traj)?;
    // LAMMPS is looked for here also before a job is submitted (a cluster's login node sees
    // the shared file system its nodes do): a missing one is refused now, not after the queue.
    let lammps = sandjumper_lammps::lammps::find(a.lmp.as_deref(), a.mpiexec.as_deref())
        .map_err(CliError::input)?;
    if a.slurm.slurm {
        crate::slurm::submit_job(
            "dem-lammps",
            &["dem", "lammps"],
            a.ranks,
            &a.out,
            &["summary.json"],
            &a.slurm,
        )?;
        if a.json && !a.slurm.queue.slurm_no_wait {
            let p = a.out.join("summary.json");
            let text = std::fs::read_to_string(&p)
                .map_err(|e| CliError::internal(format!("{}: {e}", p.display())))?;
            print!("{text}");
        }
        return Ok(());
    }
    // What this run will cost, before it starts (the paper preset is a cluster's job): the
    // settle at most its longest, at the small preset's measured 4 million grain-steps per
    // core-second.
    let grains = spec.grain_count() as f64;
    let steps = spec.max_settle_s / spec.time_step_s()
        + sandjumper_lammps::script::pieces(&spec, &traj)
            .iter()
            .map(|p| p.steps as f64)
            .sum::<f64>();
    eprintln!(
        "dem lammps: {:.0} grains, up to {:.0} steps: up to ~{:.1} core-hours (~{:.1} h on {} \
         rank(s))",
        grains,
        steps,
        grains * steps / 4e6 / 3600.0,
        grains * steps / 4e6 / 3600.0 / f64::from(a.ranks),
        a.ranks
    );
    let staged = StagedDir::create(&a.out)?;
    let mut bar = Bar { bar: None };
    let result = outputs::run(
        &spec,
        &traj,
        &lammps,
        a.ranks,
        a.min_speed_ratio,
        staged.path(),
        &mut bar,
    );
    drop(bar);
    let summary = match result {
        Ok(s) => s,
        Err(e) => return Err(keep_failed_run(staged.path(), &a.out, e)),
    };
    let out = staged.commit()?;
    report(&summary, &out, a.json)
}

/// A run that failed keeps its LAMMPS files (inputs, logs, dumps: hours of a cluster) in
/// `OUT.failed/`, beside where its output would have been, and the error says so; the
/// output folder itself is not written.
fn keep_failed_run(staged: &Path, out: &Path, mut e: CliError) -> CliError {
    let files = staged.join("lammps");
    if !files.join("in.settle").is_file() {
        return e;
    }
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".failed");
    let kept = out.with_file_name(name);
    // Only an earlier failed run of ours is replaced.
    if kept.join("in.settle").is_file() {
        let _ = std::fs::remove_dir_all(&kept);
    }
    if !kept.exists() && std::fs::rename(&files, &kept).is_ok() {
        e.message += &format!(
            "\nthe run's LAMMPS files (inputs, logs, data, dumps) are kept in {}",
            kept.display()
        );
        // The log the message names moved with them.
        e.message = e
            .message
            .replace(&files.display().to_string(), &kept.display().to_string());
    }
    e
}

/// Run `dem lammps-read`.
pub fn run_read(a: &LammpsReadArgs) -> Result<(), CliError> {
    let dir = if a.run.join("run.toml").is_file() {
        a.run.clone()
    } else {
        a.run.join("lammps")
    };
    // The output must not be the run, or hold it, or lie inside it: replacing it would delete
    // the run's dumps.
    // A path that does not exist yet: its parent's real path and its name (a link in the
    // path must not hide that it points into the run).
    let canon = |p: &Path| {
        std::fs::canonicalize(p).unwrap_or_else(|_| {
            let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
            match (abs.parent(), abs.file_name()) {
                (Some(d), Some(n)) => std::fs::canonicalize(d)
                    .map(|d| d.join(n))
                    .unwrap_or(abs.clone()),
                _ => abs.clone(),
            }
        })
    };
    let (run, out) = (canon(&a.run), canon(&a.out));
    if run.starts_with(&out) || out.starts_with(&run) {
        return Err(CliError::input(format!(
            "--out {} is the run {} or holds it or lies in it (allowed: a folder apart from the \
             run: writing it would replace the run's files)",
            a.out.display(),
            a.run.display()
        )));
    }
    let staged = StagedDir::create(&a.out)?;
    let mut bar = Bar { bar: None };
    let summary = outputs::analyse(&dir, staged.path(), a.min_speed_ratio, &mut bar)?;
    drop(bar);
    let out = staged.commit()?;
    report(&summary, &out, a.json)
}
