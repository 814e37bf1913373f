//! `sandjumper optimize` through the real binary, on small budgets: the files it writes, that
//! its answer is what `jump`, `hil` and `rig replay` run from stroke.csv, that a seed fixes the
//! answer whatever the threads, that a search killed mid-way resumes to the same answer, and
//! the refusals of bad limits and bad stroke files.
#![cfg(feature = "optimize")]

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use sandjumper_rig::stroke_table::{RigLimits, StrokeTable};

mod common;
use common::{ok, read, refused, succeeded, workspace};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_str(&read(p)).unwrap()
}

/// A small search: a coarse paper sweep, a few hundred evaluations, two random starts.
fn small(out: &Path, extra: &[&str]) -> Vec<String> {
    let mut v: Vec<String> = [
        "optimize",
        "--out",
        s(out),
        "--evaluations",
        "720",
        "--population",
        "12",
        "--random-starts",
        "1",
        "--sweep-freq-step",
        "1",
        "--sweep-tau-step",
        "0.1",
        "--elites",
        "3",
        "--paper-candidates",
        "2",
        "--refine",
        "48",
        "--verify",
        "sil",
    ]
    .iter()
    .map(|x| x.to_string())
    .collect();
    // A flag given in `extra` replaces the default's (flag and value).
    for flag in extra.iter().filter(|x| x.starts_with("--")) {
        if let Some(i) = v.iter().position(|x| x == flag)
            && v.get(i + 1).is_some_and(|x| !x.starts_with("--"))
        {
            v.drain(i..i + 2);
        }
    }
    v.extend(extra.iter().map(|x| x.to_string()));
    v
}

fn run(args: &[String]) -> String {
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    ok(&a)
}

#[test]
fn a_small_search_writes_its_answer_and_jump_hil_and_rig_run_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("opt");
    // From the workspace (where the firmware builds and the virtual board live).
    let firmware = workspace().join(sandjumper_rig::firmware_image::EMULATED_ELF);
    let firmware = firmware.to_str().unwrap();
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(small(
            &out,
            &["--json", "--verify", "sil,pil,f407", "--firmware", firmware],
        ))
        .current_dir(workspace())
        .output()
        .unwrap();
    let stdout = succeeded(&output);
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
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
    let (h, hp, r) = (
        j["best_height_m"].as_f64().unwrap(),
        j["best_paper_stroke_height_m"].as_f64().unwrap(),
        j["height_ratio"].as_f64().unwrap(),
    );
    assert_eq!(j["height_basis"], "sil");
    assert!(hp > 0.01 && h > 0.01, "{h} {hp}");
    assert!((r - h / hp).abs() < 1e-12);
    // The answer is the best stroke through the controller of candidates.csv's ranking,
    // which holds the paper's best; the paper's answer is the best paper stroke there.
    let mut ranked = csv::Reader::from_path(out.join("candidates.csv")).unwrap();
    let col = ranked
        .headers()
        .unwrap()
        .iter()
        .position(|h| h == "controller_value")
        .unwrap();
    let values: Vec<f64> = ranked
        .records()
        .map(|r| r.unwrap()[col].parse::<f64>().unwrap_or(f64::NAN))
        .collect();
    let best = values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(f64::MIN, f64::max);
    assert_eq!(j["best_value"].as_f64().unwrap(), best, "{j}");
    assert!(values.iter().filter(|v| v.is_finite()).count() >= 2);

    // The answer and the paper's best ran through every link: the core (sil), the emulated
    // firmware under QEMU (pil) and the F407 release binary on the virtual board (f407),
    // each where it is built (.ci/run builds them; skipped with a message elsewhere).
    for stroke in ["answer", "paper_answer"] {
        let links = j[stroke]["links"].as_array().unwrap();
        assert_eq!(links.len(), 3, "{stroke}: {links:?}");
        let sil = links[0]["jump_height_m"].as_f64().unwrap();
        assert_eq!(links[0]["link"], "sil");
        for l in &links[1..] {
            if let Some(why) = l["skipped"].as_str() {
                assert!(
                    std::env::var_os("CI").is_none(),
                    "{stroke} through {}: skipped under CI: {why}",
                    l["link"]
                );
                eprintln!("skipped {} ({why})", l["link"]);
                continue;
            }
            let h = l["jump_height_m"].as_f64().unwrap();
            assert!(
                (h - sil).abs() <= 0.03 * sil,
                "{stroke}: {} {h} m against sil {sil} m",
                l["link"]
            );
            assert!(l["faults"].as_array().unwrap().is_empty(), "{l}");
        }
    }

    // The stroke passes the rig's own check, and is what jump, hil and rig replay run.
    let params = sandjumper_model::params::Params::preset(0.57).unwrap();
    let table = StrokeTable::read_csv(&out.join("stroke.csv")).unwrap();
    table.check(&RigLimits::of(&params)).unwrap();
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
    // candidates.csv ranks through the controller: the first row is the answer.
    let cands = read(&out.join("candidates.csv"));
    let first = cands.lines().nth(1).unwrap();
    assert!(
        first.contains(j["answer"]["label"].as_str().unwrap()),
        "{first}"
    );
}

