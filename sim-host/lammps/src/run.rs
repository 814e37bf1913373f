//! `dem lammps` and `dem lammps-read` as calls: a typed request, `run`/`read` with a
//! progress sink, and the run's summary as the outcome. LAMMPS itself stays a process
//! (`mpiexec -n N lmp`); a run works in `OUT.unfinished/` until it is done, and one that
//! fails or is killed is resumed from there by the same request.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use sandjumper_dem::intrude_run::Episode;
use sandjumper_dem::intruder::Trajectory;
use sandjumper_output::{Progress, StagedDir};
use sandjumper_slurm::{CommandJobOutcome, QueueOptions};

use crate::error::LammpsError;
use crate::lammps::{Lammps, Launcher};
use crate::outputs::{self, RestartEvery, Summary};
use crate::spec::{DumpFormat, LammpsSpec, Preset};

/// Grain-steps per core-second of the settle (pour and settle), measured on the small preset on
/// 2 ranks split in x and y: 20,400 grains, 23,000 steps in 49.3-50.3 s (2026-11-29).
pub const SETTLE_GRAIN_STEPS_PER_CORE_S: f64 = 4.7e6;

/// Grain-steps per core-second of the intrusion (the foot moved, force and dumps written),
/// measured in the same runs: 20,000 steps in 68.2-69.2 s.
pub const INTRUSION_GRAIN_STEPS_PER_CORE_S: f64 = 3.0e6;

/// What a run costs at most, before it starts: each stage's grain-steps at its measured rate
/// ([`SETTLE_GRAIN_STEPS_PER_CORE_S`], [`INTRUSION_GRAIN_STEPS_PER_CORE_S`]); the settle at
/// its longest (`max_settle_s`; none with `--bed`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cost {
    /// Grains.
    pub grains: f64,
    /// Steps of the settle, at most.
    pub settle_steps: f64,
    /// Steps of the intrusion.
    pub intrusion_steps: f64,
    /// Core-hours of the settle, at most.
    pub settle_core_hours: f64,
    /// Core-hours of the intrusion.
    pub intrusion_core_hours: f64,
    /// MPI ranks.
    pub ranks: u32,
}

impl fmt::Display for Cost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let total = self.settle_core_hours + self.intrusion_core_hours;
        write!(
            f,
            "dem lammps: {:.0} grains; the settle up to {:.0} steps (~{:.1} core-hours at most), \
             the intrusion {:.0} steps (~{:.1} core-hours): up to ~{:.1} core-hours (~{:.1} h on \
             {} rank(s)), at the rates measured on the small preset",
            self.grains,
            self.settle_steps,
            self.settle_core_hours,
            self.intrusion_steps,
            self.intrusion_core_hours,
            total,
            total / f64::from(self.ranks),
            self.ranks
        )
    }
}

/// Most MPI ranks a run takes ([`LammpsRequest::ranks`]).
pub const MAX_RANKS: u32 = 100_000;

