//! One run, start to end, and its folder.
//!
//! [`simulate`] writes the LAMMPS run into its folder (the inputs, the data files, the logs,
//! `force.txt`, `column.txt`, `dumps/`, restart files while it runs, and `run.toml`, the
//! manifest the read-back checks against), resuming what an earlier attempt left there;
//! [`analyse`] reads the dumps back into `flow.csv`, `force_depth.csv`, `cone.csv`,
//! `summary.json` and `lammps.png`/`.svg` (and `sidewall.csv` against a sidewall).
//! [`analyse`] alone reads a finished run again (with another speed rule, or a run made
//! elsewhere). [`crate::run::run`] puts the two together in `OUT.unfinished/` and `OUT/`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use sandjumper_dem::intruder::Trajectory;
use sandjumper_dem::outputs::median;
use sandjumper_output::{Progress, write_csv};

use crate::analysis::{self, FlowRow, Geometry, SideView};
use crate::bed::{self, Atom, Settled};
use crate::dump::{self, RunCheck};
use crate::error::LammpsError;
use crate::foot::foot_atoms;
use crate::lammps::Lammps;
use crate::restart::{self, Stage, StageRun};
use crate::script::{self, Piece, Resume};
use crate::sidewall;
use crate::spec::LammpsSpec;

/// What a run's `run.toml` records: everything the read-back checks against.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Identifies the run (a hash of its spec and trajectory), in its inputs' first lines.
    pub run_id: String,
    /// The LAMMPS that ran it.
    pub lammps_version: String,
    /// MPI ranks.
    pub ranks: u32,
    /// How they started (`srun`, `mpiexec`, or `lmp` alone).
    #[serde(default)]
    pub launcher: String,
    /// Where the trajectory came from.
    pub trajectory: String,
    /// The model's packing fraction for eq. 6 and F_p: the settled bed's, within the
    /// presets' 0.57-0.62, 1.
    pub model_phi: f64,
    /// Height of the foot's bottom when the intrusion starts, m.
    pub foot_start_bottom_m: f64,
    /// The foot and the bed.
    pub geometry: Geometry,
    /// The settled bed.
    pub settled: Settled,
    /// Whether the settle ended on its rms speed (false: on its longest time, or no settle:
    /// the bed was given).
    pub settled_by_speed: bool,
    /// The settled bed this run reused (`--bed`), if it did not pour its own.
    #[serde(default)]
    pub bed_from: Option<String>,
    /// Grains removed because the foot's start overlapped them.
    pub grains_removed_under_foot: u64,
    /// The foot's spheres.
    pub foot_spheres: u64,
    /// Steps of the settle and of the intrusion.
    pub settle_steps: u64,
    /// Steps of the intrusion.
    pub intrusion_steps: u64,
    /// Wall time of the settle's last attempt, s (a resumed settle's attempts before it
    /// were killed and not timed).
    pub settle_wall_s: f64,
    /// Wall time of the intrusion's last attempt, s.
    pub intrusion_wall_s: f64,
    /// The step the settle's last attempt resumed from (none: its start).
    #[serde(default)]
    pub settle_resumed_from: Option<u64>,
    /// The step the intrusion's last attempt resumed from (none: its start).
    #[serde(default)]
    pub intrusion_resumed_from: Option<u64>,
    /// The foot's path.
    pub pieces: Vec<Piece>,
    /// The run.
    pub spec: LammpsSpec,
}

impl Manifest {
    /// A `run.toml`'s text as a record whose spec is valid and agrees with it (errors without
    /// the file's name; the caller adds it).
    pub fn parse(text: &str) -> Result<Self, String> {
        let m: Self = toml::from_str(text).map_err(|e| e.to_string())?;
        m.spec.check().and_then(|()| m.check())?;
        Ok(m)
    }

    /// Check that the record agrees with its spec (a run.toml edited or cut by hand is
    /// refused, not read into nonsense).
    pub fn check(&self) -> Result<(), String> {
        let s = &self.spec;
        let g = &self.geometry;
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-12);
        let agrees = same(g.grain_diameter_m, s.grain_diameter_m)
            && same(g.foot_radius_m, s.foot_radius_m())
            && same(g.foot_sphere_radius_m, 0.5 * s.min_grain_diameter_m())
            && same(g.time_step_s, s.time_step_s())
            && same(g.grain_density_kg_m3, s.grain_density_kg_m3)
            && same(g.symmetry_factor, s.symmetry_factor());
        if !agrees {
            return Err(
                "its geometry (grain, foot, time step) is not its spec's: not a run \
                        record this tool wrote"
                    .into(),
            );
        }
        let finite = [
            g.surface_m,
            g.axis_m.0,
            g.axis_m.1,
            self.foot_start_bottom_m,
            self.model_phi,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !finite || !(0.57..=0.62).contains(&self.model_phi) {
            return Err("a position or the model's phi is not a number in range".into());
        }
        let steps: u64 = self.pieces.iter().map(|p| p.steps).sum();
        if steps != self.intrusion_steps || self.pieces.iter().any(|p| !p.vz_m_s.is_finite()) {
            return Err(format!(
                "its foot's pieces add up to {steps} steps where it records {} (allowed: equal, \
                 finite velocities)",
                self.intrusion_steps
            ));
        }
        Ok(())
    }

    /// The frames' steps: the camera's rate, where `column.txt` has a row.
    pub fn frame_steps(&self) -> Vec<u64> {
        let de = self.spec.dump_every();
        (0..=self.intrusion_steps / de).map(|k| k * de).collect()
    }

    /// The frames LAMMPS dumped: every [`LammpsSpec::dump_every_frames`]th (none for 0).
    pub fn dump_steps(&self) -> Vec<u64> {
        match self.spec.dump_every_frames {
            0 => Vec::new(),
            n => self.frame_steps().into_iter().step_by(n as usize).collect(),
        }
    }
}

