//! `sandjumper_optimize::run` in memory, on tiny budgets: the typed outcome, its folder, a
//! checkpointed resume, the links and the request's refusals.

use std::path::Path;
use std::sync::Mutex;

use sandjumper_optimize::{
    NoBoard, OptimizeError, OptimizeOutcome, OptimizeRequest, StrokeOnBoard, checkpoint_path, run,
    run_with_board,
};
use sandjumper_output::{Blame, Blamed, Progress, Silent};
use sandjumper_rig::hil::open::LinkArg;

/// A tiny kinematic search (no link): a coarse sweep, a few hundred evaluations.
fn tiny(out: &Path) -> OptimizeRequest {
    OptimizeRequest {
        evaluations: 240,
        population: 8,
        random_starts: 1,
        seed: 3,
        sweep_freq_step_hz: 4.0,
        sweep_tau_step_s: 0.25,
        elites: 2,
        paper_candidates: 1,
        verify: Vec::new(),
        threads: Some(2),
        out: out.to_path_buf(),
        ..OptimizeRequest::default()
    }
}

/// The best feasible kinematic value of the paper sweep.
fn paper_sweep_best(o: &OptimizeOutcome) -> f64 {
    o.paper_sweep
        .iter()
        .filter(|p| p.evaluation.feasible())
        .map(|p| p.evaluation.value)
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn a_tiny_search_is_at_least_the_paper_sweeps_best_and_writes_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("opt");
    let o = run(&tiny(&out), &Silent).unwrap();
    assert_eq!(o.height_basis, "kinematic");
    assert_eq!(o.objective, "height");
    let paper = paper_sweep_best(&o);
    assert!(paper > 0.01, "{paper}");
    assert!(o.best_value >= paper, "{} < {paper}", o.best_value);
    assert_eq!(o.best_paper_value, paper);
    assert!(o.value_ratio >= 1.0 && o.height_ratio >= 1.0);
    assert_eq!(o.paper_sweep_points, o.paper_sweep.len());
    assert_eq!(o.evaluations_resumed, 0);
    assert_eq!(o.refine_runs, 0);
    assert_eq!(o.candidates.len(), o.candidates_ranked);
    assert_eq!(o.candidates[0].label, o.answer.label);
    assert!(o.answer.links.is_empty());
    // The folder: the files, summary.json the serialised outcome, no checkpoint left.
    assert_eq!(o.dir, out);
    for f in sandjumper_optimize::outcome::FILES {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_eq!(summary, format!("{}\n", o.json().unwrap()));
    assert!(summary.starts_with("{\n  \"best_height_m\": "), "{summary}");
    assert_eq!(
        std::fs::read_to_string(out.join("stroke.csv")).unwrap(),
        o.stroke.to_csv()
    );
    assert!(!checkpoint_path(&out).exists());
    let human = o.to_string();
    assert!(
        human.starts_with("best height on eq4, phi 0.57 (kinematic): "),
        "{human}"
    );
    assert!(
        human.ends_with(&format!("wrote {}/\n", out.display())),
        "{human}"
    );
}

/// Keeps a copy of the checkpoint as the search left it (the note after the search).
struct CopyCheckpoint<'a> {
    from: &'a Path,
    copy: Mutex<Option<String>>,
}

impl Progress for CopyCheckpoint<'_> {
    fn note(&self, line: &str) {
        if line.starts_with("  search:") {
            *self.copy.lock().unwrap() = std::fs::read_to_string(self.from).ok();
        }
    }
}