/// A 3-D intrusion to run with LAMMPS: a preset scale with single values changed, and the
/// foot's motion.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct LammpsRequest {
    /// The scale to start from; the options below change single values.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "paper"))]
    pub preset: Preset,
    /// Trajectory CSV (`t_s` with `x_f_m`, as `jump --out` writes, or `depth_m`); it must
    /// start at or above the bed's surface.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "CSV", conflicts_with = "speed_m_s")
    )]
    pub trajectory: Option<PathBuf>,
    /// The foot diameter the trajectory was for (the robot's: 0.076), m: the motion is scaled
    /// to this run's foot at the same Froude number (depths by the diameters' ratio, times by
    /// its square root), so a reduced-scale run keeps the paper's depth over radius and Froude
    /// number `v^2 / (g R)` (its speeds are the square root of the size ratio times the paper's).
    #[cfg_attr(feature = "clap", arg(long = "scale-from-foot", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub scale_from_foot_m: Option<f64>,
    /// Take one episode of a jump's trajectory.csv, shifted to start at the surface:
    /// `push-off`, the foot's last intrusion before the jump's flight.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_enum, value_name = "EPISODE", requires = "trajectory")
    )]
    pub episode: Option<Episode>,
    /// Constant intrusion speed instead, m/s (from the surface).
    #[cfg_attr(feature = "clap", arg(long = "speed", value_name = "M_PER_S", value_parser = sandjumper_output::parse::parse_positive))]
    pub speed_m_s: Option<f64>,
    /// Final depth at constant speed, m.
    #[cfg_attr(feature = "clap", arg(long = "depth", value_name = "M", default_value = "0.02", value_parser = sandjumper_output::parse::parse_positive))]
    pub depth_m: f64,
    /// Foot diameter, m.
    #[cfg_attr(feature = "clap", arg(long = "foot-diameter", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub foot_diameter_m: Option<f64>,
    /// Mean grain diameter, m (uniform within +-10 %).
    #[cfg_attr(feature = "clap", arg(long = "grain-diameter", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub grain_diameter_m: Option<f64>,
    /// Bed width (square, periodic sides), m.
    #[cfg_attr(feature = "clap", arg(long = "bed-width", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub bed_width_m: Option<f64>,
    /// Bed depth, m.
    #[cfg_attr(feature = "clap", arg(long = "bed-depth", value_name = "M", value_parser = sandjumper_output::parse::parse_positive))]
    pub bed_depth_m: Option<f64>,
    /// Target packing fraction of the poured bed (0.557 to 0.625: pouring frictional spheres
    /// gives 0.583 and up, rolling friction below); also the model's phi (within the
    /// presets' 0.57 to 0.62).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PHI", value_parser = sandjumper_output::parse::parse_positive))]
    pub phi: Option<f64>,
    /// Young's modulus of the (softened) grains, Pa.
    #[cfg_attr(feature = "clap", arg(long = "youngs-modulus", value_name = "PA", value_parser = sandjumper_output::parse::parse_positive))]
    pub youngs_modulus_pa: Option<f64>,
    /// Sliding friction coefficient.
    #[cfg_attr(feature = "clap", arg(long, value_name = "MU"))]
    pub friction: Option<f64>,
    /// Normal restitution coefficient.
    #[cfg_attr(feature = "clap", arg(long, value_name = "E"))]
    pub restitution: Option<f64>,
    /// The paper's PIV geometry: a frictional sidewall with a half foot against it; the run
    /// also renders the wall's grains as the camera sees them and measures the column by
    /// PIV beside the exact 3-D column (`sidewall.csv`).
    #[cfg_attr(feature = "clap", arg(long))]
    pub sidewall: bool,
    /// A settled bed to reuse instead of pouring one (about 90 % of a run's cost): an
    /// earlier run's `lammps/settled.data`, or that run's folder. It must have been settled
    /// with the same preset and options (its box and grain sizes are checked).
    #[cfg_attr(feature = "clap", arg(long, value_name = "FILE"))]
    pub bed: Option<PathBuf>,
    /// Frames between dumps of the grains near the axis: 1 every frame, N every Nth, 0 none
    /// (the column's momentum comes from LAMMPS at every frame whatever this is; the cone
    /// from the dumped frames). A paper-sized run's dumps at every frame are ~8 GB.
    #[cfg_attr(
        feature = "clap",
        arg(long = "dump-every", value_name = "FRAMES", default_value = "1")
    )]
    pub dump_every_frames: u64,
    /// How LAMMPS writes the dumps: `gzip` (`dump custom/gz`, about 40 % of the bytes,
    /// read back as a stream) or `text`. Default: gzip where the LAMMPS found has the
    /// COMPRESS package, else text.
    #[cfg_attr(
        feature = "clap",
        arg(long = "dump-format", value_enum, value_name = "FORMAT")
    )]
    pub dump_format: Option<DumpFormat>,
    /// Dump rate (the PIV camera's), frames/s.
    #[cfg_attr(feature = "clap", arg(long, value_name = "FPS", value_parser = sandjumper_output::parse::parse_positive))]
    pub fps: Option<f64>,
    /// Seed of the grains' sizes and start.
    #[cfg_attr(feature = "clap", arg(long))]
    pub seed: Option<u64>,
    /// The added mass is taken while the foot moves down at least this share of its
    /// fastest speed.
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", default_value = "0.3", value_parser = sandjumper_dem::intrude_run::parse_share))]
    pub min_speed_ratio: f64,
    /// Wall minutes between restart files (each stage writes one about this often, at the
    /// rates measured on the small preset; only the newest two are kept). A run killed (a
    /// time limit, a lost node) resumes from the newest when the same command is given the
    /// same output again.
    #[cfg_attr(feature = "clap", arg(long = "restart-every", value_name = "MINUTES", default_value = "15", value_parser = sandjumper_output::parse::parse_positive))]
    pub restart_every_min: f64,
    /// MPI ranks (`mpiexec -n N lmp`).
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", default_value = "2", value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RANKS))))]
    pub ranks: u32,
    /// The LAMMPS executable (default: $SANDJUMPER_LMP, else lmp on PATH).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PATH"))]
    pub lmp: Option<PathBuf>,
    /// The MPI launcher (default: the mpiexec beside lmp, else on PATH).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PATH"))]
    pub mpiexec: Option<PathBuf>,
    /// How the ranks start: `mpiexec` (auto: inside a Slurm job MPICH's Hydra starts its
    /// proxies through `srun`), or `srun --mpi=pmi2` itself for an MPI built for it.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "auto"))]
    pub launcher: Launcher,
    /// Output directory.
    #[cfg_attr(feature = "clap", arg(skip))]
    pub out: PathBuf,
}

