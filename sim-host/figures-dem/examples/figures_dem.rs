//! Supplementary I and Extended Data Fig. 2 from Rust, as `sandjumper figures dem --out OUT`
//! makes them: three jumps, their push-offs driven into DEM beds, PIV on the stutter's
//! frames, the comparison written beside the runs. Without the full model's row (as
//! `--no-full-model`), which takes about 7 of the 10 minutes at full scale.
//!
//! Run it with `cargo run --release -p sandjumper-figures-dem --example figures_dem -- OUT`.

use sandjumper_figures_dem::{FiguresDemRequest, run};
use sandjumper_output::Progress;

/// Notes on stderr, as the command line prints them.
struct Notes;

impl Progress for Notes {
    fn note(&self, line: &str) {
        eprintln!("{line}");
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(out) = std::env::args_os().nth(1) else {
        return Err("usage: figures_dem OUT (the output folder to write)".into());
    };
    let request = FiguresDemRequest {
        out: out.into(),
        full_model: false,
        ..FiguresDemRequest::default()
    };
    let outcome = run(&request, &Notes)?;
    println!("{outcome}");
    Ok(())
}
