//! The rod camera's file reader (`CameraModel::from_toml`: `hil --camera FILE`, the format
//! of the `frames/camera.toml` that `hil` writes) on any text: it never panics; what it
//! accepts is valid (`validate`) with a finite ball radius in pixels.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sandjumper_imaging::render::CameraModel;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(camera) = CameraModel::from_toml(text) {
        assert!(
            camera.validate().is_ok(),
            "accepted but invalid: {camera:?}"
        );
        assert!(camera.ball_radius_px().is_finite(), "{camera:?}");
    }
});