/// `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The LAMMPS that ran it.
    pub lammps_version: String,
    /// Grains in the settled bed, and the foot's spheres.
    pub grains: u64,
    /// The foot's spheres.
    pub foot_spheres: u64,
    /// Grains removed where the foot started.
    pub grains_removed_under_foot: u64,
    /// The target packing fraction, 1.
    #[serde(deserialize_with = "number_or_nan")]
    pub target_packing_fraction: f64,
    /// The settled bed's (its bulk), 1.
    #[serde(deserialize_with = "number_or_nan")]
    pub settled_packing_fraction: f64,
    /// Whether the settle ended on its rms speed.
    pub settled_by_speed: bool,
    /// The settled bed the run reused (`--bed`), if it did not pour its own.
    pub bed_from: Option<String>,
    /// Time step, s.
    #[serde(deserialize_with = "number_or_nan")]
    pub time_step_s: f64,
    /// Frames read.
    pub frames: u64,
    /// Their rate, frames/s.
    #[serde(deserialize_with = "number_or_nan")]
    pub fps: f64,
    /// Deepest the foot went, m.
    #[serde(deserialize_with = "number_or_nan")]
    pub max_depth_m: f64,
    /// The paper's added mass over eq. 6's at the same depth: the median over the frames
    /// with the paper's added mass.
    #[serde(deserialize_with = "number_or_nan")]
    pub added_mass_vs_eq6_median: f64,
    /// The column's peak momentum, kg m/s.
    #[serde(deserialize_with = "number_or_nan")]
    pub grain_momentum_under_foot_kg_m_s: f64,
    /// The largest difference between LAMMPS's own measure of the column's momentum
    /// (`column.txt`) and the dumps' at the same frames, over the peak: the two measures of
    /// one run agree to the dumps' printed digits (NaN: a run without `column.txt`), 1.
    #[serde(default = "nan", deserialize_with = "number_or_nan")]
    pub column_lammps_vs_dumps_max_diff: f64,
    /// Against a sidewall: the sidewall PIV's added mass over the exact column's, the median
    /// over the pairs both have (`sidewall.csv`; NaN: no sidewall), 1.
    #[serde(default = "nan", deserialize_with = "number_or_nan")]
    pub sidewall_piv_vs_exact_median: f64,
    /// PIV pairs of the sidewall measure (0: no sidewall).
    #[serde(default)]
    pub sidewall_pairs: u64,
    /// The paper's added mass at the deepest frame that has one, kg.
    #[serde(deserialize_with = "number_or_nan")]
    pub final_added_mass_kg: f64,
    /// Force on the foot over the model's `F_p`: the median over the windows deeper than one
    /// grain while the foot goes down.
    #[serde(deserialize_with = "number_or_nan")]
    pub force_vs_penetration_force_median: f64,
    /// Largest force on the foot, N.
    #[serde(deserialize_with = "number_or_nan")]
    pub peak_force_n: f64,
    /// Hertz overlap of a contact carrying the peak force shared by the foot's area at one
    /// grain per d^2, over d: how soft the softened grains are at the run's peak, 1.
    #[serde(deserialize_with = "number_or_nan")]
    pub peak_overlap_ratio: f64,
    /// The jammed cone's angle to the horizontal, degrees: the mean of its sides when both
    /// narrow and agree within 10 degrees (null: none, see `cone_note`).
    pub cone_angle_deg: Option<f64>,
    /// Its left side's angle, degrees (null: it does not narrow).
    pub cone_left_deg: Option<f64>,
    /// Its right side's angle, degrees.
    pub cone_right_deg: Option<f64>,
    /// Where its sides meet below the foot, m.
    pub cone_apex_below_foot_m: Option<f64>,
    /// Rows (half a grain each) the sides were fitted through.
    pub cone_rows: usize,
    /// How the cone was found, or why not.
    pub cone_note: String,
    /// The speed rule: frames with the foot at least this share of its fastest, 1.
    #[serde(deserialize_with = "number_or_nan")]
    pub min_speed_ratio: f64,
    /// Core-seconds the two stages' last attempts took (wall time x ranks; a resumed stage's
    /// killed attempts were not timed), s.
    #[serde(deserialize_with = "number_or_nan")]
    pub core_seconds: f64,
    /// Grain-steps per core-second of the intrusion's last attempt (the cost to scale by).
    #[serde(deserialize_with = "number_or_nan")]
    pub grain_steps_per_core_second: f64,
    /// The run's id.
    pub run_id: String,
}

/// A number of `summary.json` read back: serde_json writes a NaN or an infinity (a run with no
/// sample past the speed cut, no cone measured) as `null`, read back here as NaN, which writes
/// as `null` again.
fn nan() -> f64 {
    f64::NAN
}

fn number_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// A stage (`settle`, `intrusion`, `read`) of `steps` steps (frames for `read`) starts: a
/// line for the user and a new stage of the progress sink.
fn stage(progress: &dyn Progress, name: &str, steps: u64) {
    let unit = if name == "read" {
        "frames"
    } else {
        "steps at most"
    };
    progress.note(&format!("dem lammps: {name} ({steps} {unit})"));
    progress.start(if name == "read" { "frames" } else { "steps" }, Some(steps));
}

/// The LAMMPS step reporter of a stage: `progress` advanced to each step it reports; false
/// (LAMMPS is stopped) once the caller asked the run to stop (Ctrl-C).
fn stepper(progress: &dyn Progress) -> impl FnMut(u64) -> bool + '_ {
    let mut at = 0u64;
    move |s| {
        progress.advance(s.saturating_sub(at));
        at = at.max(s);
        !progress.cancelled()
    }
}

