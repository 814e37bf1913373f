//! The `sandjumper` binary's outputs: `jump --json`, `jump --out`, `sweep`, shards and `merge`.

use std::path::Path;

mod common;
use common::{ok, read, refused};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

fn assert_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        bytes.starts_with(PNG_MAGIC),
        "{} is not a PNG",
        path.display()
    );
    assert!(bytes.len() > 10_000, "{} is nearly empty", path.display());
}

fn assert_svg(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(
        text.contains("<svg") && text.trim_end().ends_with("</svg>"),
        "{}",
        path.display()
    );
    // Text is drawn (axis labels with units).
    assert!(text.contains("<text"), "{} has no text", path.display());
}

#[test]
fn jump_json_has_every_metric_with_sane_values() {
    let out = ok(&["jump", "--kind", "single", "--freq", "10", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).expect("stdout is one JSON object");
    for key in [
        "jump_height_m",
        "final_jump_height_m",
        "max_depth_m",
        "peak_added_mass_kg",
        "liftoff_time_s",
        "apex_time_s",
        "peak_motor_force_n",
        "events",
        "rhs_evaluations",
        "warnings",
    ] {
        assert!(v.get(key).is_some(), "missing `{key}` in {out}");
    }
    assert_eq!(v["kind"], "single");
    assert_eq!(v["model"], "eq4");
    assert_eq!(v["phi"], 0.57);
    let h = v["jump_height_m"].as_f64().unwrap();
    assert!(h > 1e-4 && h < 0.2, "jump height {h} m");
    let depth = v["max_depth_m"].as_f64().unwrap();
    assert!(depth > 0.0 && depth < 0.1, "max depth {depth} m on sand");
    assert!(
        v["peak_added_mass_kg"].as_f64().unwrap() > 0.0,
        "eq4 has added mass"
    );
    let liftoff = v["liftoff_time_s"]
        .as_f64()
        .expect("a 10 Hz jump leaves the ground");
    let apex = v["apex_time_s"].as_f64().unwrap();
    assert!(
        0.0 < liftoff && liftoff < apex,
        "lift-off {liftoff} s, apex {apex} s"
    );
    assert!(v["rhs_evaluations"].as_u64().unwrap() > 100);
    let events = v["events"].as_array().unwrap();
    assert!(events.iter().any(|e| e["kind"] == "LiftOff"));
    let times: Vec<f64> = events.iter().map(|e| e["t_s"].as_f64().unwrap()).collect();
    assert!(
        times.windows(2).all(|w| w[0] <= w[1]),
        "events in time order"
    );
}

#[test]
fn jump_human_summary_names_the_jump() {
    let out = ok(&[
        "jump", "--kind", "stutter", "--freq", "12", "--model", "eq1",
    ]);
    assert!(out.contains("stutter jump, f = 12 Hz, model eq1"), "{out}");
    assert!(out.contains("jump height") && out.contains(" mm"), "{out}");
}

#[test]
fn jump_out_writes_data_picture_and_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("runs/jump");
    let json = ok(&[
        "jump",
        "--kind",
        "delayed",
        "--freq",
        "12",
        "--tau",
        "0.1",
        "--model",
        "eq4",
        "--phi",
        "0.58",
        "--out",
        s(&run),
        "--json",
    ]);
    let printed: serde_json::Value = serde_json::from_str(&json).unwrap();
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(printed, saved, "summary.json is what --json prints");

    assert_png(&run.join("jump.png"));
    assert_svg(&run.join("jump.svg"));

    let mut rdr = csv::Reader::from_path(run.join("trajectory.csv")).unwrap();
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        header,
        [
            "t_s", "x_m_m", "x_r_m", "x_f_m", "p_m", "f_s_n", "f_gm_n", "m_a_kg", "mode"
        ]
    );
    let mut last_t = f64::NEG_INFINITY;
    let mut rows = 0;
    let mut modes = std::collections::BTreeSet::new();
    for rec in rdr.records() {
        let rec = rec.unwrap();
        assert_eq!(rec.len(), 9);
        let num = |i: usize| rec[i].parse::<f64>().unwrap();
        let t = num(0);
        assert!(t >= last_t, "time goes forward");
        last_t = t;
        // p = x_m - x_r, within the stroke.
        assert!((num(4) - (num(1) - num(2))).abs() < 1e-9);
        assert!(num(4).abs() <= 0.025 + 1e-12);
        modes.insert(rec[8].to_string());
        rows += 1;
    }
    assert!(rows > 100, "{rows} rows");
    assert!(
        modes.iter().any(|m| m.eq_ignore_ascii_case("aerial")),
        "{modes:?}"
    );
    let end = saved["end_time_s"].as_f64().unwrap();
    assert!((last_t - end).abs() < 1e-9, "series ends at the run's end");

    // params.toml reads back through --params to the same parameters.
    let params = std::fs::read_to_string(run.join("params.toml")).unwrap();
    let again = ok(&[
        "params",
        "--phi",
        "0.58",
        "--params",
        s(&run.join("params.toml")),
    ]);
    assert_eq!(again, params);
    // Only the finished directory is left (no staging directories).
    let names: Vec<_> = std::fs::read_dir(dir.path().join("runs"))
        .unwrap()
        .collect();
    assert_eq!(names.len(), 1);

    // Running again replaces the earlier output.
    ok(&[
        "jump",
        "--kind",
        "single",
        "--freq",
        "9",
        "--model",
        "hard",
        "--out",
        s(&run),
    ]);
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap();
    assert_eq!(saved["kind"], "single");
}