impl Default for LammpsRequest {
    fn default() -> Self {
        Self {
            preset: Preset::Paper,
            trajectory: None,
            scale_from_foot_m: None,
            episode: None,
            speed_m_s: None,
            depth_m: 0.02,
            foot_diameter_m: None,
            grain_diameter_m: None,
            bed_width_m: None,
            bed_depth_m: None,
            phi: None,
            youngs_modulus_pa: None,
            friction: None,
            restitution: None,
            sidewall: false,
            dump_every_frames: 1,
            dump_format: None,
            bed: None,
            fps: None,
            seed: None,
            min_speed_ratio: 0.3,
            restart_every_min: 15.0,
            ranks: 2,
            lmp: None,
            mpiexec: None,
            launcher: Launcher::Auto,
            out: PathBuf::new(),
        }
    }
}

/// A finished run read back: its summary (`summary.json`, what `--json` prints) and its
/// folder.
#[derive(Clone, Debug, Serialize)]
pub struct LammpsOutcome {
    /// The summary.
    #[serde(flatten)]
    pub summary: Summary,
    /// The folder written.
    #[serde(skip)]
    pub out: PathBuf,
}

impl LammpsOutcome {
    /// The summary as pretty JSON (what `dem lammps --json` prints).
    pub fn summary_json(&self) -> Result<String, LammpsError> {
        serde_json::to_string_pretty(&self.summary)
            .map_err(|e| LammpsError::internal(format!("cannot encode the summary: {e}")))
    }
}

impl fmt::Display for LammpsOutcome {
    /// The two-part summary `dem lammps` prints on stdout.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.summary;
        writeln!(
            f,
            "3-D DEM ({}): {} grains, settled phi {:.3} (target {:.3}), {} frames at {:.0} fps to {:.1} mm",
            s.lammps_version,
            s.grains,
            s.settled_packing_fraction,
            s.target_packing_fraction,
            s.frames,
            s.fps,
            1e3 * s.max_depth_m
        )?;
        write!(
            f,
            "  added mass / eq. 6 (median)  {:.2}\n  column momentum (peak)       {:.3} g m/s (LAMMPS's own measure within {:.1e} of the dumps')\n  force / F_p(z) (median)      {:.2}\n  peak force                   {:.2} N (overlap ~{:.2} % of a grain)\n  jammed cone                  {}\n  cost                         {:.0} core-s ({:.2e} grain-steps per core-s)",
            s.added_mass_vs_eq6_median,
            1e3 * s.grain_momentum_under_foot_kg_m_s,
            s.column_lammps_vs_dumps_max_diff,
            s.force_vs_penetration_force_median,
            s.peak_force_n,
            100.0 * s.peak_overlap_ratio,
            match s.cone_angle_deg {
                Some(a) => format!("{a:.0} deg to the horizontal"),
                None => format!("none ({})", s.cone_note),
            },
            s.core_seconds,
            s.grain_steps_per_core_second
        )
    }
}

impl LammpsRequest {
    /// The run this request asks for: the preset with its single values changed.
    pub fn spec(&self) -> LammpsSpec {
        let mut s = LammpsSpec::preset(self.preset);
        let set = |v: Option<f64>, into: &mut f64| {
            if let Some(v) = v {
                *into = v;
            }
        };
        set(self.foot_diameter_m, &mut s.foot_diameter_m);
        set(self.grain_diameter_m, &mut s.grain_diameter_m);
        set(self.bed_width_m, &mut s.bed_width_m);
        set(self.bed_depth_m, &mut s.bed_depth_m);
        set(self.phi, &mut s.packing_fraction);
        set(self.youngs_modulus_pa, &mut s.youngs_modulus_pa);
        set(self.friction, &mut s.friction);
        set(self.restitution, &mut s.restitution);
        set(self.fps, &mut s.fps);
        if let Some(seed) = self.seed {
            s.seed = seed;
        }
        s.sidewall = self.sidewall;
        s.dump_every_frames = self.dump_every_frames;
        if let Some(f) = self.dump_format {
            s.dump_format = f;
        }
        s
    }

