//! `sandjumper optimize` through the real binary, the command's contract: the files it
//! writes, its `--json` (summary.json's), that `jump`, `hil` and `rig replay` run its
//! stroke.csv, and the refusals of bad limits and bad stroke files with status 2. The search's
//! behaviour (the answer, the links, a seed whatever the threads, a killed search resumed, the
//! other objectives) is tested in the library: `sim-host/optimize/tests/`.
#![cfg(feature = "optimize")]

use std::path::Path;

use sandjumper_rig::stroke_table::StrokeTable;

use crate::common;
use common::{ok, read, refused};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&read(p)).unwrap()
}

/// The smallest search the command takes: the fewest evaluations and candidates, the coarsest
/// paper sweep, one start per paper stroke, no refinement; ranked through sil (so that its
/// answer's height is `hil`'s).
const SMALLEST: [&str; 18] = [
    "--evaluations",
    "100",
    "--population",
    "4",
    "--random-starts",
    "0",
    "--sweep-freq-step",
    "5",
    "--sweep-tau-step",
    "0.5",
    "--elites",
    "1",
    "--paper-candidates",
    "1",
    "--refine",
    "0",
    "--verify",
    "sil",
];

/// Exit status 0, the files it writes, no checkpoint left, `--json` as summary.json; its
/// stroke.csv is what `jump --stroke` (the table's kinematic jump), `hil --stroke` (the
/// answer's height through sil) and `rig replay --stroke` (uploaded sample for sample) run.
#[test]
fn a_small_search_writes_its_answer_and_jump_hil_and_rig_run_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("opt");
    let args: Vec<&str> = [&["optimize", "--out", s(&out), "--json"], &SMALLEST[..]].concat();
    let j: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
    for f in [
        "stroke.csv",
        "paper_stroke.csv",
        "candidates.csv",
        "paper_sweep.csv",
        "history.csv",
        "summary.json",
        "params.toml",
        "optimize.png",
        "optimize.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert!(
        !out.with_file_name("opt.checkpoint").exists(),
        "the checkpoint is removed once the answer is written"
    );
    assert_eq!(json(&out.join("summary.json")), j);
    assert_eq!(j["height_basis"], "sil");
    let h = j["best_height_m"].as_f64().unwrap();

    // stroke.csv is what jump, hil and rig replay run.
    let table = StrokeTable::read_csv(&out.join("stroke.csv")).unwrap();
    assert_eq!(table.rate_hz, 1000);
    let stroke = out.join("stroke.csv");
    let jump: serde_json::Value =
        serde_json::from_str(&ok(&["jump", "--stroke", s(&stroke), "--json"])).unwrap();
    assert_eq!(jump["kind"], "stroke");
    let table_height = j["answer"]["table_jump_height_m"].as_f64().unwrap();
    assert!(
        (jump["jump_height_m"].as_f64().unwrap() - table_height).abs() < 1e-9,
        "jump --stroke {} vs the search's {table_height}",
        jump["jump_height_m"]
    );
    let hil: serde_json::Value =
        serde_json::from_str(&ok(&["hil", "--stroke", s(&stroke), "--json"])).unwrap();
    assert_eq!(hil["kind"], "stroke");
    assert!(
        (hil["jump_height_m"].as_f64().unwrap() - h).abs() < 1e-9,
        "hil --stroke {} vs the answer's {h}",
        hil["jump_height_m"]
    );
    let replay_out = dir.path().join("replay");
    let replay: serde_json::Value = serde_json::from_str(&ok(&[
        "rig",
        "replay",
        "--stroke",
        s(&stroke),
        "--link",
        "sil",
        "--out",
        s(&replay_out),
        "--json",
    ]))
    .unwrap();
    assert_eq!(replay["completed"], true, "{replay}");
    assert_eq!(
        replay["table_samples"].as_u64().unwrap() as usize,
        table.samples_m.len()
    );
    // Uploaded sample for sample: the replay's table.csv is the stroke.
    let uploaded = StrokeTable::read_csv(&replay_out.join("table.csv")).unwrap();
    for (a, b) in uploaded.samples_m.iter().zip(&table.samples_m) {
        assert_eq!(*a as f32, *b as f32);
    }
}

