//! Every fault path of the F407 binary ends in the whole safe state (drive enable low, force
//! zero, lift, shaker and blower off) within the time the docs promise, observed at the pins
//! of the virtual board: the robot armed on hard ground, the host (commands over USB) keeping
//! it alive with heartbeats, then one fault.

mod common;

use common::{MS, armed_actions, at, bed_switched_on, rig_messages, robot_at_single_start, send};
use sandjumper_core::Command;
use sandjumper_core::protocol::encode_frame_vec;
use sandjumper_virtual_f407::rig::BedWiring;
use sandjumper_virtual_f407::run::{Action, NoHost, RunConfig, RunReport, run};
/// When the host arms the rig (the board is enumerated by ~140 ms).
const ARM_AT: u64 = 200 * MS;
/// When the fault is injected.
const FAULT_AT: u64 = 600 * MS;

/// Configure a single 5 Hz sine and arm at `ARM_AT`; heartbeats every 20 ms until `silent_from`.
fn armed_run(silent_from: u64, end: u64, mut extra: Vec<(u64, Action)>) -> Option<RunReport> {
    let elf = common::firmware_elf()?;
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(end);
    cfg.trace_every = 1;
    cfg.robot = Some(robot_at_single_start());
    let mut actions = armed_actions(ARM_AT, silent_from.min(end));
    actions.append(&mut extra);
    cfg.actions = actions;
    Some(run(cfg, NoHost::default()).expect("the run").0)
}

/// The drive was on just before `from`, and everything is safe from `from + within` to the end.
fn safe_within(r: &RunReport, from: u64, within: u64, what: &str) {
    let before = at(r, from - MS);
    assert!(
        before.out.drive_enable,
        "{what}: the drive was not enabled before the fault: {before:?}\nlog {:?}",
        r.log
    );
    let first_safe = r
        .trace
        .iter()
        .filter(|row| row.t_ns >= from)
        .find(|row| row.out.drive_and_lift_safe() && (row.out.force_dac_v - 1.65).abs() < 1e-3)
        .unwrap_or_else(|| {
            panic!(
                "{what}: never safe after the fault; log {:?}; resets {:?}; holds {:?}; last {:?}",
                r.log, r.resets, r.holds, r.last
            )
        });
    assert!(
        first_safe.t_ns <= from + within,
        "{what}: safe only {} us after the fault",
        (first_safe.t_ns - from) / 1000
    );
    for row in r.trace.iter().filter(|row| row.t_ns >= first_safe.t_ns) {
        assert!(
            !row.out.drive_enable && !row.out.lift_enable && row.out.blower_dac_v < 0.01,
            "{what}: not safe at {} ns: {row:?}",
            row.t_ns
        );
    }
}

/// The board's first reset is the watchdog's, within 25 ms of the fault (a handler that stopped
/// the core and left the watchdog unfed).
fn the_watchdog_restarts_after_the_fault(r: &RunReport) {
    let (reset_at, cause) = r
        .resets
        .first()
        .cloned()
        .expect("the watchdog resets the board");
    assert!(
        reset_at > FAULT_AT && reset_at < FAULT_AT + 25 * MS && cause.contains("IWDG"),
        "{reset_at} {cause}"
    );
}

#[test]
fn the_host_falling_silent_stops_the_drive_after_the_command_watchdog() {
    let Some(r) = armed_run(FAULT_AT, FAULT_AT + 700 * MS, vec![]) else {
        return;
    };
    // The command watchdog: 500 ms without a frame from the host (RigConfig::watchdog_ticks).
    let last_heartbeat = FAULT_AT - 20 * MS;
    let row = at(&r, last_heartbeat + 450 * MS);
    assert!(
        row.out.drive_enable,
        "stopped before the watchdog's 500 ms: {row:?}"
    );
    safe_within(&r, last_heartbeat + 450 * MS, 60 * MS, "host silent");
    assert!(at(&r, FAULT_AT + 690 * MS).out.led_fault);
}

#[test]
fn the_usb_cable_pulled_stops_the_drive_after_the_command_watchdog() {
    let Some(r) = armed_run(
        FAULT_AT + 600 * MS,
        FAULT_AT + 700 * MS,
        vec![(FAULT_AT, Action::UsbAttached(false))],
    ) else {
        return;
    };
    safe_within(&r, FAULT_AT + 450 * MS, 80 * MS, "cable pulled");
}