    /// The foot's motion: the trajectory file (or its episode) or a constant speed.
    pub fn trajectory(&self) -> Result<Trajectory, LammpsError> {
        let t = match (&self.trajectory, self.speed_m_s) {
            (Some(p), _) => match self.episode {
                Some(Episode::PushOff) => Trajectory::push_off_from_csv(p),
                None => Trajectory::from_csv(p, (None, None)),
            }
            .map_err(LammpsError::Input)?,
            (None, Some(v)) => Trajectory::Constant {
                speed_m_s: v,
                start_depth_m: 0.0,
                end_depth_m: self.depth_m,
            },
            (None, None) => {
                return Err(LammpsError::input(
                    "give the foot's motion: --trajectory CSV [--episode push-off] or --speed M_PER_S",
                ));
            }
        };
        let t = match self.scale_from_foot_m {
            Some(d0) => t.froude_scaled(self.spec().foot_diameter_m / d0),
            None => t,
        };
        t.check_starts_at_surface().map_err(LammpsError::Input)?;
        Ok(t)
    }

    /// The words of `sandjumper dem lammps` that ask for this run, without `--ranks` and
    /// `--out` (a Slurm job adds them; [`submit`]): every value this request sets, so the job
    /// runs what was checked here (the motion [`LammpsRequest::trajectory`] takes: the file,
    /// else the speed). Values as `--flag=value`. A path that is not UTF-8 text is refused (a
    /// job script could not pass it on).
    pub fn job_arguments(&self) -> Result<Vec<String>, LammpsError> {
        // Every field named: one added later must be carried here too (or said not to be).
        let Self {
            preset,
            trajectory,
            scale_from_foot_m,
            episode,
            speed_m_s,
            depth_m,
            foot_diameter_m,
            grain_diameter_m,
            bed_width_m,
            bed_depth_m,
            phi,
            youngs_modulus_pa,
            friction,
            restitution,
            sidewall,
            dump_every_frames,
            dump_format,
            bed,
            fps,
            seed,
            min_speed_ratio,
            restart_every_min,
            ranks: _,
            lmp,
            mpiexec,
            launcher,
            out: _,
        } = self;
        let mut args: Vec<String> = vec!["dem".into(), "lammps".into()];
        args.push(format!("--preset={}", preset.name()));
        let path = |flag: &str, p: &Option<PathBuf>, args: &mut Vec<String>| {
            if let Some(p) = p {
                args.push(format!("{flag}={}", sandjumper_slurm::path_text(p, flag)?));
            }
            Ok::<(), LammpsError>(())
        };
        path("--trajectory", trajectory, &mut args)?;
        path("--bed", bed, &mut args)?;
        if trajectory.is_some() {
            match episode {
                Some(Episode::PushOff) => args.push("--episode=push-off".into()),
                None => {}
            }
        }
        let speed = if trajectory.is_some() {
            None
        } else {
            *speed_m_s
        };
        let values = [
            ("--speed", speed),
            ("--scale-from-foot", *scale_from_foot_m),
            ("--depth", Some(*depth_m)),
            ("--foot-diameter", *foot_diameter_m),
            ("--grain-diameter", *grain_diameter_m),
            ("--bed-width", *bed_width_m),
            ("--bed-depth", *bed_depth_m),
            ("--phi", *phi),
            ("--youngs-modulus", *youngs_modulus_pa),
            ("--friction", *friction),
            ("--restitution", *restitution),
            ("--fps", *fps),
            ("--min-speed-ratio", Some(*min_speed_ratio)),
            ("--restart-every", Some(*restart_every_min)),
        ];
        // `{}` writes the shortest text that reads back as the same f64.
        args.extend(
            values
                .iter()
                .filter_map(|(flag, v)| v.map(|v| format!("{flag}={v}"))),
        );
        if let Some(seed) = seed {
            args.push(format!("--seed={seed}"));
        }
        if *sidewall {
            args.push("--sidewall".into());
        }
        args.push(format!("--dump-every={dump_every_frames}"));
        if let Some(f) = dump_format {
            args.push(format!("--dump-format={}", f.name()));
        }
        path("--lmp", lmp, &mut args)?;
        path("--mpiexec", mpiexec, &mut args)?;
        args.push(format!("--launcher={}", launcher.name()));
        Ok(args)
    }