fn fnv(text: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

fn io(e: impl std::fmt::Display) -> LammpsError {
    LammpsError::internal(e.to_string())
}

/// Check `spec` and `trajectory` before anything runs: the values, a start at or above the
/// surface, the foot kept above the floor (exit 2 with what and what is allowed).
pub fn check_inputs(spec: &LammpsSpec, trajectory: &Trajectory) -> Result<(), LammpsError> {
    spec.check().map_err(LammpsError::input)?;
    trajectory
        .check_starts_at_surface()
        .map_err(LammpsError::input)?;
    spec.check_depth(max_depth(trajectory))
        .map_err(LammpsError::input)
}

/// Pour the loose grains and settle them (`in.settle`, LAMMPS on `ranks` ranks in `dir`),
/// which writes `settled.data` there; from the settle's newest restart file when an earlier
/// attempt left one.
#[allow(clippy::too_many_arguments)]
fn pour_and_settle(
    spec: &LammpsSpec,
    lammps: &Lammps,
    ranks: u32,
    run_id: &str,
    bed_box: &bed::BedBox,
    loose: &[Atom],
    restart_every: u64,
    dir: &Path,
    progress: &dyn Progress,
) -> Result<StageRun, LammpsError> {
    std::fs::write(
        dir.join("pour.data"),
        bed::data_file(&format!("sandjumper pour (run {run_id})"), bed_box, loose),
    )
    .map_err(io)?;
    let fall_s = (2.0 * bed_box.top_m / spec.gravity_m_s2).sqrt();
    if fall_s >= spec.max_settle_s {
        return Err(LammpsError::input(format!(
            "the grains take {fall_s:.2} s to fall from the loose start; the longest settle is \
             {} s (allowed: longer than the fall)",
            spec.max_settle_s
        )));
    }
    // The script's own errors (a spec it cannot pour) are the user's: checked first.
    script::settle_script(spec, run_id, bed_box.width_m, fall_s, restart_every, None)
        .map_err(LammpsError::input)?;
    let settle_max = (spec.max_settle_s / spec.time_step_s()).ceil() as u64;
    stage(progress, "settle", settle_max);
    let script = |resume: Option<Resume>| {
        script::settle_script(spec, run_id, bed_box.width_m, fall_s, restart_every, resume)
    };
    restart::run_stage(
        lammps,
        dir,
        ranks,
        &Stage {
            name: "settle",
            input: "in.settle",
            script: &script,
            prepare: &|_| Ok(()),
        },
        progress,
        &mut stepper(progress),
    )
    .map_err(LammpsError::internal)
}

/// How a finished settle went, kept in `settle.toml` beside `settled.data` (a resumed run
/// does not settle again).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SettleRecord {
    /// Its last step.
    steps: u64,
    /// Wall time of its last attempt, s.
    wall_s: f64,
    /// Whether it ended on its rms speed.
    halted: bool,
    /// The step its last attempt resumed from.
    resumed_from: Option<u64>,
    /// The bed given instead (`--bed`), if any.
    bed_from: Option<String>,
}

/// The settled bed `given` (a `settled.data`, or a run folder holding `lammps/settled.data`)
/// copied to `to`, once checked against this run's spec: the same box width as this spec's
/// pour (`bed_box`) and every grain's diameter within the spec's size range.
pub fn reuse_bed(
    spec: &LammpsSpec,
    bed_box: &bed::BedBox,
    given: &Path,
    to: &Path,
) -> Result<(), LammpsError> {
    let file = check_bed(spec, bed_box, given)?;
    std::fs::copy(&file, to).map_err(io)?;
    Ok(())
}

/// Check the settled bed `given` (a `settled.data`, or a run folder holding
/// `lammps/settled.data`) against this run's spec ([`reuse_bed`]), before anything runs; the
/// file it names.
pub fn check_bed(
    spec: &LammpsSpec,
    bed_box: &bed::BedBox,
    given: &Path,
) -> Result<std::path::PathBuf, LammpsError> {
    let file = if given.is_dir() {
        given.join("lammps").join("settled.data")
    } else {
        given.to_path_buf()
    };
    let (box_given, grains) = bed::read_data(&file).map_err(|e| {
        LammpsError::input(format!(
            "--bed {}: cannot read a settled bed: {e} (allowed: an earlier run's \
             lammps/settled.data, or its folder)",
            given.display()
        ))
    })?;
    let mismatch = |what: String| {
        LammpsError::input(format!(
            "--bed {}: {what} (allowed: a bed settled with the same preset and options)",
            file.display()
        ))
    };
    if (box_given.width_m - bed_box.width_m).abs() > 1e-9 * bed_box.width_m {
        return Err(mismatch(format!(
            "its box is {} m wide, this run's bed {} m",
            box_given.width_m, bed_box.width_m
        )));
    }
    let (lo, hi) = (spec.min_grain_diameter_m(), spec.max_grain_diameter_m());
    if let Some(a) = grains
        .iter()
        .filter(|a| a.kind == bed::GRAIN)
        .find(|a| a.diameter_m < lo * (1.0 - 1e-9) || a.diameter_m > hi * (1.0 + 1e-9))
    {
        return Err(mismatch(format!(
            "grain {} is {} m across, outside this run's {lo}..{hi} m",
            a.id, a.diameter_m
        )));
    }
    if grains.iter().all(|a| a.kind != bed::GRAIN) {
        return Err(mismatch("it holds no grains".into()));
    }
    // Walled in y or periodic: a bed settled against sidewalls has no grain across the planes
    // y = 0 and y = width; a periodic one of any size has some.
    let across = grains.iter().any(|a| {
        a.kind == bed::GRAIN
            && (a.x[1] < 0.5 * a.diameter_m || a.x[1] > box_given.width_m - 0.5 * a.diameter_m)
    });
    if spec.sidewall && across {
        return Err(mismatch(
            "it was settled without sidewalls (grains lie across the walls' planes); this run \
             has --sidewall"
                .into(),
        ));
    }
    if !spec.sidewall && !across {
        return Err(mismatch(
            "it was settled against sidewalls (no grain across y = 0); this run has none".into(),
        ));
    }
    Ok(file)
}