/// A frozen encoder (its cable pulled): the count stops, so the jump that starts next moves a
/// carriage the loop cannot see; the tracking error stops it. (Through TIM2's input filter a
/// real scale's edges never arrive faster than the core's plausibility limit, so the core's
/// `EncoderFault` is the lockstep rigs' fault, not this board's.)
#[test]
fn a_frozen_encoder_stops_the_drive_on_the_tracking_error() {
    let start = FAULT_AT + 10 * MS;
    let Some(r) = armed_run(
        FAULT_AT + 400 * MS,
        FAULT_AT + 300 * MS,
        vec![
            (FAULT_AT, Action::EncoderFrozen),
            (start, send(99, Command::Start)),
        ],
    ) else {
        return;
    };
    safe_within(&r, start, 100 * MS, "frozen encoder");
}

/// Issue 38 item 4: the force DAC spans the drive's whole +-300 N. A frozen encoder with the
/// tracking limit at its widest (0.1 m) lets the loop drive the force into saturation through the
/// whole stroke, and the DAC's output reaches its rail (within 10 mV). Buffered (`BOFF1` clear),
/// it stopped 0.2 V short: about 260 N instead of 300 N, with the integrator winding up unseen.
#[test]
fn the_force_dac_reaches_the_rail_of_the_drives_full_scale() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(FAULT_AT + 300 * MS);
    cfg.trace_every = 1;
    cfg.robot = Some(robot_at_single_start());
    let mut actions = armed_actions(ARM_AT, FAULT_AT + 300 * MS);
    let mut wide = common::single_sine();
    wide.tracking_error_limit_m = 0.1;
    actions[0] = (ARM_AT - 10 * MS, send(1, Command::Configure(wide)));
    actions.push((FAULT_AT, Action::EncoderFrozen));
    actions.push((FAULT_AT + 10 * MS, send(99, Command::Start)));
    cfg.actions = actions;
    let r = run(cfg, NoHost::default()).expect("the run").0;
    // Only while the drive is enabled: before `init` enables the DAC it reads 0 V anyway.
    let (lo, hi) = r
        .trace
        .iter()
        .filter(|row| row.out.drive_enable)
        .map(|row| row.out.force_dac_v)
        .fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v), hi.max(v)));
    assert!(
        lo < 0.01 || hi > 3.29,
        "the force DAC never reached a rail while the drive was on: {lo:.3}..{hi:.3} V; log {:?}",
        r.log
    );
}

#[test]
fn the_emergency_stop_stops_drive_and_bed_within_a_tick() {
    let pressed = BedWiring::Connected {
        emergency_stop: true,
        lift_up_limit: false,
        lift_down_limit: true,
    };
    let Some(r) = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 100 * MS,
        vec![(FAULT_AT, Action::Bed(pressed))],
    ) else {
        return;
    };
    safe_within(&r, FAULT_AT, 300_000, "emergency stop");
}

#[test]
fn the_bed_harness_pulled_out_is_an_emergency_stop() {
    let Some(r) = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 100 * MS,
        vec![(FAULT_AT, Action::Bed(BedWiring::Unwired))],
    ) else {
        return;
    };
    safe_within(&r, FAULT_AT, 300_000, "harness pulled out");
}

#[test]
fn a_bus_error_hardfault_stops_everything_and_the_watchdog_restarts_the_board() {
    // The next access to GPIOE (the tick writes it every period) fails: a precise bus error,
    // escalated to HardFault.
    let Some(r) = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 100 * MS,
        vec![(
            FAULT_AT,
            Action::BusError {
                from: 0x4002_1000,
                to: 0x4002_1400,
            },
        )],
    ) else {
        return;
    };
    safe_within(&r, FAULT_AT, 300_000, "HardFault");
    assert!(r.log.iter().any(|l| l.contains("HardFault")), "{:?}", r.log);
    the_watchdog_restarts_after_the_fault(&r);
}

/// Issue 38 item 9: the crystal stops while the rig is armed. The clock security system
/// (`CSSON`, set once the PLL runs on the crystal) switches the part to its HSI and raises the
/// NMI, whose handler makes the whole rig safe at once and reports it; the watchdog then restarts
/// the board. The binary before the review left the detector off: nothing noticed, the core
/// stopped with its clock and the drive stayed enabled until the watchdog's reset, 7-19 ms later.
#[test]
fn a_crystal_that_stops_while_armed_is_caught_by_the_clock_security_system() {
    let Some(r) = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 100 * MS,
        vec![(FAULT_AT, Action::CrystalStops)],
    ) else {
        return;
    };
    safe_within(&r, FAULT_AT, 100_000, "crystal stopped");
    assert!(
        r.log.iter().any(|l| l.contains("clock security")),
        "{:?}",
        r.log
    );
    the_watchdog_restarts_after_the_fault(&r);
}

