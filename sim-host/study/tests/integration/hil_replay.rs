//! Logs recorded from hardware-in-the-loop runs (`sandjumper_rig::hil_command::run` on sil:
//! the core's controller against the force-driven plant), written in the log format and
//! replayed in the kinematic simulation (`sandjumper_study::replay`), give the jump height and
//! the final jump height of the original run within 2 % (issue 6). Also: a log of a robot held
//! still replays to no jump. (The command line's `log check` and its refusals of bad logs:
//! `sim-host/cli/tests/integration/replay_hil.rs`.)

#![cfg(feature = "rig")]

use sandjumper_acqlog::CheckRequest;
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::params::{ModelName, Params};
use sandjumper_output::{Blame, Blamed, Silent};
use sandjumper_rig::hil_command::{self, HilRequest};
use sandjumper_study::replay::{self, ReplayRequest};

/// (HIL, replay) pairs of jump height and final jump height, the HIL log written to `dir`,
/// read back as `log check` reads it, and replayed with the HIL run's model.
fn hil_then_replay(dir: &std::path::Path, hil: HilRequest) -> [(f64, f64); 2] {
    let run = hil_command::run(&hil, &Silent).expect("the HIL run");
    let hil_command::HilJump::Loop(l) = &run else {
        panic!("sil is a lockstep link")
    };
    let summary = l.report.summary.clone();
    let path = dir.join("acquisition.csv");
    run.acquisition_log().write_file(&path).unwrap();
    let checked = sandjumper_acqlog::check::run(
        &CheckRequest {
            file: path.clone(),
            allow_gaps: false,
        },
        &Silent,
    )
    .expect("log check accepts the HIL log");
    let request = ReplayRequest {
        log: path,
        model: hil.model,
        ..ReplayRequest::default()
    };
    let replayed = replay::run_log(&request, &checked.log, &Silent).expect("the replay");
    [
        (summary.jump_height_m, replayed.summary.jump_height_m),
        (
            summary.final_jump_height_m,
            replayed.summary.final_jump_height_m,
        ),
    ]
}

/// Three HIL jumps (single 10 Hz on eq4 at phi 0.57, stutter 12 Hz on a hard floor, delayed
/// stutter 12 Hz with 0.3 s on eq4 at phi 0.62) replay to their jump height and final jump
/// height within 2 %. The camera is off (it records, it does not move the plant).
#[test]
fn hil_logs_replay_to_the_original_jump_height_within_two_percent() {
    let tmp = tempfile::tempdir().unwrap();
    for (i, (kind, freq_hz, tau_s, phi, model)) in [
        (JumpKind::Single, 10.0, None, 0.57, ModelName::Eq4),
        (JumpKind::Stutter, 12.0, None, 0.57, ModelName::Hard),
        (
            JumpKind::DelayedStutter,
            12.0,
            Some(0.3),
            0.62,
            ModelName::Eq4,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let hil = HilRequest {
            kind,
            freq_hz,
            tau_s,
            model,
            params: Params::preset(phi).unwrap(),
            camera_fps: 0,
            ..HilRequest::default()
        };
        let dir = tmp.path().join(i.to_string());
        std::fs::create_dir(&dir).unwrap();
        // The final jump height needs the push-off start, which replay takes from the
        // controller's PUSH_OFF flag in the log.
        let pairs = hil_then_replay(&dir, hil);
        for (what, (original, replayed)) in ["jump height", "final jump height"].iter().zip(pairs) {
            assert!(
                original > 5e-3,
                "{kind:?} {freq_hz} Hz: the HIL {what} must be above rest"
            );
            let error = (replayed - original).abs() / original;
            assert!(
                error < 0.02,
                "{kind:?} {freq_hz} Hz {model}: {what} replayed {replayed} m vs HIL {original} m ({:.2} %)",
                100.0 * error
            );
        }
    }
}

/// A log without `phi` metadata is refused (the caller's input) unless the packing fraction is
/// given; given, a robot held still at the bottom of its stroke does not jump.
#[test]
fn a_log_of_a_robot_held_still_replays_to_no_jump() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("still.csv");
    // 20 ms at 10 kHz at the bottom of the stroke, without `phi`.
    let rows: String = (0..200)
        .map(|k| format!("{},-18750\n", k as f64 * 1e-4))
        .collect();
    let header = "# rate_hz: 10000\n# counts_per_m: 1e6\nt_s,encoder_counts\n";
    std::fs::write(&path, format!("{header}{rows}")).unwrap();
    let request = ReplayRequest {
        log: path,
        ..ReplayRequest::default()
    };
    let e = replay::run(&request, &Silent).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(
        e.to_string()
            .contains("give the packing fraction with --phi"),
        "{e}"
    );
    let out = replay::run(
        &ReplayRequest {
            phi: Some(0.6),
            ..request
        },
        &Silent,
    )
    .unwrap();
    // A robot held still does not jump.
    assert!(
        out.summary.jump_height_m < 1e-4,
        "{}",
        out.summary.jump_height_m
    );
}

/// A log with a value that is not a number is refused (the caller's input), naming the line
/// and the column.
#[test]
fn a_bad_log_is_refused_naming_the_line() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("bad.csv");
    let lines = [
        "# rate_hz: 1000",
        "# counts_per_m: 1e6",
        "t_s,encoder_counts",
        "0,0",
        "0.001,x",
    ];
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    let e = replay::run(
        &ReplayRequest {
            log,
            phi: Some(0.57),
            ..ReplayRequest::default()
        },
        &Silent,
    )
    .unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    assert!(
        e.to_string()
            .contains("line 5: column `encoder_counts`: `x` is not a number"),
        "{e}"
    );
}