/// How often each stage writes a restart file, steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RestartEvery {
    /// Steps between the settle's restart files.
    pub settle: u64,
    /// Steps between the intrusion's (a multiple of the force window and the dump interval,
    /// so a resumed stage's windows and frames fall where the unbroken run's do).
    pub intrusion: u64,
}

/// Run `spec` on `trajectory` with `lammps` on `ranks` ranks in `dir` (the run's LAMMPS
/// folder): pour and settle (or take the settled bed `bed`, [`reuse_bed`]), place the foot,
/// intrude, and write `run.toml`. Resumes what an earlier attempt in `dir` left: a finished
/// settle (`settle.toml`) is not run again, a stage with restart files goes on from the
/// newest, a finished intrusion (`run.toml`) is not run again.
#[allow(clippy::too_many_arguments)]
pub fn simulate(
    spec: &LammpsSpec,
    trajectory: &Trajectory,
    lammps: &Lammps,
    ranks: u32,
    bed: Option<&Path>,
    restart_every: RestartEvery,
    dir: &Path,
    progress: &dyn Progress,
) -> Result<(), LammpsError> {
    check_inputs(spec, trajectory)?;
    if spec.dump_format == crate::spec::DumpFormat::Gzip
        && spec.dump_every_frames != 0
        && !lammps.compressed_dumps
    {
        return Err(LammpsError::input(format!(
            "gzip dumps: {} ({}) has no COMPRESS package (dump custom/gz) (allowed: text dumps, \
             or a LAMMPS built with COMPRESS)",
            lammps.lmp.display(),
            lammps.version
        )));
    }
    let pieces = script::pieces(spec, trajectory);
    let run_id = run_id(spec, trajectory)?;
    if dir.join("run.toml").is_file() {
        progress.note("dem lammps: the intrusion had finished; its files are read back");
        return Ok(());
    }
    std::fs::create_dir_all(dir.join("dumps")).map_err(io)?;

    // 1. Pour and settle, or the settled bed given.
    let (bed_box, loose) = bed::loose_start(spec);
    let record_path = dir.join("settle.toml");
    let record = match std::fs::read_to_string(&record_path)
        .ok()
        .and_then(|t| toml::from_str::<SettleRecord>(&t).ok())
        .filter(|r| dir.join("settled.data").is_file() && r.bed_from == bed.map(display))
    {
        Some(r) => {
            progress.note("dem lammps: the bed had settled; it is not settled again");
            r
        }
        None => {
            let r = match bed {
                Some(given) => {
                    reuse_bed(spec, &bed_box, given, &dir.join("settled.data"))?;
                    SettleRecord {
                        steps: 0,
                        wall_s: 0.0,
                        halted: false,
                        resumed_from: None,
                        bed_from: Some(display(given)),
                    }
                }
                None => {
                    let s = pour_and_settle(
                        spec,
                        lammps,
                        ranks,
                        &run_id,
                        &bed_box,
                        &loose,
                        restart_every.settle,
                        dir,
                        progress,
                    )?;
                    SettleRecord {
                        steps: s.report.last_step,
                        wall_s: s.report.wall_s,
                        halted: s.report.halted,
                        resumed_from: s.resumed_from,
                        bed_from: None,
                    }
                }
            };
            std::fs::write(&record_path, toml::to_string(&r).map_err(io)?).map_err(io)?;
            // Each restart file holds the whole bed: the settled one is all that is needed now.
            restart::remove_all(dir, "settle");
            r
        }
    };
    let (_, mut grains) =
        bed::read_data(&dir.join("settled.data")).map_err(LammpsError::internal)?;
    let settled = bed::settled(spec, &bed_box, &grains).map_err(LammpsError::internal)?;

    // 2. The foot at the trajectory's start; grains it overlaps removed.
    let axis = spec.axis_m(bed_box.width_m);
    let sphere = spec.min_grain_diameter_m();
    let bottom = settled.surface_m - trajectory.depth(0.0);
    let first_id = grains.iter().map(|a| a.id).max().unwrap_or(0) + 1;
    // The foot's spheres a thousand times denser than a grain: in the contacts' damping
    // (effective mass) the foot is then a rigid plate, as `fix move` makes it in motion.
    let foot = foot_atoms(
        spec.foot_radius_m(),
        sphere,
        axis,
        bottom,
        1e3 * spec.grain_density_kg_m3,
        first_id,
    );
    // Against a sidewall, the half of the disc in the bed (centres on or inside the wall's
    // plane).
    let foot: Vec<Atom> = foot
        .into_iter()
        .filter(|a| !spec.sidewall || a.x[1] >= axis.1)
        .collect();
    let before = grains.len();
    grains.retain(|a| !overlaps_foot(a, &foot));
    let removed = (before - grains.len()) as u64;
    let top = grains
        .iter()
        .map(|a| a.x[2] + a.diameter_m)
        .fold(bottom + 2.0 * sphere, f64::max);
    let mut atoms: Vec<Atom> = grains;
    let foot_spheres = foot.len() as u64;
    atoms.extend(foot);
    let intrude_box = bed::BedBox {
        width_m: bed_box.width_m,
        top_m: top + 0.01,
    };
    std::fs::write(
        dir.join("intrude.data"),
        bed::data_file(
            &format!("sandjumper intrusion (run {run_id})"),
            &intrude_box,
            &atoms,
        ),
    )
    .map_err(io)?;
    let intrusion_steps: u64 = pieces.iter().map(|p| p.steps).sum();
    let mut manifest = Manifest {
        run_id: run_id.clone(),
        lammps_version: lammps.version.clone(),
        ranks,
        launcher: lammps.launcher_for(ranks).into(),
        trajectory: match trajectory {
            Trajectory::Constant {
                speed_m_s,
                start_depth_m,
                end_depth_m,
            } => {
                format!("constant {speed_m_s} m/s from depth {start_depth_m} m to {end_depth_m} m")
            }
            Trajectory::Table { source, .. } => source.clone(),
        },
        model_phi: settled.packing_fraction.clamp(0.57, 0.62),
        foot_start_bottom_m: bottom,
        geometry: Geometry {
            axis_m: axis,
            foot_radius_m: spec.foot_radius_m(),
            foot_sphere_radius_m: 0.5 * sphere,
            surface_m: settled.surface_m,
            grain_density_kg_m3: spec.grain_density_kg_m3,
            grain_diameter_m: spec.grain_diameter_m,
            time_step_s: spec.time_step_s(),
            symmetry_factor: spec.symmetry_factor(),
        },
        settled,
        settled_by_speed: record.halted,
        bed_from: record.bed_from.clone(),
        grains_removed_under_foot: removed,
        foot_spheres,
        settle_steps: record.steps,
        intrusion_steps,
        settle_wall_s: record.wall_s,
        intrusion_wall_s: 0.0,
        settle_resumed_from: record.resumed_from,
        intrusion_resumed_from: None,
        pieces: pieces.clone(),
        spec: spec.clone(),
    };

    // 3. The intrusion, from its newest restart file when there is one.
    stage(progress, "intrusion", intrusion_steps);
    let every = restart_every.intrusion;
    let script = |resume: Option<Resume>| {
        Ok(script::intrude_script(
            spec,
            &run_id,
            bed_box.width_m,
            &pieces,
            axis,
            sphere,
            bottom,
            every,
            resume,
        ))
    };
    let prepare = |from: Option<u64>| match from {
        // The force windows end after the restart's step; the column is sampled at the
        // restart's step itself again (a `fix ave/time` of one sample writes at its setup).
        Some(step) => restart::cut_time_series(dir, "force.txt", step)
            .and_then(|()| restart::cut_time_series(dir, "column.txt", step.saturating_sub(1))),
        None => Ok(()),
    };
    let intrusion = restart::run_stage(
        lammps,
        dir,
        ranks,
        &Stage {
            name: "intrude",
            input: "in.intrude",
            script: &script,
            prepare: &prepare,
        },
        progress,
        &mut stepper(progress),
    )
    .map_err(LammpsError::internal)?;
    manifest.intrusion_wall_s = intrusion.report.wall_s;
    manifest.intrusion_resumed_from = intrusion.resumed_from;
    // The restart files are not needed once the stage is done (each holds the whole bed).
    let _ = std::fs::remove_dir_all(dir.join("restart"));
    std::fs::write(
        dir.join("run.toml"),
        toml::to_string(&manifest).map_err(io)?,
    )
    .map_err(io)
}

