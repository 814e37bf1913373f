//! What `sandjumper jump`, `sweep` and `merge` compute, as the library's calls
//! (`sandjumper_study::{jump, sweep}`): a jump's metrics and its trajectory file, a sweep's rows
//! in combination order and their determinism, shards that merge into the unsharded sweep and
//! the shard sets merge refuses, and the final jump height's note. (The command line's flags,
//! files and `--json` shape: `sim-host/cli/tests/integration/cli_runs.rs`.)

use std::path::Path;

use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::EventKind;
use sandjumper_model::params::ModelName;
use sandjumper_model::resolve::{ParamsFile, resolve_params};
use sandjumper_output::{Blame, Blamed, Silent};
use sandjumper_study::jump::{self, JumpRequest};
use sandjumper_study::sweep::{
    self, MergeRequest, ShardSpec, SweepRequest, SweepRunOutcome, SweepSpec, ValueRange,
};

/// `jump --kind KIND --freq F [--tau T] --model MODEL` at phi 0.57, run.
fn sine(kind: JumpKind, freq_hz: f64, tau_s: Option<f64>, model: ModelName) -> jump::JumpOutcome {
    let request = JumpRequest {
        kind,
        freq_hz,
        tau_s,
        model,
        ..JumpRequest::default()
    };
    jump::run(&request, &Silent).expect("the jump runs")
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `jump --kind single --freq 10` (eq4, phi 0.57): a jump height between 0.1 mm and 20 cm, a
/// depth in the sand under 10 cm, added mass, a lift-off before the apex, more than 100
/// right-hand-side evaluations, and its events (a lift-off among them) in time order; the
/// summary names the request.
#[test]
fn a_single_jump_has_sane_metrics() {
    let out = sine(JumpKind::Single, 10.0, None, ModelName::Eq4);
    let s = &out.simulated.summary;
    let json: serde_json::Value = serde_json::from_str(&out.json().unwrap()).unwrap();
    assert_eq!(json["kind"], "single");
    assert_eq!(json["model"], "eq4");
    assert_eq!(json["phi"], 0.57);
    let h = s.jump_height_m;
    assert!(h > 1e-4 && h < 0.2, "jump height {h} m");
    assert!(
        s.max_depth_m > 0.0 && s.max_depth_m < 0.1,
        "max depth {} m on sand",
        s.max_depth_m
    );
    assert!(s.peak_added_mass_kg > 0.0, "eq4 has added mass");
    let liftoff = s.liftoff_time_s.expect("a 10 Hz jump leaves the ground");
    assert!(
        0.0 < liftoff && liftoff < s.apex_time_s,
        "lift-off {liftoff} s, apex {} s",
        s.apex_time_s
    );
    assert!(s.rhs_evaluations > 100);
    assert!(s.events.iter().any(|e| e.kind == EventKind::LiftOff));
    assert!(
        s.events.windows(2).all(|w| w[0].t_s <= w[1].t_s),
        "events in time order"
    );
    let stutter = sine(JumpKind::Stutter, 12.0, None, ModelName::Eq1);
    let text = stutter.to_string();
    assert!(
        text.contains("stutter jump, f = 12 Hz, model eq1"),
        "{text}"
    );
    assert!(
        text.contains("jump height") && text.contains(" mm"),
        "{text}"
    );
}

/// `jump --kind delayed --freq 12 --tau 0.1 --model eq4 --phi 0.58 --out DIR`: summary.json is
/// the outcome's JSON; trajectory.csv's rows go forward in time to the run's end, keep
/// `p = x_m - x_r` within the 25 mm stroke, and include the aerial mode; params.toml read
/// back over the phi 0.58 preset gives the same parameters.
#[test]
fn a_jumps_folder_holds_its_trajectory_and_parameters() {
    let request = JumpRequest {
        kind: JumpKind::DelayedStutter,
        freq_hz: 12.0,
        tau_s: Some(0.1),
        model: ModelName::Eq4,
        phi: 0.58,
        record_series: true,
        ..JumpRequest::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let (outcome, written) = jump::run_into(&request, Some(&dir.path().join("jump")), &Silent)
        .expect("the jump runs and writes its folder");
    let run = written.expect("a folder");
    let saved: serde_json::Value = serde_json::from_str(&read(&run.join("summary.json"))).unwrap();
    let json: serde_json::Value = serde_json::from_str(&outcome.json().unwrap()).unwrap();
    assert_eq!(json, saved, "summary.json is the outcome's JSON");

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

    // params.toml reads back (as `--params`) over the preset to the same parameters.
    let text = read(&run.join("params.toml"));
    let file = ParamsFile {
        path: run.join("params.toml"),
        text: text.clone(),
    };
    assert_eq!(resolve_params(0.58, Some(&file)).unwrap().to_toml(), text);
    assert_eq!(text, outcome.params.to_toml());
}

/// The sweep `cli/tests/integration/cli_runs.rs` once ran (36 jumps; it runs 6 now): single and delayed, 6..14 Hz by 4, phi 0.57 and
/// 0.58, tau 0 and 0.2 s, eq1-linear and eq4 (36 combinations), on `threads` threads.
fn sweep_request(threads: usize) -> SweepRequest {
    let range = |s: &str| ValueRange::parse(s).unwrap().values;
    SweepRequest {
        spec: SweepSpec {
            kinds: vec![JumpKind::Single, JumpKind::DelayedStutter],
            models: vec![ModelName::Eq1Linear, ModelName::Eq4],
            phis: range("0.57:0.58:0.01"),
            freqs_hz: range("6:14:4"),
            taus_s: range("0:0.2:0.2"),
            ..SweepSpec::default()
        },
        threads: Some(threads),
        ..SweepRequest::default()
    }
}

fn run_sweep(request: &SweepRequest) -> SweepRunOutcome {
    request.validate().unwrap();
    sweep::run(request, &Silent).expect("the sweep runs")
}

/// Every combination has a row or a failure (single: 2 models x 2 phi x 3 f; delayed: 2 models
/// x 2 phi x 2 tau x 3 f), in order (the first is single, eq1-linear, phi 0.57, 6 Hz, tau 0),
/// each driven kinematically with a finite, non-negative height; sweep.toml counts 36
/// combinations; one params file per phi and the figures (height vs frequency, vs delay) are
/// written; a run on another number of threads writes the same sweep.csv.
#[test]
fn sweep_rows_cover_every_combination_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let whole = run_sweep(&sweep_request(2))
        .write(&dir.path().join("whole"))
        .unwrap();
    let text = read(&whole.dir.join("sweep.csv"));
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "kind,model,phi,freq_hz,tau_s,jump_height_m,final_jump_height_m,max_depth_m,peak_added_mass_kg,peak_motor_force_n,drive"
    );
    assert!(lines.clone().all(|l| l.ends_with(",kinematic")), "{text}");
    let failures = read(&whole.dir.join("failures.csv"));
    let failed = failures.lines().count() - 1;
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
    let meta: toml::Table = read(&whole.dir.join("sweep.toml")).parse().unwrap();
    assert_eq!(meta["total_combinations"].as_integer(), Some(36));
    assert!(whole.dir.join("params-phi-0.57.toml").exists());
    assert!(whole.dir.join("params-phi-0.58.toml").exists());
    for plot in [
        "height_vs_freq.png",
        "height_vs_freq.svg",
        "height_vs_tau.png",
    ] {
        assert!(whole.plots.iter().any(|p| p == plot), "{:?}", whole.plots);
        assert!(whole.dir.join(plot).is_file(), "{plot}");
    }

    // Deterministic: another run with another thread count gives the same file.
    let again = run_sweep(&sweep_request(1))
        .write(&dir.path().join("again"))
        .unwrap();
    assert_eq!(read(&again.dir.join("sweep.csv")), text);
}

