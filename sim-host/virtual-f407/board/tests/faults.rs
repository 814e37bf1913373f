//! Every fault path of the F407 binary ends in the whole safe state (drive enable low, force
//! zero, lift, shaker and blower off) within the time the docs promise, observed at the pins
//! of the virtual board: the robot armed on hard ground, the host (commands over USB) keeping
//! it alive with heartbeats, then one fault.

mod common;

use common::{MS, armed_actions, at, bed_switched_on, rig_messages, robot_at_single_start, send};
use sandjumper_core::Command;
use sandjumper_core::protocol::encode_frame_vec;
use sandjumper_virtual_f407::rig::{BedWiring, EmergencyStopLoop};
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
    // The stop the fault was applied at (stops are a period apart, not always on its multiples).
    let applied = r
        .trace
        .iter()
        .find(|row| row.t_ns >= from)
        .map_or(from, |row| row.t_ns);
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
        first_safe.t_ns <= applied + within,
        "{what}: safe only {} ns after the fault",
        first_safe.t_ns - applied
    );
    for row in r.trace.iter().filter(|row| row.t_ns >= first_safe.t_ns) {
        assert!(
            row.out.drive_and_lift_safe(),
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

/// Killed by `estop-not-read` (PE14 never reported) and `estop-not-latched` (the core ignores
/// the loop opening).
#[test]
fn the_emergency_stop_stops_drive_and_bed_within_a_tick() {
    let Some(r) = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 100 * MS,
        vec![(FAULT_AT, Action::EmergencyStop(EmergencyStopLoop::Open))],
    ) else {
        return;
    };
    safe_within(&r, FAULT_AT, 300_000, "emergency stop");
}

/// The stop pressed while the bed apparatus runs with the rig Idle (the host preparing the bed):
/// the lift, the blower and the shaker off within a tick (the shaker at the end of its 50 us PWM
/// period). Killed by `estop-not-read` and `bed-trip-keeps-outputs`.
#[test]
fn the_emergency_stop_stops_the_running_bed_within_a_tick() {
    let Some(r) = bed_running_then(Action::EmergencyStop(EmergencyStopLoop::Open)) else {
        return;
    };
    let first_off = r
        .trace
        .iter()
        .filter(|row| row.t_ns >= 300 * MS)
        .find(|row| row.out.drive_and_lift_safe())
        .unwrap_or_else(|| panic!("the bed never went off: {:?}", r.last));
    assert!(
        first_off.t_ns <= 300 * MS + 300_000,
        "the bed went off {} us after the stop",
        (first_off.t_ns - 300 * MS) / 1000
    );
    assert!(
        r.trace
            .iter()
            .filter(|row| row.t_ns >= first_off.t_ns)
            .all(|row| row.out.drive_and_lift_safe()),
        "an actuator came back on"
    );
    assert!(r.last.expect("ran").out.led_fault);
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
    // On the HSI the tick timer counts its 8,400 steps of a period on an 8 MHz timer clock
    // (16 MHz HSI, APB1 / 4, doubled; RM0090 6.2) instead of 84 MHz: about 952 update events
    // a second until the watchdog's reset, as on silicon (the board kept 10 kHz before).
    let (from, to) = (FAULT_AT + MS, FAULT_AT + 5 * MS);
    assert!(
        r.resets.iter().all(|(t, _)| *t < from || *t > to),
        "{:?}",
        r.resets
    );
    let (a, b) = (at(&r, from), at(&r, to));
    let rate_hz = (b.ticks - a.ticks) as f64 / ((b.t_ns - a.t_ns) as f64 * 1e-9);
    assert!(
        (800.0..1100.0).contains(&rate_hz),
        "the tick timer on the HSI: {rate_hz} Hz"
    );
    // The core falls back with it: one instruction a cycle of the HSI from the fault on.
    let fell_back = r.instruction_rates.last().copied();
    assert!(
        fell_back
            .is_some_and(|(t, rate)| rate == 16_000_000 && (FAULT_AT..FAULT_AT + MS).contains(&t)),
        "{:?}",
        r.instruction_rates
    );
    the_watchdog_restarts_after_the_fault(&r);
}

/// The virtual board is deterministic through a fault too: a property of the board (virtual
/// time, its models), not of the firmware. No firmware mutant is expected to fail it.
#[test]
fn the_virtual_board_is_deterministic_through_a_fault() {
    let pressed = Action::EmergencyStop(EmergencyStopLoop::Open);
    let a = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 50 * MS,
        vec![(FAULT_AT, pressed.clone())],
    );
    let b = armed_run(
        FAULT_AT + 200 * MS,
        FAULT_AT + 50 * MS,
        vec![(FAULT_AT, pressed)],
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
///
/// The gate's assertion checks the board's external monostable: with the whole core halted no
/// firmware can keep its heartbeat going, so no mutant can fail it (the firmware's part is in
/// `a_tick_timer_that_stops_alone_is_gated_and_reset_while_usb_runs_on`). The watchdog's reset
/// is the firmware's, but the halt here is not a debugger's: `watchdog-frozen-on-debug`
/// survives it (a documented survivor, firmware/mutants/mutants.toml).
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
/// 1 ms, and the watchdog's reset turns the blower and the shaker off. The gate's assertion is
/// the board's (a halted core toggles nothing, whatever the firmware: no mutant can fail it);
/// the watchdog's reset and everything off after it are the firmware's.
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

/// Configure and Arm at `ARM_AT` with the bed's harness `bed` and the stop's loop `stop` as
/// wired from power-up; to `ARM_AT + 5 ms`. The run and the board's answer to `Arm` (id 2).
fn arm_wired(
    bed: BedWiring,
    stop: EmergencyStopLoop,
) -> Option<(
    RunReport,
    Option<Result<sandjumper_core::Reply, sandjumper_core::Rejection>>,
)> {
    use sandjumper_core::RigMessage;
    let elf = common::firmware_elf()?;
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(ARM_AT + 5 * MS);
    cfg.trace_every = 1;
    cfg.bed = bed;
    cfg.emergency_stop = stop;
    cfg.robot = Some(robot_at_single_start());
    cfg.actions = armed_actions(ARM_AT, ARM_AT);
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    let answer = rig_messages(&host.received)
        .into_iter()
        .find_map(|m| match m {
            RigMessage::Reply { id: 2, result } => Some(result),
            _ => None,
        });
    Some((r, answer))
}

/// Issue 48 item 1, docs/bringup.md's first power-up with nothing wired, not even the stop's
/// connector: Idle, safe, no fault, and `Arm` refused with a message that names the loop; the
/// drive enable never rises. The binary before issue 48 armed (the e-stop was read only once the
/// bed's harness had been seen). Killed by `estop-not-read` and `estop-arm-not-checked`.
#[test]
fn a_board_with_nothing_wired_is_idle_and_refuses_arm_naming_the_loop() {
    use sandjumper_core::emergency_stop::EmergencyStopError;
    use sandjumper_core::{CommandError, Rejection};
    let Some((r, answer)) = arm_wired(BedWiring::Unwired, EmergencyStopLoop::Open) else {
        return;
    };
    assert_eq!(
        answer,
        Some(Err(Rejection::EmergencyStop(
            EmergencyStopError::NeverClosed
        ))),
        "the answer to Arm with nothing wired"
    );
    let message = CommandError::EmergencyStop(EmergencyStopError::NeverClosed).to_string();
    assert!(message.contains("emergency-stop loop"), "{message}");
    assert!(
        r.trace
            .iter()
            .all(|row| !row.out.drive_enable && !row.out.led_fault),
        "the drive enable rose (or a fault latched) with the stop's loop open"
    );
}

/// The same board with a jumper plug in the stop's connector (docs/bringup.md's first power-up)
/// and nothing else: it arms, the drive enable rises (the pin the test above watches does move).
#[test]
fn a_board_with_only_the_jumper_plug_arms() {
    let Some((r, answer)) = arm_wired(BedWiring::Unwired, EmergencyStopLoop::Closed) else {
        return;
    };
    assert_eq!(answer, Some(Ok(sandjumper_core::Reply::Ack)));
    let after = at(&r, ARM_AT + 4 * MS);
    assert!(
        after.out.drive_enable && !after.out.led_fault,
        "not armed with the jumper plug: {after:?}"
    );
}

/// The bed's harness connected and ready, the stop pressed since power-up: `Arm` refused (the
/// loop never read closed), no fault latched; the drive enable never rises.
#[test]
fn the_stop_pressed_at_power_up_refuses_arm_with_the_bed_connected() {
    use sandjumper_core::Rejection;
    use sandjumper_core::emergency_stop::EmergencyStopError;
    let Some((r, answer)) = arm_wired(BedWiring::READY, EmergencyStopLoop::Open) else {
        return;
    };
    assert_eq!(
        answer,
        Some(Err(Rejection::EmergencyStop(
            EmergencyStopError::NeverClosed
        )))
    );
    assert!(r.trace.iter().all(|row| !row.out.drive_enable));
}

/// Issue 48 item 1, the truth table's middle row: the bed's harness connected and ready, the
/// stop pressed since power-up (its loop never read closed). Nothing of the apparatus can be
/// switched on: the blower, the shaker and the lift are refused with the loop's message, and on
/// the pins nothing moves, no fault latches. Killed by `estop-bed-not-checked`.
#[test]
fn the_stop_pressed_at_power_up_keeps_the_bed_off() {
    use sandjumper_core::emergency_stop::EmergencyStopError;
    use sandjumper_core::{Rejection, RigMessage};
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(300 * MS);
    cfg.trace_every = 1;
    cfg.emergency_stop = EmergencyStopLoop::Open;
    cfg.actions = bed_switched_on();
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    let answers: Vec<_> = rig_messages(&host.received)
        .into_iter()
        .filter_map(|m| match m {
            RigMessage::Reply { id, result } => Some((id, result)),
            _ => None,
        })
        .collect();
    for id in 1..=3 {
        assert!(
            answers.contains(&(
                id,
                Err(Rejection::EmergencyStop(EmergencyStopError::NeverClosed))
            )),
            "bed command {id} was not refused by the loop: {answers:?}"
        );
    }
    assert!(
        r.trace
            .iter()
            .all(|row| row.out.drive_and_lift_safe() && !row.out.led_fault),
        "an actuator came on (or a fault latched) with the stop pressed since power-up"
    );
}

/// The bed's interlock at the pins: the apparatus connected with its lift up (its lower limit
/// switch open), `Arm` is refused ("lift not down") and the drive enable never rises. Killed by
/// `lift-interlock-off`.
#[test]
fn arm_is_refused_with_the_lift_not_down() {
    use sandjumper_core::Rejection;
    use sandjumper_core::bed::BedError;
    let lift_up = BedWiring::Connected {
        lift_up_limit: true,
        lift_down_limit: false,
    };
    let Some((r, answer)) = arm_wired(lift_up, EmergencyStopLoop::Closed) else {
        return;
    };
    assert_eq!(
        answer,
        Some(Err(Rejection::Interlock(BedError::LiftNotDown)))
    );
    assert!(r.trace.iter().all(|row| !row.out.drive_enable));
}

/// Issue 48 item 2: the host falls silent with the rig Idle and the bed apparatus running (lift
/// up, blower on, shaker at half duty, switched on at 200-210 ms): the bed watchdog (500 ms after
/// the host's last frame) latches `BedWatchdog` and everything goes off, on the pins, within a
/// tick of its timeout. The binary before issue 48 left all three running for good. Killed by
/// `bed-watchdog-drive-only` and `bed-trip-keeps-outputs`.
#[test]
fn a_silent_host_turns_the_idle_bed_off_after_its_watchdog() {
    use sandjumper_core::{FaultCode, RigMessage};
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(800 * MS);
    cfg.trace_every = 1;
    cfg.actions = bed_switched_on();
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    let last_frame = 210 * MS;
    let running = at(&r, last_frame + 490 * MS).out;
    assert!(
        running.lift_gated
            && running.blower_dac_v > 1.0
            && (running.shaker_duty - 0.5).abs() < 0.01,
        "the bed stopped before its watchdog's 500 ms: {running:?}"
    );
    let first_off = r
        .trace
        .iter()
        .filter(|row| row.t_ns >= last_frame)
        .find(|row| {
            !row.out.lift_enable && row.out.blower_dac_v < 0.01 && row.out.shaker_duty == 0.0
        })
        .unwrap_or_else(|| panic!("the bed ran on with the host silent: {:?}", r.last));
    let after = first_off.t_ns - last_frame;
    assert!(
        (500 * MS..502 * MS).contains(&after),
        "the bed went off {} us after the host's last frame",
        after / 1000
    );
    assert!(
        r.trace
            .iter()
            .filter(|row| row.t_ns >= first_off.t_ns)
            .all(|row| row.out.drive_and_lift_safe() && row.out.led_fault),
        "not latched off"
    );
    assert!(
        rig_messages(&host.received)
            .iter()
            .any(|m| matches!(m, RigMessage::Fault(f) if f.code == FaultCode::BedWatchdog)),
        "no BedWatchdog report"
    );
}

/// Issue 48 item 4: TIM7 alone stops (the tick's interrupt lost) while the core, USB and the rest
/// of the firmware run on, the rig armed. The heartbeat (PE8) is the tick's alone, so the
/// external gate drops the drive within its 1 ms; the watchdog, fed by the tick alone, resets the
/// board within its period; meanwhile the USB link task still takes the host's bytes (a burst of
/// heartbeats 2 ms after: the rest of the firmware did run; commands are answered by the tick, so
/// none is). Killed by `heartbeat-from-link` (the gate stays open) and
/// `watchdog-fed-by-link` (no reset).
#[test]
fn a_tick_timer_that_stops_alone_is_gated_and_reset_while_usb_runs_on() {
    use sandjumper_core::RigMessage;
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(FAULT_AT + 60 * MS);
    cfg.trace_every = 1;
    cfg.robot = Some(robot_at_single_start());
    let mut actions = armed_actions(ARM_AT, FAULT_AT);
    actions.push((FAULT_AT, Action::TickTimerStops));
    let burst: Vec<u8> = (0..40u16)
        .flat_map(|k| common::command_frame(900 + k, Command::Heartbeat))
        .collect();
    let burst_len = burst.len() as u64;
    actions.push((FAULT_AT + 2 * MS, Action::HostBytes(burst)));
    // The host goes on talking, as a host does (its traffic wakes the link task).
    actions.extend((0..18u16).map(|k| {
        (
            FAULT_AT + 4 * MS + u64::from(k) * 2 * MS,
            send(950 + k, Command::Heartbeat),
        )
    }));
    cfg.actions = actions;
    let (r, host) = run(cfg, NoHost::default()).expect("the run");
    assert!(at(&r, FAULT_AT - MS).out.drive_gated, "not armed before");
    let (reset_at, cause) = r
        .resets
        .first()
        .cloned()
        .unwrap_or_else(|| panic!("no reset after the tick stopped: {:?}", r.last));
    assert!(
        cause.contains("IWDG") && reset_at > FAULT_AT && reset_at < FAULT_AT + 25 * MS,
        "{reset_at} {cause}"
    );
    assert!(
        r.trace
            .iter()
            .filter(|row| row.t_ns >= FAULT_AT + 1_200_000 && row.t_ns < reset_at)
            .all(|row| !row.out.drive_gated && row.out.force_n == 0.0),
        "the drive saw its enable more than 1.2 ms after the tick stopped"
    );
    let taken = at(&r, reset_at - 200_000).usb_out_bytes - at(&r, FAULT_AT + MS).usb_out_bytes;
    assert!(
        taken >= burst_len,
        "the USB link took {taken} of the {burst_len} bytes sent after the tick stopped: the rest of the firmware did not run"
    );
    assert!(
        !rig_messages(&host.received)
            .iter()
            .any(|m| matches!(m, RigMessage::Reply { id: 900.., .. })),
        "a command was answered without the tick"
    );
    all_off_after_the_reset(&r);
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

/// A harness whose presence link is broken: the apparatus reads as absent (nothing of it can be
/// switched on), and the emergency stop, on its own connector, is read all the same: pressed
/// while armed, it stops the drive within a tick. (Before issue 48 the missing link had to read
/// as a stop, since the e-stop was read only with the harness.)
#[test]
fn a_broken_presence_link_leaves_the_apparatus_absent_and_the_stop_read() {
    let Some(elf) = common::firmware_elf() else {
        return;
    };
    let mut cfg = RunConfig::new(elf);
    cfg.until_ns = Some(FAULT_AT + 100 * MS);
    cfg.trace_every = 1;
    cfg.bed = BedWiring::BrokenPresenceLink;
    cfg.robot = Some(robot_at_single_start());
    cfg.actions = armed_actions(ARM_AT, FAULT_AT + 100 * MS);
    cfg.actions
        .push((FAULT_AT, Action::EmergencyStop(EmergencyStopLoop::Open)));
    let (r, _) = run(cfg, NoHost::default()).expect("the run");
    assert!(!at(&r, FAULT_AT - MS).out.led_fault);
    safe_within(&r, FAULT_AT, 300_000, "stop pressed, presence link broken");
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
    actions.push((350 * MS, Action::EmergencyStop(EmergencyStopLoop::Open)));
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
