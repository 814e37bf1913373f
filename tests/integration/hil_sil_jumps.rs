//! Software in the loop: the core's controller in-process against the simulated rig
//! (force-driven plant, DAC-quantized drive, 1 um encoder). Single, stutter and delayed-stutter
//! jumps on hard ground and on sand at phi 0.57 and 0.62.
//!
//! Facts checked:
//! - the motor tracks its trajectory within [`TRACKING_BOUND_M`] until the force command
//!   first saturates, and no fault is latched;
//! - the jump height is within [`HEIGHT_TOLERANCE`] of the kinematic simulation of the same
//!   trajectory (the paper's method: `p(t)` imposed exactly).
//!
//! - after the step of the feedforward at the start, the loop settles within milliseconds
//!   instead of ringing at its crossover.
//!
//! Why 2 mm and 15 %: the position loop is stiff as a 50 Hz loop on the carriage (1.125 kg),
//! held at the sensor frame's tick (0.1 ms); at 10 Hz forcing the one-cycle sine reaches
//! 74 m/s^2 and the spring load changes by tens of newtons within a stance, so the loop lags
//! by about 1 mm (measured 0.77-1.27 mm), about 3 % of the 37.5 mm stroke, mostly as a phase
//! lag. The jump height goes with the square of the take-off velocity, so a few percent of
//! stroke velocity is 5-12 % of height. The delayed stutter adds the spring's ringing through
//! the delay, which the carriage on its finite loop damps differently from the imposed
//! `p(t)` (measured over these nine jumps: -13.7 % to +7.5 %). 15 % bounds that while still
//! catching a controller that does not jump properly (a missed push-off changes the height by
//! a factor of two or more).

use crate::hil_common;

use hil_common::{params, sil};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::{JumpSpec, ModelName, SimOptions, simulate_jump};
use sandjumper_rig::hil::HilSpec;

/// Largest |p_cmd - p| until the force first saturates, m.
const TRACKING_BOUND_M: f64 = 0.002;
/// Largest relative deviation of the jump height from the kinematic simulation.
const HEIGHT_TOLERANCE: f64 = 0.15;

fn check(kind: JumpKind, tau_s: f64, model: ModelName, phi: f64) {
    let p = params(phi);
    let spec = HilSpec::new(kind, 10.0, tau_s, model);
    let o = sil(&p, &spec);
    let what = format!("{kind:?} tau {tau_s} on {model} at phi {phi}");
    assert!(o.faults.is_empty(), "{what}: faults {:?}", o.faults);
    let (err, tick) = o.tracking_error_until_saturation();
    assert!(err > 0.0, "{what}: no tracking measured");
    assert!(
        err <= TRACKING_BOUND_M,
        "{what}: tracking error {err} m at tick {tick:?}"
    );
    let kinematic = simulate_jump(
        &p,
        &JumpSpec {
            kind,
            freq_hz: 10.0,
            tau_s,
            model,
        },
        &SimOptions::default(),
    )
    .expect("kinematic run")
    .summary;
    let h = o.summary.jump_height_m;
    let rel = (h - kinematic.jump_height_m) / kinematic.jump_height_m;
    eprintln!(
        "{what}: HIL {h:.5} m, kinematic {:.5} m ({:+.1} %), tracking {err:.6} m",
        kinematic.jump_height_m,
        100.0 * rel
    );
    assert!(
        rel.abs() <= HEIGHT_TOLERANCE,
        "{what}: HIL height {h} m vs kinematic {} m",
        kinematic.jump_height_m
    );
    // Nothing lost on the way: every tick has its sample, in sequence.
    assert_eq!(o.samples_missing(), 0, "{what}");
    assert_eq!(o.frames_lost, 0, "{what}");
}

#[test]
fn single_jumps_track_and_match_the_kinematic_height() {
    check(JumpKind::Single, 0.0, ModelName::Hard, 0.57);
    check(JumpKind::Single, 0.0, ModelName::Eq4, 0.57);
    check(JumpKind::Single, 0.0, ModelName::Eq4, 0.62);
}

#[test]
fn stutter_jumps_track_and_match_the_kinematic_height() {
    check(JumpKind::Stutter, 0.0, ModelName::Hard, 0.57);
    check(JumpKind::Stutter, 0.0, ModelName::Eq4, 0.57);
    check(JumpKind::Stutter, 0.0, ModelName::Eq4, 0.62);
}

#[test]
fn delayed_stutter_jumps_track_and_match_the_kinematic_height() {
    check(JumpKind::DelayedStutter, 0.75, ModelName::Hard, 0.57);
    check(JumpKind::DelayedStutter, 0.75, ModelName::Eq4, 0.57);
    check(JumpKind::DelayedStutter, 0.75, ModelName::Eq4, 0.62);
}

/// Largest deviation of the force command from its 21-tick (2.1 ms) moving average between 4
/// and 31 ms after the start, N: the loop's own oscillation once the feedforward's step at the
/// start has passed (the trajectory's force changes little over 2 ms).
fn start_ringing_n(o: &sandjumper_rig::hil::HilOutcome) -> f64 {
    let f: Vec<f64> = o
        .trace
        .iter()
        .filter(|r| (0.004..0.031).contains(&r.t_s))
        .map(|r| r.drive_command_n)
        .collect();
    assert!(f.len() > 200, "{} ticks", f.len());
    (10..f.len() - 10)
        .map(|i| (f[i] - f[i - 10..=i + 10].iter().sum::<f64>() / 21.0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn the_loop_settles_after_the_start_step() {
    // The trajectory starts with its full acceleration: the feedforward steps the force by
    // ~80 N. A loop without phase margin rings after it at its crossover (the first rig gains
    // rang at ~470 Hz, +-50 N, for tens of milliseconds); the rig's gains settle within a
    // few milliseconds (measured 1.6-1.9 N of residue, quantization and the trajectory's own curvature).
    for (kind, model) in [
        (JumpKind::Single, ModelName::Hard),
        (JumpKind::Single, ModelName::Eq4),
        (JumpKind::Stutter, ModelName::Eq4),
    ] {
        let o = sil(&params(0.57), &HilSpec::new(kind, 10.0, 0.0, model));
        let ring = start_ringing_n(&o);
        eprintln!("{kind:?} on {model}: {ring:.2} N of ringing 4-31 ms after the start");
        assert!(ring < 5.0, "{kind:?} on {model}: {ring} N");
    }
}
