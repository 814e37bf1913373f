//! `figures dem` as a call: its defaults, bad requests refused before anything is written, a
//! failing stage's error named by its command line with its blame kept.

use std::path::Path;

use sandjumper_figures_dem::{FiguresDemError, FiguresDemRequest, run_with_jump};
use sandjumper_output::{Blame, Blamed, Silent};
use sandjumper_study::StudyError;
use sandjumper_study::jump::{JumpOutcome, JumpRequest};

/// A jump that fails as bad input.
fn failing_jump(_: &JumpRequest, out: &Path) -> Result<JumpOutcome, StudyError> {
    Err(StudyError::input(format!("no jump into {}", out.display())))
}

/// `figures dem` with [`failing_jump`] in place of the jumps.
fn run(request: &FiguresDemRequest) -> Result<(), FiguresDemError> {
    run_with_jump(request, &failing_jump, &Silent).map(drop)
}

/// The beds are prepared for as long as `dem bed` prepares them by default.
#[test]
fn the_beds_preparation_is_dem_beds_by_default() {
    assert_eq!(
        FiguresDemRequest::default().bed_max_time_s,
        sandjumper_dem::bed_run::BedRequest::default().max_time_s
    );
}

#[test]
fn a_foot_a_frequency_or_a_bed_time_out_of_range_is_refused_and_nothing_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("dem");
    for (request, allowed) in [
        (
            FiguresDemRequest {
                foot_width_m: 0.5,
                out: out.clone(),
                ..FiguresDemRequest::default()
            },
            "0.005..=0.2",
        ),
        (
            FiguresDemRequest {
                freq_hz: 100.0,
                out: out.clone(),
                ..FiguresDemRequest::default()
            },
            "0.5..=40",
        ),
        (
            FiguresDemRequest {
                bed_max_time_s: 0.0,
                out: out.clone(),
                ..FiguresDemRequest::default()
            },
            "bed preparation 0 s (allowed: above 0)",
        ),
    ] {
        let e = run(&request).unwrap_err();
        assert_eq!(e.blame(), Blame::Input);
        assert!(e.to_string().contains(allowed), "{e}");
        assert!(!out.exists());
    }
}

#[test]
fn a_failing_stage_is_named_by_its_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("dem");
    let request = FiguresDemRequest {
        out: out.clone(),
        ..FiguresDemRequest::default()
    };
    let e = run(&request).unwrap_err();
    assert_eq!(e.blame(), Blame::Input);
    let m = e.to_string();
    assert!(
        m.starts_with("sandjumper jump --kind single --freq 10 --phi 0.57 --out "),
        "{m}"
    );
    assert!(m.contains(": no jump into "), "{m}");
    assert!(!out.exists());
}