#[test]
fn a_checkpointed_resume_gives_the_same_answer() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let sink = CopyCheckpoint {
        from: &checkpoint_path(&whole),
        copy: Mutex::new(None),
    };
    let a = run(&tiny(&whole), &sink).unwrap();
    let recorded = sink.copy.lock().unwrap().take().expect("a checkpoint");
    // A search killed mid-way: the header and the first half of its evaluations.
    let lines: Vec<&str> = recorded.lines().collect();
    assert!(
        lines.len() > 100 && lines.len() <= 1 + a.evaluations,
        "{}",
        lines.len()
    );
    let kept = (lines.len() - 1) / 2;
    let half = lines[..1 + kept].join("\n") + "\n";
    let resumed = dir.path().join("resumed");
    std::fs::write(checkpoint_path(&resumed), half).unwrap();
    let b = run(
        &OptimizeRequest {
            threads: Some(1),
            ..tiny(&resumed)
        },
        &Silent,
    )
    .unwrap();
    assert!(
        b.evaluations_resumed >= kept && b.evaluations_resumed < a.evaluations,
        "{} resumed of {} ({kept} kept)",
        b.evaluations_resumed,
        a.evaluations
    );
    assert_eq!(b.evaluations, a.evaluations);
    assert_eq!(b.stroke, a.stroke);
    assert_eq!(b.history, a.history);
    assert_eq!(b.answer.label, a.answer.label);
    assert_eq!(b.best_value, a.best_value);
    assert!(!checkpoint_path(&resumed).exists());
    // A checkpoint of another search is refused (the caller's input), naming it.
    std::fs::write(
        checkpoint_path(&resumed),
        "sandjumper-optimize-checkpoint 1 {\"seed\":99}\n",
    )
    .unwrap();
    let e = run(&tiny(&resumed), &Silent).unwrap_err();
    assert!(matches!(e, OptimizeError::Checkpoint(_)), "{e:?}");
    assert_eq!(e.blame(), Blame::Input);
    assert!(e.to_string().contains("other settings"), "{e}");
}

#[test]
fn ranked_through_sil_refined_and_f407_through_the_board_given() {
    let dir = tempfile::tempdir().unwrap();
    let request = OptimizeRequest {
        verify: vec![LinkArg::Sil, LinkArg::F407],
        refine: 24,
        ..tiny(&dir.path().join("sil"))
    };
    let boards = Mutex::new(0);
    let board = |r: &OptimizeRequest, t: &sandjumper_rig::stroke_table::StrokeTable| {
        assert_eq!(r.table_rate_hz, t.rate_hz);
        *boards.lock().unwrap() += 1;
        sandjumper_optimize::LinkRun::skipped(&LinkArg::F407, "a test's board".into())
    };
    let o = run_with_board(&request, &Silent, &board).unwrap();
    assert_eq!(o.height_basis, "sil");
    assert_eq!(o.refine_runs, 24);
    assert!(o.best_height_m > 0.01, "{}", o.best_height_m);
    assert!(o.best_value >= o.best_paper_value);
    assert_eq!(o.best_value, o.answer.controller_value.unwrap());
    assert_eq!(o.best_height_m, o.answer.links[0].jump_height_m.unwrap());
    for s in [&o.answer, &o.paper_answer] {
        assert_eq!(s.links.len(), 2);
        assert_eq!(s.links[0].link, "sil");
        assert_eq!(s.links[1].skipped.as_deref(), Some("a test's board"));
    }
    let through_board = 2 + usize::from(o.kinematic_optimum.is_some());
    assert_eq!(*boards.lock().unwrap(), through_board);
    // The candidates rank through sil: the first is the answer, the values descend.
    assert_eq!(o.candidates[0].controller_value, o.best_value);
    let values: Vec<f64> = o
        .candidates
        .iter()
        .map(|c| c.controller_value)
        .filter(|v| v.is_finite())
        .collect();
    assert!(values.windows(2).all(|w| w[0] >= w[1]), "{values:?}");
    // Without a board (`NoBoard`), an F407 run is skipped, saying why.
    let why = NoBoard
        .replay(&request, &o.stroke)
        .skipped
        .unwrap_or_default();
    assert!(why.contains("no virtual board"), "{why}");
}