    /// Check the request before anything runs: the motion, the values, the foot kept above
    /// the floor.
    pub fn validate(&self) -> Result<(), LammpsError> {
        self.checked().map(drop)
    }

    /// [`LammpsRequest::validate`], giving back the run and the motion it checked.
    fn checked(&self) -> Result<(LammpsSpec, Trajectory), LammpsError> {
        sandjumper_dem::intrude_run::check_motion(
            self.trajectory.is_some(),
            self.speed_m_s.is_some(),
            self.episode.is_some(),
            false,
        )
        .map_err(LammpsError::input)?;
        if !(0.0..=1.0).contains(&self.min_speed_ratio) {
            return Err(LammpsError::input(format!(
                "--min-speed-ratio {} not allowed (allowed: 0 to 1)",
                self.min_speed_ratio
            )));
        }
        if !(self.restart_every_min.is_finite() && self.restart_every_min > 0.0) {
            return Err(LammpsError::input(format!(
                "--restart-every {} not allowed (allowed: minutes above 0)",
                self.restart_every_min
            )));
        }
        if !(1..=MAX_RANKS).contains(&self.ranks) {
            return Err(LammpsError::input(format!(
                "--ranks {} not allowed (allowed: 1 to {MAX_RANKS})",
                self.ranks
            )));
        }
        let (spec, trajectory) = (self.spec(), self.trajectory()?);
        outputs::check_inputs(&spec, &trajectory)?;
        Ok((spec, trajectory))
    }

    /// What the run of `spec` along `traj` costs at most ([`Cost`]).
    pub fn cost(&self, spec: &LammpsSpec, traj: &Trajectory) -> Cost {
        let grains = spec.grain_count() as f64;
        let settle_steps = if self.bed.is_some() {
            0.0
        } else {
            (spec.max_settle_s / spec.time_step_s()).ceil()
        };
        let intrusion_steps = crate::script::pieces(spec, traj)
            .iter()
            .map(|p| p.steps as f64)
            .sum::<f64>();
        Cost {
            grains,
            settle_steps,
            intrusion_steps,
            settle_core_hours: grains * settle_steps / SETTLE_GRAIN_STEPS_PER_CORE_S / 3600.0,
            intrusion_core_hours: grains * intrusion_steps
                / INTRUSION_GRAIN_STEPS_PER_CORE_S
                / 3600.0,
            ranks: self.ranks,
        }
    }

    /// How often each stage of the run of `spec` writes a restart file: about every
    /// [`LammpsRequest::restart_every_min`] wall minutes at the measured rates on
    /// [`LammpsRequest::ranks`] ranks; the intrusion's on the grid of its force windows and
    /// dumps, the settle's on its speed checks.
    pub fn restart_every(&self, spec: &LammpsSpec) -> RestartEvery {
        let grains = spec.grain_count().max(1) as f64;
        let core_s = 60.0 * self.restart_every_min * f64::from(self.ranks);
        let on_grid = |rate: f64, grid: u64| {
            let steps = (core_s * rate / grains / grid as f64).floor() as u64;
            steps.max(1) * grid
        };
        let dt = spec.time_step_s();
        let check = ((0.005 / dt).round() as u64).max(1);
        let (fe, de) = (spec.force_every(), spec.dump_every());
        let lcm = fe / gcd(fe, de) * de;
        RestartEvery {
            settle: on_grid(SETTLE_GRAIN_STEPS_PER_CORE_S, check),
            intrusion: on_grid(INTRUSION_GRAIN_STEPS_PER_CORE_S, lcm),
        }
    }

    /// How `lammps` writes this run's dumps: `--dump-format`, else gzip where it has the
    /// COMPRESS package and text where it has not. Gzip asked of a LAMMPS without it is
    /// refused (bad input, before anything runs).
    pub fn dump_format_for(&self, lammps: &Lammps) -> Result<DumpFormat, LammpsError> {
        match self.dump_format {
            Some(DumpFormat::Gzip) if !lammps.compressed_dumps && self.dump_every_frames != 0 => {
                Err(LammpsError::input(format!(
                    "--dump-format gzip: {} ({}) has no COMPRESS package (dump custom/gz) \
                 (allowed: --dump-format text, or a LAMMPS built with COMPRESS)",
                    lammps.lmp.display(),
                    lammps.version
                )))
            }
            Some(f) => Ok(f),
            None if lammps.compressed_dumps => Ok(DumpFormat::Gzip),
            None => Ok(DumpFormat::Text),
        }
    }

