//! `sandjumper dem bed | intrude | collide` at the command line (#23): what they print
//! (`--json` keys, the dimensionless numbers), which files an intrusion writes, a stopped run
//! that prints where it resumes and writes nothing until resumed, and bad input refused with
//! exit 2 and a message.
//!
//! The behaviour (collisions against the analytic spring-dashpot, checkpoints, determinism
//! and resume, structure, added mass, PIV on the DEM's frames) is checked on the library
//! calls in `sim-host/dem/tests/` (`collisions.rs`, `dem_bed.rs`, `intrusion.rs`).

use std::path::Path;

use crate::common;
use common::sandjumper_text;

#[test]
fn collide_prints_the_verification_numbers_as_json() {
    let (code, out, err) = sandjumper_text(&[
        "dem",
        "collide",
        "--d1",
        "1e-3",
        "--d2",
        "1.4e-3",
        "--kn",
        "1000",
        "--damping",
        "0.005",
        "--speed",
        "0.3",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for k in ["restitution", "contact_time_s", "effective_mass_kg", "dt_s"] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k} in {out}");
    }
    // The numbers themselves (the effective mass, the restitution against the analytic one):
    // sim-host/dem/tests/integration/collisions.rs.
    assert!(v["restitution_error"].as_f64().is_some(), "{out}");
}