#[test]
fn the_defaults_are_the_command_lines_and_bad_limits_are_refused() {
    let d = OptimizeRequest::default();
    assert_eq!((d.evaluations, d.population, d.moves), (192_000, 24, 4));
    assert_eq!(d.verify, vec![LinkArg::Sil, LinkArg::Pil, LinkArg::F407]);
    assert_eq!(d.params.sand.packing_fraction, 0.57);
    let e = d.validate().unwrap_err();
    assert!(e.to_string().contains("--out"), "{e}");
    let ok = OptimizeRequest {
        out: "o".into(),
        ..d
    };
    ok.validate().unwrap();
    let refused = |r: OptimizeRequest, words: &[&str]| {
        let e = r.validate().unwrap_err();
        assert_eq!(e.blame(), Blame::Input);
        for w in words {
            assert!(e.to_string().contains(w), "{e} lacks {w}");
        }
    };
    refused(
        OptimizeRequest {
            max_duration_s: 5.0,
            ..ok.clone()
        },
        &["--max-duration 5 s", "replay buffer"],
    );
    refused(
        OptimizeRequest {
            table_rate_hz: 3000,
            ..ok.clone()
        },
        &["--table-rate 3000 Hz does not divide the 10000 Hz control rate"],
    );
    refused(
        OptimizeRequest {
            max_stroke_m: 0.03,
            ..ok.clone()
        },
        &["--max-stroke", "0.025"],
    );
    refused(
        OptimizeRequest {
            moves: 1,
            ..ok.clone()
        },
        &["--moves"],
    );
    refused(
        OptimizeRequest {
            verify: vec![LinkArg::Serial("/dev/ttyACM0".into())],
            ..ok.clone()
        },
        &["serial:/dev/ttyACM0", "not allowed in --verify"],
    );
    // Refused before anything is written.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let e = run(
        &OptimizeRequest {
            max_duration_s: 5.0,
            out: out.clone(),
            ..ok
        },
        &Silent,
    )
    .unwrap_err();
    assert!(matches!(e, OptimizeError::Invalid(_)), "{e:?}");
    assert!(!out.exists() && !checkpoint_path(&out).exists());
}

#[test]
fn the_value_parsers_name_the_flag_and_what_is_allowed() {
    let max_stroke = sandjumper_optimize::ranged("--max-stroke", 0.0, 0.025, "m");
    assert_eq!(max_stroke(" 0.02 "), Ok(0.02));
    assert_eq!(
        max_stroke("0.03"),
        Err("--max-stroke `0.03` out of range (allowed: 0 < X <= 0.025 m)".to_string())
    );
    assert_eq!(
        sandjumper_optimize::parse_verify("sil, f407"),
        Ok(vec![LinkArg::Sil, LinkArg::F407])
    );
    assert_eq!(sandjumper_optimize::parse_verify("none"), Ok(Vec::new()));
    assert_eq!(
        sandjumper_optimize::parse_verify("sil,serial"),
        Err(
            "link `serial` not allowed in --verify (allowed: sil, pil, f407, a comma-separated \
             list of them, or none)"
                .to_string()
        )
    );
}

/// Stops the search once `after` of its evaluations are counted (Ctrl-C in a face).
struct StopAfter {
    /// The stage it stops.
    stage: &'static str,
    after: u64,
    searching: std::sync::atomic::AtomicBool,
    done: std::sync::atomic::AtomicU64,
    /// The length of the stage it stops.
    len: std::sync::atomic::AtomicU64,
}

impl StopAfter {
    fn new(stage: &'static str, after: u64) -> Self {
        Self {
            stage,
            after,
            searching: std::sync::atomic::AtomicBool::new(false),
            done: std::sync::atomic::AtomicU64::new(0),
            len: std::sync::atomic::AtomicU64::new(0),
        }
    }
}

