//! Processor in the loop: the real firmware, built for QEMU mps2-an386, against the simulated
//! rig over the semihosting FIFOs (QEMU `-icount`: deterministic). The same jump through PIL
//! and SIL gives the same height (within 0.5 %) and the same fault behaviour; the firmware
//! exits cleanly; a hung firmware fails the run within seconds.
//!
//! Needs `qemu-system-arm` and the `thumbv7em-none-eabihf` target: skipped with a message when
//! QEMU is missing, unless `CI` is set (then it fails).

use crate::hil_common;

use std::path::Path;
use std::time::{Duration, Instant};

use hil_common::{delayed, params, sil};
use sandjumper_core::FaultCode;
use sandjumper_model::ModelName;
use sandjumper_rig::hil::emulated_firmware;
use sandjumper_rig::hil::pil::{self, PilConfig};
use sandjumper_rig::hil::{
    HilOutcome, HilSpec, InjectedFault, Injection, LinkError, RigModelConfig, run_jump,
};

fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// QEMU and the firmware toolchain are there; if not, skip with a message (fail in CI).
fn qemu_available() -> bool {
    emulated_firmware::test_prerequisites("the processor-in-the-loop tests")
        .map_err(|skip| eprintln!("{skip}"))
        .is_ok()
}

/// The emulated-board firmware, built once per test run.
fn firmware_elf() -> &'static Path {
    emulated_firmware::build_once(workspace()).unwrap_or_else(|e| panic!("{e}"))
}

/// Zero force from the first faulted answer on (as in SIL), and the firmware's exit status
/// carries the fault: 16 + code.
fn assert_zero_force_and_exit_code(p: &HilOutcome, code: FaultCode, context: &str) {
    let first = p
        .trace
        .iter()
        .position(|r| r.faulted)
        .expect("faulted answer");
    assert!(
        p.trace[first..].iter().all(|r| r.drive_command_n == 0.0),
        "{context}: force after the fault"
    );
    assert_eq!(
        p.link.exit_code,
        Some(16 + i32::from(code.code())),
        "{context}"
    );
}

fn pil(spec: &HilSpec) -> HilOutcome {
    let mut link = pil::start(&PilConfig::new(firmware_elf())).expect("QEMU starts and answers");
    run_jump(&params(0.57), spec, RigModelConfig::default(), &mut link).expect("PIL run")
}

#[test]
fn delayed_stutter_through_pil_matches_sil_and_the_firmware_exits_cleanly() {
    if !qemu_available() {
        return;
    }
    let spec = delayed(0.75, ModelName::Eq4);
    let p = pil(&spec);
    let s = sil(&params(0.57), &spec);
    let (hp, hs) = (p.summary.jump_height_m, s.summary.jump_height_m);
    eprintln!(
        "PIL {hp:.6} m, SIL {hs:.6} m; PIL {:.2}x real time, max {:?} instructions per tick",
        p.realtime_factor, p.link.max_tick_instructions
    );
    assert!(((hp - hs) / hs).abs() <= 0.005, "PIL {hp} m vs SIL {hs} m");
    assert!(p.faults.is_empty(), "{:?}", p.faults);
    assert_eq!(p.link.exit_code, Some(0), "the firmware exits cleanly");
    // Every tick's sample arrived, in order, and the loop ran as long as SIL's.
    assert_eq!(p.samples_missing(), 0);
    assert_eq!(p.samples.len(), s.samples.len());
    assert_eq!(p.ticks, s.ticks);
    assert_eq!(p.frames_lost, 0);
    // The control tick's cost was measured on the emulated Cortex-M4.
    let max = p.link.max_tick_instructions.expect("instruction count");
    assert!(max > 50, "{max} instructions");
}

#[test]
fn faults_through_pil_match_sil() {
    if !qemu_available() {
        return;
    }
    for (fault, code) in [
        (
            InjectedFault::EncoderJump { counts: 5_000 },
            FaultCode::EncoderFault,
        ),
        (InjectedFault::Overrun, FaultCode::DeadlineOverrun),
        (
            InjectedFault::CorruptFrames { count: 12 },
            FaultCode::LinkCorrupted,
        ),
        (InjectedFault::EncoderFrozen, FaultCode::TrackingError),
        // The bed apparatus's inputs ride in the lockstep frames.
        (InjectedFault::EmergencyStop, FaultCode::EmergencyStop),
    ] {
        let mut spec = delayed(0.75, ModelName::Eq4);
        spec.injections.push(Injection { at_s: 0.03, fault });
        let p = pil(&spec);
        let s = sil(&params(0.57), &spec);
        let (fp, fs) = (p.first_fault(), s.first_fault());
        eprintln!(
            "{fault:?}: PIL {fp:?} (exit {:?}), SIL {fs:?}",
            p.link.exit_code
        );
        assert_eq!(fp.map(|f| f.code), Some(code), "{fault:?}");
        assert_eq!(fp, fs, "{fault:?}: same code, same tick");
        assert_eq!(p.frames_rejected, s.frames_rejected, "{fault:?}");
        assert_zero_force_and_exit_code(&p, code, &format!("{fault:?}"));
    }
}

#[test]
fn a_link_that_stops_mid_jump_is_link_lost_in_the_firmware() {
    if !qemu_available() {
        return;
    }
    let mut spec = delayed(0.75, ModelName::Eq4);
    spec.injections.push(Injection {
        at_s: 0.03,
        fault: InjectedFault::LinkStops,
    });
    let p = pil(&spec);
    assert_eq!(p.first_fault().map(|f| f.code), Some(FaultCode::LinkLost));
    assert_zero_force_and_exit_code(&p, FaultCode::LinkLost, "link stops");
}

#[test]
fn a_hung_firmware_fails_the_run_within_seconds() {
    if !qemu_available() {
        return;
    }
    let config = PilConfig {
        answer_timeout: Duration::from_secs(2),
        ..PilConfig::new(firmware_elf())
    };
    let start = Instant::now();
    let result = pil::start_session(&config, &["hang"]);
    let elapsed = start.elapsed();
    assert!(
        matches!(result, Err(LinkError::Timeout { .. })),
        "{:?}",
        result.err()
    );
    assert!(elapsed < Duration::from_secs(10), "took {elapsed:?}");
}