/// Shards 1/3..3/3 of the sweep say which they are; merged in any order they give the
/// unsharded sweep's rows, failures, parameters and sweep.toml. A shard given twice, a missing
/// shard, a shard of another sweep, one of another shard count and a shard whose rows were cut
/// are refused (the caller's input), and nothing is written.
#[test]
fn shards_merge_into_the_unsharded_sweep_and_bad_sets_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let request = sweep_request(2);
    let shard = |request: &SweepRequest, index: usize, count: usize, name: &str| {
        let out = run_sweep(&SweepRequest {
            shard: Some(ShardSpec { index, count }),
            ..request.clone()
        });
        assert_eq!((out.meta.shard.index, out.meta.shard.count), (index, count));
        out.write(&p(name)).unwrap().dir
    };
    let whole = run_sweep(&request).write(&p("whole")).unwrap().dir;
    for i in 1..=3 {
        let dir = shard(&request, i, 3, &format!("s{i}"));
        let meta: toml::Table = read(&dir.join("sweep.toml")).parse().unwrap();
        assert_eq!(meta["shard"]["index"].as_integer(), Some(i as i64));
        assert_eq!(meta["shard"]["count"].as_integer(), Some(3));
    }
    // Any order of shards.
    let merge = |names: &[&str], out: &str| {
        sweep::merge(
            &MergeRequest {
                dirs: names.iter().map(|n| p(n)).collect(),
                out: p(out),
            },
            &Silent,
        )
    };
    let merged = merge(&["s3", "s1", "s2"], "merged").unwrap();
    let written = merged.write(&p("merged")).unwrap();
    for file in [
        "sweep.csv",
        "failures.csv",
        "params-phi-0.57.toml",
        "params-phi-0.58.toml",
    ] {
        assert_eq!(
            read(&written.dir.join(file)),
            read(&whole.join(file)),
            "{file}"
        );
    }
    assert!(written.plots.iter().any(|p| p == "height_vs_freq.png"));
    let merged: toml::Table = read(&p("merged/sweep.toml")).parse().unwrap();
    let unsharded: toml::Table = read(&whole.join("sweep.toml")).parse().unwrap();
    assert_eq!(
        merged, unsharded,
        "merged metadata is the unsharded sweep's"
    );

    // Overlap, missing shard, and a shard of another sweep are refused; nothing is written.
    let refused = |names: &[&str], culprits: &[&str]| {
        let e = merge(names, "bad").expect_err("refused");
        assert_eq!(e.blame(), Blame::Input, "{e}");
        for c in culprits {
            assert!(e.to_string().contains(c), "{names:?}: {e}");
        }
    };
    refused(&["s1", "s1", "s2", "s3"], &["shard 1/3 given twice"]);
    refused(&["s1", "s3"], &["missing shard(s) 2/3"]);
    let mut other = request.clone();
    other.spec.freqs_hz = ValueRange::parse("6:14:2").unwrap().values;
    shard(&other, 2, 3, "o2");
    refused(&["s1", "o2", "s3"], &["different sweeps"]);
    shard(&request, 2, 4, "h2");
    refused(&["s1", "h2", "s3"], &["same N"]);
    // A shard whose rows were tampered with.
    let csv = read(&p("s2/sweep.csv"));
    let cut: String = csv.lines().take(3).map(|l| format!("{l}\n")).collect();
    std::fs::write(p("s2/sweep.csv"), cut).unwrap();
    refused(&["s1", "s2", "s3"], &["shard 2/3", "incomplete"]);
    assert!(!p("bad").exists());
}

