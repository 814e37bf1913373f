//! The `sandjumper` binary's outputs, the contract: what `jump --json` prints, the files
//! `jump --out`, `sweep` (whole and in shards) and `merge` write, the shard sets `merge`
//! refuses (exit 2, nothing written), and the summary's words. The numbers (a jump's metrics,
//! the trajectory, the sweep's rows and their determinism, shards merging to the unsharded
//! sweep) are tested through `sandjumper_study` in `sim-host/study/tests/integration/jump_sweep.rs`.

use std::path::Path;

use crate::common;
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

/// `jump --json` prints one JSON object with every metric, the request echoed.
#[test]
fn jump_json_has_every_metric() {
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
    assert!(
        v["liftoff_time_s"].is_f64(),
        "a 10 Hz jump leaves the ground"
    );
    assert!(
        v["events"]
            .as_array()
            .unwrap()
            .iter()
            .all(|e| e["kind"].is_string() && e["t_s"].is_f64())
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

/// `jump --out DIR --json` writes summary.json (what --json prints), jump.png, jump.svg,
/// trajectory.csv (its header) and params.toml (which `params --params` reads back to the same
/// text), leaves no staging folder, and a second run replaces the folder.
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

/// The smallest sweep that writes every file: single and delayed at 10 Hz, phi 0.57 and 0.58
/// (one params file each), tau 0 and 0.2 s (the delay figure), eq4: 6 jumps. (The 36-jump
/// sweep these tests ran before is `sim-host/study/tests/integration/jump_sweep.rs`'s.)
const SWEEP: &[&str] = &[
    "sweep",
    "--kind",
    "single,delayed",
    "--freq",
    "10",
    "--phi",
    "0.57:0.58:0.01",
    "--tau",
    "0:0.2:0.2",
    "--model",
    "eq4",
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

/// `sweep --out DIR` writes sweep.csv (its header), failures.csv, sweep.toml (counting every
/// combination), one params file per phi and the figures.
#[test]
fn sweep_writes_its_rows_metadata_parameters_and_figures() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    sweep(&whole, &[]);
    let text = read(&whole.join("sweep.csv"));
    assert_eq!(
        text.lines().next().unwrap(),
        "kind,model,phi,freq_hz,tau_s,jump_height_m,final_jump_height_m,max_depth_m,peak_added_mass_kg,peak_motor_force_n,drive"
    );
    let failures = read(&whole.join("failures.csv"));
    assert_eq!(
        failures.lines().next().unwrap(),
        "kind,model,phi,freq_hz,tau_s,error"
    );
    let meta: toml::Table = read(&whole.join("sweep.toml")).parse().unwrap();
    assert_eq!(meta["total_combinations"].as_integer(), Some(6));
    assert!(whole.join("params-phi-0.57.toml").exists());
    assert!(whole.join("params-phi-0.58.toml").exists());
    assert_png(&whole.join("height_vs_freq.png"));
    assert_svg(&whole.join("height_vs_freq.svg"));
    assert_png(&whole.join("height_vs_tau.png"));
}

/// `sweep --shard I/N` writes its shard (sweep.toml says which); `merge` of all shards in any
/// order writes the merged folder; a shard given twice, a missing shard, a shard of another
/// sweep, one of another shard count and a shard whose rows were cut are refused with exit 2,
/// naming the problem, and nothing is written.
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
    for f in [
        "sweep.csv",
        "failures.csv",
        "sweep.toml",
        "params-phi-0.57.toml",
        "params-phi-0.58.toml",
    ] {
        assert!(p("merged").join(f).is_file(), "{f}");
    }
    assert_eq!(read(&p("merged/sweep.csv")), read(&p("whole/sweep.csv")));
    assert_png(&p("merged/height_vs_freq.png"));

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
    other[4] = "10:12:2";
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
    // A shard whose rows were tampered with (2 rows a shard: the header and one are left).
    let csv = read(&p("s2/sweep.csv"));
    let cut: String = csv.lines().take(2).map(|l| format!("{l}\n")).collect();
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
/// (The heights themselves: `sim-host/study/tests/integration/jump_sweep.rs`.)
#[test]
fn a_final_height_that_is_not_positive_is_explained() {
    const NOTE: &str = "push-off did not lift the rod above its rest height";
    let stalled = ["jump", "--kind", "stutter", "--freq", "12", "--phi", "0.57"];
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[&stalled[..], &["--json"]].concat())).expect("JSON");
    assert_eq!(json["final_jump_note"], NOTE);
    assert!(ok(&stalled).contains(NOTE));
    let readme_first = [
        "jump", "--kind", "delayed", "--freq", "10", "--tau", "0.1", "--model", "eq4", "--phi",
        "0.57",
    ];
    let json: serde_json::Value =
        serde_json::from_str(&ok(&[&readme_first[..], &["--json"]].concat())).expect("JSON");
    assert!(json.get("final_jump_note").is_none(), "{json}");
    assert!(!ok(&readme_first).contains(NOTE));
}
