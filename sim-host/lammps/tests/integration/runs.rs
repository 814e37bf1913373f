//! `dem lammps` and `dem lammps-read` as library calls: their refusals before anything runs,
//! a LAMMPS that fails keeping its files, a read-back that refuses its own run as output.

use std::path::{Path, PathBuf};

use sandjumper_lammps::run::{self, LammpsReadRequest, LammpsRequest};
use sandjumper_lammps::spec::Preset;
use sandjumper_output::{Blame, Blamed, Silent};

fn small(out: &std::path::Path) -> LammpsRequest {
    LammpsRequest {
        preset: Preset::Small,
        speed_m_s: Some(0.1),
        out: out.to_path_buf(),
        ..LammpsRequest::default()
    }
}

#[test]
fn bad_values_and_a_missing_lammps_are_refused_before_anything_runs() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("run");
    let cases = [
        (
            LammpsRequest {
                lmp: Some("/nonexistent/lmp".into()),
                ..small(&out)
            },
            "pip install",
        ),
        (
            LammpsRequest {
                phi: Some(0.7),
                ..small(&out)
            },
            "0.7",
        ),
        (
            LammpsRequest {
                speed_m_s: None,
                ..small(&out)
            },
            "--speed",
        ),
        (
            LammpsRequest {
                depth_m: 0.04,
                ..small(&out)
            },
            "5 grain diameters above the floor",
        ),
    ];
    for (request, why) in cases {
        let e = run::run(&request, &Silent).unwrap_err();
        assert_eq!(e.blame(), Blame::Input, "{e}");
        assert!(e.to_string().contains(why), "{e}");
        assert!(!out.exists());
    }
    assert!(small(&out).validate().is_ok());
}