impl Progress for StopAfter {
    fn start(&self, what: &str, len: Option<u64>) {
        use std::sync::atomic::Ordering::SeqCst;
        self.searching.store(what == self.stage, SeqCst);
        self.done.store(0, SeqCst);
        if what == self.stage {
            self.len.store(len.unwrap_or(0), SeqCst);
        }
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, std::sync::atomic::Ordering::SeqCst);
    }
    fn cancelled(&self) -> bool {
        use std::sync::atomic::Ordering::SeqCst;
        self.searching.load(SeqCst) && self.done.load(SeqCst) >= self.after
    }
}

/// The sweep of the paper's strokes its caller stops ends there: no further stroke starts,
/// nothing is written. Tried: with the sweep ignoring the stop, every stroke ran.
#[test]
fn a_paper_sweep_stopped_by_its_caller_runs_no_further_stroke() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stopped");
    let stop = StopAfter::new("paper strokes", 16);
    let e = run(&tiny(&out), &stop).unwrap_err();
    assert!(
        e.to_string()
            .contains("stopped in the sweep of the paper's strokes"),
        "{e}"
    );
    let (done, len) = (
        stop.done.load(std::sync::atomic::Ordering::SeqCst),
        stop.len.load(std::sync::atomic::Ordering::SeqCst),
    );
    assert!(len > 64, "{len} strokes");
    assert!(done < 48, "{done} of {len} strokes ran after a stop at 16");
    assert!(!out.exists());
}

/// A run its caller stops while it runs the candidates through the controller starts no
/// further candidate there and writes nothing. Tried: without the checks after the search,
/// every candidate ran and the folder was written.
#[test]
fn a_run_stopped_among_the_controller_runs_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stopped");
    let stop = StopAfter::new("runs through the controller", 1);
    let request = OptimizeRequest {
        verify: vec![sandjumper_rig::hil::open::LinkArg::Sil],
        refine: 0,
        ..tiny(&out)
    };
    let Err(e) = run(&request, &stop) else {
        panic!("the run went on to its end");
    };
    assert!(e.to_string().starts_with("interrupted: stopped"), "{e}");
    let (done, len) = (
        stop.done.load(std::sync::atomic::Ordering::SeqCst),
        stop.len.load(std::sync::atomic::Ordering::SeqCst),
    );
    assert!(len >= 3 && done < len, "{done} of {len} candidates ran");
    assert!(!out.exists());
}

/// A search its caller stops ends after the generation it is in, its checkpoint kept beside
/// the folder and no folder written; the same request again resumes it to the answer of a
/// search never stopped. Tried: with `cma_run` ignoring the stop, the search ran to its end.
#[test]
fn a_search_stopped_by_its_caller_keeps_its_checkpoint_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stopped");
    let stop = StopAfter::new("evaluations", 40);
    let e = run(&tiny(&out), &stop).unwrap_err();
    assert!(
        e.to_string().starts_with("interrupted after generation"),
        "{e}"
    );
    assert!(checkpoint_path(&out).is_file());
    assert!(!out.exists());
    let stopped_lines = std::fs::read_to_string(checkpoint_path(&out))
        .unwrap()
        .lines()
        .count();
    let resumed = run(&tiny(&out), &Silent).unwrap();
    let whole = run(&tiny(&dir.path().join("whole")), &Silent).unwrap();
    assert!(
        resumed.evaluations_resumed + 1 >= stopped_lines - 1 && resumed.evaluations_resumed > 0,
        "{} resumed, {stopped_lines} checkpoint lines",
        resumed.evaluations_resumed
    );
    assert_eq!(resumed.stroke, whole.stroke);
    assert_eq!(resumed.best_value, whole.best_value);
}