const SWEEP: &[&str] = &[
    "sweep",
    "--kind",
    "single,delayed",
    "--freq",
    "6:14:4",
    "--phi",
    "0.57:0.58:0.01",
    "--tau",
    "0:0.2:0.2",
    "--model",
    "eq1-linear,eq4",
];

fn sweep(out: &Path, extra: &[&str]) {
    let mut args = SWEEP.to_vec();
    args.extend(["--out", s(out)]);
    args.extend(extra);
    if !extra.contains(&"--threads") {
        args.extend(["--threads", "2"]);
    }
    ok(&args);
}

#[test]
fn sweep_rows_cover_every_combination_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    sweep(&whole, &[]);
    let text = read(&whole.join("sweep.csv"));
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "kind,model,phi,freq_hz,tau_s,jump_height_m,final_jump_height_m,max_depth_m,peak_added_mass_kg,peak_motor_force_n,drive"
    );
    assert!(lines.clone().all(|l| l.ends_with(",kinematic")), "{text}");
    let failures = read(&whole.join("failures.csv"));
    let failed = failures.lines().count() - 1;
    // single: 2 models x 2 phi x 3 f; delayed: 2 models x 2 phi x 2 tau x 3 f.
    assert_eq!(lines.clone().count() + failed, 12 + 24);
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&first[..2], ["single", "eq1-linear"]);
    let nums: Vec<f64> = first[2..5].iter().map(|v| v.parse().unwrap()).collect();
    assert_eq!(nums, [0.57, 6.0, 0.0]);
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 11);
        let h: f64 = f[5].parse().unwrap();
        assert!(h.is_finite() && h >= 0.0, "{line}");
    }
    let meta: toml::Table = read(&whole.join("sweep.toml")).parse().unwrap();
    assert_eq!(meta["total_combinations"].as_integer(), Some(36));
    assert!(whole.join("params-phi-0.57.toml").exists());
    assert!(whole.join("params-phi-0.58.toml").exists());
    assert_png(&whole.join("height_vs_freq.png"));
    assert_svg(&whole.join("height_vs_freq.svg"));
    assert_png(&whole.join("height_vs_tau.png"));

    // Deterministic: another run with another thread count gives the same file.
    let again = dir.path().join("again");
    sweep(&again, &["--threads", "1"]);
    assert_eq!(read(&again.join("sweep.csv")), text);
}

