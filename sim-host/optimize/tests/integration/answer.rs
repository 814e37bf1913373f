//! `sandjumper_optimize::run` on the small budgets the command line's tests used: the answer
//! is the best stroke through the controller and the rig accepts it, a seed fixes it whatever
//! the threads, a search killed mid-way resumes to it, and the other objectives and the hard
//! ground run. (Moved from `cli/tests/integration/optimize.rs`, which keeps the command's contract.)

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use sandjumper_model::ModelName;
use sandjumper_optimize::evaluate::Objective;
use sandjumper_optimize::{
    OptimizeError, OptimizeOutcome, OptimizeRequest, checkpoint_lock_path, checkpoint_path, run,
};
use sandjumper_output::{Blame, Blamed, Progress, Silent};
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::stroke_table::{RigLimits, StrokeTable};

/// The workspace's root directory (two levels above `sim-host/optimize`).
fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("sim-host/optimize sits in the workspace")
}

/// A small search: a coarse paper sweep, a few hundred evaluations, two random starts, the
/// candidates ranked through sil and the best refined there (`optimize --evaluations 720
/// --population 12 --random-starts 1 --sweep-freq-step 1 --sweep-tau-step 0.1 --elites 3
/// --paper-candidates 2 --refine 48 --verify sil`).
fn small(out: &Path) -> OptimizeRequest {
    OptimizeRequest {
        evaluations: 720,
        population: 12,
        random_starts: 1,
        sweep_freq_step_hz: 1.0,
        sweep_tau_step_s: 0.1,
        elites: 3,
        paper_candidates: 2,
        refine: 48,
        verify: vec![LinkArg::Sil],
        firmware: workspace().join(sandjumper_rig::firmware_image::EMULATED_ELF),
        out: out.to_path_buf(),
        ..OptimizeRequest::default()
    }
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The answer is the best stroke through the controller of the candidates' ranking, which
/// holds the paper's best; the paper's answer is the best paper stroke there; both ran through
/// every link (sil, the emulated firmware under QEMU, the F407 release binary on the virtual
/// board, each where it is built: `.ci/run` builds them; skipped with a message elsewhere)
/// within 3 % of sil; the stroke passes the rig's own check and its table's jump is the one
/// written in stroke.csv.
#[test]
fn the_answer_is_the_best_through_the_controller_and_every_link_runs_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("opt");
    let o = run(
        &OptimizeRequest {
            verify: vec![LinkArg::Sil, LinkArg::Pil, LinkArg::F407],
            ..small(&out)
        },
        &Silent,
    )
    .unwrap();
    let (h, hp) = (o.best_height_m, o.best_paper_stroke_height_m);
    assert_eq!(o.height_basis, "sil");
    assert!(hp > 0.01 && h > 0.01, "{h} {hp}");
    assert!((o.height_ratio - h / hp).abs() < 1e-12);
    assert_eq!(o.refine_runs, 48);
    // The best through the controller among the ranked candidates (at least two of them ran).
    let ran = o
        .candidates
        .iter()
        .filter(|c| c.controller_value.is_finite());
    assert!(ran.clone().count() >= 2, "{:?}", o.candidates);
    let best = ran.map(|c| c.controller_value).fold(f64::MIN, f64::max);
    assert_eq!(o.best_value, best);
    // candidates.csv ranks through the controller: its first row is the answer.
    assert_eq!(o.candidates[0].label, o.answer.label);
    let cands = read(&out.join("candidates.csv"));
    let first = cands.lines().nth(1).unwrap();
    assert!(first.contains(&o.answer.label), "{first}");
    for (what, stroke) in [("answer", &o.answer), ("paper_answer", &o.paper_answer)] {
        let links = &stroke.links;
        assert_eq!(links.len(), 3, "{what}: {links:?}");
        assert_eq!(links[0].link, "sil");
        let sil = links[0].jump_height_m.unwrap();
        for l in &links[1..] {
            if let Some(why) = &l.skipped {
                assert!(
                    std::env::var_os("CI").is_none(),
                    "{what} through {}: skipped under CI: {why}",
                    l.link
                );
                eprintln!("skipped {} ({why})", l.link);
                continue;
            }
            let lh = l.jump_height_m.unwrap();
            assert!(
                (lh - sil).abs() <= 0.03 * sil,
                "{what}: {} {lh} m against sil {sil} m",
                l.link
            );
            assert!(l.faults.is_empty(), "{what}: {l:?}");
        }
    }
    // The stroke passes the rig's own check at 1 kHz, and stroke.csv is it: read back, its
    // jump is the table's jump the answer reports (what `jump --stroke` runs).
    o.stroke.check(&RigLimits::of(&o.params)).unwrap();
    assert_eq!(o.stroke.rate_hz, 1000);
    let table = StrokeTable::read_csv(&out.join("stroke.csv")).unwrap();
    assert_eq!(table.rate_hz, 1000);
    assert_eq!(table.samples_m.len(), o.stroke.samples_m.len());
    table.check(&RigLimits::of(&o.params)).unwrap();
    let jump = sandjumper_model::jump::simulate_stroke(
        &o.params,
        ModelName::Eq4,
        table.kinematic_stroke().unwrap(),
        &sandjumper_model::SimOptions::default(),
    )
    .unwrap();
    assert!(
        (jump.summary.jump_height_m - o.answer.table_jump_height_m).abs() < 1e-9,
        "stroke.csv's jump {} vs the search's {}",
        jump.summary.jump_height_m,
        o.answer.table_jump_height_m
    );
}

