//! Campaigns (#24) through the simulated bed and controller: a small campaign end to end,
//! `kill -9` at random moments and resumed to the same results, bed preparations that fail
//! and the campaign's policy, the Bluesky documents, and bad campaign files.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use rand::{RngExt, SeedableRng};

use crate::common;
use common::{read, sandjumper_text};

const SMALL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/campaign-small.toml"
);

fn with_suffix(p: &Path, s: &str) -> PathBuf {
    let mut o = p.as_os_str().to_owned();
    o.push(s);
    PathBuf::from(o)
}

/// The small campaign with `edit` applied to its text, written into `dir`.
fn campaign_file(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let p = dir.join("campaign.toml");
    std::fs::write(&p, edit(read(Path::new(SMALL)))).unwrap();
    p
}

fn csv_rows(p: &Path) -> Vec<Vec<String>> {
    read(p)
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

#[test]
fn a_small_campaign_runs_end_to_end_through_sil() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("small");
    let o = out.to_str().unwrap();
    let (c, stdout, e) = sandjumper_text(&["campaign", "run", SMALL, "--link", "sil", "--out", o]);
    assert_eq!(c, 0, "{e}");
    assert!(stdout.contains("8 points done"), "{stdout}");
    for f in [
        "results.csv",
        "documents.jsonl",
        "journal.jsonl",
        "campaign.toml",
        "height_vs_phi.png",
        "height_vs_phi.svg",
        "fig2a.png",
        "fig2a.svg",
        "points/0000/acquisition.csv",
        "points/0000/point.json",
        "points/0000/params.toml",
        "points/0000/frames",
    ] {
        assert!(out.join(f).exists(), "missing {f}");
    }
    assert!(!with_suffix(&out, ".incomplete").exists());
    let rows = csv_rows(&out.join("results.csv"));
    assert_eq!(rows.len(), 8);
    let header = read(&out.join("results.csv"));
    let cols: Vec<&str> = header.lines().next().unwrap().split(',').collect();
    let col = |n: &str| cols.iter().position(|c| *c == n).unwrap();
    let mut kinds_phis = std::collections::BTreeSet::new();
    for r in &rows {
        assert_eq!(r[col("status")], "done", "{r:?}");
        let target: f64 = r[col("target_phi")].parse().unwrap();
        let achieved: f64 = r[col("achieved_phi")].parse().unwrap();
        assert!((achieved - target).abs() <= 0.004, "{r:?}");
        kinds_phis.insert((r[col("kind")].clone(), r[col("target_phi")].clone()));
        // The replay predicts the simulated plant's jump (the paper's comparison).
        let predicted: f64 = r[col("predicted_jump_height_m")].parse().unwrap();
        let plant: f64 = r[col("plant_jump_height_m")].parse().unwrap();
        assert!(
            (predicted - plant).abs() < 0.05 * plant,
            "replay {predicted} vs plant {plant}: {r:?}"
        );
        // The camera measures the plant's jump where the ball stayed in view.
        let measured: f64 = r[col("measured_jump_height_m")].parse().unwrap();
        let flagged: usize = r[col("frames_flagged")].parse().unwrap();
        if flagged == 0 {
            assert!(
                (measured - plant).abs() < 0.02 * plant,
                "camera {measured} vs plant {plant}: {r:?}"
            );
        } else {
            assert!(measured < plant, "a ball out of view reads low: {r:?}");
        }
    }
    assert_eq!(kinds_phis.len(), 4, "two kinds x two phis");

    // The Bluesky documents: one start, one descriptor with units, an event per jump, one
    // stop; the fields the event-model schemas require.
    let docs: Vec<serde_json::Value> = read(&out.join("documents.jsonl"))
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let names: Vec<&str> = docs.iter().map(|d| d[0].as_str().unwrap()).collect();
    assert_eq!(names[0], "start");
    assert_eq!(names[1], "descriptor");
    assert_eq!(names.iter().filter(|n| **n == "event").count(), 8);
    assert_eq!(names[names.len() - 1], "stop");
    let start = &docs[0][1];
    let desc = &docs[1][1];
    for k in ["uid", "time"] {
        assert!(!start[k].is_null(), "start.{k}");
    }
    for k in ["uid", "time", "run_start", "data_keys"] {
        assert!(!desc[k].is_null(), "descriptor.{k}");
    }
    assert_eq!(desc["run_start"], start["uid"]);
    for (key, dk) in desc["data_keys"].as_object().unwrap() {
        for k in ["dtype", "shape", "source"] {
            assert!(!dk[k].is_null(), "data_keys.{key}.{k}");
        }
    }
    assert_eq!(desc["data_keys"]["measured_jump_height_m"]["units"], "m");
    for (n, d) in docs.iter().filter(|d| d[0] == "event").enumerate() {
        let ev = &d[1];
        assert_eq!(ev["descriptor"], desc["uid"]);
        assert_eq!(ev["seq_num"], n + 1);
        for k in ["uid", "time", "data", "timestamps"] {
            assert!(!ev[k].is_null(), "event.{k}");
        }
        for key in ev["data"].as_object().unwrap().keys() {
            assert!(!desc["data_keys"][key].is_null(), "{key} not described");
            assert!(!ev["timestamps"][key].is_null(), "{key} has no timestamp");
        }
    }
    // Valid against the event-model package's own schemas (vendored in tests/fixtures).
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/event-model");
    let validator = |name: &str| {
        let schema: serde_json::Value =
            serde_json::from_str(&read(&fixtures.join(format!("{name}.json")))).unwrap();
        jsonschema::validator_for(&schema).unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    let schemas = [
        ("start", validator("run_start")),
        ("descriptor", validator("event_descriptor")),
        ("event", validator("event")),
        ("stop", validator("run_stop")),
    ];
    for d in &docs {
        let (_, v) = schemas.iter().find(|(n, _)| d[0] == *n).unwrap();
        let errors: Vec<String> = v.iter_errors(&d[1]).map(|e| e.to_string()).collect();
        assert!(errors.is_empty(), "{}: {errors:?}", d[0]);
    }
    // The validator catches what it should: a stop without its exit status.
    let mut bad = docs[docs.len() - 1][1].clone();
    bad.as_object_mut().unwrap().remove("exit_status");
    assert!(!schemas[3].1.is_valid(&bad));
    let stop = &docs[docs.len() - 1][1];
    assert_eq!(stop["exit_status"], "success");
    assert_eq!(stop["run_start"], start["uid"]);
    assert_eq!(stop["num_events"]["primary"], 8);

    let (c, s, e) = sandjumper_text(&["campaign", "status", o, "--json"]);
    assert_eq!(c, 0, "{e}");
    let st: serde_json::Value = serde_json::from_str(&s).unwrap();
    assert_eq!(st["state"], "finished");
    assert_eq!(st["done"], 8);
    // A finished campaign has nothing to resume.
    let (c, _, e) = sandjumper_text(&["campaign", "resume", o]);
    assert_eq!(c, 2);
    assert!(e.contains("finished"), "{e}");
}

#[test]
fn a_campaign_killed_at_random_moments_resumes_to_the_same_results() {
    let tmp = tempfile::tempdir().unwrap();
    let straight = tmp.path().join("straight");
    let (c, _, e) = sandjumper_text(&[
        "campaign",
        "run",
        SMALL,
        "--link",
        "sil",
        "--out",
        straight.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");

    let killed = tmp.path().join("killed");
    let k = killed.to_str().unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    // Eight kills at random moments (on a slow machine a session may not finish a point
    // before its kill), then a last session runs to the end.
    let common::Killed {
        kills, sessions, ..
    } = common::kill_at_random(
        || {
            let args: &[&str] = if with_suffix(&killed, ".incomplete").is_dir() {
                &["campaign", "resume", k]
            } else {
                &["campaign", "run", SMALL, "--link", "sil", "--out", k]
            };
            args.iter().map(|a| a.to_string()).collect()
        },
        || Duration::from_millis(rng.random_range(20..600)),
        || killed.is_dir(),
        8,
    );
    assert!(kills >= 3, "only {kills} kills: the test proved little");
    assert!(killed.is_dir(), "finished under its own name");
    assert_eq!(
        read(&straight.join("results.csv")),
        read(&killed.join("results.csv")),
        "killed {kills} times and resumed: the same results"
    );
    // No point done twice, every interruption recorded.
    let journal = read(&killed.join("journal.jsonl"));
    let done = journal
        .lines()
        .filter(|l| l.contains("\"event\":\"done\""))
        .count();
    assert_eq!(done, 8, "each point done exactly once");
    let (c, s, e) = sandjumper_text(&["campaign", "status", k, "--json"]);
    assert_eq!(c, 0, "{e}");
    let st: serde_json::Value = serde_json::from_str(&s).unwrap();
    assert!(
        st["sessions"].as_u64().unwrap() >= 2,
        "resumed sessions recorded: {st}"
    );
    assert!(
        st["interruptions"].as_u64().unwrap() >= 1,
        "points cut by a kill are recorded as interrupted: {st}"
    );
    eprintln!("killed {kills} times over {sessions} sessions: {st}");
    // The documents are one run: one start, one stop.
    let docs = read(&killed.join("documents.jsonl"));
    assert_eq!(
        docs.lines().filter(|l| l.starts_with("[\"start\"")).count(),
        1
    );
    assert_eq!(
        docs.lines().filter(|l| l.starts_with("[\"stop\"")).count(),
        1
    );
}

#[test]
fn a_bed_that_cannot_be_prepared_is_recorded_and_the_policy_decides() {
    let tmp = tempfile::tempdir().unwrap();
    // One measurement allowed: every bed needing a compaction fails.
    let f = campaign_file(tmp.path(), |t| {
        t.replace("max_attempts = 12", "max_attempts = 1")
            .replace("phis = [0.58, 0.61]", "phis = [0.61]")
    });
    let out = tmp.path().join("skip");
    let (c, _, e) = sandjumper_text(&[
        "campaign",
        "run",
        f.to_str().unwrap(),
        "--link",
        "sil",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    let rows = csv_rows(&out.join("results.csv"));
    assert_eq!(rows.len(), 4, "the campaign went on past each failure");
    for r in &rows {
        assert!(r.contains(&"bed-not-prepared".to_string()), "{r:?}");
        assert!(
            r.iter().any(|c| c.contains("after 1 measurements")),
            "{r:?}"
        );
    }
    // Policy `stop`: the first failure ends the session (exit 1), recorded; a resume goes on
    // with the next point.
    let f = campaign_file(tmp.path(), |t| {
        t.replace("max_attempts = 12", "max_attempts = 1")
            .replace("phis = [0.58, 0.61]", "phis = [0.61]")
            .replace(
                "on_failed_preparation = \"skip\"",
                "on_failed_preparation = \"stop\"",
            )
    });
    let out = tmp.path().join("stop");
    let o = out.to_str().unwrap();
    let (c, _, e) = sandjumper_text(&[
        "campaign",
        "run",
        f.to_str().unwrap(),
        "--link",
        "sil",
        "--out",
        o,
    ]);
    assert_eq!(c, 1, "{e}");
    assert!(e.contains("policy is `stop`"), "{e}");
    let work = with_suffix(&out, ".incomplete");
    assert_eq!(csv_rows(&work.join("results.csv")).len(), 1);
    let (c, _, e) = sandjumper_text(&["campaign", "resume", o]);
    assert_eq!(c, 1, "{e}");
    assert_eq!(csv_rows(&work.join("results.csv")).len(), 2);
}

#[test]
fn bad_campaign_files_are_refused_with_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    for (edit, line, what) in [
        (
            ("seed = 7", "seed = 7\ncolour = \"red\""),
            "12",
            "unknown field `colour`",
        ),
        (
            ("phis = [0.58, 0.61]", "phis = []"),
            "21",
            "grid.phis is empty",
        ),
        (
            ("phis = [0.58, 0.61]", "phis = [0.58, 0.65]"),
            "21",
            "outside what the bed can reach",
        ),
        (
            ("tolerance = 0.004", "tolerance = 0.0"),
            "29",
            "bed.tolerance",
        ),
        (
            ("tolerance = 0.004", "tolerance = -0.01"),
            "29",
            "allowed: a positive",
        ),
    ] {
        let f = campaign_file(tmp.path(), |t| t.replace(edit.0, edit.1));
        let out = tmp.path().join("never");
        let (c, _, e) = sandjumper_text(&[
            "campaign",
            "run",
            f.to_str().unwrap(),
            "--link",
            "sil",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(c, 2, "{edit:?}: {e}");
        assert!(
            e.contains(&format!("campaign.toml:{line}:")),
            "{edit:?}: {e}"
        );
        assert!(e.contains(what), "{edit:?}: {e}");
        assert!(!out.exists() && !with_suffix(&out, ".incomplete").exists());
    }
    // A link that is not there, a board without the bed's protocol, a status of nothing.
    let out = tmp.path().join("x");
    let x = out.to_str().unwrap();
    let (c, _, e) = sandjumper_text(&["campaign", "run", SMALL, "--link", "hil", "--out", x]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("allowed: sil, pil"), "{e}");
    let (c, _, e) = sandjumper_text(&["campaign", "run", SMALL, "--port", "/dev/null", "--out", x]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("[bed.height_sensor]"), "{e}");
    let (c, _, e) = sandjumper_text(&["campaign", "status", x]);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("no campaign here"), "{e}");
}

/// Two sessions started at the same moment on one output: one runs the campaign, the other is
/// refused with exit status 2 naming why (another session starting or running it, or the
/// folder it made), and the campaign is the one a single session makes. Before the start lock,
/// the loser cleared or renamed the winner's plan under it and failed with an internal error.
#[test]
fn two_sessions_started_at_once_on_one_output_leave_one_campaign() {
    let tmp = tempfile::tempdir().unwrap();
    let file = campaign_file(tmp.path(), |t| {
        t.replace("track = true", "track = false")
            .replace("fps = 200", "fps = 0")
    });
    let f = file.to_str().unwrap();
    let straight = tmp.path().join("straight");
    let (c, _, e) = sandjumper_text(&[
        "campaign",
        "run",
        f,
        "--link",
        "sil",
        "--out",
        straight.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{e}");
    for round in 0..4 {
        let out = tmp.path().join(format!("raced{round}"));
        let o = out.to_str().unwrap();
        let spawn = || {
            Command::new(env!("CARGO_BIN_EXE_sandjumper"))
                .args(["campaign", "run", f, "--link", "sil", "--out", o])
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (spawn(), spawn());
        let results: Vec<_> = [a, b]
            .into_iter()
            .map(|c| c.wait_with_output().unwrap())
            .collect();
        let codes: Vec<_> = results.iter().map(|r| r.status.code()).collect();
        let errors: Vec<String> = results
            .iter()
            .map(|r| String::from_utf8_lossy(&r.stderr).into_owned())
            .collect();
        assert!(
            codes.contains(&Some(0)) && codes.iter().all(|c| matches!(c, Some(0) | Some(2))),
            "round {round}: exit statuses {codes:?}: {errors:?}"
        );
        if codes == [Some(2), Some(2)] || codes == [Some(0), Some(0)] {
            panic!("round {round}: {codes:?}: {errors:?}");
        }
        let loser = &errors[codes.iter().position(|c| *c == Some(2)).unwrap()];
        assert!(
            loser.contains("another session") || loser.contains("exists"),
            "round {round}: {loser}"
        );
        assert_eq!(
            read(&straight.join("results.csv")),
            read(&out.join("results.csv")),
            "round {round}"
        );
    }
}