/// A path as the manifest records it.
fn display(p: &Path) -> String {
    p.display().to_string()
}

/// The run's id: a hash of its spec and the foot's path, in its inputs' first lines.
pub fn run_id(spec: &LammpsSpec, trajectory: &Trajectory) -> Result<String, LammpsError> {
    let pieces = script::pieces(spec, trajectory);
    let spec_text = toml::to_string(spec).map_err(io)?;
    Ok(fnv(&format!("{spec_text}{pieces:?}")))
}

/// The deepest the trajectory goes, m (its table's deepest sample, or its end).
fn max_depth(t: &Trajectory) -> f64 {
    match t {
        Trajectory::Constant {
            start_depth_m,
            end_depth_m,
            ..
        } => start_depth_m.max(*end_depth_m),
        Trajectory::Table { depth_m, .. } => depth_m.iter().copied().fold(f64::MIN, f64::max),
    }
}

fn overlaps_foot(a: &Atom, foot: &[Atom]) -> bool {
    let Some(f) = foot.first() else {
        return false;
    };
    // Only grains reaching the foot's layer can overlap it.
    if a.x[2] + 0.5 * a.diameter_m <= f.x[2] - 0.5 * f.diameter_m {
        return false;
    }
    foot.iter().any(|f| {
        let d2: f64 = (0..3).map(|c| (a.x[c] - f.x[c]).powi(2)).sum();
        d2.sqrt() < 0.5 * (a.diameter_m + f.diameter_m)
    })
}