#[test]
fn unphysical_collisions_are_refused_with_exit_2() {
    let base = [
        "dem", "collide", "--d1", "1e-3", "--d2", "1e-3", "--speed", "0.3",
    ];
    let cases: [(&[&str], &str); 4] = [
        (&["--kn=-5", "--damping", "0"], "stiffness"),
        (&["--kn", "1000", "--damping", "1"], "overdamps"),
        (
            &["--kn", "1000", "--damping", "0", "--dt", "1e-5"],
            "t_c/10",
        ),
        (&["--kn", "1000", "--damping=-1"], "damping"),
    ];
    for (extra, want) in cases {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let (code, _, err) = sandjumper_text(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(err.contains(want), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // --force-step runs the coarse step anyway.
    let (code, _, err) = sandjumper_text(&[
        "dem",
        "collide",
        "--d1",
        "1e-3",
        "--wall",
        "--kn",
        "1000",
        "--damping",
        "0",
        "--speed",
        "0.3",
        "--dt",
        "1e-5",
        "--force-step",
    ]);
    assert_eq!(code, 0, "{err}");
}

fn bed(dir: &Path, extra: &[&str]) -> String {
    let out = dir.join("bed");
    let mut args = vec![
        "dem",
        "bed",
        "--pack",
        "0.8",
        "--width",
        "0.016",
        "--height",
        "0.008",
        "--overlap",
        "0.02",
        "--out",
    ];
    let o = out.to_str().unwrap().to_string();
    args.push(&o);
    args.extend_from_slice(extra);
    let (code, _, err) = sandjumper_text(&args);
    assert_eq!(code, 0, "{err}");
    o
}

fn intrude(bed: &str, out: &Path, extra: &[&str]) -> (i32, String, String) {
    let o = out.to_str().unwrap().to_string();
    let mut args = vec![
        "dem",
        "intrude",
        "--bed",
        bed,
        "--speed",
        "0.3",
        "--overlap",
        "0.02",
        "--walls",
        "--out",
        &o,
    ];
    if !extra.contains(&"--depth") {
        args.extend_from_slice(&["--depth", "0.002"]);
    }
    if !extra.contains(&"--foot-width") {
        args.extend_from_slice(&["--foot-width", "0.006"]);
    }
    args.extend_from_slice(extra);
    sandjumper_text(&args)
}

/// A stopped intrusion (`--stop-after`) says where it stopped and writes no output folder;
/// `--resume` finishes it; a `--resume` with nothing to resume exits 2 naming `--resume`.
/// (That the resumed run gives the same bits as a straight one, on one or two threads:
/// sim-host/dem/tests/integration/intrusion.rs.)
#[test]
fn a_stopped_intrusion_resumes_and_a_resume_of_nothing_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let res = tmp.path().join("res");
    let (c, out, e) = intrude(
        &b,
        &res,
        &[
            "--no-frames",
            "--checkpoint-every",
            "1000",
            "--stop-after",
            "2500",
        ],
    );
    assert_eq!(c, 0, "{e}");
    assert!(out.contains("stopped after 2500"), "{out}");
    assert!(!res.exists(), "a stopped run must not look finished");
    let r = res.to_str().unwrap();
    let (c, _, e) = sandjumper_text(&["dem", "intrude", "--resume", "--out", r]);
    assert_eq!(c, 0, "{e}");
    assert!(res.join("force_depth.csv").is_file());
    // A resume with nothing to resume is refused.
    let none = tmp.path().join("none");
    let (c, _, e) = sandjumper_text(&[
        "dem",
        "intrude",
        "--resume",
        "--out",
        none.to_str().unwrap(),
    ]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("--resume"), "{e}");
}

/// `dem intrude --json` writes its folder (data, figures, frames for `piv`, the camera, the
/// resolved parameters), prints the dimensionless numbers on stderr and the summary's keys
/// on stdout: one name per quantity, `window_depth_warning` exactly when the bottom tenth's
/// share is above 5 %. (What the numbers are: the added mass growing then saturating, the
/// force resisting the foot, in sim-host/dem/tests/integration/intrusion.rs, on a bed wide against the
/// foot; here the small bed with walls, which writes the same files.)
#[test]
fn an_intrusion_writes_its_folder_and_prints_its_summary_as_json() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let out = tmp.path().join("run");
    let (c, json, e) = intrude(&b, &out, &["--json"]);
    assert_eq!(c, 0, "{e}");
    for f in [
        "force_depth.csv",
        "force_depth.png",
        "force_depth.svg",
        "flow.csv",
        "added_mass.csv",
        "added_mass.png",
        "added_mass.svg",
        "shear_rate.png",
        "shear_rate.svg",
        "snapshot.png",
        "snapshot.svg",
        "animation.gif",
        "dem.toml",
        "summary.json",
        "u_m_s.npy",
        "v_m_s.npy",
        "shear_rate_per_s.npy",
        "foot.csv",
        "camera.toml",
        "frames/frame_000000.png",
        "fields/0000.csv",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    assert!(
        e.contains("Froude"),
        "the dimensionless numbers are printed: {e}"
    );
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    for k in [
        "grain_momentum_under_foot_kg_m_s",
        "added_mass_vs_eq6_median",
        "momentum_beyond_cone_depth_share",
        "momentum_in_window_bottom_tenth_share",
    ] {
        assert!(v[k].is_number(), "{k} in {json}");
    }
    assert!(
        v.get("added_mass_ratio_to_model").is_none(),
        "one name per quantity"
    );
    let bottom = v["momentum_in_window_bottom_tenth_share"].as_f64().unwrap();
    assert_eq!(
        v.get("window_depth_warning").is_some(),
        bottom > 0.05,
        "{json}"
    );
}

#[test]
fn bad_intrusions_are_refused_with_exit_2() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let out = tmp.path().join("x");
    let (c, _, e) = intrude(&b, &out, &["--foot-width", "0.05"]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("wider than the bed"), "{e}");
    // Trajectory CSVs: a missing column, time going back.
    let t1 = tmp.path().join("t1.csv");
    std::fs::write(&t1, "t_s,height\n0,0\n0.001,0.001\n").unwrap();
    let t2 = tmp.path().join("t2.csv");
    std::fs::write(&t2, "t_s,depth_m\n0,0\n0.002,0.001\n0.001,0.002\n").unwrap();
    let o = out.to_str().unwrap();
    for (t, want) in [(&t1, "no `x_f_m` or `depth_m`"), (&t2, "does not increase")] {
        let (c, _, e) = sandjumper_text(&[
            "dem",
            "intrude",
            "--bed",
            &b,
            "--trajectory",
            t.to_str().unwrap(),
            "--foot-width",
            "0.006",
            "--out",
            o,
        ]);
        assert_eq!(c, 2, "{e}");
        assert!(e.contains(want), "{e}");
    }
    // A corrupt bed checkpoint.
    let ck = Path::new(&b).join("bed.ckpt");
    let mut bytes = std::fs::read(&ck).unwrap();
    let k = bytes.len() / 3;
    bytes[k] ^= 1;
    std::fs::write(&ck, bytes).unwrap();
    let (c, _, e) = intrude(&b, &out, &[]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("checksum"), "{e}");
    // More pinned threads than cores.
    let (c, _, e) = intrude(&b, &out, &["--threads", "100000", "--pin-threads"]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("--pin-threads: 100000 threads need"), "{e}");
    // Unphysical grains.
    let (c, _, e) = sandjumper_text(&["dem", "bed", "--kn=-1", "--out", o]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("stiffness"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}

/// A jump's trajectory starts with the foot at rest below the surface of an intact bed: it
/// is refused as it is with exit 2, the message naming `--episode push-off`; `--episode` with
/// `--from` is refused too. (The push-off taken, stopped and resumed:
/// sim-host/dem/tests/integration/intrusion.rs.)
#[test]
fn a_jump_trajectory_is_refused_below_the_surface_and_the_episode_takes_no_from() {
    let tmp = tempfile::tempdir().unwrap();
    let b = bed(tmp.path(), &[]);
    let jump = tmp.path().join("jump");
    let (c, _, e) = sandjumper_text(&[
        "jump",
        "--kind",
        "stutter",
        "--freq",
        "20",
        "--model",
        "eq4",
        "--phi",
        "0.57",
        "--out",
        jump.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    let traj = jump.join("trajectory.csv");
    let out = tmp.path().join("run");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "dem",
            "intrude",
            "--bed",
            &b,
            "--trajectory",
            traj.to_str().unwrap(),
            "--foot-width",
            "0.006",
            "--overlap",
            "0.02",
            "--no-frames",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        sandjumper_text(&args)
    };
    let (c, _, e) = run(&[]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("below the bed's surface"), "{e}");
    assert!(e.contains("--episode push-off"), "{e}");
    let (c, _, e) = run(&["--episode", "push-off", "--from", "0.1"]);
    assert_eq!(c, 2, "{e}");
    assert!(!out.exists());
}

/// Two processes on one output: while a `dem intrude` runs, a second one into the same
/// `--out` (fresh or `--resume`) is refused with exit 2 naming the first's process, and the
/// first's checkpoint is left alone; `kill -9` of the first leaves no stale lock, and
/// `--resume` finishes it to the same bits as an unbroken run.
#[test]
fn a_second_process_is_refused_and_a_killed_run_resumes_to_the_unbroken_bits() {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let b = bed(dir.path(), &[]);
    let words = |out: &Path| -> Vec<String> {
        [
            "dem",
            "intrude",
            "--bed",
            &b,
            "--speed",
            "0.002",
            "--depth",
            "0.002",
            "--foot-width",
            "0.006",
            "--overlap",
            "0.02",
            "--walls",
            "--no-frames",
            "--threads",
            "1",
            "--checkpoint-every",
            "5000",
            "--out",
        ]
        .iter()
        .map(|w| w.to_string())
        .chain([out.to_str().unwrap().to_string()])
        .collect()
    };
    let out = dir.path().join("raced");
    let mut first = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(words(&out))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Running once its lock names it and it has written a regular checkpoint past step 0.
    let work = dir.path().join("raced.incomplete");
    let me = format!("process {} on ", first.id());
    let mut waited = 0;
    while !(std::fs::read_to_string(work.join(".lock")).is_ok_and(|r| r.starts_with(&me))
        && std::fs::metadata(work.join("run.ckpt")).is_ok_and(|m| m.len() > 0))
    {
        assert!(
            first.try_wait().unwrap().is_none(),
            "the first run ended before the race"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
        waited += 1;
        assert!(waited < 30_000, "the first run never started");
    }
    for extra in [&[][..], &["--resume"][..]] {
        let mut w = words(&out);
        w.extend(extra.iter().map(|s| s.to_string()));
        let refs: Vec<&str> = w.iter().map(String::as_str).collect();
        let (code, _, err) = sandjumper_text(&refs);
        assert!(
            first.try_wait().unwrap().is_none(),
            "the first run ended during the race (slow it down: a lower --speed)"
        );
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(&me) && err.contains("one run writes"), "{err}");
    }
    // The live run's checkpoint is still there (a second fresh start would have cleared it).
    assert!(work.join("run.ckpt").is_file());
    first.kill().unwrap(); // SIGKILL
    first.wait().unwrap();
    let mut w = words(&out);
    w.push("--resume".into());
    let refs: Vec<&str> = w.iter().map(String::as_str).collect();
    let (code, _, err) = sandjumper_text(&refs);
    assert_eq!(code, 0, "{err}");
    let straight = dir.path().join("straight");
    let w = words(&straight);
    let refs: Vec<&str> = w.iter().map(String::as_str).collect();
    let (code, _, err) = sandjumper_text(&refs);
    assert_eq!(code, 0, "{err}");
    for f in ["force_depth.csv", "flow.csv"] {
        assert_eq!(
            std::fs::read_to_string(out.join(f)).unwrap(),
            std::fs::read_to_string(straight.join(f)).unwrap(),
            "{f}: killed and resumed against unbroken"
        );
    }
}
