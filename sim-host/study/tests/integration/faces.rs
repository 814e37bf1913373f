//! What the command line's faces take from the library: the value parsers' refusals, the
//! lines `sweep` and `merge` print, `figures`' summary, and the jump's and replay's folders
//! written by `run_into` (bad input refused before the folder is touched).

use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::Silent;
use sandjumper_study::figures::FiguresReport;
use sandjumper_study::jump::{self, JumpRequest};
use sandjumper_study::replay::{self, ReplayRequest};
use sandjumper_study::sweep::{self, MergeRequest, ShardSpec, SweepRequest, SweepSpec};

#[test]
fn the_value_parsers_say_what_is_allowed() {
    let r = sweep::parse_freq_range("5:7:1").unwrap();
    assert_eq!(r.values, vec![5.0, 6.0, 7.0]);
    let e = sweep::parse_freq_range("0:2:1").unwrap_err();
    assert!(
        e.starts_with("range `0:2:1`: frequency 0 Hz is not positive"),
        "{e}"
    );
    assert!(
        sweep::parse_tau_range("-1")
            .unwrap_err()
            .contains("is negative")
    );
    assert!(
        sweep::parse_phi_range("1.5")
            .unwrap_err()
            .contains("not a fraction")
    );
    assert_eq!(
        sweep::parse_shard("2/3").unwrap(),
        ShardSpec { index: 2, count: 3 }
    );
    assert!(
        sweep::parse_shard("0/3")
            .unwrap_err()
            .contains("numbered from 1")
    );
    assert_eq!(replay::parse_window_ms("2.5").unwrap(), 2.5);
    assert_eq!(
        replay::parse_window_ms("0").unwrap_err(),
        "`0` is not a window length: a number of milliseconds in (0, 1000]"
    );
    assert_eq!(sandjumper_study::fit::parse_phi(" 0.6 ").unwrap(), 0.6);
    assert_eq!(
        sandjumper_study::fit::parse_phi("x").unwrap_err(),
        "`x` is not a number"
    );
}

#[test]
fn a_shard_and_a_merge_say_what_they_wrote() {
    let request = SweepRequest {
        spec: SweepSpec {
            kinds: vec![JumpKind::Single],
            freqs_hz: vec![10.0, 14.0],
            ..SweepSpec::default()
        },
        threads: Some(1),
        ..SweepRequest::default()
    };
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
        let line = shard.report(&written.dir, &written.plots);
        assert!(
            line.starts_with(&format!("swept shard {index}/2: 1 of 2 jumps in ")),
            "{line}"
        );
        assert!(
            line.ends_with("(sweep.csv, failures.csv, sweep.toml, params.toml)"),
            "{line}"
        );
        assert!(shard.warnings().is_empty());
        shards.push(written.dir);
    }
    let out = dir.path().join("merged");
    let merged = sweep::merge(
        &MergeRequest {
            dirs: shards,
            out: out.clone(),
        },
        &Silent,
    )
    .unwrap();
    let written = merged.write(&out).unwrap();
    let lines = merged.report(&written);
    assert_eq!(lines.len(), 1, "no failures, no warning: {lines:?}");
    assert!(
        lines[0].starts_with("merged 2 shard(s): 2 rows, 0 failures; wrote "),
        "{lines:?}"
    );
    assert!(
        lines[0].ends_with(", height_vs_freq.png, height_vs_freq.svg)"),
        "{lines:?}"
    );
}

#[test]
fn figures_summarise_files_jumps_time_and_findings() {
    let report = FiguresReport {
        dir: "figs".into(),
        files: vec!["a.svg".into(), "b.csv".into()],
        jumps: 7,
        failures: 1,
        findings: vec![("best_f_hz".into(), "12".into())],
        elapsed_s: 2.04,
    };
    assert_eq!(
        report.to_string(),
        "wrote 2 files to figs (7 jumps, 1 failed, 2.0 s)\n  best_f_hz = 12\n"
    );
}

#[test]
fn run_into_refuses_bad_input_before_touching_the_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("jump");
    let bad = JumpRequest {
        phi: 0.5,
        record_series: true,
        ..JumpRequest::default()
    };
    assert!(jump::run_into(&bad, Some(&out), &Silent).is_err());
    assert!(!out.exists(), "nothing written for a refused jump");
    let good = JumpRequest {
        record_series: true,
        ..JumpRequest::default()
    };
    let (outcome, written) = jump::run_into(&good, Some(&out), &Silent).unwrap();
    let written = written.expect("a folder");
    assert!(written.join("summary.json").is_file());
    assert!(outcome.simulated.summary.jump_height_m > 0.0);
    let (_, none) = jump::run_into(&JumpRequest::default(), None, &Silent).unwrap();
    assert!(none.is_none());
    let missing = ReplayRequest {
        log: dir.path().join("no-such-log.csv"),
        ..ReplayRequest::default()
    };
    let replay_out = dir.path().join("replay");
    let e = replay::run_into(&missing, Some(&replay_out), &Silent).unwrap_err();
    assert!(e.to_string().starts_with("log `"), "{e}");
    assert!(!replay_out.exists(), "the log is checked first");
}
