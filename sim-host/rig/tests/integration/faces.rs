//! What the command line's faces take from the library: value parsers, early refusals, the
//! output folder, and what a run prints, writes and shows on a live view (sil, cheap).

use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::Silent;
use sandjumper_rig::hil::open::LinkArg;
use sandjumper_rig::hil_command::{
    self as hil, HilRequest, parse_bench_runs, parse_camera_fps, parse_encoder_noise,
    parse_gain_lowering, parse_rtol, refuse_early, run_dir, scratch_dir,
};
use sandjumper_rig::tool::jump::JumpRequest;
use sandjumper_rig::tool::output::{ProgramOutcome, ProgramRequest};
use sandjumper_rig::tool::replay::{Clip, parse_clip, parse_factor};
use sandjumper_rig::tool::target::{Target, parse_board_pace};

#[test]
fn value_parsers_accept_their_range_and_say_what_is_allowed() {
    assert_eq!(parse_rtol("1e-6"), Ok(1e-6));
    assert_eq!(
        parse_rtol("0.1").unwrap_err(),
        "plant rtol 0.1 out of range (allowed: 1e-12..=1e-3)"
    );
    assert_eq!(parse_encoder_noise("2"), Ok(2.0));
    assert!(parse_encoder_noise("-1").unwrap_err().contains("0..=1000"));
    assert_eq!(parse_camera_fps("500"), Ok(500));
    assert!(parse_camera_fps("5001").unwrap_err().contains("0..=5000"));
    assert_eq!(parse_bench_runs("3"), Ok(3));
    assert!(parse_bench_runs("0").unwrap_err().contains("1..=1000"));
    assert_eq!(parse_gain_lowering("0.05"), Ok(0.05_f32));
    assert!(parse_gain_lowering("0").is_err());
    assert_eq!(parse_factor("scale")("2"), Ok(2.0));
    assert_eq!(
        parse_factor("scale")("0").unwrap_err(),
        "scale `0` not allowed (allowed: 0 < X <= 10)"
    );
    assert_eq!(
        parse_clip("0.1:0.3"),
        Ok(Clip {
            start_s: 0.1,
            end_s: 0.3
        })
    );
    assert!(parse_clip("0.3:0.1").is_err());
    assert_eq!(parse_board_pace("0.5"), Ok(0.5));
    assert!(parse_board_pace("2").is_err());
}

#[test]
fn early_refusals_and_the_scratch_folder_of_the_virtual_board() {
    let sil = HilRequest::default();
    let e = refuse_early(&sil, true, Some(2)).unwrap_err().to_string();
    assert!(e.starts_with("--live shows one jump"), "{e}");
    assert!(refuse_early(&sil, false, Some(2)).is_ok());
    let board = HilRequest {
        link: LinkArg::F407,
        ..HilRequest::default()
    };
    let e = refuse_early(&board, false, Some(2))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("--bench is not available with --link f407"),
        "{e}"
    );
    let noisy = HilRequest {
        encoder_noise_counts: 1.0,
        ..board.clone()
    };
    let e = refuse_early(&noisy, false, None).unwrap_err().to_string();
    assert!(e.starts_with("--encoder-noise is not available"), "{e}");
    // Without --out: nothing on a lockstep link, a scratch folder on the board.
    assert!(scratch_dir(&sil, None).unwrap().is_none());
    assert!(run_dir(None, None).is_none());
    let scratch = scratch_dir(&board, None)
        .unwrap()
        .expect("a scratch folder");
    let dir = run_dir(None, Some(&scratch)).unwrap();
    assert_eq!(dir, scratch.path().join("jump"));
    let out = std::path::Path::new("out");
    assert!(scratch_dir(&board, Some(out)).unwrap().is_none());
    assert_eq!(run_dir(Some(out), Some(&scratch)).unwrap(), out);
    assert!(!board.keeps_own_time() && !board.shows_errors_live() && board.uses_camera());
}

#[test]
fn a_hil_jump_prints_writes_and_ends_its_live_view() {
    let request = HilRequest {
        freq_hz: 10.0,
        camera_fps: 0,
        ..HilRequest::default()
    };
    let jump = hil::run(&request, &Silent).expect("runs");
    let text = jump.printed(false).unwrap();
    assert!(text.starts_with("single through sil, f = 10 Hz"), "{text}");
    let json: serde_json::Value = serde_json::from_str(&jump.printed(true).unwrap()).unwrap();
    let h = json["jump_height_m"].as_f64().unwrap();
    let (t_end, line, ok) = jump.live_end(None).expect("a lockstep run's view ends");
    assert!(t_end > 0.0 && ok);
    assert_eq!(line, format!("jump height {:.2} mm, 0 faults", 1e3 * h));
    assert!(jump.live_end(Some("no room")).is_none());
    assert!(!jump.acquisition_log().rows.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let staged = sandjumper_output::StagedDir::create(&dir.path().join("hil")).unwrap();
    let written = ProgramOutcome::write(&jump, staged, false).unwrap();
    assert!(written.join("summary.json").is_file());
    ProgramOutcome::check(&jump, &written).unwrap();
}

#[test]
fn a_rig_program_is_checked_then_run_and_prints_its_summary() {
    let request = JumpRequest {
        camera_fps: 0,
        ..JumpRequest::new(Target::on(LinkArg::Sil), JumpKind::Single, 10.0)
    };
    request.check().expect("a valid jump");
    let outcome = request.run_checked((), &Silent, None).expect("runs");
    assert_eq!(outcome.printed(false).unwrap(), outcome.to_string());
    assert!(outcome.printed(true).unwrap().ends_with("}\n"));
    let bad = JumpRequest::new(Target::on(LinkArg::Sil), JumpKind::Single, 1000.0);
    assert!(bad.check().is_err());
}
