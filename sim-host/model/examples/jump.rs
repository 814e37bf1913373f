//! The paper's delayed stutter jump (f = 10 Hz, tau = 0.1 s, the eq4 ground model, phi =
//! 0.57) through the model's API, printing its height: what `sandjumper jump --kind delayed
//! --freq 10 --tau 0.1 --model eq4 --phi 0.57` simulates.
//!
//! Run it with `cargo run --example jump -p sandjumper-model`.

use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::jump::{JumpSpec, simulate_jump};
use sandjumper_model::options::SimOptions;
use sandjumper_model::params::ModelName;
use sandjumper_model::resolve::{ParamsFile, resolve_params};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The phi = 0.57 preset; overrides (as `--params FILE.toml` gives them) go on top.
    let overrides = ParamsFile {
        path: "<example>".into(),
        text: "[drive]\n".into(),
    };
    let params = resolve_params(0.57, Some(&overrides))?;
    let spec = JumpSpec {
        kind: JumpKind::DelayedStutter,
        freq_hz: 10.0,
        tau_s: 0.1,
        model: ModelName::Eq4,
    };
    let outcome = simulate_jump(&params, &spec, &SimOptions::default())?;
    let s = &outcome.summary;
    println!(
        "delayed stutter, f = 10 Hz, tau = 0.1 s, eq4, phi = 0.57: jump height {:.2} mm \
         (apex at t = {:.4} s), max depth {:.2} mm",
        1e3 * s.jump_height_m,
        s.apex_time_s,
        1e3 * s.max_depth_m
    );
    for w in &outcome.warnings {
        println!("warning: {w}");
    }
    Ok(())
}