/// Verification through pil or the F407 alone still ranks and refines through sil (the same
/// controller core, thousands of runs a second) and runs the answer through the link asked
/// for: pil alone refined nothing before, and the F407 alone ranked through a board run that
/// could not happen, leaving the answer on the kinematic model without a word. A run that
/// cannot happen says why, in the outcome and as a warning.
#[test]
fn verifying_through_pil_or_the_f407_alone_ranks_and_refines_through_sil() {
    struct Notes(Mutex<Vec<String>>);
    impl Progress for Notes {
        fn note(&self, line: &str) {
            self.0.lock().unwrap().push(line.to_string());
        }
    }
    let dir = tempfile::tempdir().unwrap();
    for link in [LinkArg::Pil, LinkArg::F407] {
        let request = OptimizeRequest {
            verify: vec![link.clone()],
            refine: 12,
            ..tiny(&dir.path().join(link.to_string()))
        };
        let notes = Notes(Mutex::new(Vec::new()));
        let o = run_with_board(&request, &notes, &NoBoard).unwrap();
        assert_eq!(o.height_basis, "sil", "{link}");
        assert_eq!(o.refine_runs, 12, "{link}");
        let asked = o
            .answer
            .links
            .iter()
            .find(|l| l.link == link.to_string())
            .unwrap_or_else(|| panic!("{link}: {:?}", o.answer.links));
        if link == LinkArg::F407 {
            let why = asked.skipped.as_deref().unwrap_or_default();
            assert!(why.contains("no virtual board"), "{why}");
            let notes = notes.0.lock().unwrap();
            assert!(
                notes
                    .iter()
                    .any(|n| n.starts_with("warning: --verify f407: not run: ")),
                "{notes:?}"
            );
        }
    }
}

/// IPOP: a start whose CMA-ES stops by its own criteria with budget left starts again with
/// twice the population, until the start's budget is spent; every run is reported with its
/// best, and the answer is the best of all runs. (Two moves, the fewest: a small space, where
/// CMA-ES converges well within the budget.)
#[test]
fn a_start_that_converges_early_restarts_with_a_doubled_population() {
    let dir = tempfile::tempdir().unwrap();
    let request = OptimizeRequest {
        evaluations: 9000,
        population: 6,
        random_starts: 0,
        moves: 2,
        ..tiny(&dir.path().join("ipop"))
    };
    let o = run(&request, &Silent).unwrap();
    for r in &o.restarts {
        eprintln!("{r:?}");
    }
    let starts = o.restarts.iter().map(|r| r.start).max().unwrap() + 1;
    let per_start = request.evaluations / starts;
    for s in 0..starts {
        let runs: Vec<_> = o.restarts.iter().filter(|r| r.start == s).collect();
        assert!(runs.iter().map(|r| r.evaluations).sum::<usize>() <= per_start);
        for (k, r) in runs.iter().enumerate() {
            assert_eq!((r.restart, r.population), (k, 6 << k), "{runs:?}");
        }
        // Every run but the last stopped by its own criteria, not the budget.
        for r in &runs[..runs.len() - 1] {
            assert!(!r.stopped_because.contains("MaxFunctionEvals"), "{runs:?}");
        }
    }
    assert!(
        o.restarts.len() > starts,
        "no start restarted: {:?}",
        o.restarts
    );
    let best_run = o
        .restarts
        .iter()
        .map(|r| r.best_value)
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    let a = &o.restart_agreement;
    assert!(a.within_1_percent >= 1 && a.within_1_percent <= a.feasible_runs);
    assert!(a.spread >= 0.0);
    // The kinematic model's best is the best of every run.
    let kinematic_best = o
        .candidates
        .iter()
        .map(|c| c.kinematic_value)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        kinematic_best >= best_run - 1e-12,
        "{kinematic_best} {best_run}"
    );
}