    /// The LAMMPS (and MPI launcher) this request names or finds.
    pub fn lammps(&self) -> Result<Lammps, LammpsError> {
        crate::lammps::find(self.lmp.as_deref(), self.mpiexec.as_deref(), self.launcher)
            .map_err(LammpsError::Input)
    }
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a.max(1) } else { gcd(b, a % b) }
}

/// What a run submitted to Slurm ([`submit`]) came to.
#[derive(Clone, Debug)]
pub enum Submitted {
    /// Submitted without waiting ([`QueueOptions::no_wait`]): Slurm's job id.
    Queued {
        /// Slurm's job id.
        id: String,
    },
    /// The job ran and wrote its folder: its summary, read back from its `summary.json`.
    Done {
        /// The finished run (boxed: a summary is a few hundred bytes, a job id a string).
        outcome: Box<LammpsOutcome>,
    },
}

/// Submit the run `request` asks for to Slurm as one job of [`LammpsRequest::ranks`] tasks
/// that runs `program` (the `sandjumper` binary, on the cluster's shared file system) with
/// [`LammpsRequest::job_arguments`] ([`sandjumper_slurm::submit_command`]), wait for it unless
/// `queue` says not to, and check it. The request is checked and LAMMPS looked for here first
/// (a cluster's login node sees the shared file system its nodes do): a missing one is refused
/// now, not after the queue.
pub fn submit(
    request: &LammpsRequest,
    program: &Path,
    queue: &QueueOptions,
    progress: &dyn Progress,
) -> Result<Submitted, LammpsError> {
    let (mut spec, traj) = request.checked()?;
    let lammps = request.lammps()?;
    spec.dump_format = request.dump_format_for(&lammps)?;
    resume_in_its_format(request, &mut spec, &traj)?;
    // An unfinished run of other inputs in the output is refused now, not after the queue.
    Unfinished::of(request, &spec, &traj)?.earlier_in(&unfinished_dir(&request.out))?;
    // A restart file at least four times within the job's time limit: a job killed at its
    // limit and submitted again loses at most a quarter of it.
    let mut in_job = request.clone();
    // The job writes the dumps as checked here (the login node's LAMMPS is the nodes').
    in_job.dump_format = Some(spec.dump_format);
    if let Some(limit) = queue.time_limit_min() {
        in_job.restart_every_min = in_job.restart_every_min.min(limit / 4.0);
    }
    let args = in_job.job_arguments()?;
    let job = sandjumper_slurm::CommandJob {
        name: "dem-lammps",
        program,
        args: &args,
        tasks: request.ranks,
        out: &request.out,
        expect: &["summary.json"],
        queue: queue.clone(),
    };
    let outcome = sandjumper_slurm::submit_command(&job, progress)
        .map_err(|e| kept(&unfinished_dir(&request.out), e.into()))?;
    match outcome {
        CommandJobOutcome::Queued { id } => Ok(Submitted::Queued { id }),
        CommandJobOutcome::Done { .. } => {
            let p = request.out.join("summary.json");
            let summary = std::fs::read_to_string(&p)
                .map_err(|e| e.to_string())
                .and_then(|text| serde_json::from_str(&text).map_err(|e| e.to_string()))
                .map_err(|e| LammpsError::internal(format!("{}: {e}", p.display())))?;
            Ok(Submitted::Done {
                outcome: Box::new(LammpsOutcome {
                    summary,
                    out: request.out.clone(),
                }),
            })
        }
    }
}

/// The folder a run into `out` works in until it is done: `OUT.unfinished/`, beside it. It
/// holds the LAMMPS files (`lammps/`) and, while a run works in it, its writer's lock
/// (`.lock`); a run killed leaves it, and the same command resumes from it.
pub fn unfinished_dir(out: &Path) -> PathBuf {
    let mut name = out
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".unfinished");
    out.with_file_name(name)
}

/// What an unfinished folder was started for: a run resumes only the same run.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Unfinished {
    /// The run's id ([`outputs::run_id`]).
    run_id: String,
    /// The settled bed it reuses, if any.
    bed_from: Option<String>,
}