/// The same seed gives the same stroke, history and ranking on one thread as on two; without
/// a link the answer is the kinematic model's.
#[test]
fn a_seed_fixes_the_answer_whatever_the_threads() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let seeded = |out: &Path, threads: usize| OptimizeRequest {
        threads: Some(threads),
        seed: 7,
        ..small(out)
    };
    let oa = run(&seeded(&a, 1), &Silent).unwrap();
    let ob = run(&seeded(&b, 2), &Silent).unwrap();
    assert_eq!((oa.threads, ob.threads), (1, 2));
    assert_eq!(oa.stroke, ob.stroke);
    for f in ["stroke.csv", "history.csv", "candidates.csv"] {
        assert_eq!(read(&a.join(f)), read(&b.join(f)), "{f}");
    }
    assert_eq!(oa.height_basis, "sil");
    assert_eq!(oa.refine_runs, 48);
    let c = dir.path().join("c");
    let oc = run(
        &OptimizeRequest {
            verify: Vec::new(),
            ..seeded(&c, 2)
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(oc.height_basis, "kinematic");
}

/// Stops the process's work as a kill would: a panic out of the run once the checkpoint holds
/// `lines` lines (seen at a progress step, after a generation).
struct KillAt<'a> {
    checkpoint: &'a Path,
    lines: usize,
}

impl Progress for KillAt<'_> {
    fn advance(&self, _: u64) {
        let n = std::fs::read_to_string(self.checkpoint).map_or(0, |t| t.lines().count());
        if n >= self.lines {
            panic!("killed at {n} checkpoint lines");
        }
    }
}

/// Run `request`, killed once its checkpoint holds `lines` lines: whether it was killed
/// (false: it finished first).
fn killed_at(request: &OptimizeRequest, lines: usize) -> bool {
    let kill = KillAt {
        checkpoint: &checkpoint_path(&request.out),
        lines,
    };
    catch_unwind(AssertUnwindSafe(|| run(request, &kill))).is_err()
}

