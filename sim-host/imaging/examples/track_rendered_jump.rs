//! Track a jump from Rust: the rod camera's frames of a 30 mm hop rendered into a folder, then
//! `sandjumper_imaging::run` measures the jump height from them the paper's way.
//!
//! Run it with `cargo run --release -p sandjumper-imaging --example track_rendered_jump`.

use sandjumper_imaging::render::{CameraModel, write_png};
use sandjumper_imaging::run::{self, TrackRequest};
use sandjumper_output::Silent;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (fps, apex_t, apex_h) = (500.0, 0.12, 0.03);
    let height = |t: f64| {
        let h = apex_h - 0.5 * 9.81 * (t - apex_t) * (t - apex_t);
        if t < 0.04 { 0.0 } else { f64::max(h, 0.0) }
    };
    let cam = CameraModel::default();
    let dir = std::env::temp_dir().join(format!("sandjumper-track-example-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let background = cam.background_image();
    for k in 0..100u32 {
        let t0 = f64::from(k) / fps;
        let frame = cam.render_on(&background, t0, |t| cam.centre_px(height(t)), k.into());
        write_png(&frame, &dir.join(format!("frame_{k:06}.png")))?;
    }

    let request = TrackRequest {
        frames: dir.display().to_string(),
        m_per_px: cam.m_per_px,
        fps: Some(fps),
        ..TrackRequest::default()
    };
    let outcome = run::run(&request, &Silent)?;
    print!("{outcome}");
    println!("true jump height {:.3} mm", 1e3 * apex_h);
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