/// The robot's physical limits are constraints: the rig's height caps the rod's rise (the
/// answer and every feasible candidate stay under a 40 mm frame, which the unconstrained
/// search's answer passes), and a spring allowed to compress less refuses the strokes that
/// compress it more, naming the limit. A compression beyond the spring's free length is
/// refused before anything runs.
#[test]
fn the_rigs_height_and_the_springs_free_length_are_constraints() {
    let dir = tempfile::tempdir().unwrap();
    let free = run(&tiny(&dir.path().join("free")), &Silent).unwrap();
    assert!(
        free.answer.kinematic.jump_height_m > 0.04,
        "{:?}",
        free.answer.kinematic
    );
    let low = run(
        &OptimizeRequest {
            max_rise_m: 0.04,
            ..tiny(&dir.path().join("low"))
        },
        &Silent,
    )
    .unwrap();
    assert!(low.answer.kinematic.jump_height_m <= 0.04);
    for c in low
        .candidates
        .iter()
        .filter(|c| c.kinematic_value.is_finite())
    {
        assert!(c.kinematic_height_m <= 0.04, "{}", c.kinematic_height_m);
    }
    assert!(
        low.paper_sweep
            .iter()
            .filter_map(|p| p.evaluation.violation.as_deref())
            .any(|v| v.contains("above the rig's 40.0 mm")),
        "no paper stroke met the frame"
    );
    // Through the controller too: a run above the frame is worth nothing, so the answer
    // ranked and refined through sil keeps under it.
    let ranked = run(
        &OptimizeRequest {
            max_rise_m: 0.04,
            verify: vec![LinkArg::Sil],
            refine: 24,
            ..tiny(&dir.path().join("low-sil"))
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(ranked.height_basis, "sil");
    assert!(ranked.best_height_m <= 0.04, "{}", ranked.best_height_m);
    let stiff = run(
        &OptimizeRequest {
            max_spring_compression_m: Some(0.005),
            ..tiny(&dir.path().join("stiff"))
        },
        &Silent,
    );
    match stiff {
        Ok(o) => assert!(
            o.paper_sweep
                .iter()
                .filter_map(|p| p.evaluation.violation.as_deref())
                .any(|v| v.contains("beyond the 5.0 mm it allows")),
            "no stroke compressed the spring past 5 mm"
        ),
        Err(e) => assert!(
            matches!(e, OptimizeError::NoFeasiblePaperStroke { .. }),
            "{e:?}"
        ),
    }
    let e = run(
        &OptimizeRequest {
            max_spring_compression_m: Some(0.5),
            ..tiny(&dir.path().join("long"))
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(e.to_string().contains("--max-spring-compression"), "{e}");
}

/// A search over several beds stopped mid-way resumes to the answer of an unbroken one, and
/// its checkpoint is refused by a search over other beds (its values are worst cases over
/// its own beds).
#[test]
fn a_search_over_beds_resumes_and_its_checkpoint_knows_its_beds() {
    use sandjumper_model::params::Params;
    let dir = tempfile::tempdir().unwrap();
    let over = |out: &Path, beds: &[f64]| OptimizeRequest {
        params: Params::preset(0.595).unwrap(),
        beds: beds.iter().map(|&p| Params::preset(p).unwrap()).collect(),
        ..tiny(out)
    };
    let out = dir.path().join("beds");
    let e = run(
        &over(&out, &[0.57, 0.62]),
        &StopAfter::new("evaluations", 40),
    )
    .unwrap_err();
    assert!(e.to_string().starts_with("interrupted"), "{e}");
    let refused = run(&over(&out, &[0.57, 0.6, 0.62]), &Silent).unwrap_err();
    assert!(refused.to_string().contains("beds"), "{refused}");
    let resumed = run(&over(&out, &[0.57, 0.62]), &Silent).unwrap();
    let whole = run(&over(&dir.path().join("whole"), &[0.57, 0.62]), &Silent).unwrap();
    assert!(resumed.evaluations_resumed > 0);
    assert_eq!(resumed.stroke, whole.stroke);
    assert_eq!(resumed.best_value, whole.best_value);
    assert_eq!(format!("{:?}", resumed.beds), format!("{:?}", whole.beds));
}
