//! Every command's typed call through the core in this process (sil): the outcome checked in
//! memory, no binary, no files unless asked for. Cheap: short jumps and programs.

use sandjumper_core::RigState;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::{Blame, Blamed, Progress, Silent, StagedDir};
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil_command::{self, HilJump, HilRequest, NamedStroke, with_jump_height};
use sandjumper_rig::stroke_table::StrokeTable;
use sandjumper_rig::tool::calibrate::{CalibrateRequest, acknowledge_reset, calibrate};
use sandjumper_rig::tool::flash::{FlashRequest, Flashed, flash};
use sandjumper_rig::tool::intrude::{self, IntrudeRequest};
use sandjumper_rig::tool::jump::{self, JumpRequest};
use sandjumper_rig::tool::replay::{self, ReplayRequest};
use sandjumper_rig::tool::status::{WatchRequest, status, watch};
use sandjumper_rig::tool::target::Target;
use sandjumper_rig::watch::RunWatch;

/// A one-cycle cosine stroke of `amplitude_m` at `freq_hz`, sampled at 1 kHz.
fn cosine(amplitude_m: f64, freq_hz: f64) -> StrokeTable {
    let n = (1000.0 / freq_hz) as usize + 1;
    let record: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            let t = k as f64 / 1000.0;
            (
                t,
                -amplitude_m * (std::f64::consts::TAU * freq_hz * t).cos(),
            )
        })
        .collect();
    StrokeTable::resample(&record, 1000)
}

#[derive(Default)]
struct Counted {
    titles: Vec<String>,
    periods: u64,
    steps: u64,
}

impl RunWatch for Counted {
    fn started(&mut self, title: &str, _t_s: f64) {
        self.titles.push(title.to_string());
    }
    fn period(&mut self, _: &sandjumper_rig::hil::PeriodView) {
        self.periods += 1;
    }
    fn program(
        &mut self,
        _: &sandjumper_rig::tool::session::ProgramView<'_>,
        _: Option<f64>,
        _: f64,
    ) {
        self.steps += 1;
    }
}

#[test]
fn hil_through_sil_jumps_reports_every_period_and_serialises_the_jump_height() {
    let request = HilRequest {
        freq_hz: 10.0,
        camera_fps: 0,
        ..HilRequest::default()
    };
    let mut seen = Counted::default();
    request.check(&Silent).expect("a valid request");
    let jump = hil_command::run_checked(&request, &Silent, Some(&mut seen)).expect("runs");
    let HilJump::Loop(run) = &jump else {
        panic!("sil is a lockstep link")
    };
    let h = run.report.summary.jump_height_m;
    assert!(h > 0.001 && h < 0.05, "jump height {h} m");
    assert!(run.report.faults.is_empty(), "{:?}", run.report.faults);
    // Every period but the idle one before `Arm`.
    assert_eq!(seen.periods + 1, run.outcome.ticks);
    assert_eq!(
        seen.titles,
        ["hil --link sil: single at 10 Hz, eq4, phi 0.57"]
    );
    let json: serde_json::Value = serde_json::from_str(&jump.json().unwrap()).unwrap();
    assert_eq!(json["jump_height_m"].as_f64(), Some(h));
    assert_eq!(json["link"], "sil");
    assert!(
        run.to_string()
            .starts_with("single through sil, f = 10 Hz, model eq4")
    );
}

#[test]
fn hil_refuses_a_stroke_beyond_the_stroke_and_lockstep_flags_on_the_board() {
    let request = HilRequest {
        stroke: Some(NamedStroke {
            name: "wide.csv".into(),
            table: cosine(0.03, 5.0),
        }),
        ..HilRequest::default()
    };
    let e = request.validate().expect_err("30 mm leaves the stroke");
    assert_eq!(e.blame(), Blame::Input);
    assert!(
        e.to_string()
            .starts_with("wide.csv: refused before anything ran"),
        "{e}"
    );
    let board = HilRequest {
        link: LinkArg::F407,
        freq_hz: 10.0,
        rtol: Some(1e-8),
        ..HilRequest::default()
    };
    let e = board.validate().expect_err("--rtol is lockstep only");
    assert!(
        e.to_string()
            .starts_with("--rtol is not available with --link f407"),
        "{e}"
    );
}

#[test]
fn the_boards_record_gains_jump_height_after_its_own_keys() {
    #[derive(serde::Serialize)]
    struct Record {
        link: &'static str,
        simulated_jump_height_m: Option<f64>,
    }
    let text = with_jump_height(
        &Record {
            link: "f407",
            simulated_jump_height_m: Some(0.0123),
        },
        Some(0.0123),
    )
    .unwrap();
    assert_eq!(
        text,
        "{\n  \"link\": \"f407\",\n  \"simulated_jump_height_m\": 0.0123,\n  \"jump_height_m\": 0.0123\n}"
    );
}