#[test]
fn a_seed_fixes_the_answer_whatever_the_threads() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    run(&small(&a, &["--threads", "1", "--seed", "7"]));
    run(&small(&b, &["--threads", "2", "--seed", "7"]));
    assert_eq!(read(&a.join("stroke.csv")), read(&b.join("stroke.csv")));
    assert_eq!(read(&a.join("history.csv")), read(&b.join("history.csv")));
    assert_eq!(
        read(&a.join("candidates.csv")),
        read(&b.join("candidates.csv"))
    );
    let j = json(&a.join("summary.json"));
    assert_eq!(j["height_basis"], "sil");
    assert_eq!(j["refine_runs"], 48);
    // Without a link the answer is the kinematic model's.
    let c = dir.path().join("c");
    run(&small(&c, &["--seed", "7", "--verify", "none"]));
    assert_eq!(json(&c.join("summary.json"))["height_basis"], "kinematic");
}

fn kill_when_checkpoint_has(args: &[String], ckpt: &Path, lines: usize) -> bool {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sandjumper"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        let n = std::fs::read_to_string(ckpt).map_or(0, |t| t.lines().count());
        if n >= lines {
            child.kill().unwrap();
            child.wait().unwrap();
            return true;
        }
        if child.try_wait().unwrap().is_some() || start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            return false;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn a_search_killed_mid_way_resumes_to_the_same_answer() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let args = |out: &PathBuf| small(out, &["--evaluations", "2400", "--refine", "96"]);
    let j: serde_json::Value =
        serde_json::from_str(&run(&[args(&whole), vec!["--json".to_string()]].concat())).unwrap();
    let searched = j["evaluations"].as_u64().unwrap() as usize;
    let out = dir.path().join("resumed");
    let ckpt = dir.path().join("resumed.checkpoint");
    // Killed three times: twice in the kinematic search, once in the refinement through sil
    // (its values follow the search's in the checkpoint).
    let mut kills = 0;
    for lines in [200, 1200, searched + 40] {
        kills += usize::from(kill_when_checkpoint_has(&args(&out), &ckpt, lines));
    }
    assert!(
        kills >= 2,
        "the search finished before it could be killed ({kills} kills)"
    );
    assert!(ckpt.is_file());
    let stdout = run(&[args(&out), vec!["--json".to_string()]].concat());
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(j["evaluations_resumed"].as_u64().unwrap() >= 199, "{j}");
    assert_eq!(j["refine_runs"], 96);
    assert_eq!(
        read(&whole.join("stroke.csv")),
        read(&out.join("stroke.csv"))
    );
    assert_eq!(
        read(&whole.join("history.csv")),
        read(&out.join("history.csv"))
    );
    assert!(!ckpt.exists());
    // The killed runs' half-written folders are gone with the resumed run.
    let partials: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .starts_with(".resumed.partial-")
        })
        .collect();
    assert!(partials.is_empty(), "{partials:?}");
    // A checkpoint made with other settings is refused, not silently reused.
    std::fs::write(&ckpt, "sandjumper-optimize-checkpoint 1 {\"seed\":99}\n").unwrap();
    refused(
        &args(&out).iter().map(String::as_str).collect::<Vec<_>>(),
        &["other settings", "resumed.checkpoint"],
    );
}

#[test]
fn other_objectives_and_hard_ground_run() {
    let dir = tempfile::tempdir().unwrap();
    for (name, extra) in [
        ("energy", vec!["--objective", "height-per-energy"]),
        (
            "final",
            vec!["--objective", "final-height", "--model", "hard"],
        ),
    ] {
        let out = dir.path().join(name);
        let j: serde_json::Value = serde_json::from_str(&run(&small(
            &out,
            &[extra.as_slice(), &["--json", "--verify", "none"]].concat(),
        )))
        .unwrap();
        assert!(j["best_value"].as_f64().unwrap().is_finite(), "{name}: {j}");
        assert!(j["value_ratio"].as_f64().unwrap() >= 1.0, "{name}: {j}");
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