#[test]
fn bad_limits_and_bad_stroke_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let o = s(&out);
    refused(
        &["optimize", "--out", o, "--max-stroke", "0.03"],
        &["--max-stroke", "0.025"],
    );
    refused(
        &["optimize", "--out", o, "--max-duration", "5"],
        &["--max-duration", "replay buffer"],
    );
    refused(
        &["optimize", "--out", o, "--table-rate", "3000"],
        &["--table-rate", "10000"],
    );
    refused(
        &["optimize", "--out", o, "--verify", "serial"],
        &["serial", "allowed"],
    );
    refused(&["optimize", "--out", o, "--moves", "1"], &["--moves"]);
    refused(
        &["optimize", "--out", o, "--phi-range", "0.62:0.57"],
        &["--phi-range", "0.62:0.57", "A < B"],
    );
    refused(
        &["optimize", "--out", o, "--phi-range", "0.57:0.60:0.01"],
        &["--phi-range", "A:B"],
    );
    refused(
        &["optimize", "--out", o, "--phi-range", "0.5:0.6"],
        &["--phi-range", "0.5", "phi"],
    );
    refused(
        &["optimize", "--out", o, "--phi-points", "3"],
        &["--phi-points", "--phi-range"],
    );
    refused(
        &[
            "optimize",
            "--out",
            o,
            "--phi",
            "0.6",
            "--phi-range",
            "0.57:0.62",
        ],
        &["--phi", "--phi-range"],
    );
    let nowhere = dir.path().join("nowhere");
    refused(
        &["optimize", "--out", o, "--start-from", s(&nowhere)],
        &["--start-from", "nowhere", "summary.json"],
    );
    assert!(!out.exists(), "nothing written on refusal");

    let missing = dir.path().join("missing.csv");
    refused(
        &["jump", "--stroke", s(&missing)],
        &["missing.csv", "cannot read"],
    );
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let header = write("header.csv", "t,p\n0,0\n0.001,0\n");
    refused(
        &["hil", "--stroke", s(&header)],
        &["header.csv", "line 1", "t_s,p_m"],
    );
    let wide: String = std::iter::once("t_s,p_m".to_string())
        .chain(
            (0..50).map(|k| format!("{},{}", k as f64 / 1000.0, if k == 25 { 0.03 } else { 0.0 })),
        )
        .collect::<Vec<_>>()
        .join("\n");
    let wide = write("wide.csv", &wide);
    for cmd in [vec!["jump"], vec!["hil"]] {
        let args = [cmd.as_slice(), &["--stroke", s(&wide)]].concat();
        refused(&args, &["wide.csv", "refused", "outside the stroke"]);
    }
    let replay_out = dir.path().join("r");
    refused(
        &[
            "rig",
            "replay",
            "--stroke",
            s(&wide),
            "--link",
            "sil",
            "--out",
            s(&replay_out),
        ],
        &["refused before anything moved", "outside the stroke"],
    );
    // A 1 mm kink at 1 kHz asks more than the drive's 300 N.
    let kink: String = std::iter::once("t_s,p_m".to_string())
        .chain((0..50).map(|k| {
            format!(
                "{},{}",
                k as f64 / 1000.0,
                if k == 25 { 0.001 } else { 0.0 }
            )
        }))
        .collect::<Vec<_>>()
        .join("\n");
    let kink = write("kink.csv", &kink);
    refused(&["hil", "--stroke", s(&kink)], &["kink.csv", "300 N"]);
    // --stroke with a sine's arguments is a usage error.
    refused(
        &["jump", "--stroke", s(&kink), "--kind", "single"],
        &["--stroke"],
    );
}

/// A search killed with `kill -9` (no clean-up runs) at random moments, in its kinematic
/// search, its re-ranking or its refinement through sil, and run again with the same command
/// each time, ends with the unbroken search's answer: the same stroke.csv, candidates and
/// height. (The library's tests stop a search at chosen checkpoint lines; this kills the
/// process wherever the clock says.)
#[test]
fn a_search_killed_with_kill_9_at_random_moments_resumes_to_the_unbroken_answer() {
    use rand::{RngExt, SeedableRng};
    use std::time::Duration;

    let dir = tempfile::tempdir().unwrap();
    let search = |out: &Path| -> Vec<String> {
        [
            "optimize",
            "--out",
            s(out),
            "--evaluations",
            "6000",
            "--population",
            "8",
            "--random-starts",
            "1",
            "--sweep-freq-step",
            "5",
            "--sweep-tau-step",
            "0.5",
            "--elites",
            "2",
            "--paper-candidates",
            "1",
            "--refine",
            "48",
            "--verify",
            "sil",
        ]
        .map(String::from)
        .to_vec()
    };
    let whole = dir.path().join("whole");
    let started = std::time::Instant::now();
    ok(&search(&whole)
        .iter()
        .map(String::as_str)
        .collect::<Vec<_>>());
    let whole_s = started.elapsed().as_secs_f64();

    let out = dir.path().join("killed");
    let mut rng = rand::rngs::StdRng::seed_from_u64(54);
    // A moment within the unbroken search's time (each session resumes where the last
    // stopped, so later ones end sooner).
    let crate::common::Killed {
        kills,
        sessions,
        finished,
    } = crate::common::kill_at_random(
        || search(&out),
        || Duration::from_secs_f64(rng.random_range(0.03..0.45) * whole_s),
        || out.join("summary.json").is_file(),
        6,
    );
    // Each kill is early in its session, but a slow machine may still finish a session first.
    assert!(kills >= 2, "only {kills} kills: the test proved little");
    for f in ["stroke.csv", "candidates.csv", "paper_sweep.csv"] {
        assert_eq!(
            read(&whole.join(f)),
            read(&out.join(f)),
            "{f}: killed {kills} times and resumed, another answer"
        );
    }
    let (a, b) = (
        json(&whole.join("summary.json")),
        json(&out.join("summary.json")),
    );
    assert_eq!(a["best_height_m"], b["best_height_m"]);
    // (A kill between the answer's rename and the checkpoint's removal leaves the
    // checkpoint beside a finished answer: harmless, and checked only when not killed.)
    if finished {
        assert!(
            !dir.path().join("killed.checkpoint").exists(),
            "the checkpoint is removed once the answer is written"
        );
    }
    eprintln!(
        "killed {kills} times over {sessions} sessions; the unbroken search took {whole_s:.1} s"
    );
}
