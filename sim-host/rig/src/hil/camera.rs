//! The rig's rod camera, simulated: every frame the firmware triggered, rendered by the
//! imaging module's camera model from the plant's rod height over the frame's exposure
//! (the exposure starts at the trigger's rising edge, as on the rig), written as numbered PNGs
//! beside the acquisition log, with the camera model as `camera.toml`.

use std::path::Path;

use rayon::prelude::*;

use super::rig_model::CameraFrame;
use super::run::HilOutcome;
use sandjumper_imaging::render::{CameraModel, write_png};

/// File name of frame `n` (numbered like the log's `camera_frame`).
pub fn frame_file_name(n: u32) -> String {
    format!("frame_{n:06}.png")
}

/// Rod height above rest at plant time `t_s` (since the run began), m: linear between the
/// heights at the periods' starts (`heights[k]` at `k * period_s`), held at the ends.
fn rod_height_at(heights: &[f64], period_s: f64, t_s: f64) -> f64 {
    let (Some(first), Some(last)) = (heights.first(), heights.last()) else {
        return 0.0;
    };
    let k = t_s / period_s;
    if k <= 0.0 {
        return *first;
    }
    let i = k.floor() as usize;
    if i + 1 >= heights.len() {
        return *last;
    }
    let f = k - i as f64;
    heights[i] * (1.0 - f) + heights[i + 1] * f
}

/// The rod heights of a loop run by period (from its trace).
pub fn heights_by_period(outcome: &HilOutcome) -> Vec<f64> {
    let mut out = Vec::with_capacity(outcome.trace.len());
    for row in &outcome.trace {
        let k = row.period as usize;
        if out.len() <= k {
            out.resize(k + 1, row.rod_height_m);
        }
        out[k] = row.rod_height_m;
    }
    out
}

/// Render and write every camera frame of a run into `dir` (created if needed), in parallel,
/// from the rod heights at the start of each period (`heights[k]`, m above rest); returns the
/// number written.
pub fn write_frames(
    frames: &[CameraFrame],
    heights: &[f64],
    camera: &CameraModel,
    period_s: f64,
    dir: &Path,
) -> Result<usize, String> {
    camera.validate()?;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let background = camera.background_image();
    frames
        .par_iter()
        .map(|f| {
            let t0 = f.period as f64 * period_s;
            let frame = camera.render_on(
                &background,
                t0,
                |t| camera.centre_px(rod_height_at(heights, period_s, t)),
                u64::from(f.frame),
            );
            write_png(&frame, &dir.join(frame_file_name(f.frame)))
        })
        .collect::<Result<Vec<()>, String>>()?;
    let toml =
        toml::to_string(camera).map_err(|e| format!("cannot encode the camera model: {e}"))?;
    std::fs::write(
        dir.join("camera.toml"),
        format!(
            "# The simulated rod camera these frames were rendered with (exposure starts at the\n\
             # trigger); frame_NNNNNN.png is camera_frame NNNNNN of the acquisition log.\n{toml}"
        ),
    )
    .map_err(|e| format!("cannot write camera.toml: {e}"))?;
    Ok(frames.len())
}

/// The camera model of a TOML file (`hil --camera`; every key optional), or the defaults
/// without one. A file that cannot be read or parsed is bad input naming `--camera`.
pub fn read_camera(path: Option<&Path>) -> Result<CameraModel, crate::error::RigError> {
    path.map_or(Ok(CameraModel::default()), |p| {
        CameraModel::from_toml_file(p)
            .map_err(|e| crate::error::RigError::input(format!("--camera {e}")))
    })
}