/// Read the run in `dir` (its `run.toml`, `intrude.data`, `force.txt` and `dumps/`) back
/// into `out`. A dump or force file cut short, or of another run, is refused (exit 2)
/// naming the file.
pub fn analyse(
    dir: &Path,
    out: &Path,
    min_speed_ratio: f64,
    progress: &dyn Progress,
) -> Result<Summary, LammpsError> {
    if !(min_speed_ratio > 0.0 && min_speed_ratio < 1.0) {
        return Err(LammpsError::input(format!(
            "the speed rule is {min_speed_ratio} of the fastest (allowed: between 0 and 1)"
        )));
    }
    let manifest_path = dir.join("run.toml");
    let text = std::fs::read_to_string(&manifest_path).map_err(|e| {
        LammpsError::input(format!(
            "{}: {e} (a LAMMPS run of `sandjumper dem lammps` has it in its lammps/ folder)",
            manifest_path.display()
        ))
    })?;
    let m = Manifest::parse(&text)
        .map_err(|e| LammpsError::input(format!("{}: {e}", manifest_path.display())))?;
    let data = dir.join("intrude.data");
    let (bed_box, atoms) = bed::read_data(&data).map_err(LammpsError::input)?;
    let first = std::fs::read_to_string(&data)
        .map_err(|e| LammpsError::input(format!("{}: {e}", data.display())))?;
    if !first.lines().next().unwrap_or("").contains(&m.run_id) {
        return Err(LammpsError::input(format!(
            "{}: not the data file of run {} (its run.toml)",
            data.display(),
            m.run_id
        )));
    }
    let check = RunCheck {
        width_m: bed_box.width_m,
        radius_by_id: atoms.iter().map(|a| (a.id, 0.5 * a.diameter_m)).collect(),
        format: m.spec.dump_format,
    };
    let g = m.geometry;
    let phi = m.model_phi;
    let r = g.foot_radius_m;
    let eq6 = |d: f64| sandjumper_dem::outputs::model_added_mass(phi, r, d);
    let fp = |d: f64| {
        if d > 0.0 {
            sandjumper_dem::outputs::model_penetration_force(phi, r, d)
        } else {
            Ok(0.0)
        }
    };
    let steps = m.frame_steps();
    let dumped: std::collections::BTreeSet<u64> = m.dump_steps().into_iter().collect();
    let dumps = dir.join("dumps");
    let dt = m.geometry.time_step_s;
    // LAMMPS's own measure of the column at every frame, where the run has it.
    let column_path = dir.join("column.txt");
    let column = if column_path.is_file() {
        let column = analysis::read_column(&column_path).map_err(LammpsError::input)?;
        let by_step: std::collections::HashMap<u64, analysis::ColumnRow> =
            column.iter().map(|c| (c.step, *c)).collect();
        if by_step.len() != column.len()
            || column.len() != steps.len()
            || steps.iter().any(|s| !by_step.contains_key(s))
        {
            return Err(LammpsError::input(format!(
                "{}: {} rows ({} steps) where the run has {} frames (the file is cut short, holds \
                 a step twice, or is not of this run)",
                column_path.display(),
                column.len(),
                by_step.len(),
                steps.len()
            )));
        }
        Some(by_step)
    } else if dumped.len() != steps.len() {
        return Err(LammpsError::input(format!(
            "{}: missing, and the run dumped {} of its {} frames (allowed: a run that dumps \
             every frame, or its column.txt)",
            column_path.display(),
            dumped.len(),
            steps.len()
        )));
    } else {
        None
    };
    stage(progress, "read", dumped.len() as u64);
    // The frames read and measured on every core (a frame in memory per thread).
    let frame_row = |&s: &u64| -> Result<FlowRow, LammpsError> {
        let mut row = if dumped.contains(&s) {
            let f = dump::read_frame(&dumps, s, &check).map_err(LammpsError::input)?;
            let row = analysis::frame_row(&f, &g).map_err(LammpsError::input)?;
            // The foot where this run's pieces put it: a frame of the same bed on another
            // trajectory (or at another step) is not this run's.
            let expected = script::bottom_at(&m.pieces, dt, m.foot_start_bottom_m, s);
            let got = g.surface_m - row.depth_m;
            if (got - expected).is_nan() || (got - expected).abs() > FOOT_TOLERANCE_M {
                return Err(LammpsError::input(format!(
                    "{}: the foot's bottom is at {:.6} mm where this run put it at {:.6} mm at \
                     step {s} (a dump of another run)",
                    dump::frame_path(&dumps, s, check.format).display(),
                    1e3 * got,
                    1e3 * expected
                )));
            }
            progress.advance(1);
            row
        } else {
            // No dump: the column as LAMMPS measured it, the foot where its pieces put it.
            let c = column
                .as_ref()
                .and_then(|c| c.get(&s))
                .copied()
                .ok_or_else(|| LammpsError::internal(format!("no column row of step {s}")))?;
            FlowRow {
                t_s: s as f64 * dt,
                depth_m: g.surface_m - script::bottom_at(&m.pieces, dt, m.foot_start_bottom_m, s),
                foot_speed_m_s: -script::velocity_at(&m.pieces, s),
                momentum_under_foot_kg_m_s: g.symmetry_factor * c.momentum_kg_m_s,
                grains_under_foot: c.grains,
                momentum_ring_kg_m_s: g.symmetry_factor * c.ring_kg_m_s,
                momentum_under_foot_lammps_kg_m_s: f64::NAN,
                added_mass_kg: f64::NAN,
                eq6_added_mass_kg: f64::NAN,
            }
        };
        if let Some(c) = column.as_ref().and_then(|c| c.get(&s)) {
            row.momentum_under_foot_lammps_kg_m_s = g.symmetry_factor * c.momentum_kg_m_s;
        }
        Ok(row)
    };
    let mut rows: Vec<FlowRow> = {
        use rayon::prelude::*;
        steps.par_iter().map(frame_row).collect::<Result<_, _>>()?
    };
    analysis::added_mass(&mut rows, min_speed_ratio, &eq6).map_err(LammpsError::internal)?;
    // The cone over the frames with the paper's added mass (read again: one frame in
    // memory at a time, whatever the bed's size).
    let mut view = SideView::new(&g);
    for (row, &s) in rows.iter().zip(&steps) {
        if row.added_mass_kg.is_finite() && dumped.contains(&s) {
            let f = dump::read_frame(&dumps, s, &check).map_err(LammpsError::input)?;
            view.add(&f, &g, row);
        }
    }
    let cone = view.cone(&g);
    let force_path = dir.join("force.txt");
    let force = analysis::read_force(&force_path, &g, &fp).map_err(LammpsError::input)?;
    let fe = m.spec.force_every();
    let windows = m.intrusion_steps / fe;
    if force.len() as u64 != windows {
        return Err(LammpsError::input(format!(
            "{}: {} force windows where the run has {windows} (the file is cut short, or not \
             of this run)",
            force_path.display(),
            force.len()
        )));
    }
    // Each window's mean foot height is the pieces' at its middle (the motion is linear
    // within a window).
    for (k, f) in force.iter().enumerate() {
        let (a, b) = (k as u64 * fe, (k as u64 + 1) * fe);
        let mid = 0.5
            * (script::bottom_at(&m.pieces, dt, m.foot_start_bottom_m, a + 1)
                + script::bottom_at(&m.pieces, dt, m.foot_start_bottom_m, b));
        let got = g.surface_m - f.depth_m;
        if (got - mid).is_nan() || (got - mid).abs() > FOOT_TOLERANCE_M {
            return Err(LammpsError::input(format!(
                "{}: window {} has the foot at {:.6} mm where this run put it at {:.6} mm (a \
                 force file of another run)",
                force_path.display(),
                k + 1,
                1e3 * got,
                1e3 * mid
            )));
        }
    }
    // The paper's sidewall PIV of the same frames, beside the exact column.
    let sidewall_rows = if m.spec.sidewall {
        stage(
            progress,
            "sidewall PIV",
            steps.len().saturating_sub(1) as u64,
        );
        let mut read = |s: u64| dump::read_frame(&dumps, s, &check);
        let rho_phi = m.spec.grain_density_kg_m3 * m.settled.packing_fraction;
        let r = sidewall::measure(&steps, &mut read, &rows, &g, rho_phi, min_speed_ratio)
            .map_err(LammpsError::input)?;
        write_csv(&out.join("sidewall.csv"), &r, &[]).map_err(LammpsError::internal)?;
        Some(r)
    } else {
        None
    };
    let mut summary = summarise(&m, &rows, &force, &cone, min_speed_ratio);
    if let Some(r) = &sidewall_rows {
        summary.sidewall_piv_vs_exact_median = sidewall::piv_over_exact_median(r);
        summary.sidewall_pairs = r.len() as u64;
    }
    write_outputs(out, &m, &rows, &force, &cone, &summary)?;
    Ok(summary)
}

