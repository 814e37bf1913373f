//! The study commands as library calls: each `run` gives its typed outcome in memory, the
//! same JSON keys as `summary.json`, and writes its folder (small, fast configurations).

use std::fmt::Write as _;

use sandjumper_acqlog::{AcqLog, Column, LogMetadata, LogRow};
use sandjumper_core::trajectory::{JumpKind, SineJump};
use sandjumper_model::resolve::ParamsFile;
use sandjumper_output::{Blame, Blamed, Silent};
use sandjumper_study::fit::intrusion::CurveKind;
use sandjumper_study::fit::{FitKind, FitRequest};
use sandjumper_study::jump::{self, JumpRequest};
use sandjumper_study::replay::{self, ReplayRequest};
use sandjumper_study::sweep::{self, MergeRequest, ShardSpec, SweepRequest, SweepSpec};

fn delayed() -> JumpRequest {
    JumpRequest {
        kind: JumpKind::DelayedStutter,
        freq_hz: 10.0,
        tau_s: Some(0.1),
        ..JumpRequest::default()
    }
}

#[test]
fn a_jump_runs_serialises_as_summary_json_and_writes_its_folder() {
    let out = jump::run(&delayed(), &Silent).unwrap();
    let h = out.simulated.summary.jump_height_m;
    assert!(
        (0.06..0.08).contains(&h),
        "the paper's delayed stutter: {h} m"
    );
    let json: serde_json::Value = serde_json::from_str(&out.json().unwrap()).unwrap();
    assert_eq!(json["kind"], "delayed");
    assert_eq!(json["tau_s"], 0.1);
    assert_eq!(json["jump_height_m"], h);
    assert!(
        out.to_string()
            .starts_with("delayed stutter (τ = 0.1 s), f = 10 Hz, model eq4")
    );
    let dir = tempfile::tempdir().unwrap();
    let req = JumpRequest {
        record_series: true,
        ..delayed()
    };
    let written = jump::run(&req, &Silent)
        .unwrap()
        .write(&dir.path().join("jump"))
        .unwrap();
    for f in ["trajectory.csv", "params.toml", "summary.json", "jump.svg"] {
        assert!(written.join(f).is_file(), "{f}");
    }
}

#[test]
fn a_bad_phi_is_the_callers_input_with_the_command_lines_words() {
    let req = JumpRequest {
        phi: 0.5,
        ..delayed()
    };
    let e = req.validate().unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(
        e.to_string()
            .starts_with("--phi 0.5 is outside the presets' range"),
        "{e}"
    );
    let with_sand = JumpRequest {
        params: Some(ParamsFile {
            path: "sand.toml".into(),
            text: "[sand]\n".into(),
        }),
        ..req
    };
    assert!(with_sand.validate().is_ok());
}

#[test]
fn a_replayed_log_predicts_the_logged_jump() {
    let amplitude = sandjumper_model::params::Params::preset(0.57)
        .unwrap()
        .robot
        .stroke_amplitude_m;
    let sine = SineJump::new(JumpKind::Single, amplitude, 12.0, 0.0).unwrap();
    let rate = 10_000.0;
    let mut log = AcqLog::new(LogMetadata::new(rate, 1.0e6), &[Column::PCmdM]);
    log.meta.phi = Some(0.57);
    let last = (sine.end_s() * rate).round() as i64;
    for k in 0..=last {
        let t = k as f64 / rate;
        let p = sine.eval(t).position_m;
        let mut row = LogRow::new(k as u64, t, (p * 1.0e6).round() as i64);
        row.p_cmd_m = Some(p);
        log.rows.push(row);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("log.csv");
    log.write_file(&path).unwrap();
    let out = replay::run(
        &ReplayRequest {
            log: path,
            ..ReplayRequest::default()
        },
        &Silent,
    )
    .unwrap();
    let exact = jump::run(
        &JumpRequest {
            freq_hz: 12.0,
            ..JumpRequest::default()
        },
        &Silent,
    )
    .unwrap();
    let (r, e) = (
        out.summary.jump_height_m,
        exact.simulated.summary.jump_height_m,
    );
    assert!((r - e).abs() < 0.01 * e, "replayed {r} m vs exact {e} m");
    let json: serde_json::Value = serde_json::from_str(&out.json().unwrap()).unwrap();
    assert_eq!(json["phi"], 0.57);
    assert!(
        json["replay"]["samples"].as_u64().unwrap() > 800,
        "1/12 s at 10 kHz"
    );
    assert!(out.to_string().contains("  replayed log       "));
}

#[test]
fn two_shards_merge_into_the_whole_sweep() {
    let request = SweepRequest {
        spec: SweepSpec {
            kinds: vec![JumpKind::Single, JumpKind::Stutter],
            freqs_hz: vec![10.0, 14.0],
            ..SweepSpec::default()
        },
        threads: Some(1),
        ..SweepRequest::default()
    };
    let whole = sweep::run(&request, &Silent).unwrap();
    assert_eq!(whole.outcome.rows.len(), 4);
    assert!(whole.outcome.failures.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let mut shards = Vec::new();
    for index in 1..=2 {
        let shard = sweep::run(
            &SweepRequest {
                shard: Some(ShardSpec { index, count: 2 }),
                ..request.clone()
            },
            &Silent,
        )
        .unwrap();
        let written = shard.write(&dir.path().join(format!("s{index}"))).unwrap();
        assert!(written.plots.is_empty(), "a shard draws no figures");
        shards.push(written.dir);
    }
    let out = dir.path().join("merged");
    let merged = sweep::merge(
        &MergeRequest {
            dirs: shards.clone(),
            out: out.clone(),
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(merged.outcome, whole.outcome);
    assert_eq!(merged.meta.spec_hash, whole.meta.spec_hash);
    let written = merged.write(&out).unwrap();
    assert!(written.plots.contains(&"height_vs_freq.svg".to_string()));
    assert!(written.dir.join("params.toml").is_file());
    let refused = sweep::merge(
        &MergeRequest {
            dirs: shards.clone(),
            out: shards[0].clone(),
        },
        &Silent,
    )
    .unwrap_err();
    assert!(
        refused
            .to_string()
            .contains("is one of the shard directories"),
        "{refused}"
    );
}

#[test]
fn an_intrusion_fit_finds_the_curves_resistances() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("intrusion.csv");
    let mut text = String::from("depth_m,force_n\n");
    for i in 0..100 {
        let z = 0.0005 * f64::from(i);
        let f = if z <= 0.015 {
            1600.0 * z
        } else {
            24.0 + 1100.0 * (z - 0.015)
        };
        let _ = writeln!(text, "{z},{f}");
    }
    std::fs::write(&csv, text).unwrap();
    let request = FitRequest {
        file: csv,
        kind: FitKind::Intrusion {
            curve: CurveKind::First,
            z_start_m: None,
        },
        ..FitRequest::default()
    };
    let report = sandjumper_study::fit::run(&request, &Silent).unwrap();
    let json: serde_json::Value = serde_json::from_str(&report.to_json()).unwrap();
    let k1 = json["fits"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["param"] == "k1")
        .unwrap()["value"]
        .as_f64()
        .unwrap();
    assert!((k1 / 1600.0 - 1.0).abs() < 0.05, "k1 {k1}");
    let bad = FitRequest {
        kind: FitKind::Intrusion {
            curve: CurveKind::Auto,
            z_start_m: Some(-1.0),
        },
        ..request
    };
    assert_eq!(
        bad.validate().unwrap_err().to_string(),
        "--z-start -1: allowed a depth > 0 in m"
    );
}
