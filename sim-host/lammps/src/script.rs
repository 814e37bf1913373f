//! The two LAMMPS inputs of a run.
//!
//! 1. `in.settle`: the loose grains ([`crate::bed::loose_start`]) fall under gravity onto a
//!    frictional floor with the pouring friction and settle until their rms speed is below
//!    the spec's (`fix halt`), or the longest settle passes; `write_data settled.data`.
//! 2. `in.intrude`: the settled grains with the grain friction, and the foot
//!    ([`crate::foot`]) moved by `fix move linear` one piece at a time along the prescribed
//!    trajectory (pieces on the force windows' step grid, so the foot is exactly where the
//!    trajectory says at every window's end); the contact force on the foot (the mean over
//!    each window) and the foot's lowest centre go to `force.txt`; the grains within the
//!    dump radius of the axis, and the foot, go to `dumps/frame.STEP.txt[.gz]` at the camera's
//!    rate.

use std::fmt::Write as _;

use sandjumper_dem::intruder::Trajectory;

use crate::spec::LammpsSpec;

/// One piece of the foot's path: `steps` steps at vertical velocity `vz_m_s` (up positive).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Piece {
    /// Steps.
    pub steps: u64,
    /// Vertical velocity, m/s (up positive: an intrusion is negative).
    pub vz_m_s: f64,
}

/// The trajectory as pieces on the force windows' grid: each window's depth change over its
/// duration, neighbouring equal velocities merged. Returns the pieces and the total steps.
pub fn pieces(spec: &LammpsSpec, trajectory: &Trajectory) -> Vec<Piece> {
    let dt = spec.time_step_s();
    let fe = spec.force_every();
    let window = fe as f64 * dt;
    let windows = (trajectory.duration_s() / window).ceil().max(1.0) as u64;
    let mut out: Vec<Piece> = Vec::new();
    let mut add = |steps: u64, vz: f64| match out.last_mut() {
        Some(p) if (p.vz_m_s - vz).abs() <= 1e-12 * vz.abs().max(1e-9) => p.steps += steps,
        _ => out.push(Piece { steps, vz_m_s: vz }),
    };
    for k in 0..windows {
        let (t0, t1) = (k as f64 * window, (k + 1) as f64 * window);
        add(fe, -(trajectory.depth(t1) - trajectory.depth(t0)) / window);
    }
    // Held at its last depth up to the next dump, so the end is in a frame.
    let de = spec.dump_every();
    let total = windows * fe;
    if !total.is_multiple_of(de) {
        add(de - total % de, 0.0);
    }
    out
}

/// The foot's bottom height `steps` steps into `pieces`, from `start_m`.
pub fn bottom_at(pieces: &[Piece], dt: f64, start_m: f64, steps: u64) -> f64 {
    let (mut z, mut left) = (start_m, steps);
    for p in pieces {
        let n = left.min(p.steps);
        z += p.vz_m_s * n as f64 * dt;
        left -= n;
        if left == 0 {
            break;
        }
    }
    z
}

/// The foot's vertical velocity at the end of step `step` of `pieces` (the piece that step
/// belongs to; 0 at step 0, when the foot has not yet moved), m/s (up positive).
pub fn velocity_at(pieces: &[Piece], step: u64) -> f64 {
    let mut end = 0;
    for p in pieces {
        end += p.steps;
        if step > 0 && step <= end {
            return p.vz_m_s;
        }
    }
    0.0
}

/// The contact model's coefficients with friction `mu` (pair and wall alike), and rolling
/// friction `rolling` (LAMMPS's `rolling sds`, no rolling damping) when given.
fn contact(spec: &LammpsSpec, mu: f64, rolling: Option<f64>) -> String {
    let roll = rolling.map_or(String::new(), |mu_r| {
        format!(" rolling sds {:e} 0.0 {mu_r}", spec.rolling_stiffness_n_m())
    });
    format!(
        "hertz/material {:e} {} {} tangential mindlin NULL 1.0 {} damping coeff_restitution{roll}",
        spec.youngs_modulus_pa, spec.restitution, spec.poisson_ratio, mu
    )
}

/// Where a stage's atoms come from: a data file (its start) or a restart file LAMMPS wrote
/// while an earlier attempt ran ([`Resume`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start<'a> {
    /// `read_data FILE`: the stage from its start.
    Data(&'a str),
    /// `read_restart`: the stage from a restart file.
    Restart(Resume<'a>),
}

/// A restart file a stage resumes from: LAMMPS's `restart` command wrote it at `step`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resume<'a> {
    /// The file, relative to the run's folder.
    pub file: &'a str,
    /// The step it holds.
    pub step: u64,
}