/// A search killed three times (twice in the kinematic search, once in the refinement through
/// sil, whose values follow the search's in the checkpoint), a half-written line left at the
/// end once, resumes to the answer of the search run whole; a killed run's half-written folder
/// goes with the resumed run, a live run's stays; a checkpoint of other settings is refused,
/// naming it. (A kill is
/// a panic out of the run's progress here; the command line's test killed the process.)
#[test]
fn a_search_killed_mid_way_resumes_to_the_same_answer() {
    let dir = tempfile::tempdir().unwrap();
    let args = |out: &Path| OptimizeRequest {
        evaluations: 2400,
        refine: 96,
        ..small(out)
    };
    let whole: OptimizeOutcome = run(&args(&dir.path().join("whole")), &Silent).unwrap();
    let searched = whole.evaluations;
    let out = dir.path().join("resumed");
    let ckpt = checkpoint_path(&out);
    let mut kills = 0;
    for lines in [200, 1200, searched + 40] {
        kills += usize::from(killed_at(&args(&out), lines));
        if lines == 200 {
            // Killed while writing a line.
            let mut text = read(&ckpt);
            text.push_str("00000000000000ab 3ff0");
            std::fs::write(&ckpt, text).unwrap();
        }
    }
    assert_eq!(kills, 3, "the search finished before it could be killed");
    assert!(ckpt.is_file());
    let partials = |dir: &Path| -> Vec<_> {
        std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .filter(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".resumed.partial-")
            })
            .collect()
    };
    // A process killed by a signal leaves its half-written folder (a panic unwinding here
    // removes it), its marker naming a process that is gone (above any pid_max): the resumed
    // run removes it. Another live run's staging folder beside it (this process's) is left as
    // it is.
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_default();
    let staging = |name: &str, pid: u64| {
        let d = dir.path().join(format!(".resumed.partial-{name}"));
        std::fs::create_dir(&d).unwrap();
        std::fs::write(d.join("stroke.csv"), "t_s,p_m\n").unwrap();
        std::fs::write(
            d.join(sandjumper_output::MARKER_FILE),
            format!("written by the sandjumper CLI (process {pid} on {host})\n"),
        )
        .unwrap();
        d
    };
    let left_by_a_kill = staging("kill9", 99_999_999);
    let live = staging("live", u64::from(std::process::id()));
    let o = run(&args(&out), &Silent).unwrap();
    assert!(o.evaluations_resumed >= 199, "{}", o.evaluations_resumed);
    assert_eq!(o.refine_runs, 96);
    assert_eq!(o.stroke, whole.stroke);
    assert_eq!(o.history, whole.history);
    let whole_dir = dir.path().join("whole");
    for f in ["stroke.csv", "history.csv"] {
        assert_eq!(read(&whole_dir.join(f)), read(&out.join(f)), "{f}");
    }
    assert!(!ckpt.exists());
    let left: Vec<_> = partials(dir.path()).into_iter().map(|e| e.path()).collect();
    assert_eq!(left, vec![live.clone()], "killed: {left_by_a_kill:?}");
    assert!(live.join("stroke.csv").is_file());
    std::fs::remove_dir_all(&live).unwrap();
    // A checkpoint made with other settings is refused, not silently reused.
    std::fs::write(&ckpt, "sandjumper-optimize-checkpoint 1 {\"seed\":99}\n").unwrap();
    let e = run(&args(&out), &Silent).unwrap_err();
    assert!(matches!(e, OptimizeError::Checkpoint(_)), "{e:?}");
    assert_eq!(e.blame(), Blame::Input);
    let m = e.to_string();
    assert!(
        m.contains("other settings") && m.contains("resumed.checkpoint"),
        "{m}"
    );
    // The same checkpoint marked finished by another writer than the folder's: a search
    // killed before its folder took its place (the folder there is another's). Still refused.
    let finished_by = |writer: &str| {
        std::fs::write(
            &ckpt,
            format!("sandjumper-optimize-checkpoint 1 {{\"seed\":99}}\nfinished {writer}\n"),
        )
        .unwrap()
    };
    finished_by("written by the sandjumper CLI (process 1 on elsewhere)");
    let e = run(&args(&out), &Silent).unwrap_err();
    assert!(e.to_string().contains("other settings"), "{e}");
    // Marked finished by the folder's own writer: a search killed after its folder took its
    // place and before it removed its checkpoint. Removed, and the search runs.
    finished_by(read(&out.join(sandjumper_output::MARKER_FILE)).trim());
    run(&small(&out), &Silent).unwrap();
    assert!(!ckpt.exists());
}

