//! `hil` and `jump` report the same events: every event-time field of the summary (first and
//! final lift-off, apex, final apex) of a jump through the loop (sil, and pil when QEMU is
//! there) agrees with the kinematic jump of the same trajectory within the loop's lag.
//!
//! The expected lag, stated from the physics rather than fitted:
//! - a lift-off happens when the stroke unloads the foot; the position loop follows the
//!   stroke with a phase lag of about a millisecond (see `hil_sil_jumps.rs`), so lift-off
//!   times agree within [`LIFTOFF_LAG_S`];
//! - an apex comes a flight time after its lift-off; a jump through the loop is a few percent
//!   lower than the kinematic one (the loop's lag costs take-off speed), and a lower jump
//!   peaks earlier by the difference of the rise times `sqrt(2 h / g)`. Apex times agree
//!   within that difference plus [`LIFTOFF_LAG_S`].
//!
//! The stutter's final height is measured from the push-off half's start in both (the tail
//! of the preliminary hop is not the push-off's apex): that is what this test caught in `hil`
//! (its final lift-off was the first lift-off, its stutter's final apex the push-off start).

use crate::hil_common;

use hil_common::{params, sil};
use sandjumper_core::trajectory::JumpKind;
use sandjumper_model::{JumpSpec, JumpSummary, ModelName, SimOptions, simulate_jump};
use sandjumper_rig::hil::pil::{self, PilConfig};
use sandjumper_rig::hil::{HilSpec, RigModelConfig, emulated_firmware, run_jump};

/// Largest difference of lift-off times between the loop and the imposed stroke, s.
const LIFTOFF_LAG_S: f64 = 0.001;
const G: f64 = 9.81;

fn kinematic(spec: &HilSpec, phi: f64) -> JumpSummary {
    simulate_jump(
        &params(phi),
        &JumpSpec {
            kind: spec.kind,
            freq_hz: spec.freq_hz,
            tau_s: spec.tau_s,
            model: spec.model,
        },
        &SimOptions::default(),
    )
    .expect("kinematic jump")
    .summary
}

/// Rise time from lift-off to an apex `h` above rest, s (0 for a non-positive height).
fn rise_s(h: f64) -> f64 {
    (2.0 * h.max(0.0) / G).sqrt()
}

fn check(link: &str, what: &str, loop_run: &JumpSummary, jump: &JumpSummary) {
    let (lo_l, lo_j) = (loop_run.liftoff_time_s, jump.liftoff_time_s);
    let (flo_l, flo_j) = (loop_run.final_liftoff_time_s, jump.final_liftoff_time_s);
    let ctx = format!("{link} {what}: loop {loop_run:?}\njump {jump:?}");
    let (lo_l, lo_j) = (
        lo_l.unwrap_or_else(|| panic!("{ctx}")),
        lo_j.unwrap_or_else(|| panic!("{ctx}")),
    );
    assert!((lo_l - lo_j).abs() <= LIFTOFF_LAG_S, "lift-off: {ctx}");
    let (flo_l, flo_j) = (
        flo_l.unwrap_or_else(|| panic!("{ctx}")),
        flo_j.unwrap_or_else(|| panic!("{ctx}")),
    );
    assert!(
        (flo_l - flo_j).abs() <= LIFTOFF_LAG_S,
        "final lift-off: {ctx}"
    );
    let apex_tol =
        (rise_s(loop_run.jump_height_m) - rise_s(jump.jump_height_m)).abs() + LIFTOFF_LAG_S;
    assert!(
        (loop_run.apex_time_s - jump.apex_time_s).abs() <= apex_tol,
        "apex (tolerance {apex_tol} s): {ctx}"
    );
    let final_tol = (rise_s(loop_run.final_jump_height_m) - rise_s(jump.final_jump_height_m)).abs()
        + LIFTOFF_LAG_S;
    assert!(
        (loop_run.final_apex_time_s - jump.final_apex_time_s).abs() <= final_tol,
        "final apex (tolerance {final_tol} s): {ctx}"
    );
}

fn specs() -> Vec<(HilSpec, f64)> {
    vec![
        (
            HilSpec::new(JumpKind::Single, 10.0, 0.0, ModelName::Eq4),
            0.57,
        ),
        (
            HilSpec::new(JumpKind::Stutter, 10.0, 0.0, ModelName::Eq4),
            0.57,
        ),
        (
            HilSpec::new(JumpKind::DelayedStutter, 10.0, 0.3, ModelName::Eq4),
            0.57,
        ),
        (
            HilSpec::new(JumpKind::DelayedStutter, 10.0, 0.3, ModelName::Eq4),
            0.62,
        ),
        (
            HilSpec::new(JumpKind::Single, 12.0, 0.0, ModelName::Hard),
            0.57,
        ),
    ]
}

#[test]
fn sil_and_jump_agree_on_every_event_time() {
    for (spec, phi) in specs() {
        let o = sil(&params(phi), &spec);
        let what = format!(
            "{:?} {} Hz tau {} at phi {phi}",
            spec.kind, spec.freq_hz, spec.tau_s
        );
        check("sil", &what, &o.summary, &kinematic(&spec, phi));
    }
}

#[test]
fn pil_and_jump_agree_on_every_event_time() {
    if emulated_firmware::test_prerequisites("the PIL event-time test")
        .map_err(|skip| eprintln!("{skip}"))
        .is_err()
    {
        return;
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let elf = emulated_firmware::build_once(root).unwrap_or_else(|e| panic!("{e}"));
    // The delayed stutter: its final lift-off is the one `hil` got wrong.
    let (spec, phi) = specs().swap_remove(2);
    let mut link = pil::start(&PilConfig::new(elf)).expect("QEMU starts and answers");
    let o = run_jump(&params(phi), &spec, RigModelConfig::default(), &mut link).expect("PIL run");
    check("pil", "delayed stutter", &o.summary, &kinematic(&spec, phi));
}