#[test]
fn a_failed_lammps_keeps_its_files_beside_the_output_for_the_same_command_to_resume() {
    let work = tempfile::tempdir().unwrap();
    let fake = failing_lammps(work.path(), false);
    let out = work.path().join("run");
    let e = run::run(
        &LammpsRequest {
            ranks: 1,
            lmp: Some(fake.clone()),
            ..small(&out)
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Internal, "{e}");
    assert!(e.to_string().contains("run.unfinished"), "{e}");
    assert!(e.to_string().contains("the same command resumes it"), "{e}");
    assert!(
        work.path()
            .join("run.unfinished/lammps/in.settle")
            .is_file()
    );
    assert!(!out.exists());
    // The lock is the process's: it ended with the call.
    assert!(!sandjumper_output::WriterLock::is_held(
        &work.path().join("run.unfinished/.lock")
    ));
    // Another run into the same output, of other inputs, is refused (exit 2), here and as a
    // Slurm job before it is queued (no sbatch is looked for).
    let other = LammpsRequest {
        ranks: 1,
        seed: Some(7),
        lmp: Some(fake),
        ..small(&out)
    };
    let queue = sandjumper_slurm::QueueOptions::default();
    for e in [
        run::run(&other, &Silent).unwrap_err(),
        run::submit(&other, Path::new("/opt/sandjumper"), &queue, &Silent).unwrap_err(),
    ] {
        assert_eq!(e.blame(), Blame::Input, "{e}");
        let text = e.to_string();
        assert!(
            text.contains("holds an unfinished run of other inputs"),
            "{e}"
        );
    }
    assert!(!work.path().join("run.slurm").exists());
}

#[test]
fn a_read_back_refuses_an_output_inside_its_run_and_a_folder_without_one() {
    let work = tempfile::tempdir().unwrap();
    let inside = LammpsReadRequest {
        run: work.path().to_path_buf(),
        out: work.path().join("again"),
        ..LammpsReadRequest::default()
    };
    let e = run::read(&inside, &Silent).unwrap_err();
    assert!(e.to_string().contains("or holds it or lies in it"), "{e}");
    let nothing = LammpsReadRequest {
        run: work.path().join("empty"),
        out: work.path().join("out"),
        ..LammpsReadRequest::default()
    };
    let e = run::read(&nothing, &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(e.to_string().contains("run.toml"), "{e}");
}

#[test]
fn a_slurm_submission_refuses_what_a_run_refuses_before_it_looks_for_slurm() {
    let work = tempfile::tempdir().unwrap();
    let out = work.path().join("run");
    let queue = sandjumper_slurm::QueueOptions::default();
    for (request, why) in [
        (
            LammpsRequest {
                speed_m_s: None,
                ..small(&out)
            },
            "--speed",
        ),
        (
            LammpsRequest {
                lmp: Some("/nonexistent/lmp".into()),
                ..small(&out)
            },
            "pip install",
        ),
    ] {
        let e = run::submit(&request, Path::new("/opt/sandjumper"), &queue, &Silent).unwrap_err();
        assert_eq!(e.blame(), Blame::Input, "{e}");
        assert!(e.to_string().contains(why), "{e}");
        assert!(!out.exists() && !work.path().join("run.slurm").exists());
    }
}

/// The cost printed before a run: each stage at its measured rate, the settle at its longest,
/// none with a bed given; the paper preset's push-off a cluster's job.
#[test]
fn the_cost_counts_each_stage_at_its_rate_and_a_given_bed_saves_the_settle() {
    let work = tempfile::tempdir().unwrap();
    let request = small(&work.path().join("run"));
    let (spec, traj) = (request.spec(), request.trajectory().unwrap());
    let poured = request.cost(&spec, &traj);
    let reused = LammpsRequest {
        bed: Some(work.path().join("bed")),
        ..request.clone()
    }
    .cost(&spec, &traj);
    assert!(poured.settle_steps > 0.0 && poured.settle_core_hours > 0.0);
    assert_eq!((reused.settle_steps, reused.settle_core_hours), (0.0, 0.0));
    assert_eq!(reused.intrusion_core_hours, poured.intrusion_core_hours);
    let grain_steps = poured.grains * poured.intrusion_steps;
    assert!(
        (poured.intrusion_core_hours * 3600.0 * run::INTRUSION_GRAIN_STEPS_PER_CORE_S
            - grain_steps)
            .abs()
            < 1e-6 * grain_steps
    );
    let text = poured.to_string();
    assert!(
        text.contains("settle") && text.contains("intrusion"),
        "{text}"
    );
    let paper = LammpsRequest {
        speed_m_s: Some(0.5),
        depth_m: 0.03,
        ranks: 256,
        out: work.path().join("paper"),
        ..LammpsRequest::default()
    };
    let cost = paper.cost(&paper.spec(), &paper.trajectory().unwrap());
    eprintln!("{cost}");
    assert!(
        cost.settle_core_hours > 10.0 * cost.intrusion_core_hours,
        "{cost}"
    );
}

/// A stand-in LAMMPS in `dir` that answers `-h` (with the COMPRESS package when `compress`)
/// and fails every run.
fn failing_lammps(dir: &Path, compress: bool) -> PathBuf {
    let fake = dir.join(if compress { "lmp-gz" } else { "lmp-text" });
    std::fs::write(
        &fake,
        format!(
            "#!/bin/sh\nif [ \"$1\" = \"-h\" ]; then\n  printf '\\nLarge-scale Atomic/Molecular \
             Massively Parallel Simulator - 1 Jan 2099 - fake\\n\\nInstalled packages:\\n\\n{}GRANULAR\\n\\n\
             List of individual style options\\n'\n  exit 0\nfi\necho 'ERROR: this LAMMPS fails \
             every run (fake.cpp:1)'\nexit 1\n",
            if compress { "COMPRESS " } else { "" }
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    fake
}

#[test]
fn gzip_dumps_need_compress_and_an_unfinished_text_run_resumes_as_text() {
    use sandjumper_lammps::spec::DumpFormat;
    let work = tempfile::tempdir().unwrap();
    let (plain, gz) = (
        failing_lammps(work.path(), false),
        failing_lammps(work.path(), true),
    );
    let out = work.path().join("run");
    // Gzip asked of a LAMMPS without COMPRESS: refused before anything is made (exit 2);
    // with no dumps at all there is nothing to compress, and it is not.
    let e = run::run(
        &LammpsRequest {
            ranks: 1,
            lmp: Some(plain.clone()),
            dump_format: Some(DumpFormat::Gzip),
            ..small(&out)
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert!(e.to_string().contains("COMPRESS"), "{e}");
    assert!(!run::unfinished_dir(&out).exists());
    // A text run that failed (as a run before gzip was the default did) ...
    let text = LammpsRequest {
        ranks: 1,
        lmp: Some(gz.clone()),
        dump_format: Some(DumpFormat::Text),
        ..small(&out)
    };
    let e = run::run(&text, &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Internal, "{e}");
    // ... is resumed by the command without --dump-format on a LAMMPS with COMPRESS (whose
    // default is gzip): the fake fails it again, but as a resume, not as other inputs.
    let e = run::run(
        &LammpsRequest {
            dump_format: None,
            ..text.clone()
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Internal, "{e}");
    assert!(e.to_string().contains("the same command resumes it"), "{e}");
    // Gzip asked for explicitly is another run.
    let e = run::run(
        &LammpsRequest {
            dump_format: Some(DumpFormat::Gzip),
            ..text
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input, "{e}");
    assert!(e.to_string().contains("other inputs"), "{e}");
}