/// Height per energy, and the final hop's height on hard ground: an answer, at least the
/// paper's best.
#[test]
fn other_objectives_and_hard_ground_run() {
    let dir = tempfile::tempdir().unwrap();
    for (name, objective, model) in [
        ("energy", Objective::HeightPerEnergy, ModelName::Eq4),
        ("final", Objective::FinalHeight, ModelName::Hard),
    ] {
        let o = run(
            &OptimizeRequest {
                objective,
                model,
                verify: Vec::new(),
                ..small(&dir.path().join(name))
            },
            &Silent,
        )
        .unwrap();
        assert!(o.best_value.is_finite(), "{name}: {}", o.best_value);
        assert!(o.value_ratio >= 1.0, "{name}: {}", o.value_ratio);
    }
}

/// A checkpoint has one writer: a second search into the same folder while the first holds
/// its checkpoint's lock is refused before it starts, naming the process that holds it, and
/// runs once the lock is let go.
#[test]
fn a_second_search_on_a_checkpoint_in_use_is_refused_naming_its_holder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("busy");
    let lock_path = checkpoint_lock_path(&out);
    let held = sandjumper_output::WriterLock::take(&lock_path).unwrap();
    let e = run(&small(&out), &Silent).unwrap_err();
    assert!(matches!(e, OptimizeError::Checkpoint(_)), "{e:?}");
    assert_eq!(e.blame(), Blame::Input);
    let m = e.to_string();
    assert!(
        m.contains("busy.checkpoint.lock") && m.contains("is locked by"),
        "{m}"
    );
    if Path::new("/proc/locks").exists() {
        assert!(
            m.contains(&format!("process {} on ", std::process::id())),
            "{m}"
        );
    }
    assert!(!out.exists(), "nothing written");
    drop(held);
    run(&small(&out), &Silent).unwrap();
    assert!(!lock_path.exists(), "the lock goes with the checkpoint");
}

/// The centre of mass's rise as the objective (`--objective com-rise`): the answer's value is
/// its rise through the controller, at least the paper's; every answer and every candidate
/// reports the rod's apex and the centre of mass's rise side by side, and under the height
/// objective the centre of mass rises less than the rod (a motor lowered in flight counts for
/// the rod only).
#[test]
fn the_centre_of_mass_objective_runs_and_every_answer_reports_both_measures() {
    let dir = tempfile::tempdir().unwrap();
    let com = run(
        &OptimizeRequest {
            objective: Objective::ComRise,
            ..small(&dir.path().join("com"))
        },
        &Silent,
    )
    .unwrap();
    assert!(com.value_ratio >= 1.0, "{}", com.value_ratio);
    let sil = &com.answer.links[0];
    assert_eq!(sil.link, "sil");
    assert_eq!(Some(com.best_value), sil.com_rise_m);
    assert!(com.answer.kinematic.com_rise_m > 0.01);
    let height = run(&small(&dir.path().join("height")), &Silent).unwrap();
    for s in [&height.answer, &height.paper_answer] {
        let k = &s.kinematic;
        assert!(k.com_rise_m.is_finite() && k.jump_height_m.is_finite());
        assert!(k.com_rise_m < k.jump_height_m, "{k:?}");
        assert!(s.links[0].com_rise_m.is_some_and(f64::is_finite));
    }
    let csv = read(&dir.path().join("height/candidates.csv"));
    assert!(
        csv.lines().next().unwrap().contains("kinematic_com_rise_m"),
        "{csv}"
    );
}
