//! `sandjumper dem lammps` and `dem lammps-read` at the command line, without running
//! LAMMPS: a missing LAMMPS and bad values refused with exit 2 before anything runs, a LAMMPS
//! that fails (a fake) exiting 1 with its files kept and its log named, `--slurm` without
//! Slurm, and read-backs refused (into the run itself, a folder without its manifest).
//!
//! The run on a real LAMMPS, checked against numbers derived from its files, and the
//! read-back's refusals of spoilt dumps: sim-host/lammps/tests/integration/real_lammps.rs.

use crate::common;

use std::path::Path;
use std::process::Command;

use common::sandjumper;

/// `dem lammps-read RUN --out OUT` (and `extra`).
fn read_back(run: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "dem",
        "lammps-read",
        run.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    sandjumper(&args)
}

#[test]
fn without_lammps_or_with_bad_values_dem_lammps_refuses_before_anything_runs() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("run");
    let cases: [(&[&str], &str); 6] = [
        (
            &["--speed", "0.1", "--lmp", "/nonexistent/lmp"],
            "pip install",
        ),
        (&["--speed", "0.1", "--phi", "0.7"], "0.7"),
        (
            &["--speed", "0.1", "--foot-diameter", "0.005"],
            "4 grain diameters",
        ),
        (&[], "--speed"),
        (
            &["--speed", "0.1", "--depth", "0.04"],
            "5 grain diameters above the floor",
        ),
        (
            &["--speed", "0.1", "--grain-diameter", "0.0001"],
            "grains (allowed: up to",
        ),
    ];
    for (extra, why) in cases {
        let mut args = vec![
            "dem",
            "lammps",
            "--preset",
            "small",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = sandjumper(&args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {e}");
        assert!(e.contains(why), "{extra:?}: {e}");
        assert!(!out.exists());
    }
    // A LAMMPS that fails: the run's files are kept beside the output, the log named, and the
    // same command said to resume it.
    let fake = work.path().join("lmp");
    std::fs::write(
        &fake,
        "#!/bin/sh\nif [ \"$1\" = \"-h\" ]; then\n  printf '\\nLarge-scale Atomic/Molecular \
         Massively Parallel Simulator - 1 Jan 2099 - fake\\n\\nInstalled packages:\\n\\nGRANULAR\\n\\n\
         List of individual style options\\n'\n  exit 0\nfi\necho 'ERROR: this LAMMPS fails every \
         run (fake.cpp:1)'\nexit 1\n",
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let o = sandjumper(&[
        "dem",
        "lammps",
        "--preset",
        "small",
        "--speed",
        "0.1",
        "--ranks",
        "1",
        "--lmp",
        fake.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let kept = work.path().join("run.unfinished/lammps");
    assert!(e.contains("this LAMMPS fails every run"), "{e}");
    assert!(e.contains("the same command resumes it"), "{e}");
    assert!(
        e.contains(&kept.join("log.settle").display().to_string()),
        "{e}"
    );
    assert!(kept.join("in.settle").is_file() && kept.join("pour.data").is_file());
    assert!(!out.exists());
    // --slurm without Slurm.
    let o = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args([
            "dem",
            "lammps",
            "--preset",
            "small",
            "--speed",
            "0.1",
            "--lmp",
            fake.to_str().unwrap(),
            "--slurm",
            "--out",
            out.to_str().unwrap(),
        ])
        .env("PATH", work.path())
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("sbatch"), "{e}");
    // A run read back into itself.
    let fake_run = work.path().join("fake-run");
    std::fs::create_dir_all(&fake_run).unwrap();
    std::fs::write(fake_run.join("run.toml"), "").unwrap();
    let o = read_back(&fake_run, &fake_run.join("lammps"), &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--out"));
    assert!(fake_run.join("run.toml").is_file());
    // A run folder without its manifest.
    let empty = work.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = read_back(&empty, &out, &[]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("run.toml"), "{e}");
}
