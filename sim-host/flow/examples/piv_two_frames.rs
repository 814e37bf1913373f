//! PIV on two frames from Rust: two synthetic grain frames with a known shift, analysed by
//! `sandjumper_flow::run`, and the displacement it recovers.
//!
//! Run it with `cargo run --release -p sandjumper-flow --example piv_two_frames`.

use sandjumper_flow::piv::PivConfig;
use sandjumper_flow::piv_synthetic::{self, SyntheticField, SyntheticRequest};
use sandjumper_flow::run::{self, PivRequest};
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // Two 256 x 256 frames of grains, the second moved by (2.3, -1.2) px.
    let shift = (2.3, -1.2);
    let synthetic = piv_synthetic::run(
        &SyntheticRequest {
            field: SyntheticField::Shift,
            size_px: (256, 256),
            shift_px: Some(shift),
            ..SyntheticRequest::default()
        },
        &Silent,
    )?;
    let dir = std::env::temp_dir().join(format!("sandjumper-piv-example-{}", std::process::id()));
    synthetic.write(&dir)?;

    // The PIV run: two passes (32 then 16 px windows), everything else as `sandjumper piv`.
    let request = PivRequest {
        frames: dir.display().to_string(),
        piv: PivConfig {
            windows: vec![32, 16],
            ..PivConfig::default()
        },
        ..PivRequest::default()
    };
    let outcome = run::run(&request, &Silent)?;
    let field = &outcome.run.results[0].field;
    let mean = |v: &[f64]| {
        let ok: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        ok.iter().sum::<f64>() / ok.len() as f64
    };
    println!(
        "{} vectors on a {}x{} grid; mean displacement ({:.3}, {:.3}) px, true ({}, {}) px",
        outcome.vectors,
        field.nx,
        field.ny,
        mean(&field.u),
        mean(&field.v),
        shift.0,
        shift.1
    );
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
