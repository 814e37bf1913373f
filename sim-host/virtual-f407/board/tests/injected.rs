//! The bring-up's test images (firmware `inject_f407.rs`: `SANDJUMPER_INJECT=panic`,
//! `hardfault`, `stack-overflow`, `unhandled-interrupt`, each fired by the control tick 2 s
//! after start-up) on the
//! virtual board, armed with the robot on hard ground: the fault handlers put the whole rig in
//! the safe state at once, report over RTT, and the watchdog restarts the board, which reports
//! the watchdog reset. The images are built into `target/inject-<kind>` of the main workspace
//! (`tests/integration/virtual_f407.rs` builds them; `SANDJUMPER_F407_INJECT_DIR` names another place).

mod common;

use std::path::PathBuf;

use common::{MS, armed_actions, robot_at_single_start};
use sandjumper_virtual_f407::run::{NoHost, RunConfig, RunReport, run};

fn image(kind: &str) -> Option<PathBuf> {
    let dir = std::env::var_os("SANDJUMPER_F407_INJECT_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../target"));
    let elf = dir.join(format!(
        "inject-{kind}/thumbv7em-none-eabihf/release/sandjumper-firmware"
    ));
    if elf.is_file() {
        return Some(elf);
    }
    let msg = format!(
        "skipped: no test image at {} (SANDJUMPER_INJECT={kind} cargo build -p sandjumper-firmware --target thumbv7em-none-eabihf --release --target-dir target/inject-{kind})",
        elf.display()
    );
    assert!(std::env::var_os("CI").is_none(), "{msg}");
    eprintln!("{msg}");
    None
}

/// Armed at 200 ms with heartbeats, run to 2.1 s.
fn armed(elf: PathBuf) -> RunReport {
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(2_100 * MS);
    cfg.trace_every = 1;
    cfg.robot = Some(robot_at_single_start());
    cfg.actions = armed_actions(200 * MS, 2_100 * MS);
    run(cfg, NoHost::default()).expect("the run").0
}

/// The control tick the images fire their fault at (`firmware/src/inject_f407.rs`,
/// `INJECT_AT_TICK`): 2 s of ticks after the tick starts.
const INJECT_AT_TICK: u64 = 20_000;

/// When the fault fires, ns: the stop where TIM7 has counted [`INJECT_AT_TICK`] updates (2 s of
/// ticks after the start-up, which itself takes a few ms on the HSI and the PLL's lock).
fn injection_at(r: &RunReport) -> u64 {
    r.trace
        .iter()
        .find(|row| row.ticks >= INJECT_AT_TICK)
        .map(|row| row.t_ns)
        .expect("the tick reached the injection")
}

/// The drive on until the fault, the whole safe state within 100 us of it, the report, and the
/// watchdog's restart.
fn check(kind: &str, report: &str) {
    let Some(elf) = image(kind) else { return };
    let r = armed(elf);
    let fault_at = r
        .trace
        .windows(2)
        .find(|w| w[0].out.drive_enable && !w[1].out.drive_enable)
        .map(|w| w[1].t_ns)
        .unwrap_or_else(|| panic!("{kind}: the drive never went off; log {:?}", r.log));
    let injected = injection_at(&r);
    assert!(
        (injected - 10 * MS..injected + 10 * MS).contains(&fault_at),
        "{kind}: the drive went off at {fault_at} ns, not at the fault at {injected} ns"
    );
    let row = common::at(&r, fault_at);
    assert!(
        row.out.drive_and_lift_safe()
            && row.out.force_n == 0.0
            && (row.out.force_dac_v - 1.65).abs() < 1e-3,
        "{kind}: {row:?}"
    );
    assert!(
        r.log.iter().any(|l| l.contains(report)),
        "{kind}: no `{report}` in {:?}",
        r.log
    );
    let (reset_at, cause) = r
        .resets
        .first()
        .cloned()
        .unwrap_or_else(|| panic!("{kind}: no watchdog reset"));
    assert!(
        reset_at > fault_at && reset_at < fault_at + 25 * MS && cause.contains("IWDG"),
        "{kind}: {reset_at} {cause}"
    );
    assert!(
        r.log.iter().any(|l| l.contains("reset cause Watchdog")),
        "{kind}: {:?}",
        r.log
    );
    for row in r.trace.iter().filter(|row| row.t_ns >= fault_at) {
        assert!(
            !row.out.drive_enable,
            "{kind}: the drive came back at {} ns",
            row.t_ns
        );
    }
}