/// How far a frame's foot may be from where the run's pieces put it, m.
pub const FOOT_TOLERANCE_M: f64 = 1e-7;

fn summarise(
    m: &Manifest,
    rows: &[FlowRow],
    force: &[analysis::ForceRow],
    cone: &Option<analysis::Cone>,
    min_speed_ratio: f64,
) -> Summary {
    let d = m.spec.grain_diameter_m;
    let with_mass: Vec<&FlowRow> = rows
        .iter()
        .filter(|r| r.added_mass_kg.is_finite())
        .collect();
    // Windows deeper than a grain while the foot goes down (depth still growing).
    let mut ratios = Vec::new();
    let mut deepest = f64::NEG_INFINITY;
    for f in force {
        if f.depth_m > deepest && f.depth_m > d && f.model_penetration_force_n > 0.0 {
            ratios.push(f.force_n / f.model_penetration_force_n);
        }
        deepest = deepest.max(f.depth_m);
    }
    let peak = force.iter().map(|f| f.force_n).fold(0.0, f64::max);
    // Hertz: F = 4/3 E* sqrt(R*) delta^(3/2), two grains of diameter d: R* = d/4,
    // E* = E / (2 (1 - nu^2)); the peak shared at one contact per d^2 of the foot.
    let s = &m.spec;
    let e_star = s.youngs_modulus_pa / (2.0 * (1.0 - s.poisson_ratio * s.poisson_ratio));
    let per_contact = peak * d * d / (core::f64::consts::PI * s.foot_radius_m().powi(2));
    let overlap = (per_contact / (4.0 / 3.0 * e_star * (0.25 * d).sqrt())).powf(2.0 / 3.0);
    let core_seconds = (m.settle_wall_s + m.intrusion_wall_s) * f64::from(m.ranks);
    let peak_p = rows
        .iter()
        .map(|r| r.momentum_under_foot_kg_m_s.abs())
        .fold(0.0, f64::max);
    let column_diff = rows
        .iter()
        .map(|r| (r.momentum_under_foot_lammps_kg_m_s - r.momentum_under_foot_kg_m_s).abs())
        .fold(0.0, |a: f64, d| {
            if d.is_nan() || a.is_nan() {
                f64::NAN
            } else {
                a.max(d)
            }
        })
        / peak_p;
    // The rate of the intrusion's last attempt: the steps it ran over its wall time.
    let grain_steps = m.settled.grains as f64
        * (m.intrusion_steps - m.intrusion_resumed_from.unwrap_or(0).min(m.intrusion_steps)) as f64;
    Summary {
        lammps_version: m.lammps_version.clone(),
        grains: m.settled.grains - m.grains_removed_under_foot,
        foot_spheres: m.foot_spheres,
        grains_removed_under_foot: m.grains_removed_under_foot,
        target_packing_fraction: s.packing_fraction,
        settled_packing_fraction: m.settled.packing_fraction,
        settled_by_speed: m.settled_by_speed,
        bed_from: m.bed_from.clone(),
        time_step_s: m.geometry.time_step_s,
        frames: rows.len() as u64,
        fps: s.actual_fps(),
        max_depth_m: rows
            .iter()
            .map(|r| r.depth_m)
            .fold(f64::NEG_INFINITY, f64::max),
        added_mass_vs_eq6_median: median(
            with_mass
                .iter()
                .filter(|r| r.eq6_added_mass_kg > 0.0)
                .map(|r| r.added_mass_kg / r.eq6_added_mass_kg)
                .collect(),
        ),
        grain_momentum_under_foot_kg_m_s: rows
            .iter()
            .map(|r| r.momentum_under_foot_kg_m_s)
            .fold(f64::NEG_INFINITY, f64::max),
        column_lammps_vs_dumps_max_diff: column_diff,
        sidewall_piv_vs_exact_median: f64::NAN,
        sidewall_pairs: 0,
        final_added_mass_kg: with_mass
            .iter()
            .max_by(|a, b| a.depth_m.total_cmp(&b.depth_m))
            .map_or(f64::NAN, |r| r.added_mass_kg),
        force_vs_penetration_force_median: median(ratios),
        peak_force_n: peak,
        peak_overlap_ratio: overlap / d,
        cone_angle_deg: cone.as_ref().map(|c| c.angle_deg).filter(|a| a.is_finite()),
        cone_left_deg: cone.as_ref().map(|c| c.left_deg).filter(|a| a.is_finite()),
        cone_right_deg: cone.as_ref().map(|c| c.right_deg).filter(|a| a.is_finite()),
        cone_apex_below_foot_m: cone
            .as_ref()
            .map(|c| c.apex_depth_m)
            .filter(|a| a.is_finite()),
        cone_rows: cone.as_ref().map_or(0, |c| c.rows.len()),
        cone_note: match cone {
            None if m.spec.dump_every_frames == 0 => {
                "no dumps (--dump-every 0): the cone needs the grains".into()
            }
            None => "fewer than three rows below the foot where the co-moving region is \
                     narrower than the foot"
                .into(),
            Some(c) if c.angle_deg.is_finite() => format!(
                "both sides narrow and agree, over {} rows and {} frames",
                c.rows.len(),
                c.samples
            ),
            Some(c) => format!(
                "the sides ({:.0} and {:.0} deg) do not both narrow, or differ by more than 10 \
                 deg, over {} rows",
                c.left_deg,
                c.right_deg,
                c.rows.len()
            ),
        },
        min_speed_ratio,
        core_seconds,
        grain_steps_per_core_second: grain_steps / (m.intrusion_wall_s * f64::from(m.ranks)),
        run_id: m.run_id.clone(),
    }
}

