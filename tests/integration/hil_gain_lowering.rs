//! Gain-lowering damping through SIL (docs/model.md section 2: "during a long delay the firmware
//! lowers its position gain to damp the spring's ringing"). With a 0.75 s delay, the spring's
//! ringing at the end of the delay is at least 5x smaller with gain lowering than without, and
//! the ramp back to full gains is bumpless.

use crate::hil_common;

use hil_common::{delayed, params, sil, spring_ringing_n};
use sandjumper_core::sample::flags;
use sandjumper_model::ModelName;
use sandjumper_rig::hil::HilSpec;

/// The delay ends at T/2 + tau = 0.8 s; the gains ramp back over its last 50 ms. The ringing
/// is measured over the 100 ms before the ramp back starts (almost one 8 Hz period).
const WINDOW_S: (f64, f64) = (0.65, 0.75);

fn lowered() -> HilSpec {
    let mut s = delayed(0.75, ModelName::Hard);
    s.gain_lowering = Some(HilSpec::gain_lowering_factor(0.05));
    s
}

#[test]
fn gain_lowering_damps_the_spring_ringing_at_least_fivefold() {
    for (model, phi) in [
        (ModelName::Hard, 0.57),
        (ModelName::Eq4, 0.57),
        (ModelName::Eq4, 0.62),
    ] {
        let p = params(phi);
        let full = sil(&p, &delayed(0.75, model));
        let mut spec = lowered();
        spec.model = model;
        let low = sil(&p, &spec);
        assert!(
            full.faults.is_empty() && low.faults.is_empty(),
            "{:?} {:?}",
            full.faults,
            low.faults
        );
        let (a_full, a_low) = (
            spring_ringing_n(&full, WINDOW_S.0, WINDOW_S.1),
            spring_ringing_n(&low, WINDOW_S.0, WINDOW_S.1),
        );
        eprintln!(
            "{model} phi {phi}: ringing {a_full:.3} N with full gains, {a_low:.3} N lowered ({:.1}x)",
            a_full / a_low
        );
        // A real ringing to damp: the preliminary hop's landing excites the spring.
        assert!(
            a_full > 1.0,
            "{model}: only {a_full} N of ringing without gain lowering"
        );
        assert!(
            a_full >= 5.0 * a_low,
            "{model} phi {phi}: {a_full} N vs {a_low} N"
        );
        // The delay really ran with lowered gains (the controller flags it).
        assert!(
            low.samples
                .iter()
                .any(|s| s.flags & flags::GAINS_LOWERED != 0)
        );
        assert!(
            !full
                .samples
                .iter()
                .any(|s| s.flags & flags::GAINS_LOWERED != 0)
        );
    }
}

#[test]
fn the_ramp_back_to_full_gains_is_bumpless() {
    // Without the integrator the lowered position gain holds the carriage's weight with a
    // ~2 mm error: switching the full gain back in one tick would step the force by ~200 N.
    let mut spec = lowered();
    spec.gains.ki_n_per_m_s = 0.0;
    let o = sil(&params(0.57), &spec);
    assert!(o.faults.is_empty(), "{:?}", o.faults);
    // Force command per tick during the ramp back (the last 50 ms of the delay) vs the hold
    // before it: a gain step would show as a jump of kp * error (kp = 111 kN/m: 1 N per
    // 9 um of error) in one tick.
    let force: Vec<(f64, f64)> = o
        .samples
        .iter()
        .filter(|s| s.flags & flags::DELAY != 0)
        .map(|s| {
            (
                (s.tick as f64 - o.start_period as f64) * 1e-4,
                f64::from(s.force_n),
            )
        })
        .collect();
    assert!(force.len() > 7000, "{} delay samples", force.len());
    let steps = |t0: f64, t1: f64| {
        force
            .windows(2)
            .filter(|w| w[0].0 >= t0 && w[1].0 <= t1)
            .map(|w| (w[1].1 - w[0].1).abs())
            .fold(0.0, f64::max)
    };
    let hold = steps(0.60, 0.75);
    let ramp = steps(0.75, 0.80);
    // What switching the gains back in one tick would do: the position error when the ramp
    // starts times the position gain that returns.
    let at_ramp = o
        .samples
        .iter()
        .find(|s| s.tick as f64 - o.start_period as f64 >= 7500.0)
        .expect("sample at the ramp start");
    let error_m = f64::from(at_ramp.commanded_position_m) - at_ramp.encoder_count as f64 * 1e-6;
    let returning = f64::from(spec.gains.kp_n_per_m) * (1.0 - 0.05);
    let instant_step = returning * error_m.abs();
    eprintln!(
        "largest per-tick force change: {hold:.3} N holding, {ramp:.3} N ramping back; \
         an instant switch would step {instant_step:.1} N (error {:.3} mm)",
        1e3 * error_m
    );
    // 1 % of F_peak per tick at most, and a small fraction of the step a switch would give.
    assert!(
        ramp <= 3.0,
        "ramp back steps the force by {ramp} N in one tick"
    );
    assert!(
        instant_step > 50.0,
        "the test needs a real error to switch on: {instant_step} N"
    );
    assert!(
        ramp <= 0.05 * instant_step,
        "ramp {ramp} N per tick vs an instant switch of {instant_step} N"
    );
}