#[test]
fn shards_merge_into_the_unsharded_sweep_and_bad_sets_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    sweep(&p("whole"), &[]);
    for i in 1..=3 {
        sweep(&p(&format!("s{i}")), &["--shard", &format!("{i}/3")]);
        let meta: toml::Table = read(&p(&format!("s{i}/sweep.toml"))).parse().unwrap();
        assert_eq!(meta["shard"]["index"].as_integer(), Some(i));
        assert_eq!(meta["shard"]["count"].as_integer(), Some(3));
    }
    // Any order of shards.
    ok(&[
        "merge",
        s(&p("s3")),
        s(&p("s1")),
        s(&p("s2")),
        "--out",
        s(&p("merged")),
    ]);
    assert_eq!(read(&p("merged/sweep.csv")), read(&p("whole/sweep.csv")));
    assert_eq!(
        read(&p("merged/failures.csv")),
        read(&p("whole/failures.csv"))
    );
    assert_eq!(
        read(&p("merged/params-phi-0.57.toml")),
        read(&p("whole/params-phi-0.57.toml"))
    );
    assert_png(&p("merged/height_vs_freq.png"));
    let merged: toml::Table = read(&p("merged/sweep.toml")).parse().unwrap();
    let whole: toml::Table = read(&p("whole/sweep.toml")).parse().unwrap();
    assert_eq!(merged, whole, "merged metadata is the unsharded sweep's");

    // Overlap, missing shard, and a shard of another sweep are refused; nothing is written.
    let bad = p("bad");
    refused(
        &[
            "merge",
            s(&p("s1")),
            s(&p("s1")),
            s(&p("s2")),
            s(&p("s3")),
            "--out",
            s(&bad),
        ],
        &["shard 1/3 given twice"],
    );
    refused(
        &["merge", s(&p("s1")), s(&p("s3")), "--out", s(&bad)],
        &["missing shard(s) 2/3"],
    );
    let mut other = SWEEP.to_vec();
    other[4] = "6:14:2";
    let o2 = p("o2");
    other.extend(["--out", s(&o2), "--shard", "2/3"]);
    ok(&other);
    refused(
        &[
            "merge",
            s(&p("s1")),
            s(&p("o2")),
            s(&p("s3")),
            "--out",
            s(&bad),
        ],
        &["different sweeps"],
    );
    sweep(&p("h2"), &["--shard", "2/4"]);
    refused(
        &[
            "merge",
            s(&p("s1")),
            s(&p("h2")),
            s(&p("s3")),
            "--out",
            s(&bad),
        ],
        &["same N"],
    );
    // A shard whose rows were tampered with.
    let csv = read(&p("s2/sweep.csv"));
    let cut: String = csv.lines().take(3).map(|l| format!("{l}\n")).collect();
    std::fs::write(p("s2/sweep.csv"), cut).unwrap();
    refused(
        &[
            "merge",
            s(&p("s1")),
            s(&p("s2")),
            s(&p("s3")),
            "--out",
            s(&bad),
        ],
        &["shard 2/3", "incomplete"],
    );
    assert!(!bad.exists());
}

/// A final jump height that is not positive is said in words (summary, JSON); a jump that
/// lifts the rod above rest carries no such note. The README's first command is such a jump.
#[test]
fn a_final_height_that_is_not_positive_is_explained() {
    const NOTE: &str = "push-off did not lift the rod above its rest height";
    let stalled = ["jump", "--kind", "stutter", "--freq", "12", "--phi", "0.57"];
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[&stalled[..], &["--json"]].concat())).expect("JSON");
    assert!(
        json["final_jump_height_m"].as_f64().unwrap() <= 0.0,
        "{json}"
    );
    assert_eq!(json["final_jump_note"], NOTE);
    assert!(ok(&stalled).contains(NOTE));
    let readme_first = [
        "jump", "--kind", "delayed", "--freq", "10", "--tau", "0.1", "--model", "eq4", "--phi",
        "0.57",
    ];
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[&readme_first[..], &["--json"]].concat())).expect("JSON");
    assert!(
        json["final_jump_height_m"].as_f64().unwrap() > 0.03,
        "{json}"
    );
    assert!(json.get("final_jump_note").is_none(), "{json}");
    assert!(!ok(&readme_first).contains(NOTE));
}
