//! Camera triggers through SIL (docs/model.md section 6): at 200 fps exactly one frame per 5 ms
//! (50 ticks at 10 kHz), at 500 fps one per 2 ms (20 ticks), from the arm on (frames of the
//! rod at rest come first); every frame the rig model's camera
//! took corresponds to the controller's sample record of the same tick, in order.

use crate::hil_common;

use hil_common::{params, sil};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::ModelName;
use sandjumper_rig::hil::HilSpec;

fn check(fps: u32, ticks_per_frame: u32) {
    let mut spec = HilSpec::new(JumpKind::DelayedStutter, 10.0, 0.3, ModelName::Eq4);
    spec.camera_fps = fps;
    let o = sil(&params(0.6), &spec);
    assert!(o.faults.is_empty(), "{:?}", o.faults);
    // The controller's records: frame k starts on run tick k * ticks_per_frame.
    let framed: Vec<(u32, u32)> = o
        .samples
        .iter()
        .filter_map(|s| s.camera_frame.map(|f| (s.tick, f)))
        .collect();
    let first_tick = framed[0].0;
    for (k, (tick, frame)) in framed.iter().enumerate() {
        assert_eq!(*frame as usize, k, "frames numbered in order");
        assert_eq!(
            tick - first_tick,
            k as u32 * ticks_per_frame,
            "frame {k} at {fps} fps"
        );
    }
    // The camera runs from Arm: its first frame is on the armed controller's first tick, and
    // the frames before the trajectory's start show the rod at rest (the settling time).
    let armed_tick = o
        .samples
        .iter()
        .find(|s| s.flags & sandjumper_core::sample::flags::ARMED != 0)
        .map(|s| s.tick)
        .unwrap();
    assert_eq!(first_tick, armed_tick);
    let at_rest = framed
        .iter()
        .filter(|(tick, _)| u64::from(*tick) < o.start_period)
        .count() as u64;
    assert_eq!(
        at_rest,
        (o.start_period - u64::from(armed_tick)).div_ceil(u64::from(ticks_per_frame))
    );
    assert!(at_rest >= 20, "{at_rest} frames at rest");
    // The camera (rising edges of the trigger line, seen by the rig model) took the same
    // frames on the same ticks: period index = controller tick (one frame per period).
    assert_eq!(
        o.camera_frames.len(),
        framed.len(),
        "camera frames vs sample records"
    );
    for (cam, (tick, frame)) in o.camera_frames.iter().zip(&framed) {
        assert_eq!(cam.frame, *frame);
        assert_eq!(cam.period, u64::from(*tick));
    }
    // Frames cover the whole run from the arm on.
    let run_ticks = o.ticks - u64::from(armed_tick);
    assert_eq!(
        framed.len() as u64,
        run_ticks.div_ceil(u64::from(ticks_per_frame))
    );
}

#[test]
fn rod_tracking_camera_at_200_fps_takes_one_frame_every_5_ms() {
    check(200, 50);
}

#[test]
fn piv_camera_at_500_fps_takes_one_frame_every_2_ms() {
    check(500, 20);
}