/// A final jump height that is not positive carries its note (the summary, the JSON): the
/// stutter at 12 Hz on eq4 stalls; the README's first command (delayed, 10 Hz, 0.1 s) lifts the
/// rod more than 3 cm above rest and carries no note.
#[test]
fn a_final_height_that_is_not_positive_is_explained() {
    const NOTE: &str = "push-off did not lift the rod above its rest height";
    let stalled = sine(JumpKind::Stutter, 12.0, None, ModelName::Eq4);
    let s = &stalled.simulated.summary;
    assert!(s.final_jump_height_m <= 0.0, "{}", s.final_jump_height_m);
    assert_eq!(s.final_height_note(), Some(NOTE));
    let json: serde_json::Value = serde_json::from_str(&stalled.json().unwrap()).unwrap();
    assert_eq!(json["final_jump_note"], NOTE);
    assert!(stalled.to_string().contains(NOTE));
    let readme_first = sine(JumpKind::DelayedStutter, 10.0, Some(0.1), ModelName::Eq4);
    let s = &readme_first.simulated.summary;
    assert!(s.final_jump_height_m > 0.03, "{}", s.final_jump_height_m);
    assert!(s.final_height_note().is_none());
    let json: serde_json::Value = serde_json::from_str(&readme_first.json().unwrap()).unwrap();
    assert!(json.get("final_jump_note").is_none(), "{json}");
    assert!(!readme_first.to_string().contains(NOTE));
}

/// A caller that asks the call to stop once `after` steps are done (Ctrl-C in a face).
struct StopAfter {
    after: u64,
    done: std::sync::atomic::AtomicU64,
}

impl sandjumper_output::Progress for StopAfter {
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, std::sync::atomic::Ordering::SeqCst);
    }
    fn cancelled(&self) -> bool {
        self.done.load(std::sync::atomic::Ordering::SeqCst) >= self.after
    }
}

/// A sweep its caller stops (`Progress::cancelled`) runs no further jump: one thread, 36
/// combinations, stopped after 5: the error says 5 of 36 were done, and only 5 were counted.
/// Tried: without the sweep's check, all 36 ran ("36 of 36").
#[test]
fn a_sweep_stopped_by_its_caller_runs_no_further_jump() {
    let stop = StopAfter {
        after: 5,
        done: std::sync::atomic::AtomicU64::new(0),
    };
    let e = sweep::run(&sweep_request(1), &stop).unwrap_err();
    assert_eq!(e.to_string(), "interrupted: 5 of 36 jumps done");
    assert_eq!(e.blame(), Blame::Internal);
    assert_eq!(stop.done.load(std::sync::atomic::Ordering::SeqCst), 5);
}