fn write_outputs(
    out: &Path,
    m: &Manifest,
    rows: &[FlowRow],
    force: &[analysis::ForceRow],
    cone: &Option<analysis::Cone>,
    summary: &Summary,
) -> Result<(), LammpsError> {
    write_csv(&out.join("flow.csv"), rows, &[]).map_err(LammpsError::internal)?;
    write_csv(&out.join("force_depth.csv"), force, &[]).map_err(LammpsError::internal)?;
    let cone_rows = cone.as_ref().map_or(&[][..], |c| &c.rows[..]);
    write_csv(
        &out.join("cone.csv"),
        cone_rows,
        &["depth_below_foot_m", "left_m", "right_m", "contrast"],
    )
    .map_err(LammpsError::internal)?;
    std::fs::write(
        out.join("lammps.toml"),
        toml::to_string(&m.spec).map_err(io)?,
    )
    .map_err(io)?;
    let json = serde_json::to_string_pretty(summary).map_err(io)?;
    std::fs::write(out.join("summary.json"), json + "\n").map_err(io)?;
    let title = format!(
        "3-D DEM (LAMMPS): {:.0} mm foot in {:.1} mm grains, bed phi {:.3}",
        1e3 * m.spec.foot_diameter_m,
        1e3 * m.spec.grain_diameter_m,
        m.settled.packing_fraction
    );
    crate::figure::draw(
        out,
        &title,
        rows,
        force,
        cone.as_ref(),
        &summary.cone_note,
        m.spec.foot_radius_m(),
    )
    .map_err(LammpsError::internal)
}

#[cfg(test)]
mod summary_tests {
    use super::Summary;

    /// A summary whose medians and deepest values are not numbers (a run with no sample past
    /// the speed cut) is written with `null`s and reads back to the same text: what a Slurm
    /// job's `summary.json` goes through before `dem lammps --slurm --json` prints it. Fails
    /// without `number_or_nan` (serde_json refuses `null` for an `f64`).
    #[test]
    fn a_summary_with_nulls_reads_back_to_the_same_text() {
        let summary = Summary {
            lammps_version: "LAMMPS (22 Jul 2025)".into(),
            grains: 1200,
            foot_spheres: 61,
            grains_removed_under_foot: 3,
            target_packing_fraction: 0.6,
            settled_packing_fraction: 0.59,
            settled_by_speed: true,
            bed_from: None,
            time_step_s: 1e-6,
            frames: 0,
            fps: 2000.0,
            max_depth_m: f64::NEG_INFINITY,
            added_mass_vs_eq6_median: f64::NAN,
            grain_momentum_under_foot_kg_m_s: f64::NEG_INFINITY,
            column_lammps_vs_dumps_max_diff: f64::NAN,
            sidewall_piv_vs_exact_median: f64::NAN,
            sidewall_pairs: 0,
            final_added_mass_kg: f64::NAN,
            force_vs_penetration_force_median: f64::NAN,
            peak_force_n: 0.0,
            peak_overlap_ratio: 0.0,
            cone_angle_deg: None,
            cone_left_deg: None,
            cone_right_deg: None,
            cone_apex_below_foot_m: None,
            cone_rows: 0,
            cone_note: "no cone".into(),
            min_speed_ratio: 0.5,
            core_seconds: 12.5,
            grain_steps_per_core_second: 3.0e5,
            run_id: "r".into(),
        };
        let text = serde_json::to_string_pretty(&summary).unwrap();
        assert!(
            text.contains("\"added_mass_vs_eq6_median\": null"),
            "{text}"
        );
        let back: Summary = serde_json::from_str(&text).unwrap();
        assert!(back.final_added_mass_kg.is_nan() && back.max_depth_m.is_nan());
        assert_eq!(serde_json::to_string_pretty(&back).unwrap(), text);
    }
}