/// The bed apparatus running (blower, shaker, lift: the rig Idle, the host's heartbeats on)
/// when the image's fault comes at 2 s: all of it is off from the fault on. The binary before
/// the review made only the drive safe in its handlers.
fn check_bed(kind: &str) {
    let Some(elf) = image(kind) else { return };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(2_050 * MS);
    cfg.trace_every = 1;
    cfg.actions = common::bed_switched_on();
    cfg.actions
        .extend(common::heartbeats(220 * MS, 2_050 * MS, 4));
    let r = run(cfg, NoHost::default()).expect("the run").0;
    let injected = injection_at(&r);
    let running = common::at(&r, injected - 10 * MS);
    assert!(
        running.out.lift_enable && running.out.blower_dac_v > 1.0 && running.out.shaker_duty > 0.4,
        "{kind}: the bed did not run before the fault: {running:?}; log {:?}",
        r.log
    );
    let off_at = r
        .trace
        .windows(2)
        .find(|w| w[0].out.lift_enable && !w[1].out.lift_enable)
        .map(|w| w[1].t_ns)
        .unwrap_or_else(|| panic!("{kind}: the lift never went off; log {:?}", r.log));
    assert!(
        (injected - MS..injected + MS).contains(&off_at),
        "{kind}: the lift went off at {off_at} ns, not at the fault at {injected} ns"
    );
    // The lift, the blower and the drive at once; the shaker's new duty (0) loads at the end
    // of its PWM period (TIM3's compare preload, 50 us at 20 kHz): by the next 100 us stop.
    let first = common::at(&r, off_at);
    assert!(
        !first.out.lift_enable && first.out.blower_dac_v < 0.01 && !first.out.drive_enable,
        "{kind}: {first:?}"
    );
    for row in r.trace.iter().filter(|row| row.t_ns >= off_at + 100_000) {
        assert!(
            row.out.drive_and_lift_safe(),
            "{kind}: the bed still on at {} ns: {row:?}",
            row.t_ns
        );
    }
}

#[test]
fn an_injected_panic_makes_the_rig_safe_reports_and_restarts() {
    check("panic", "panic: ");
}

#[test]
fn the_panic_hardfault_and_default_handlers_turn_a_running_bed_off() {
    for kind in ["panic", "hardfault", "unhandled-interrupt"] {
        check_bed(kind);
    }
}

/// An interrupt enabled with no handler of its own ends in cortex-m-rt's default handler, which
/// makes the whole rig safe like the others (the binary before the review dropped the drive
/// only, leaving the lift, the blower and the shaker on).
#[test]
fn an_unhandled_interrupt_makes_the_rig_safe_reports_and_restarts() {
    check("unhandled-interrupt", "unexpected exception or interrupt");
}

#[test]
fn an_injected_hardfault_makes_the_rig_safe_reports_and_restarts() {
    check("hardfault", "HardFault: pc=");
}

/// A stack overflow is not caught by the HardFault handler: the core pushes the exception's
/// frame below the stack, which (flip-link's stack at the bottom of RAM) faults again while
/// entering HardFault, and the core locks up (ARMv7-M B1.5.15): nothing runs, PE7 stays high,
/// nothing is reported. The external enable gate (drive and lift enables) closes within its
/// period (the heartbeat stopped), and the watchdog's reset ends the rest (blower and shaker:
/// the DAC and TIM3 back to their reset state), then the board reports it.
///
/// What fails here and what cannot: the gate's timing checks the board's external monostable
/// (a locked-up core toggles nothing, whatever the firmware), so no firmware mutant can fail
/// it; the watchdog's reset within its period and the reported cause are the firmware's
/// (`watchdog-frozen-on-debug` is not among the mutants that reach a lockup; the watchdog's
/// own mutants are killed in `faults.rs` and `bring_up.rs`).
#[test]
fn a_stack_overflow_locks_the_core_up_the_enable_gate_drops_the_drive_and_the_watchdog_restarts() {
    let Some(elf) = image("stack-overflow") else {
        return;
    };
    let r = armed(elf);
    let gate_closed = r
        .trace
        .windows(2)
        .find(|w| w[0].out.drive_gated && !w[1].out.drive_gated)
        .map(|w| w[1].t_ns)
        .expect("the drive's gated enable never dropped");
    let (reset_at, cause) = r.resets.first().cloned().expect("no watchdog reset");
    assert!(cause.contains("IWDG"), "{cause}");
    // The overflow comes at the 2 s tick; the heartbeat's last edge is then; the gate closes
    // one monostable period later, long before the watchdog.
    let injected = injection_at(&r);
    assert!(
        (injected..injected + 3 * MS).contains(&gate_closed),
        "the gate closed at {gate_closed} ns, the fault at {injected} ns"
    );
    assert!(
        reset_at > gate_closed + 3 * MS && reset_at < gate_closed + 25 * MS,
        "reset at {reset_at} ns"
    );
    let stuck = r
        .trace
        .iter()
        .find(|row| row.t_ns > gate_closed && row.t_ns < reset_at)
        .expect("row");
    assert!(
        stuck.out.drive_enable && !stuck.out.drive_gated && stuck.out.force_n == 0.0,
        "{stuck:?}"
    );
    assert!(
        !r.log.iter().any(|l| l.contains("HardFault")),
        "the handler ran: {:?}",
        r.log
    );
    assert!(
        r.log.iter().any(|l| l.contains("reset cause Watchdog")),
        "{:?}",
        r.log
    );
}
