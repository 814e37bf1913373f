//! A two-point campaign through the simulated bed and the controller in this process (sil),
//! called from Rust: the repository's small campaign cut to one kind, one frequency and two
//! packing fractions, without the camera.
//!
//! Run it from the repository's root:
//!
//! ```text
//! cargo run -p sandjumper-campaign --example campaign_sil
//! ```

use sandjumper_campaign::session::{self, Hooks, RunRequest};
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let small = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/campaign-small.toml"
    );
    let text = std::fs::read_to_string(small)?
        .replace(r#"kinds = ["single", "delayed"]"#, r#"kinds = ["single"]"#)
        .replace("frequencies_hz = [10.0, 14.0]", "frequencies_hz = [10.0]")
        .replace("fps = 200", "fps = 0")
        .replace("track = true", "track = false");
    let dir = std::env::temp_dir().join(format!("sandjumper-campaign-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let file = dir.join("campaign.toml");
    std::fs::write(&file, text)?;
    let request = RunRequest {
        file,
        link: Some("sil".into()),
        out: dir.join("out"),
        ..RunRequest::default()
    };
    // Each point's line as it is done, then how the session ended.
    let hooks = Hooks {
        live: None,
        on_point: Some(Box::new(|_row, line| println!("{line}"))),
    };
    let outcome = session::run(&request, hooks, &Silent)?;
    println!("{outcome}");
    println!("results: {}", dir.join("out/results.csv").display());
    Ok(())
}