#[test]
fn rig_jump_through_sil_completes_and_writes_its_folder() {
    let request = JumpRequest {
        camera_fps: 0,
        ..JumpRequest::new(Target::on(LinkArg::Sil), JumpKind::Single, 10.0)
    };
    request.validate().unwrap();
    let mut seen = Counted::default();
    let outcome = jump::run_watching(&request, &Silent, Some(&mut seen)).expect("runs");
    assert!(outcome.completed && outcome.faults.is_empty());
    assert!(outcome.samples > 1000, "{}", outcome.samples);
    let h = outcome.simulated_jump_height_m.expect("a simulated rig");
    assert!(h > 0.001, "{h}");
    assert!(outcome.tracking_error_max_m < 0.005);
    assert_eq!(seen.titles, ["rig jump on sil"]);
    assert!(seen.steps > 1000);
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("jump");
    let written = outcome
        .write(StagedDir::create(&target).unwrap(), false)
        .unwrap();
    for f in ["acquisition.csv", "params.toml", "summary.json", "jump.svg"] {
        assert!(written.join(f).is_file(), "{f}");
    }
    outcome.check(&written).expect("completed cleanly");
}

#[test]
fn rig_replay_of_a_stroke_in_memory_returns_height_faults_and_tracking() {
    let request = ReplayRequest::stroke(Target::on(LinkArg::Sil), cosine(0.015, 8.0), "memory");
    let outcome = replay::run(&request, &Silent).expect("runs");
    assert!(outcome.completed);
    assert!(
        outcome.fault_names().is_empty(),
        "{:?}",
        outcome.fault_names()
    );
    assert_eq!(outcome.table_rate_hz, 1000.0);
    assert!(
        outcome.tracking_error_max_m < 0.005,
        "{}",
        outcome.tracking_error_max_m
    );
    assert!(outcome.reproduction_error_max_m < 0.005);
    assert!(outcome.simulated_jump_height_m.is_some());
    assert_eq!(outcome.source_log, "memory");
    // Too fast for the drive: refused before anything moved, naming the source.
    let fast = ReplayRequest::stroke(Target::on(LinkArg::Sil), cosine(0.02, 40.0), "fast");
    let e = fast.plan().expect_err("beyond the drive's force");
    assert!(
        e.to_string()
            .starts_with("fast: refused before anything moved"),
        "{e}"
    );
}

#[test]
fn rig_intrude_through_sil_measures_force_against_depth() {
    let request = IntrudeRequest {
        speed_m_s: 0.04,
        hold_s: 0.05,
        ..IntrudeRequest::default()
    };
    let outcome = intrude::run(&request, &Silent).expect("runs");
    assert!(outcome.completed, "{:?}", outcome.faults);
    assert!(outcome.intrusion_points > 10 && outcome.reintrusion_points > 0);
    let f = outcome.force_at_depth_n.expect("a force at depth");
    assert!(f > 0.0, "{f}");
    // Depth strictly increases along the curve.
    assert!(
        outcome
            .intrusion
            .windows(2)
            .all(|w| w[1].depth_m > w[0].depth_m)
    );
}

#[test]
fn status_calibration_reset_and_flash_on_sil() {
    let sil = Target::on(LinkArg::Sil);
    let report = status(&sil, &Silent).unwrap();
    assert_eq!(report.link, "sil");
    assert_eq!(report.status.state, RigState::Idle);
    assert!(
        report
            .to_string()
            .starts_with("controller on sil\n  state              Idle")
    );
    let cal = calibrate(
        &CalibrateRequest {
            target: sil.clone(),
            zero_code: 2100,
            codes_per_newton: 6.5,
            save: None,
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(cal.calibration.zero_code, 2100);
    let bad = CalibrateRequest {
        target: sil.clone(),
        zero_code: 2100,
        codes_per_newton: -1.0,
        save: None,
    };
    assert_eq!(bad.validate().unwrap_err().blame(), Blame::Input);
    assert_eq!(acknowledge_reset(&sil, &Silent).unwrap().link, "sil");
    let flashed = flash(
        &FlashRequest {
            target: sil,
            ..FlashRequest::default()
        },
        &Silent,
    )
    .unwrap();
    assert!(matches!(flashed, Flashed::Nothing(_)));
}

/// Cancelled after its first poll.
struct StopSoon(std::sync::atomic::AtomicU32);

impl Progress for StopSoon {
    fn cancelled(&self) -> bool {
        self.0.fetch_add(1, std::sync::atomic::Ordering::SeqCst) >= 1
    }
}

#[test]
fn a_watch_ends_when_its_caller_cancels_and_says_so() {
    let mut lines = Vec::new();
    let watched = watch(
        &WatchRequest {
            target: Target::on(LinkArg::Sil),
            watch_for_s: Some(60.0),
        },
        &StopSoon(Default::default()),
        &mut |l| {
            lines.push(l.to_string());
            Ok(())
        },
        None,
    )
    .unwrap();
    assert_eq!(watched.polls, 1);
    assert!(watched.watched_s < 30.0);
    assert_eq!(lines.len(), 1);
    assert!(lines[0].contains("state Idle (phase"), "{}", lines[0]);
}
