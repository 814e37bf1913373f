//! A small sweep through the library, as `sandjumper sweep --kind single,stutter --freq
//! 8:14:2 --out sweep` runs it: jump height against forcing frequency for two jump kinds,
//! printed, and the sweep's folder (sweep.csv, sweep.toml, params.toml, figures) written.
//!
//! Run it with `cargo run --example sweep -p sandjumper-study -- [OUT_DIR]`.

use sandjumper_core::trajectory::JumpKind;
use sandjumper_output::Silent;
use sandjumper_study::sweep::{self, SweepRequest, SweepSpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let request = SweepRequest {
        spec: SweepSpec {
            kinds: vec![JumpKind::Single, JumpKind::Stutter],
            freqs_hz: vec![8.0, 10.0, 12.0, 14.0],
            ..SweepSpec::default()
        },
        ..SweepRequest::default()
    };
    let swept = sweep::run(&request, &Silent)?;
    for row in &swept.outcome.rows {
        println!(
            "{:8} f = {:4} Hz: jump height {:6.2} mm",
            row.kind,
            row.freq_hz,
            1e3 * row.jump_height_m
        );
    }
    for line in swept.warnings() {
        println!("{line}");
    }
    if let Some(out) = std::env::args().nth(1) {
        let written = swept.write(out.as_ref())?;
        println!("wrote {}", written.dir.display());
    }
    Ok(())
}