/// The lines every stage starts with. The ranks split the bed in x and y only
/// (`processors * * 1`): a bed settling from its loose start to a third of its height would
/// leave the upper ranks of a split in z empty. Atoms are found by a hash (`map hash`): an
/// array indexed by atom id costs every rank memory for every atom (about 61 MB a rank at 15
/// million atoms).
///
/// From a restart file, LAMMPS keeps the atoms, the groups, the contacts' history (the pair's
/// and the floor's, given back to a fix of the same ID) and the moving foot's origin; the pair
/// style is given again (LAMMPS 22 Jul 2025 restores it with no cut-off and newton on) and the
/// clock is set again (it restarts the time at the restart's step).
fn header(
    spec: &LammpsSpec,
    what: &str,
    run_id: &str,
    (start, box_width_m): (Start, f64),
    mu: f64,
    rolling: Option<f64>,
) -> String {
    let skin = 0.2 * spec.grain_diameter_m;
    let c = contact(spec, mu, rolling);
    // With a sidewall the bed is walled in y (fixed boundaries, a frictional wall each side).
    let (boundary, walls) = if spec.sidewall {
        (
            "p f fm",
            format!("fix sides grains wall/gran granular {c} yplane 0.0 {box_width_m:e}\n"),
        )
    } else {
        ("p p fm", String::new())
    };
    let read = match start {
        Start::Data(data) => format!(
            "units si\n\
             atom_style sphere\n\
             atom_modify map hash\n\
             processors * * 1\n\
             boundary {boundary}\n\
             newton off\n\
             read_data {data}\n"
        ),
        Start::Restart(r) => format!(
            "# resumed from step {step}\n\
             atom_modify map hash\n\
             processors * * 1\n\
             newton off\n\
             read_restart {file}\n\
             reset_timestep {step} time {time:e}\n",
            step = r.step,
            file = r.file,
            time = r.step as f64 * spec.time_step_s()
        ),
    };
    format!(
        "# sandjumper dem lammps: {what} (run {run_id})\n\
         {read}\
         comm_modify vel yes\n\
         group grains type 1\n\
         pair_style granular\n\
         pair_coeff * * {c}\n\
         fix floor grains wall/gran granular {c} zplane 0.0 NULL\n\
         {walls}\
         neighbor {skin:e} bin\n\
         timestep {:e}\n",
        spec.time_step_s()
    )
}

/// The ranks' sub-domains moved (in x and y, by the grains' count) every 5 ms of simulated
/// time when a rank holds 10 % more than the mean: a slab stays even while it settles, and
/// the denser column under the foot does not load its ranks more than the rest.
fn balance_line(spec: &LammpsSpec) -> String {
    let every = ((0.005 / spec.time_step_s()).round() as u64).max(1);
    format!("fix balance all balance {every} 1.1 shift xy 10 1.1\n")
}

/// Restart files of a stage (`settle` or `intrude`): `restart/STAGE.STEP`, every `every`
/// steps.
pub fn restart_line(stage: &str, every: u64) -> String {
    format!("restart {every} restart/{stage}.*\n")
}

/// `in.settle`: pour and settle, writing a restart file every `restart_every` steps; from
/// `resume` on, when given.
pub fn settle_script(
    spec: &LammpsSpec,
    run_id: &str,
    box_width_m: f64,
    fall_s: f64,
    restart_every: u64,
    resume: Option<Resume>,
) -> Result<String, String> {
    let start = resume.map_or(Start::Data("pour.data"), Start::Restart);
    let mut s = header(
        spec,
        "pour and settle",
        run_id,
        (start, box_width_m),
        spec.pour_friction()?,
        spec.pour_rolling_friction(),
    );
    let dt = spec.time_step_s();
    let fall = (fall_s / dt).ceil() as u64;
    let rest = ((spec.max_settle_s - fall_s).max(0.0) / dt).ceil() as u64;
    let check = ((0.005 / dt).round() as u64).max(1);
    let at = resume.map_or(0, |r| r.step);
    let _ = write!(
        s,
        "neigh_modify delay 0 every 1 check yes\n\
         fix gravity grains gravity {} vector 0 0 -1\n\
         fix integrate grains nve/sphere\n\
         {balance}\
         variable rms_speed equal sqrt(2*ke/mass(grains))\n\
         thermo_style custom step time atoms ke v_rms_speed\n\
         thermo {check}\n\
         thermo_modify lost error norm no\n\
         {}",
        spec.gravity_m_s2,
        restart_line("settle", restart_every),
        balance = balance_line(spec),
    );
    let cap = |step: u64| spec.capped_step(step);
    if at < fall {
        let _ = writeln!(
            s,
            "# the fall: no grain can be at rest before the highest has reached the bed\n\
             run {} upto",
            cap(fall)
        );
    }
    let _ = write!(
        s,
        "fix halt grains halt {check} v_rms_speed < {:e} error continue\n\
         run {} upto\n\
         unfix halt\n\
         write_data settled.data\n",
        spec.settled_rms_speed_m_s,
        cap(fall + rest)
    );
    Ok(s)
}