#[test]
fn the_fault_runs_are_identical_twice() {
    let pressed = BedWiring::Connected {
        emergency_stop: true,
        lift_up_limit: false,
        lift_down_limit: true,
    };
    let a = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 50 * MS,
        vec![(FAULT_AT, Action::Bed(pressed))],
    );
    let b = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 50 * MS,
        vec![(FAULT_AT, Action::Bed(pressed))],
    );
    let (Some(a), Some(b)) = (a, b) else { return };
    assert_eq!(a.trace, b.trace);
    assert_eq!(a.log, b.log);
}

/// A HardFault while the bed apparatus runs (blower, shaker, lift: the host prepares the bed
/// with the rig Idle) turns all of it off, not only the drive.
#[test]
fn a_hardfault_while_the_bed_runs_turns_the_bed_off_too() {
    let Some(r) = bed_running_then(Action::BusError {
        from: 0x4002_1000,
        to: 0x4002_1400,
    }) else {
        return;
    };
    let after: Vec<_> = r.trace.iter().filter(|row| row.t_ns >= 301 * MS).collect();
    assert!(
        after.iter().all(|row| !row.out.lift_enable
            && row.out.blower_dac_v < 0.01
            && row.out.shaker_duty == 0.0
            && !row.out.drive_enable),
        "the bed still runs after the HardFault: {:?}",
        after.first()
    );
}

/// The bed apparatus switched on with the rig Idle ([`bed_switched_on`]), running at 290 ms
/// (lift up, blower on, shaker at half duty), then `fault` at 300 ms; to 400 ms.
fn bed_running_then(fault: Action) -> Option<RunReport> {
    let elf = common::firmware_elf()?;
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(400 * MS);
    cfg.trace_every = 1;
    cfg.actions = bed_switched_on();
    cfg.actions.push((300 * MS, fault));
    let (r, _) = run(cfg, NoHost::default()).expect("the run");
    let running = at(&r, 290 * MS);
    assert!(
        running.out.lift_gated
            && running.out.blower_dac_v > 1.0
            && (running.out.shaker_duty - 0.5).abs() < 0.01,
        "the bed did not run: {running:?}"
    );
    Some(r)
}

/// Every output safe from the board's first reset on.
fn all_off_after_the_reset(r: &RunReport) {
    let reset_at = r.resets.first().expect("a reset").0;
    assert!(
        r.trace
            .iter()
            .filter(|row| row.t_ns > reset_at)
            .all(|row| row.out.drive_and_lift_safe()),
        "an output on after the reset at {reset_at} ns"
    );
}

/// The core stops (a stalled tick) while the rig is armed: the external enable gate drops the
/// drive's enable within its 1 ms once the heartbeat stops, force zero at the drive, and the
/// watchdog's reset (7-19 ms) then sets every pin to its reset state.
#[test]
fn a_stalled_tick_while_armed_is_gated_at_once_and_reset_by_the_watchdog() {
    let Some(r) = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 100 * MS,
        vec![(FAULT_AT, Action::Hold(true))],
    ) else {
        return;
    };
    assert!(at(&r, FAULT_AT - MS).out.drive_gated, "not armed before");
    let gated: Vec<_> = r
        .trace
        .iter()
        .filter(|row| row.t_ns >= FAULT_AT + 1_200_000)
        .collect();
    assert!(
        gated
            .iter()
            .all(|row| !row.out.drive_gated && row.out.force_n == 0.0),
        "the drive saw its enable more than 1.2 ms after the stall"
    );
    the_watchdog_restarts_after_the_fault(&r);
    all_off_after_the_reset(&r);
}

/// The core stops while the bed apparatus runs (the rig Idle): the gate drops the lift within
/// 1 ms, and the watchdog's reset turns the blower and the shaker off.
#[test]
fn a_stalled_tick_while_the_bed_runs_ends_with_the_bed_off_at_the_watchdog() {
    let Some(r) = bed_running_then(Action::Hold(true)) else {
        return;
    };
    assert!(
        r.trace
            .iter()
            .filter(|row| row.t_ns >= 301_200_000)
            .all(|row| !row.out.lift_gated),
        "the lift saw its enable more than 1.2 ms after the stall"
    );
    let (reset_at, cause) = r.resets.first().cloned().expect("the watchdog resets");
    assert!(
        cause.contains("IWDG") && reset_at > 300 * MS && reset_at < 325 * MS,
        "{reset_at} {cause}"
    );
    all_off_after_the_reset(&r);
}