/// With no `--dump-format`, an unfinished run in the output that wrote text dumps (one from
/// before gzip was the default, or from a LAMMPS without COMPRESS) is resumed as text: the
/// same command resumes it.
fn resume_in_its_format(
    request: &LammpsRequest,
    spec: &mut LammpsSpec,
    traj: &Trajectory,
) -> Result<(), LammpsError> {
    if request.dump_format.is_some() || spec.dump_format == DumpFormat::Text {
        return Ok(());
    }
    let work = unfinished_dir(&request.out);
    if Unfinished::of(request, spec, traj)?
        .earlier_in(&work)
        .is_ok()
    {
        return Ok(());
    }
    let text = LammpsSpec {
        dump_format: DumpFormat::Text,
        ..spec.clone()
    };
    if matches!(
        Unfinished::of(request, &text, traj)?.earlier_in(&work),
        Ok(Some(_))
    ) {
        *spec = text;
    }
    Ok(())
}

/// The record's name in an unfinished folder.
const UNFINISHED_RECORD: &str = "unfinished.toml";

impl Unfinished {
    /// What `request` (its run `spec` along `traj`) would start.
    fn of(
        request: &LammpsRequest,
        spec: &LammpsSpec,
        traj: &Trajectory,
    ) -> Result<Self, LammpsError> {
        Ok(Self {
            run_id: outputs::run_id(spec, traj)?,
            bed_from: request.bed.as_ref().map(|b| b.display().to_string()),
        })
    }

    /// The unfinished run in `work` this one resumes (`Some`), or none there (`None`); an
    /// unfinished run of other inputs, or LAMMPS files of no run that can be told, is refused
    /// (exit 2).
    fn earlier_in(&self, work: &Path) -> Result<Option<Self>, LammpsError> {
        let record = work.join(UNFINISHED_RECORD);
        let parsed = std::fs::read_to_string(&record)
            .ok()
            .and_then(|t| toml::from_str::<Unfinished>(&t).ok());
        match parsed {
            None if work.join("lammps").is_dir() => Err(LammpsError::input(format!(
                "{} holds LAMMPS files whose run cannot be told ({} is missing or not a record \
                 this tool wrote): look inside, and remove the folder to start again",
                work.display(),
                record.display()
            ))),
            None => Ok(None),
            Some(earlier) if earlier == *self => Ok(Some(earlier)),
            Some(earlier) => {
                let on = |b: &Option<String>| {
                    b.as_ref()
                        .map_or(String::new(), |b| format!(" on the bed {b}"))
                };
                Err(LammpsError::input(format!(
                    "{} holds an unfinished run of other inputs (run {}{}; this one is run {}{}): \
                     resume it with its own command, or remove the folder (allowed: one run per \
                     output)",
                    work.display(),
                    earlier.run_id,
                    on(&earlier.bed_from),
                    self.run_id,
                    on(&self.bed_from)
                )))
            }
        }
    }
}

