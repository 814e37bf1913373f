//! A small stroke search: the paper's strokes swept coarsely, a few hundred CMA-ES
//! evaluations on the kinematic model (no link), the best stroke printed. Runs in seconds:
//!
//! ```text
//! cargo run --release -p sandjumper-optimize --example stroke_search
//! ```
//!
//! The folder (stroke.csv for `sandjumper jump --stroke`, summary.json, the figure) goes to
//! the system's temporary directory. For the command's full search, keep
//! `OptimizeRequest::default()`'s budget and links.

use sandjumper_optimize::outcome::chain_text;
use sandjumper_optimize::{OptimizeRequest, run};
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let request = OptimizeRequest {
        evaluations: 240,
        population: 8,
        random_starts: 1,
        sweep_freq_step_hz: 4.0,
        sweep_tau_step_s: 0.25,
        elites: 2,
        paper_candidates: 1,
        verify: Vec::new(),
        out: std::env::temp_dir().join("sandjumper-stroke-search"),
        ..OptimizeRequest::default()
    };
    let outcome = run(&request, &Silent)?;
    println!(
        "best {}: {:.2} mm, the paper's best {:.2} mm (ratio {:.3}, {})",
        outcome.objective,
        1e3 * outcome.best_height_m,
        1e3 * outcome.best_paper_stroke_height_m,
        outcome.height_ratio,
        outcome.height_basis
    );
    println!("  {}", outcome.answer.label);
    if let Some(chain) = &outcome.answer.chain {
        println!("  {}", chain_text(chain));
    }
    println!("  wrote {}", outcome.dir.display());
    Ok(())
}