/// docs/bringup.md steps 2, 4 and 7 with nothing wired to the bed inputs: the board answers,
/// takes a configuration and arms (the drive enable rises), where the floating inputs used to
/// latch the emergency stop and refuse `Arm` ("lift not down").
#[test]
fn a_board_with_nothing_wired_can_be_armed() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(ARM_AT + 5 * MS);
    cfg.trace_every = 1;
    cfg.bed = BedWiring::Unwired;
    cfg.robot = Some(robot_at_single_start());
    cfg.actions = armed_actions(ARM_AT, ARM_AT);
    let (r, _) = run(cfg, NoHost::default()).expect("the run");
    let after = at(&r, ARM_AT + 4 * MS);
    assert!(
        after.out.drive_enable && !after.out.led_fault,
        "not armed with nothing wired: {after:?}"
    );
}

/// With nothing wired the apparatus is absent: nothing of it can be switched on (no limit
/// switch or emergency stop is read). The binary before the review ran the lift, blower and
/// shaker of an absent apparatus.
#[test]
fn an_absent_bed_apparatus_cannot_be_switched_on() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(300 * MS);
    cfg.trace_every = 1;
    cfg.bed = BedWiring::Unwired;
    cfg.actions = bed_switched_on();
    let (r, _) = run(cfg, NoHost::default()).expect("the run");
    let last = r.last.expect("ran").out;
    assert!(
        last.drive_and_lift_safe(),
        "an absent apparatus was switched on: {last:?}"
    );
}

/// A harness whose presence link is broken but whose emergency stop is wired and released:
/// the e-stop proves the harness, and the missing link reads as a stop (never as "no
/// apparatus", which would leave the e-stop unread).
#[test]
fn a_broken_presence_link_reads_as_an_emergency_stop() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(100 * MS);
    cfg.bed = BedWiring::BrokenPresenceLink;
    let (r, _) = run(cfg, NoHost::default()).expect("the run");
    assert!(
        r.last.expect("ran").out.led_fault,
        "a broken presence link left the e-stop unmonitored"
    );
}

/// Lockstep (hardware in the loop on the real board, the host's sensor frames): the real bed
/// apparatus is held off whatever it was doing, and the real emergency stop still stops, though
/// the frames carry simulated bed inputs. The binary before issue 38 left the real blower
/// running and read only the frames' e-stop.
#[test]
fn lockstep_keeps_the_real_bed_off_and_the_real_emergency_stop_stops() {
    use sandjumper_core::bed::{BedCommand, BedInputs};
    use sandjumper_core::{FaultCode, HostMessage, RigMessage, SensorFrame};
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(420 * MS);
    cfg.trace_every = 1;
    let mut actions = vec![(
        200 * MS,
        send(1, Command::Bed(BedCommand::Blower { volts: 5.0 })),
    )];
    let simulated_bed = BedInputs {
        lift_up_limit: false,
        lift_down_limit: true,
        emergency_stop: false,
        height_raw: 2000,
    };
    for k in 0..100u32 {
        let sensor = SensorFrame {
            frame: k,
            encoder_count: 0,
            current_a: None,
            overrun: false,
            bed: Some(simulated_bed),
        };
        let bytes = encode_frame_vec(&HostMessage::Sensor(sensor))
            .expect("a frame")
            .to_vec();
        actions.push((300 * MS + u64::from(k) * MS, Action::HostBytes(bytes)));
    }
    let pressed = BedWiring::Connected {
        emergency_stop: true,
        lift_up_limit: false,
        lift_down_limit: true,
    };
    actions.push((350 * MS, Action::Bed(pressed)));
    cfg.actions = actions;
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    assert!(
        at(&r, 290 * MS).out.blower_dac_v > 1.0,
        "the blower never ran"
    );
    let locked = at(&r, 310 * MS).out;
    assert!(
        locked.blower_dac_v < 0.01,
        "the real blower runs on in lockstep: {locked:?}"
    );
    let faults: Vec<_> = rig_messages(&host.received)
        .into_iter()
        .filter_map(|m| match m {
            RigMessage::Actuator(a) => Some((a.frame, a.fault)),
            _ => None,
        })
        .collect();
    assert!(
        faults.iter().any(|(f, _)| *f < 40),
        "no actuator frames answered"
    );
    assert!(
        faults
            .iter()
            .any(|(f, fault)| *f >= 50 && *fault == Some(FaultCode::EmergencyStop)),
        "the real emergency stop did not stop the lockstep rig: {:?}",
        faults.iter().rev().take(3).collect::<Vec<_>>()
    );
}