/// Run the intrusion `request` asks for with LAMMPS here, read its dumps back and write its
/// folder. LAMMPS works in [`unfinished_dir`] (locked: one run at a time), writing restart
/// files as it goes: a run that fails or is killed keeps it, and the same command resumes it
/// from its newest restart file; a finished run moves its LAMMPS files into the output and
/// removes it.
pub fn run(request: &LammpsRequest, progress: &dyn Progress) -> Result<LammpsOutcome, LammpsError> {
    let (mut spec, traj) = request.checked()?;
    let lammps = request.lammps()?;
    spec.dump_format = request.dump_format_for(&lammps)?;
    resume_in_its_format(request, &mut spec, &traj)?;
    // The output can be written, and a bed given fits (checked now, not after hours of
    // LAMMPS, and before an unfinished folder is made).
    drop(StagedDir::create(&request.out)?);
    if let Some(bed) = &request.bed {
        outputs::check_bed(&spec, &crate::bed::loose_box(&spec), bed)?;
    }
    // What this run will cost, before it starts (the paper preset is a cluster's job).
    progress.note(&request.cost(&spec, &traj).to_string());
    let work = unfinished_dir(&request.out);
    std::fs::create_dir_all(&work)
        .map_err(|e| LammpsError::input(format!("cannot create {}: {e}", work.display())))?;
    let _lock = sandjumper_output::lock::WriterLock::take_recorded(&work.join(".lock"))
        .map_err(|e| LammpsError::input(e.to_string()))?;
    let this = Unfinished::of(request, &spec, &traj)?;
    match this.earlier_in(&work)? {
        Some(_) => progress.note(&format!(
            "dem lammps: resuming the unfinished run in {}",
            work.display()
        )),
        None => {
            // Written whole or not at all (a kill while it is written leaves no half record).
            let partial = work.join(".unfinished.toml.partial");
            std::fs::write(&partial, toml::to_string(&this).map_err(internal)?)
                .map_err(internal)?;
            std::fs::rename(&partial, work.join(UNFINISHED_RECORD)).map_err(internal)?;
        }
    }
    let lammps_dir = work.join("lammps");
    let result = outputs::simulate(
        &spec,
        &traj,
        &lammps,
        request.ranks,
        request.bed.as_deref(),
        request.restart_every(&spec),
        &lammps_dir,
        progress,
    )
    .and_then(|()| {
        let staged = StagedDir::create(&request.out)?;
        let summary = outputs::analyse(
            &lammps_dir,
            staged.path(),
            request.min_speed_ratio,
            progress,
        )?;
        Ok((staged, summary))
    });
    progress.finish();
    let (staged, summary) = match result {
        Ok(r) => r,
        Err(e) => return Err(kept(&work, e)),
    };
    // The read-back first, then the LAMMPS files moved beside it: a commit that fails (the
    // output filled by something else meanwhile) leaves them where they are.
    let out = staged.commit().map_err(|e| kept(&work, e.into()))?;
    std::fs::rename(&lammps_dir, out.join("lammps")).map_err(|e| {
        kept(
            &work,
            LammpsError::internal(format!(
                "cannot move the LAMMPS files into {}: {e}",
                out.display()
            )),
        )
    })?;
    // Its lock file goes with it; a run started meanwhile makes a folder of its own.
    sandjumper_output::remove_work_dir(&work);
    Ok(LammpsOutcome { summary, out })
}

fn internal(e: impl fmt::Display) -> LammpsError {
    LammpsError::internal(e.to_string())
}

/// The error of a run that failed, saying where its files are and that the same command
/// resumes it.
fn kept(work: &Path, e: LammpsError) -> LammpsError {
    if !work.join("lammps").is_dir() {
        return e;
    }
    e.map_message(|mut message| {
        message += &format!(
            "\nthe run's LAMMPS files (inputs, logs, data, dumps, restart files) are kept in {}: \
             the same command resumes it from its newest restart file",
            work.display()
        );
        message
    })
}

/// A finished `dem lammps` run to read back again (another speed rule, or a run made
/// elsewhere).
#[derive(Clone, Debug, PartialEq)]
pub struct LammpsReadRequest {
    /// A run's folder (`dem lammps --out`), or its `lammps/` folder.
    pub run: PathBuf,
    /// The speed rule of the added mass, 1. Default 0.3.
    pub min_speed_ratio: f64,
    /// Output directory (apart from the run).
    pub out: PathBuf,
}

impl Default for LammpsReadRequest {
    fn default() -> Self {
        Self {
            run: PathBuf::new(),
            min_speed_ratio: 0.3,
            out: PathBuf::new(),
        }
    }
}

impl LammpsReadRequest {
    /// Refuse an output that is the run, holds it or lies in it (writing it would replace
    /// the run's dumps).
    pub fn validate(&self) -> Result<(), LammpsError> {
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
        let (run, out) = (canon(&self.run), canon(&self.out));
        if run.starts_with(&out) || out.starts_with(&run) {
            return Err(LammpsError::input(format!(
                "--out {} is the run {} or holds it or lies in it (allowed: a folder apart from the \
                 run: writing it would replace the run's files)",
                self.out.display(),
                self.run.display()
            )));
        }
        Ok(())
    }
}

/// Read a finished run's dumps back into a new folder.
pub fn read(
    request: &LammpsReadRequest,
    progress: &dyn Progress,
) -> Result<LammpsOutcome, LammpsError> {
    let dir = if request.run.join("run.toml").is_file() {
        request.run.clone()
    } else {
        request.run.join("lammps")
    };
    request.validate()?;
    let staged = StagedDir::create(&request.out)?;
    let summary = outputs::analyse(&dir, staged.path(), request.min_speed_ratio, progress);
    progress.finish();
    let summary = summary?;
    let out = staged.commit()?;
    Ok(LammpsOutcome { summary, out })
}
