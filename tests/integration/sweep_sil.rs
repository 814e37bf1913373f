//! `sweep --link sil [--gain-lowering F]`: every jump of the sweep through the software-in-the-
//! loop rig. Facts checked:
//! - each row equals what `hil --link sil` reports for the same jump (same rtol, same gain
//!   lowering), to the bit: one code path;
//! - the CSV and `sweep.toml` say which drive was used;
//! - shards of a SIL sweep merge into the unsharded sweep, byte for byte.

use std::path::Path;

use clap::Parser;
use sandjumper_cli::cli::{Cli, execute};

fn run(args: &[&str]) {
    let mut all = vec!["sandjumper"];
    all.extend_from_slice(args);
    let cli = Cli::try_parse_from(all).unwrap_or_else(|e| panic!("{args:?}: {e}"));
    execute(cli).unwrap_or_else(|e| panic!("{args:?}: {}", e.message));
}

fn rows(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("sweep.csv")).expect("sweep.csv");
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

const SWEEP: [&str; 12] = [
    "sweep",
    "--kind",
    "single,delayed",
    "--freq",
    "9:11:2",
    "--tau",
    "0.1:0.2:0.1",
    "--link",
    "sil",
    "--gain-lowering",
    "0.05",
    "--rtol",
];
const RTOL: &str = "1e-6";

#[test]
fn a_sil_sweep_equals_hil_jump_by_jump_and_says_its_drive() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sweep");
    let out_s = out.to_str().unwrap();
    let mut args = SWEEP.to_vec();
    args.extend([RTOL, "--out", out_s]);
    run(&args);
    let rows = rows(&out);
    assert_eq!(rows.len(), 2 + 4, "2 single + 2 x 2 delayed");
    let meta = std::fs::read_to_string(out.join("sweep.toml")).unwrap();
    assert!(
        meta.contains("drive = \"sil-gain-lowering-0.05\""),
        "{meta}"
    );
    for (k, r) in rows.iter().enumerate() {
        let (kind, phi, freq, tau, height, drive) = (&r[0], &r[2], &r[3], &r[4], &r[5], &r[10]);
        assert_eq!(drive, "sil-gain-lowering-0.05");
        let hil_out = tmp.path().join(format!("hil{k}"));
        let mut hil = vec![
            "hil",
            "--link",
            "sil",
            "--kind",
            kind,
            "--freq",
            freq,
            "--phi",
            phi,
            "--rtol",
            RTOL,
            "--out",
            hil_out.to_str().unwrap(),
        ];
        if kind == "delayed" {
            hil.extend(["--tau", tau, "--gain-lowering", "0.05"]);
        }
        run(&hil);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(hil_out.join("summary.json")).unwrap())
                .unwrap();
        let hil_height = summary["jump_height_m"].as_f64().unwrap();
        assert_eq!(
            height.parse::<f64>().unwrap(),
            hil_height,
            "row {r:?} vs hil {hil_height}"
        );
    }
}

#[test]
fn shards_of_a_sil_sweep_merge_to_the_unsharded_sweep() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = |name: &str| tmp.path().join(name);
    let whole = dir("whole");
    let mut args = SWEEP.to_vec();
    args.extend([RTOL, "--out", whole.to_str().unwrap()]);
    run(&args);
    let mut shards = Vec::new();
    for i in 1..=2 {
        let shard = dir(&format!("shard{i}"));
        let spec = format!("{i}/2");
        let mut args = SWEEP.to_vec();
        args.extend([RTOL, "--out", shard.to_str().unwrap(), "--shard", &spec]);
        run(&args);
        shards.push(shard);
    }
    let merged = dir("merged");
    run(&[
        "merge",
        shards[0].to_str().unwrap(),
        shards[1].to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert_eq!(
        std::fs::read(merged.join("sweep.csv")).unwrap(),
        std::fs::read(whole.join("sweep.csv")).unwrap()
    );
}