/// `in.intrude`: the foot on its `pieces`, the force and the dumps, a restart file every
/// `restart_every` steps of the intrusion; from `resume` on, when given (the bed's relaxation
/// against the still foot is then behind it). The foot's axis is at (`cx`, `cy`);
/// `foot_sphere_m` is its spheres' diameter.
///
/// Each piece's `fix move` has its own ID (`move_K`): a restart within piece K gives that
/// fix its origin back, so the foot goes on from where it was; a piece that starts at the
/// restart's step starts anew from there.
#[allow(clippy::too_many_arguments)]
pub fn intrude_script(
    spec: &LammpsSpec,
    run_id: &str,
    box_width_m: f64,
    pieces: &[Piece],
    centre: (f64, f64),
    foot_sphere_m: f64,
    bottom_m: f64,
    restart_every: u64,
    resume: Option<Resume>,
) -> String {
    let start = resume.map_or(Start::Data("intrude.data"), Start::Restart);
    let mut s = header(
        spec,
        "intrusion",
        run_id,
        (start, box_width_m),
        spec.friction,
        // The grains that poured with rolling friction keep it (it stands for their shape).
        spec.pour_rolling_friction(),
    );
    let fe = spec.force_every();
    let de = spec.dump_every();
    let total: u64 = pieces.iter().map(|p| p.steps).sum();
    let reach = spec.dump_radius_factor * spec.foot_radius_m();
    let relax = ((spec.relax_s / spec.time_step_s()).round() as u64).max(1);
    let cap = |step: u64| spec.capped_step(step);
    let relax = cap(relax);
    let _ = write!(
        s,
        "group foot type 2\n\
         neigh_modify delay 0 every 1 check yes exclude type 2 2\n\
         fix gravity grains gravity {g} vector 0 0 -1\n\
         fix integrate grains nve/sphere\n\
         {balance}",
        g = spec.gravity_m_s2,
        balance = balance_line(spec),
    );
    // force.txt and column.txt from the start, or appended to (the caller cut them at the
    // restart's step).
    let force_file = match resume {
        None => {
            let _ = write!(
                s,
                "# the bed relaxes against the foot, held still (the contacts' history starts anew)\n\
                 fix hold foot move linear 0 0 0\n\
                 thermo {relax}\n\
                 run {relax}\n\
                 unfix hold\n\
                 reset_timestep 0 time 0\n"
            );
            "file force.txt"
        }
        Some(_) => "append force.txt",
    };
    let column_file = force_file.replace("force.txt", "column.txt");
    let r = spec.foot_radius_m();
    let _ = write!(
        s,
        "{restart}\
         compute foot_fz foot reduce sum fz\n\
         compute foot_zmin foot reduce min z\n\
         variable t equal time\n\
         fix force all ave/time 1 {fe} {fe} v_t c_foot_fz c_foot_zmin {force_file} format \" %.9g\"\n\
         # the column under the foot, measured in LAMMPS: the grains whose centres lie within\n\
         # the foot's radius of its axis and below its bottom (regions that move with it), and\n\
         # the ring R..2R below it; each grain's down momentum summed\n\
         variable foot_dz equal 0\n\
         region under cylinder z {cx:e} {cy:e} {r:e} INF {bottom_m:e} side in move NULL NULL v_foot_dz\n\
         region wide cylinder z {cx:e} {cy:e} {r2:e} INF {bottom_m:e} side in move NULL NULL v_foot_dz\n\
         region beyond cylinder z {cx:e} {cy:e} {r:e} INF INF side out\n\
         region ring intersect 2 wide beyond\n\
         variable down_p atom -mass*vz\n\
         variable one atom 1\n\
         compute under_p grains reduce/region under sum v_down_p\n\
         compute under_n grains reduce/region under sum v_one\n\
         compute ring_p grains reduce/region ring sum v_down_p\n\
         fix column all ave/time {de} 1 {de} c_under_p c_under_n c_ring_p {column_file} format \" %.12g\"\n\
         {dumps}\
         thermo_style custom step time atoms c_foot_fz c_foot_zmin\n\
         thermo {de}\n\
         thermo_modify lost error norm no\n\
         # the foot: {n} piece(s), {total} steps; its spheres are {fd:e} m across\n",
        restart = restart_line("intrude", restart_every),
        dumps = match spec.dump_every_frames {
            0 => "# no dumps: the column is LAMMPS's own (column.txt)\n".to_string(),
            n => format!(
                "region near cylinder z {cx:e} {cy:e} {reach:e} INF INF side in\n\
                 dump frames all {style} {every} dumps/frame.*.{ext} id type x y z vx vy vz radius\n\
                 dump_modify frames region near sort id format float %.9g\n",
                cx = centre.0,
                cy = centre.1,
                every = de * n,
                style = match spec.dump_format {
                    crate::spec::DumpFormat::Text => "custom",
                    crate::spec::DumpFormat::Gzip => "custom/gz",
                },
                ext = match spec.dump_format {
                    crate::spec::DumpFormat::Text => "txt",
                    crate::spec::DumpFormat::Gzip => "txt.gz",
                },
            ),
        },
        r2 = 2.0 * r,
        cx = centre.0,
        cy = centre.1,
        n = pieces.len(),
        fd = foot_sphere_m,
    );
    let from = resume.map_or(0, |r| r.step);
    let (mut end, mut dz) = (0, 0.0);
    let dt = spec.time_step_s();
    let total: u64 = pieces.iter().map(|p| p.steps).sum();
    for (k, p) in pieces.iter().enumerate() {
        let start = end;
        end += p.steps;
        // A restart written at the last step (the run killed before it was recorded done) runs
        // the last piece for no step: its setup writes the last column row again.
        let last_again = from >= total && k + 1 == pieces.len();
        if (end > from && start < cap(end)) || last_again {
            // The regions follow the foot: its displacement along this piece, exact at every
            // step (the path is the pieces').
            let _ = write!(
                s,
                "variable foot_dz equal {dz:e}+({:e})*(step-{start})*{dt:e}\n\
                 fix move_{k} foot move linear 0 0 {:e}\nrun {} upto\nunfix move_{k}\n",
                p.vz_m_s,
                p.vz_m_s,
                cap(end)
            );
        }
        dz += p.vz_m_s * p.steps as f64 * dt;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::{LammpsSpec, Preset};

    #[test]
    fn a_table_becomes_pieces_that_end_where_it_does() {
        let spec = LammpsSpec::preset(Preset::Small);
        let t = Trajectory::Table {
            t_s: vec![0.0, 0.004, 0.010],
            depth_m: vec![0.0, 0.002, 0.0026],
            source: "test".into(),
        };
        let p = pieces(&spec, &t);
        let dt = spec.time_step_s();
        let total: u64 = p.iter().map(|p| p.steps).sum();
        assert_eq!(total % spec.dump_every(), 0, "the end is in a frame");
        assert!(total as f64 * dt >= 0.010 - 1e-12);
        // The integrated path equals the table at every window end.
        let mut z = 0.0;
        let mut steps = 0;
        for piece in &p {
            z += piece.vz_m_s * piece.steps as f64 * dt;
            steps += piece.steps;
            let t_end = steps as f64 * dt;
            assert!((-z - t.depth(t_end)).abs() < 1e-12, "{t_end}");
        }
        // A constant speed is one piece.
        let c = Trajectory::Constant {
            speed_m_s: 0.1,
            start_depth_m: 0.0,
            end_depth_m: 0.02,
        };
        let p = pieces(&spec, &c);
        assert_eq!(p.len(), 1);
        assert!((p[0].vz_m_s + 0.1).abs() < 1e-12);
    }

    #[test]
    fn the_scripts_name_the_contacts_the_rates_and_the_run() {
        let spec = LammpsSpec::preset(Preset::Small);
        let s = settle_script(&spec, "abc", 0.06, 0.1, 1000, None).unwrap();
        assert!(s.contains("(run abc)"));
        // The pour's friction sets the packing; the intrusion has the grains'.
        let pour = spec.pour_friction().unwrap();
        assert!(s.contains(&format!(
            "tangential mindlin NULL 1.0 {pour} damping coeff_restitution"
        )));
        assert!(s.contains("write_data settled.data"));
        let p = [Piece {
            steps: spec.force_every() * 3,
            vz_m_s: -0.1,
        }];
        let deck = |resume| {
            intrude_script(
                &spec,
                "abc",
                0.06,
                &p,
                (0.03, 0.03),
                0.0018,
                0.03,
                100,
                resume,
            )
        };
        let i = deck(None);
        assert!(i.contains(&format!(
            "custom/gz {} dumps/frame.*.txt.gz id",
            spec.dump_every()
        )));
        assert!(i.contains("exclude type 2 2"));
        assert!(i.contains("tangential mindlin NULL 1.0 0.5 damping coeff_restitution"));
        assert!(i.contains("fix move_0 foot move linear 0 0 -1e-1\nrun 150 upto\n"));
        assert!(i.contains("restart 100 restart/intrude.*") && i.contains("file force.txt"));
        // Resumed from the last step: the last piece again, for no step.
        let end = spec.force_every() * 3;
        let again = deck(Some(Resume {
            file: "restart/intrude.150",
            step: end,
        }));
        assert!(again.contains(&format!("run {end} upto")), "{again}");
        assert!(again.contains("read_restart restart/intrude.150") && again.contains("append"));
    }
}
